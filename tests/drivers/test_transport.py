"""Transports against tiny loopback servers (127.0.0.1, OS-assigned ports), URLs, the fake."""

from __future__ import annotations

import re
import socket
import threading
import time
from collections.abc import Callable, Iterator

import pytest

from imucalib.drivers import FakeTransport, SerialTransport, TcpTransport, VisaTransport
from imucalib.drivers.transport import open_transport, parse_transport_url
from imucalib.errors import ConfigurationError, DeviceError, DeviceTimeoutError

Handler = Callable[[socket.socket], None]


@pytest.fixture
def serve() -> Iterator[Callable[[Handler], int]]:
    """Start a one-client server on 127.0.0.1 running `handler`; return its port."""
    listeners: list[socket.socket] = []
    threads: list[threading.Thread] = []

    def start(handler: Handler) -> int:
        lst = socket.create_server(("127.0.0.1", 0))
        listeners.append(lst)

        def run() -> None:
            try:
                conn, _ = lst.accept()
            except OSError:  # closed without a client
                return
            with conn:
                handler(conn)

        t = threading.Thread(target=run, daemon=True)
        t.start()
        threads.append(t)
        return int(lst.getsockname()[1])

    yield start
    for lst in listeners:
        lst.close()
    for t in threads:
        t.join(timeout=2)


def _echo_lines(conn: socket.socket) -> None:
    buf = b""
    while True:
        data = conn.recv(100)
        if not data:
            return
        buf += data
        while b"\n" in buf:
            line, buf = buf.split(b"\n", 1)
            if line == b"QUIET":
                continue
            if line == b"BYE":
                return
            conn.sendall(b"<" + line + b">\n")


def test_tcp_request_reply_timeout_and_peer_close(serve: Callable[[Handler], int]) -> None:
    port = serve(_echo_lines)
    t = TcpTransport("127.0.0.1", port)
    t.write(b"ab\ncd\n")
    assert t.read_until(b"\n", timeout_s=1.0) == b"<ab>\n"
    assert t.read(2, timeout_s=1.0) == b"<c"
    assert t.read_until(b">\n", timeout_s=1.0) == b"d>\n"
    t.write(b"QUIET\n")
    start = time.monotonic()
    message = re.escape("no reply ending in b'\\n' within 0.2 s")
    with pytest.raises(DeviceTimeoutError, match=message):
        t.read_until(b"\n", timeout_s=0.2)
    assert 0.15 < time.monotonic() - start < 1.0
    t.write(b"BYE\n")
    with pytest.raises(DeviceError, match="connection closed by the device"):
        t.read_until(b"\n", timeout_s=1.0)
    t.close()
    t.close()  # idempotent
    with pytest.raises(DeviceError, match="the link is closed"):
        t.write(b"x")


def test_tcp_refused() -> None:
    lst = socket.create_server(("127.0.0.1", 0))
    port = lst.getsockname()[1]
    lst.close()
    with pytest.raises(DeviceError, match=f"tcp://127.0.0.1:{port}: cannot connect"):
        TcpTransport("127.0.0.1", port)


def test_serial_over_socket_url_and_loop(serve: Callable[[Handler], int]) -> None:
    port = serve(_echo_lines)
    s = SerialTransport(f"socket://127.0.0.1:{port}", baudrate=9600)
    s.write(b"hello\n")
    assert s.read_until(b"\n", timeout_s=1.0) == b"<hello>\n"
    s.write(b"BYE\n")
    with pytest.raises(DeviceError, match="link lost while reading"):
        s.read_until(b"\n", timeout_s=1.0)
    s.close()
    loop = SerialTransport("loop://")
    loop.write(b"\xaa\x55xyz")
    assert loop.read(10, timeout_s=0.5) == b"\xaa\x55xyz"
    with pytest.raises(DeviceTimeoutError, match=re.escape("nothing received within 0.1 s")):
        loop.read(1, timeout_s=0.1)
    loop.close()


