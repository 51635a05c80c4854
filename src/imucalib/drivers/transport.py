"""Byte transports: the only place where drivers touch sockets, serial ports and VISA sessions.

A transport moves bytes and nothing else; the dialect codecs (:mod:`~imucalib.drivers.acl`, …)
turn commands into bytes and replies into values, and the device classes put the two together.

Contents
--------
:class:`Transport`
    The protocol: ``write``, ``read``, ``read_until``, ``close``.
:class:`TcpTransport`
    A TCP client socket (time-outs raise :class:`~imucalib.errors.DeviceTimeoutError`, a lost or
    closed connection :class:`~imucalib.errors.DeviceError`).
:class:`SerialTransport`
    pyserial, also on its URLs (``loop://``, ``socket://127.0.0.1:PORT``), so a serial dialect is
    tested over a socket.
:class:`VisaTransport`
    pyvisa (pyvisa-py ``@py`` backend by default), e.g. ``TCPIP::127.0.0.1::PORT::SOCKET``.
:class:`TransportSpec`, :func:`parse_transport_url`, :func:`open_transport`
    The station file's transport URLs (``tcp://host:port``, ``serial://PORT?baud=9600``,
    ``visa://RESOURCE``) and the transport each one opens.
:func:`log_wire`
    Debug-log one command or reply with its monotonic time stamp.

The fake transport for unit tests is :class:`~imucalib.drivers.fake.FakeTransport`.
"""

from __future__ import annotations

import logging
import socket
import time
from dataclasses import dataclass
from typing import Any, Literal, Protocol, runtime_checkable
from urllib.parse import parse_qs

from imucalib.errors import ConfigurationError, DeviceError, DeviceTimeoutError

__all__ = [
    "SerialTransport",
    "TcpTransport",
    "Transport",
    "TransportSpec",
    "VisaTransport",
    "log_wire",
    "open_transport",
    "parse_transport_url",
]

_LOG = logging.getLogger(__name__)
_MAX_LINE_BYTES = 1 << 20  # a reply without its terminator after this many bytes is garbage


def log_wire(logger: logging.Logger, where: str, direction: str, data: bytes | str) -> None:
    """Debug-log one command or reply, stamped with ``time.monotonic()``.

    Parameters
    ----------
    logger : logging.Logger
        The device module's logger.
    where : str
        Device name or address.
    direction : {"tx", "rx"}
        Sent or received.
    data : bytes or str
        What went over the wire.
    """
    if logger.isEnabledFor(logging.DEBUG):
        logger.debug("%.6f %s %s %r", time.monotonic(), where, direction, data)


@runtime_checkable
class Transport(Protocol):
    """A byte pipe to one device.

    ``read`` returns as soon as at least one byte is available (at most `n_bytes`);
    ``read_until`` returns everything up to and including `terminator`. Both raise
    :class:`~imucalib.errors.DeviceTimeoutError` when nothing (or no terminator) arrives within
    `timeout_s`, and :class:`~imucalib.errors.DeviceError` when the link is lost or closed.
    """

    def write(self, data: bytes) -> None:
        """Send `data` entirely."""
        ...

    def read(self, n_bytes: int, *, timeout_s: float) -> bytes:
        """Return 1 to `n_bytes` bytes, waiting at most `timeout_s` for the first. [s]"""
        ...

    def read_until(self, terminator: bytes, *, timeout_s: float) -> bytes:
        """Return the bytes up to and including `terminator`, waiting at most `timeout_s`. [s]"""
        ...

    def close(self) -> None:
        """Close the link (idempotent)."""
        ...


