"""Scripted stand-ins for a transport and a register link, for pure unit tests of device classes.

Contents
--------
:class:`FakeTransport`
    Replays scripted exchanges: each expected write is answered by its scripted reply (or a
    scripted exception, e.g. a dropped connection); unsolicited bytes (a stream) are fed with
    :meth:`FakeTransport.feed`.
:class:`FakeRegisterLink`
    A dictionary of 16-bit registers behind the :class:`~imucalib.drivers.modbus.RegisterLink`
    protocol.
"""

from __future__ import annotations

import threading
import time
from collections import deque
from collections.abc import Iterable, Mapping, Sequence

from imucalib.errors import DeviceError, DeviceTimeoutError

__all__ = ["FakeRegisterLink", "FakeTransport"]


class FakeTransport:
    """A transport that replays a script of (expected write, reply) pairs.

    Parameters
    ----------
    script : iterable of (bytes, bytes or Exception)
        Each write must equal the next expected bytes; its reply (bytes) is then readable, or
        its exception is raised by the write (``DeviceError("connection lost")`` models a drop).
    strict : bool
        Raise :class:`~imucalib.errors.DeviceError` on a write that the script does not expect
        (True), or accept it silently (False, for stream tests that ignore commands).

    Attributes
    ----------
    written : list of bytes
        Every write, in order.
    closed : bool
        Whether :meth:`close` was called.

    Notes
    -----
    A read with nothing buffered waits at most ``min(timeout_s, 0.05)`` s for :meth:`feed`
    before it raises :class:`~imucalib.errors.DeviceTimeoutError`, so tests never wait long.
    """

    def __init__(self, script: Iterable[tuple[bytes, bytes | Exception]] = (), *,
                 strict: bool = True) -> None:
        self._script: deque[tuple[bytes, bytes | Exception]] = deque(script)
        self.strict = strict
        self.written: list[bytes] = []
        self.closed = False
        self._buf = bytearray()
        self._cond = threading.Condition()

    def expect(self, request: bytes, reply: bytes | Exception) -> FakeTransport:
        """Append one exchange to the script; returns self for chaining."""
        with self._cond:
            self._script.append((request, reply))
        return self

    def feed(self, data: bytes) -> None:
        """Make `data` readable (unsolicited bytes, e.g. a sample stream)."""
        with self._cond:
            self._buf += data
            self._cond.notify_all()

    @property
    def pending(self) -> int:
        """Number of scripted exchanges not yet used."""
        return len(self._script)

    def write(self, data: bytes) -> None:
        """Check `data` against the script and queue the scripted reply."""
        with self._cond:
            if self.closed:
                raise DeviceError("FakeTransport: the link is closed")
            self.written.append(bytes(data))
            if not self._script:
                if self.strict:
                    raise DeviceError(f"FakeTransport: unexpected write {bytes(data)!r}; "
                                      "the script is exhausted")
                return
            expected, reply = self._script.popleft()
            if bytes(data) != expected:
                raise DeviceError(
                    f"FakeTransport: expected write {expected!r}; got {bytes(data)!r}"
                )
            if isinstance(reply, Exception):
                raise reply
            self._buf += reply
            self._cond.notify_all()

    def _wait(self, ready: bool, timeout_s: float) -> None:
        if not ready:
            self._cond.wait(min(max(timeout_s, 0.0), 0.05))

    def read(self, n_bytes: int, *, timeout_s: float) -> bytes:
        """Return 1 to `n_bytes` buffered bytes (DeviceTimeoutError when none arrive)."""
        with self._cond:
            if self.closed:
                raise DeviceError("FakeTransport: the link is closed")
            self._wait(bool(self._buf), timeout_s)
            if not self._buf:
                raise DeviceTimeoutError(f"FakeTransport: nothing to read within {timeout_s:g} s")
            n = max(int(n_bytes), 1)
            out = bytes(self._buf[:n])
            del self._buf[:n]
            return out

    def read_until(self, terminator: bytes, *, timeout_s: float) -> bytes:
        """Return buffered bytes up to and including `terminator`."""
        deadline = time.monotonic() + min(timeout_s, 0.05)
        with self._cond:
            while True:
                if self.closed:
                    raise DeviceError("FakeTransport: the link is closed")
                idx = self._buf.find(terminator)
                if idx >= 0:
                    out = bytes(self._buf[:idx + len(terminator)])
                    del self._buf[:idx + len(terminator)]
                    return out
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    raise DeviceTimeoutError(
                        f"FakeTransport: no {terminator!r} within {timeout_s:g} s "
                        f"(buffered {bytes(self._buf[:80])!r})"
                    )
                self._cond.wait(remaining)

    def close(self) -> None:
        """Mark the link closed; later reads and writes raise DeviceError."""
        with self._cond:
            self.closed = True
            self._cond.notify_all()


class FakeRegisterLink:
    """16-bit holding registers in a dictionary (unset registers read as 0).

    Parameters
    ----------
    registers : mapping of int to int, optional
        Initial register values.

    Attributes
    ----------
    registers : dict of int to int
        The register file.
    writes : list of (int, list of int)
        Every write (address, values), in order.
    fail_with : Exception or None
        When set, every read and write raises it (a lost link).
    """

    def __init__(self, registers: Mapping[int, int] | None = None) -> None:
        self.registers: dict[int, int] = dict(registers or {})
        self.writes: list[tuple[int, list[int]]] = []
        self.fail_with: Exception | None = None
        self.closed = False

    def read_registers(self, address: int, count: int) -> list[int]:
        """Return `count` registers from `address`."""
        if self.fail_with is not None:
            raise self.fail_with
        return [self.registers.get(address + i, 0) for i in range(count)]

    def write_registers(self, address: int, values: Sequence[int]) -> None:
        """Store `values` from `address` on."""
        if self.fail_with is not None:
            raise self.fail_with
        self.writes.append((address, [int(v) for v in values]))
        for i, v in enumerate(values):
            self.registers[address + i] = int(v) & 0xFFFF

    def close(self) -> None:
        """Mark the link closed."""
        self.closed = True