def test_visa_socket_resource(serve: Callable[[Handler], int]) -> None:
    port = serve(_echo_lines)
    v = VisaTransport(f"TCPIP::127.0.0.1::{port}::SOCKET")
    v.write(b"idn\n")
    assert v.read_until(b"\n", timeout_s=2.0) == b"<idn>\n"
    v.write(b"QUIET\n")
    with pytest.raises(DeviceTimeoutError):
        v.read_until(b"\n", timeout_s=0.2)
    v.close()


@pytest.mark.parametrize("url, scheme, host, port, device, baud", [
    ("tcp://127.0.0.1:9878", "tcp", "127.0.0.1", 9878, "", 9600),
    ("serial:///dev/ttyUSB0?baud=115200", "serial", "", 0, "/dev/ttyUSB0", 115200),
    ("serial://socket://127.0.0.1:5000?baud=9600", "serial", "", 0, "socket://127.0.0.1:5000",
     9600),
    ("visa://TCPIP::127.0.0.1::9878::SOCKET", "visa", "", 0, "TCPIP::127.0.0.1::9878::SOCKET",
     9600),
])
def test_parse_transport_url(url: str, scheme: str, host: str, port: int, device: str,
                             baud: int) -> None:
    spec = parse_transport_url(url)
    assert (spec.scheme, spec.host, spec.port, spec.device, spec.baudrate) == (
        scheme, host, port, device, baud)


@pytest.mark.parametrize("url, message", [
    ("tcp://127.0.0.1:70000", "port 70000 in 'tcp://127.0.0.1:70000' is outside 1–65535"),
    ("tcp://127.0.0.1:0", "port 0 in 'tcp://127.0.0.1:0' is outside 1–65535"),
    ("tcp://127.0.0.1:http", "port 'http' in 'tcp://127.0.0.1:http' is not an integer"),
    ("tcp://127.0.0.1", "transport 'tcp://127.0.0.1' must be tcp://HOST:PORT"),
    ("udp://127.0.0.1:5", "has unknown scheme 'udp'; expected tcp, serial or visa"),
    ("COM3", "transport 'COM3' must be a URL"),
    ("serial:///dev/ttyS0?baud=fast", "baud 'fast' in 'serial:///dev/ttyS0\\?baud=fast' is not"),
    ("visa://TCPIP::127.0.0.1::99999::SOCKET", "port 99999 in"),
])
def test_parse_transport_url_errors(url: str, message: str) -> None:
    with pytest.raises(ConfigurationError, match=message):
        parse_transport_url(url)


def test_open_transport_dispatch(serve: Callable[[Handler], int]) -> None:
    port = serve(_echo_lines)
    t = open_transport(f"tcp://127.0.0.1:{port}")
    assert isinstance(t, TcpTransport)
    t.close()


def test_fake_transport_script() -> None:
    fake = FakeTransport([(b"*IDN?\n", b"00000003SIM\n"),
                          (b"X\n", DeviceError("connection lost"))])
    fake.write(b"*IDN?\n")
    assert fake.read_until(b"\n", timeout_s=1.0) == b"00000003SIM\n"
    with pytest.raises(DeviceError, match="connection lost"):
        fake.write(b"X\n")
    with pytest.raises(DeviceError, match="unexpected write b'Y\\\\n'; the script is exhausted"):
        fake.write(b"Y\n")
    other = FakeTransport([(b"A\n", b"")])
    with pytest.raises(DeviceError, match="expected write b'A\\\\n'; got b'B\\\\n'"):
        other.write(b"B\n")
    with pytest.raises(DeviceTimeoutError):
        other.read(1, timeout_s=0.01)
    other.feed(b"stream")
    assert other.read(3, timeout_s=0.01) == b"str"
    other.close()
    with pytest.raises(DeviceError, match="the link is closed"):
        other.read(1, timeout_s=0.01)