class _Buffered:
    """Shared buffering of the socket and serial transports (subclasses implement ``_recv``)."""

    name = "transport"

    def __init__(self) -> None:
        self._buf = bytearray()
        self._closed = False

    def _recv(self, n_bytes: int, timeout_s: float) -> bytes:  # pragma: no cover - abstract
        raise NotImplementedError

    def _check_open(self) -> None:
        if self._closed:
            raise DeviceError(f"{self.name}: the link is closed")

    def _take(self, n: int) -> bytes:
        out = bytes(self._buf[:n])
        del self._buf[:n]
        return out

    def read(self, n_bytes: int, *, timeout_s: float) -> bytes:
        """Return 1 to `n_bytes` bytes, waiting at most `timeout_s` for the first. [s]"""
        self._check_open()
        if not self._buf:
            self._buf += self._recv(max(int(n_bytes), 1), float(timeout_s))
        return self._take(max(int(n_bytes), 1))

    def read_until(self, terminator: bytes, *, timeout_s: float) -> bytes:
        """Return the bytes up to and including `terminator`, waiting at most `timeout_s`. [s]"""
        self._check_open()
        deadline = time.monotonic() + float(timeout_s)
        start = 0
        while True:
            idx = self._buf.find(terminator, start)
            if idx >= 0:
                return self._take(idx + len(terminator))
            if len(self._buf) > _MAX_LINE_BYTES:
                raise DeviceError(
                    f"{self.name}: no terminator {terminator!r} in {len(self._buf)} bytes"
                )
            start = max(0, len(self._buf) - len(terminator) + 1)
            remaining = deadline - time.monotonic()
            try:
                if remaining <= 0.0:
                    raise DeviceTimeoutError("deadline passed")
                self._buf += self._recv(65536, remaining)
            except DeviceTimeoutError:
                raise DeviceTimeoutError(
                    f"{self.name}: no reply ending in {terminator!r} within {timeout_s:g} s "
                    f"(got {bytes(self._buf[:80])!r})"
                ) from None


class TcpTransport(_Buffered):
    """A TCP client connection.

    Parameters
    ----------
    host : str
        Address of the device (the simulator servers listen on ``127.0.0.1``).
    port : int
        TCP port.
    connect_timeout_s : float
        Time allowed to establish the connection. [s]

    Raises
    ------
    DeviceTimeoutError
        If the connection is not established within `connect_timeout_s`.
    DeviceError
        If the connection is refused or fails.
    """

    def __init__(self, host: str, port: int, *, connect_timeout_s: float = 3.0) -> None:
        super().__init__()
        self.host, self.port = host, int(port)
        self.name = f"tcp://{host}:{self.port}"
        try:
            self._sock = socket.create_connection((host, self.port), timeout=connect_timeout_s)
        except TimeoutError as exc:
            raise DeviceTimeoutError(
                f"{self.name}: no connection within {connect_timeout_s:g} s"
            ) from exc
        except OSError as exc:
            raise DeviceError(f"{self.name}: cannot connect: {exc}") from exc
        self._sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)

    def write(self, data: bytes) -> None:
        """Send `data` entirely."""
        self._check_open()
        try:
            self._sock.sendall(data)
        except OSError as exc:
            raise DeviceError(f"{self.name}: connection lost while writing: {exc}") from exc

    def _recv(self, n_bytes: int, timeout_s: float) -> bytes:
        try:
            self._sock.settimeout(max(timeout_s, 1e-4))
            chunk = self._sock.recv(n_bytes)
        except TimeoutError as exc:
            raise DeviceTimeoutError(f"{self.name}: nothing received within {timeout_s:.3g} s"
                                     ) from exc
        except OSError as exc:
            if self._closed:
                raise DeviceError(f"{self.name}: the link is closed") from exc
            raise DeviceError(f"{self.name}: connection lost while reading: {exc}") from exc
        if not chunk:
            if self._closed:
                raise DeviceError(f"{self.name}: the link is closed")
            raise DeviceError(f"{self.name}: connection closed by the device")
        return chunk

    def close(self) -> None:
        """Close the connection (idempotent); a blocked ``read`` in another thread returns."""
        if self._closed:
            return
        self._closed = True
        try:
            self._sock.shutdown(socket.SHUT_RDWR)
        except OSError:
            pass
        self._sock.close()

    def __repr__(self) -> str:
        return f"TcpTransport({self.host!r}, {self.port})"


