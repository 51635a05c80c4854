"""A small Modbus facade: 16-bit holding registers and IEEE-754 floats across two of them.

pymodbus changes its API between minor versions (``slave`` became ``device_id``; the datastore
classes move; see docs/drivers.md, "Sources"). Everything that touches it is in this module, so a
version bump is a one-file change.

Contents
--------
:class:`RegisterLink`
    The protocol the chamber classes use: ``read_registers``, ``write_registers``, ``close``.
:class:`ModbusTcpLink`
    A :class:`RegisterLink` on pymodbus' synchronous TCP client (function codes 3 and 16).
:func:`floats_to_registers`, :func:`registers_to_floats`
    Pure conversions, low word first by default (Watlow's default word order).
:func:`read_floats`, :func:`write_float`, :func:`read_string`
    Convenience on any :class:`RegisterLink`.

A dictionary-backed link for unit tests is :class:`~imucalib.drivers.fake.FakeRegisterLink`.
"""

from __future__ import annotations

import inspect
import logging
import struct
from collections.abc import Sequence
from typing import Any, Protocol, runtime_checkable

from imucalib.drivers.transport import log_wire
from imucalib.errors import DeviceError, DeviceTimeoutError, InvalidInputError

__all__ = [
    "ModbusTcpLink",
    "RegisterLink",
    "floats_to_registers",
    "read_floats",
    "read_string",
    "registers_to_floats",
    "write_float",
]

_LOG = logging.getLogger(__name__)


@runtime_checkable
class RegisterLink(Protocol):
    """Access to a device's 16-bit holding registers (0-based protocol addresses)."""

    def read_registers(self, address: int, count: int) -> list[int]:
        """Return `count` registers starting at `address`."""
        ...

    def write_registers(self, address: int, values: Sequence[int]) -> None:
        """Write `values` to consecutive registers starting at `address`."""
        ...

    def close(self) -> None:
        """Close the link (idempotent)."""
        ...


def floats_to_registers(values: Sequence[float], *, low_word_first: bool = True) -> list[int]:
    """Return the 16-bit registers of IEEE-754 float32 `values`, two per value.

    Examples
    --------
    >>> floats_to_registers([1.0])
    [0, 16256]
    >>> floats_to_registers([1.0], low_word_first=False)
    [16256, 0]
    """
    out: list[int] = []
    for v in values:
        high, low = struct.unpack(">HH", struct.pack(">f", float(v)))
        out += [low, high] if low_word_first else [high, low]
    return out


def registers_to_floats(registers: Sequence[int], *, low_word_first: bool = True) -> list[float]:
    """Return the float32 values held in pairs of 16-bit `registers`.

    Raises
    ------
    InvalidInputError
        If the number of registers is odd or a register is outside 0–65535.
    """
    regs = [int(r) for r in registers]
    if len(regs) % 2:
        raise InvalidInputError(f"floats take two registers each; got {len(regs)} register(s)")
    bad = [r for r in regs if not 0 <= r <= 0xFFFF]
    if bad:
        raise InvalidInputError(f"registers must be in 0–65535; got {bad[:3]}")
    out = []
    for i in range(0, len(regs), 2):
        a, b = regs[i], regs[i + 1]
        high, low = (b, a) if low_word_first else (a, b)
        out.append(struct.unpack(">f", struct.pack(">HH", high, low))[0])
    return out


def read_floats(link: RegisterLink, address: int, count: int = 1, *,
                low_word_first: bool = True) -> list[float]:
    """Read `count` float32 values from 2·`count` registers at `address`."""
    return registers_to_floats(link.read_registers(address, 2 * count),
                               low_word_first=low_word_first)


def write_float(link: RegisterLink, address: int, value: float, *,
                low_word_first: bool = True) -> None:
    """Write one float32 value to the two registers at `address`."""
    link.write_registers(address, floats_to_registers([value], low_word_first=low_word_first))


