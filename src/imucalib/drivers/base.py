"""Plumbing shared by the device classes: a locked request/reply channel and the check result.

Contents
--------
:class:`LineChannel`
    Owns a transport (opened by a factory, so it can be reopened after a lost link), serialises
    exchanges with a lock, logs every command and reply with its monotonic time stamp, and
    drops the link on any transport error so that a late reply can never be taken for the
    answer to the next command.
:class:`DeviceCheck`
    What ``imucalib station check`` reports for one device.
:data:`TransportOpener`
    A callable returning a freshly opened :class:`~imucalib.drivers.transport.Transport`.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from imucalib.drivers.transport import Transport, log_wire
from imucalib.errors import DeviceError

__all__ = ["DeviceCheck", "LineChannel", "TransportOpener"]

#: Opens the transport of a device (called on connect and on a reconnect).
TransportOpener = Callable[[], Transport]


@dataclass(frozen=True)
class DeviceCheck:
    """The result of checking one device without moving it.

    Attributes
    ----------
    role : str
        ``table``, ``centrifuge``, ``chamber`` or ``imu``.
    name : str
        Device name.
    kind : str
        Dialect (``acutrol``, ``watlow-f4t``, ``packet`` …).
    address : str
        Transport URL.
    identity : str
        What the device answered to its identification query.
    state : str
        Status summary (modes, interlock, faults, alarms, counters).
    reading : str
        One reading (angles and rates, temperature, samples received).
    ok : bool
        False when the device reports a fault or alarm.
    details : dict
        Machine-readable values behind the texts.
    """

    role: str
    name: str
    kind: str
    address: str
    identity: str
    state: str
    reading: str
    ok: bool = True
    details: dict[str, Any] = field(default_factory=dict)


class LineChannel:
    """Request/reply exchanges over a transport that may be lost and reopened.

    Parameters
    ----------
    name : str
        Device name for messages and the log.
    opener : callable
        Returns a newly opened transport.
    terminator : bytes
        End of a reply line.
    timeout_s : float
        Time allowed for each reply line. [s]
    logger : logging.Logger
        The device module's logger (debug level: every command and reply).
    """

    def __init__(self, name: str, opener: TransportOpener, *, terminator: bytes,
                 timeout_s: float, logger: logging.Logger) -> None:
        self.name = name
        self._opener = opener
        self.terminator = terminator
        self.timeout_s = float(timeout_s)
        self._log = logger
        self._transport: Transport | None = None
        self._lost: str | None = None
        self.lock = threading.RLock()

    @property
    def is_open(self) -> bool:
        """Whether the link is open."""
        return self._transport is not None

    def open(self) -> None:
        """Open the link (nothing when already open).

        Raises
        ------
        DeviceError
            If the transport cannot be opened.
        """
        with self.lock:
            if self._transport is None:
                self._transport = self._opener()
                self._lost = None
                self._log.debug("%s: link open", self.name)

    def close(self) -> None:
        """Close the link (idempotent, never raises)."""
        with self.lock:
            transport, self._transport = self._transport, None
        if transport is not None:
            try:
                transport.close()
            except Exception as exc:  # closing must not raise
                self._log.debug("%s: close failed: %s", self.name, exc)

    def reopen(self) -> None:
        """Close and open the link again."""
        with self.lock:
            self.close()
            self.open()

    def _fail(self, exc: DeviceError) -> None:
        self._lost = str(exc)
        self._log.warning("%s: link dropped after an error: %s", self.name, exc)
        self.close()

    def _require(self) -> Transport:
        if self._transport is None:
            why = f" (link lost: {self._lost})" if self._lost else ""
            raise DeviceError(f"{self.name}: not connected{why}; call connect()")
        return self._transport

    def send(self, data: bytes) -> None:
        """Send a command that gets no reply.

        Raises
        ------
        DeviceError
            If the link is closed or lost (it is then dropped).
        """
        with self.lock:
            transport = self._require()
            log_wire(self._log, self.name, "tx", data)
            try:
                transport.write(data)
            except DeviceError as exc:
                self._fail(exc)
                raise

    def exchange(self, data: bytes, *, lines: int = 1) -> list[bytes]:
        """Send a command and return its reply lines (terminators stripped).

        Raises
        ------
        DeviceTimeoutError
            If a reply line does not arrive in time (the link is then dropped).
        DeviceError
            If the link is closed or lost (it is then dropped).
        """
        with self.lock:
            transport = self._require()
            log_wire(self._log, self.name, "tx", data)
            out = []
            try:
                transport.write(data)
                for _ in range(lines):
                    line = transport.read_until(self.terminator, timeout_s=self.timeout_s)
                    log_wire(self._log, self.name, "rx", line)
                    out.append(line[:-len(self.terminator)])
            except DeviceError as exc:
                self._fail(exc)
                raise
            return out