class SerialTransport(_Buffered):
    """A serial port through pyserial (device names and pyserial URLs).

    Parameters
    ----------
    port : str
        A device (``/dev/ttyUSB0``, ``COM3``) or a pyserial URL (``loop://``,
        ``socket://127.0.0.1:5000``, ``rfc2217://…``).
    baudrate : int
        Line speed (ignored by ``socket://``). [baud]
    bytesize, parity, stopbits
        Framing, 8N1 by default.

    Raises
    ------
    DeviceError
        If the port cannot be opened.
    """

    def __init__(self, port: str, *, baudrate: int = 9600, bytesize: int = 8, parity: str = "N",
                 stopbits: float = 1) -> None:
        import serial  # lazily: only serial stations need it

        super().__init__()
        self.port, self.baudrate = port, int(baudrate)
        self.name = f"serial://{port}"
        self._serial_exc: type[Exception] = serial.SerialException
        try:
            self._ser = serial.serial_for_url(port, baudrate=self.baudrate, bytesize=bytesize,
                                              parity=parity, stopbits=stopbits, timeout=0.1)
        except (serial.SerialException, ValueError, OSError) as exc:
            raise DeviceError(f"{self.name}: cannot open: {exc}") from exc

    def write(self, data: bytes) -> None:
        """Send `data` entirely."""
        self._check_open()
        try:
            self._ser.write(data)
        except (self._serial_exc, OSError) as exc:
            raise DeviceError(f"{self.name}: link lost while writing: {exc}") from exc

    def _recv(self, n_bytes: int, timeout_s: float) -> bytes:
        try:
            self._ser.timeout = max(timeout_s, 1e-4)
            first = self._ser.read(1)
            if not first:
                raise DeviceTimeoutError(f"{self.name}: nothing received within "
                                         f"{timeout_s:.3g} s")
            self._ser.timeout = 0
            rest = self._ser.read(n_bytes - 1) if n_bytes > 1 else b""
        except DeviceTimeoutError:
            raise
        except (self._serial_exc, OSError, TypeError, AttributeError, ValueError) as exc:
            # pyserial's socket:// raises SerialException('socket disconnected') when the peer
            # closes; a port closed under a blocked reader raises TypeError, AttributeError or
            # ValueError (select on a closed descriptor)
            raise DeviceError(f"{self.name}: link lost while reading: {exc}") from exc
        return bytes(first) + bytes(rest)

    def close(self) -> None:
        """Close the port (idempotent)."""
        if self._closed:
            return
        self._closed = True
        try:
            self._ser.close()
        except (self._serial_exc, OSError):
            pass

    def __repr__(self) -> str:
        return f"SerialTransport({self.port!r}, baudrate={self.baudrate})"