def read_string(link: RegisterLink, address: int, count: int) -> str:
    """Read an ASCII string stored one character per register (zeros end or pad it)."""
    chars = [r & 0xFF for r in link.read_registers(address, count)]
    return "".join(chr(c) for c in chars if c).strip()


class ModbusTcpLink:
    """Holding registers over Modbus TCP, on pymodbus' synchronous client.

    Parameters
    ----------
    host : str
        Device address.
    port : int
        TCP port (502 on a Watlow F4T).
    device_id : int
        Modbus unit identifier (1 by default).
    timeout_s : float
        Time allowed per request. [s]

    Raises
    ------
    DeviceError
        If the connection cannot be established.
    """

    def __init__(self, host: str, port: int = 502, *, device_id: int = 1,
                 timeout_s: float = 2.0) -> None:
        from pymodbus.client import ModbusTcpClient  # lazily: only Modbus stations need it

        self.host, self.port, self.device_id = host, int(port), int(device_id)
        self.name = f"modbus-tcp://{host}:{self.port}/{self.device_id}"
        self.timeout_s = float(timeout_s)
        self._client: Any = ModbusTcpClient(host, port=self.port, timeout=self.timeout_s,
                                            retries=0)
        self._id_keyword = self._unit_keyword(self._client)
        if not self._client.connect():
            raise DeviceError(f"{self.name}: cannot connect")

    @staticmethod
    def _unit_keyword(client: Any) -> str:
        """Return the keyword naming the unit: ``device_id`` (3.10+), ``slave`` or ``unit``."""
        params = inspect.signature(client.read_holding_registers).parameters
        for name in ("device_id", "slave", "unit"):
            if name in params:
                return name
        raise DeviceError("this pymodbus version takes no unit keyword this facade knows; "
                          "pin pymodbus~=3.16")

    def _call(self, what: str, fn: Any, *args: Any, **kwargs: Any) -> Any:
        from pymodbus.exceptions import ConnectionException, ModbusException, ModbusIOException

        kwargs[self._id_keyword] = self.device_id
        log_wire(_LOG, self.name, "tx", f"{what} {args}")
        try:
            response = fn(*args, **kwargs)
        except ConnectionException as exc:
            raise DeviceError(f"{self.name}: {what}: connection lost: {exc}") from exc
        except ModbusIOException as exc:
            raise DeviceTimeoutError(f"{self.name}: {what}: no valid reply within "
                                     f"{self.timeout_s:g} s: {exc}") from exc
        except (ModbusException, OSError) as exc:
            raise DeviceError(f"{self.name}: {what} failed: {exc}") from exc
        if response.isError():
            code = getattr(response, "exception_code", None)
            raise DeviceError(f"{self.name}: {what}: the device answered with Modbus exception "
                              f"code {code}")
        log_wire(_LOG, self.name, "rx", repr(getattr(response, "registers", "ok")))
        return response

    def read_registers(self, address: int, count: int) -> list[int]:
        """Return `count` holding registers starting at `address` (function code 3)."""
        response = self._call(f"read {count} register(s) at {address}",
                              self._client.read_holding_registers, int(address), count=int(count))
        regs = [int(r) for r in response.registers]
        if len(regs) != count:
            raise DeviceError(f"{self.name}: asked for {count} register(s) at {address}; "
                              f"got {len(regs)}")
        return regs

    def write_registers(self, address: int, values: Sequence[int]) -> None:
        """Write `values` from `address` on (function code 16)."""
        self._call(f"write {len(values)} register(s) at {address}", self._client.write_registers,
                   int(address), [int(v) for v in values])

    def close(self) -> None:
        """Close the connection (idempotent)."""
        try:
            self._client.close()
        except Exception as exc:  # closing must not raise
            _LOG.debug("%s: close failed: %s", self.name, exc)

    def __repr__(self) -> str:
        return f"ModbusTcpLink({self.host!r}, {self.port}, device_id={self.device_id})"