class VisaTransport:
    """A VISA session through pyvisa (pyvisa-py's ``@py`` backend by default).

    Parameters
    ----------
    resource : str
        VISA resource name, e.g. ``TCPIP::127.0.0.1::9878::SOCKET`` or ``GPIB0::1::INSTR``.
    backend : str
        pyvisa backend (``"@py"``: pure Python; ``"@ivi"``: NI-VISA or another vendor VISA).
    open_timeout_s : float
        Time allowed to open the session. [s]

    Notes
    -----
    :meth:`read_until` uses the last byte of the terminator as the VISA termination character;
    :meth:`read` returns exactly `n_bytes` bytes. pyvisa-py reports a connection that the device
    closed as a read time-out, so a lost link raises
    :class:`~imucalib.errors.DeviceTimeoutError` (a :class:`~imucalib.errors.DeviceError`).
    """

    def __init__(self, resource: str, *, backend: str = "@py", open_timeout_s: float = 3.0) -> None:
        import pyvisa  # lazily: only VISA stations need it

        self.resource, self.backend = resource, backend
        self.name = f"visa://{resource}"
        self._errors = pyvisa.errors
        self._closed = False
        try:
            self._rm = pyvisa.ResourceManager(backend)
            inst: Any = self._rm.open_resource(resource, open_timeout=int(open_timeout_s * 1000))
        except (pyvisa.errors.Error, OSError, ValueError) as exc:
            raise DeviceError(f"{self.name}: cannot open: {exc}") from exc
        self._inst: Any = inst
        self._inst.write_termination = ""
        self._inst.read_termination = None

    def _check_open(self) -> None:
        if self._closed:
            raise DeviceError(f"{self.name}: the link is closed")

    def _fail(self, exc: Exception, what: str, timeout_s: float) -> DeviceError:
        code = getattr(exc, "error_code", None)
        if code == self._errors.StatusCode.error_timeout:
            return DeviceTimeoutError(f"{self.name}: nothing received within {timeout_s:.3g} s "
                                      "(or the device closed the connection)")
        return DeviceError(f"{self.name}: {what} failed: {exc}")

    def write(self, data: bytes) -> None:
        """Send `data` entirely."""
        self._check_open()
        try:
            self._inst.write_raw(data)
        except (self._errors.Error, OSError) as exc:
            raise self._fail(exc, "write", 0.0) from exc

    def read(self, n_bytes: int, *, timeout_s: float) -> bytes:
        """Return exactly `n_bytes` bytes, waiting at most `timeout_s`. [s]"""
        self._check_open()
        try:
            self._inst.timeout = max(1, int(timeout_s * 1000))
            self._inst.read_termination = None
            return bytes(self._inst.read_bytes(int(n_bytes), break_on_termchar=False))
        except (self._errors.Error, OSError) as exc:
            raise self._fail(exc, "read", timeout_s) from exc

    def read_until(self, terminator: bytes, *, timeout_s: float) -> bytes:
        """Return the bytes up to and including `terminator`, waiting at most `timeout_s`. [s]"""
        self._check_open()
        deadline = time.monotonic() + float(timeout_s)
        out = b""
        try:
            self._inst.read_termination = terminator[-1:].decode("latin-1")
            while not out.endswith(terminator):
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    raise DeviceTimeoutError(f"{self.name}: no reply ending in {terminator!r} "
                                             f"within {timeout_s:g} s")
                self._inst.timeout = max(1, int(remaining * 1000))
                out += bytes(self._inst.read_raw())
        except (self._errors.Error, OSError) as exc:
            raise self._fail(exc, "read", timeout_s) from exc
        return out

    def close(self) -> None:
        """Close the session (idempotent)."""
        if self._closed:
            return
        self._closed = True
        try:
            self._inst.close()
            self._rm.close()
        except (self._errors.Error, OSError):
            pass

    def __repr__(self) -> str:
        return f"VisaTransport({self.resource!r}, backend={self.backend!r})"


# --- transport URLs -----------------------------------------------------------------------------
Scheme = Literal["tcp", "serial", "visa"]


@dataclass(frozen=True)
class TransportSpec:
    """A parsed transport URL.

    Attributes
    ----------
    scheme : {"tcp", "serial", "visa"}
        Which transport.
    url : str
        The URL as written.
    host, port : str, int
        TCP address (``tcp``).
    device : str
        Serial device or pyserial URL (``serial``), or VISA resource (``visa``).
    baudrate : int
        Serial line speed. [baud]
    parity : str
        Serial parity (N, E, O).
    backend : str
        pyvisa backend (``visa``).
    """

    scheme: Scheme
    url: str
    host: str = ""
    port: int = 0
    device: str = ""
    baudrate: int = 9600
    parity: str = "N"
    backend: str = "@py"

    def describe(self) -> str:
        """Return the URL (as written)."""
        return self.url


def _split_query(rest: str) -> tuple[str, dict[str, str]]:
    base, _, query = rest.partition("?")
    params = {k.lower(): v[-1] for k, v in parse_qs(query, keep_blank_values=True).items()}
    return base, params


def _parse_port(text: str, url: str) -> int:
    try:
        port = int(text)
    except ValueError:
        raise ConfigurationError(f"port {text!r} in {url!r} is not an integer") from None
    if not 1 <= port <= 65535:
        raise ConfigurationError(f"port {port} in {url!r} is outside 1–65535")
    return port


def parse_transport_url(url: str) -> TransportSpec:
    """Parse a transport URL of the station file.

    Accepted forms::

        tcp://HOST:PORT
        serial://DEVICE?baud=9600&parity=N      DEVICE: /dev/ttyUSB0, COM3, or a pyserial URL
                                                 such as socket://127.0.0.1:5000 or loop://
        visa://RESOURCE?backend=@py             RESOURCE: TCPIP::HOST::PORT::SOCKET, GPIB0::1::INSTR

    Raises
    ------
    ConfigurationError
        For an unknown scheme, a missing host, or a port that is not an integer in 1–65535;
        the message quotes the URL.
    """
    if not isinstance(url, str) or "://" not in url:
        raise ConfigurationError(
            f"transport {url!r} must be a URL tcp://HOST:PORT, serial://DEVICE?baud=N or "
            "visa://RESOURCE"
        )
    scheme, _, rest = url.partition("://")
    scheme = scheme.lower()
    if scheme == "tcp":
        base, _ = _split_query(rest)
        host, sep, port_txt = base.rpartition(":")
        if not sep or not host:
            raise ConfigurationError(f"transport {url!r} must be tcp://HOST:PORT")
        return TransportSpec("tcp", url, host=host.strip("[]"), port=_parse_port(port_txt, url))
    if scheme == "serial":
        device, params = _split_query(rest)
        if not device:
            raise ConfigurationError(f"transport {url!r} names no serial device")
        if device.startswith("socket://"):
            _parse_port(device.rpartition(":")[2].split("/")[0], url)
        try:
            baud = int(params.get("baud", "9600"))
        except ValueError:
            raise ConfigurationError(f"baud {params['baud']!r} in {url!r} is not an integer"
                                     ) from None
        if baud <= 0:
            raise ConfigurationError(f"baud {baud} in {url!r} must be > 0")
        parity = params.get("parity", "N").upper()
        if parity not in {"N", "E", "O", "M", "S"}:
            raise ConfigurationError(f"parity {parity!r} in {url!r} must be one of N, E, O, M, S")
        return TransportSpec("serial", url, device=device, baudrate=baud, parity=parity)
    if scheme == "visa":
        resource, params = _split_query(rest)
        if not resource:
            raise ConfigurationError(f"transport {url!r} names no VISA resource")
        parts = resource.split("::")
        if parts[0].upper().startswith("TCPIP") and len(parts) >= 4 \
                and parts[-1].upper() == "SOCKET":
            _parse_port(parts[2], url)
        return TransportSpec("visa", url, device=resource, backend=params.get("backend", "@py"))
    raise ConfigurationError(
        f"transport {url!r} has unknown scheme {scheme!r}; expected tcp, serial or visa"
    )


def open_transport(spec: TransportSpec | str, *, connect_timeout_s: float = 3.0) -> Transport:
    """Open the transport a URL (or parsed :class:`TransportSpec`) describes.

    Raises
    ------
    ConfigurationError
        For a malformed URL (see :func:`parse_transport_url`).
    DeviceError
        If the link cannot be opened.
    """
    sp = parse_transport_url(spec) if isinstance(spec, str) else spec
    _LOG.debug("opening %s", sp.url)
    if sp.scheme == "tcp":
        return TcpTransport(sp.host, sp.port, connect_timeout_s=connect_timeout_s)
    if sp.scheme == "serial":
        return SerialTransport(sp.device, baudrate=sp.baudrate, parity=sp.parity)
    return VisaTransport(sp.device, backend=sp.backend, open_timeout_s=connect_timeout_s)
