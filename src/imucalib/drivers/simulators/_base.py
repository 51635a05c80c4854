"""Threaded loopback servers and the shared virtual time of the simulators.

Contents
--------
:class:`SimTimeBase`
    The virtual time of every server sharing one rig: (monotonic − start) × speed.
:class:`SimServer`
    A TCP listener on 127.0.0.1 (port 0: the OS picks; :attr:`SimServer.port` tells which),
    one thread per client, :meth:`SimServer.drop_connections` and :meth:`SimServer.close`.
:class:`LineSimServer`
    A :class:`SimServer` answering terminated command lines.
"""

from __future__ import annotations

import logging
import socket
import threading
from typing import Any

from imucalib.drivers.clock import MonotonicClock
from imucalib.sim.rig import TwinRig

__all__ = ["LineSimServer", "SimServer", "SimTimeBase"]

_LOG = logging.getLogger(__name__)
_HOST = "127.0.0.1"


class SimTimeBase(MonotonicClock):
    """Virtual time shared by the simulator servers of one rig (and, in tests, the station).

    Simulated time is (``time.monotonic()`` − start) × `speed`, so every server sharing one
    instance sees the same physics; it is also a :class:`~imucalib.station.devices.Clock`, so a
    station under test can use it as its clock and wait in virtual seconds.

    Parameters
    ----------
    speed : float
        Simulated seconds per wall second (1: real time; e.g. 20 for fast tests).
    """


class SimServer:
    """A TCP server on 127.0.0.1 with one thread per client.

    Parameters
    ----------
    name : str
        Server name for logs.
    port : int
        Port to listen on; 0 (default) lets the OS choose (:attr:`port` tells which).

    Notes
    -----
    Subclasses implement :meth:`handle`, which owns one client connection until it returns.
    """

    def __init__(self, name: str, *, port: int = 0) -> None:
        self.name = name
        self._listener = socket.create_server((_HOST, int(port)))
        self._listener.settimeout(0.1)
        self.port: int = self._listener.getsockname()[1]
        self._clients: set[socket.socket] = set()
        self._clients_lock = threading.Lock()
        self._closed = threading.Event()
        self._threads: list[threading.Thread] = []
        self.connections_accepted = 0
        self._accept_thread = threading.Thread(target=self._accept_loop,
                                               name=f"{name}-accept", daemon=True)

    # --- lifecycle ----------------------------------------------------------------------------
    def start(self) -> SimServer:
        """Start accepting clients; returns self."""
        self._accept_thread.start()
        _LOG.info("%s listening on %s:%d", self.name, _HOST, self.port)
        return self

    def __enter__(self) -> SimServer:
        if not self._accept_thread.is_alive():
            self.start()
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    @property
    def address(self) -> str:
        """``127.0.0.1:PORT``."""
        return f"{_HOST}:{self.port}"

    def _accept_loop(self) -> None:
        while not self._closed.is_set():
            try:
                conn, _ = self._listener.accept()
            except TimeoutError:
                continue
            except OSError:
                break
            conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            conn.settimeout(None)
            with self._clients_lock:
                self._clients.add(conn)
                self.connections_accepted += 1
            thread = threading.Thread(target=self._serve, args=(conn,),
                                      name=f"{self.name}-client", daemon=True)
            self._threads.append(thread)
            thread.start()

    def _serve(self, conn: socket.socket) -> None:
        try:
            self.handle(conn)
        except OSError as exc:
            _LOG.debug("%s: client gone: %s", self.name, exc)
        except Exception:
            _LOG.exception("%s: handler failed", self.name)
        finally:
            with self._clients_lock:
                self._clients.discard(conn)
            try:
                conn.close()
            except OSError:
                pass

    def handle(self, conn: socket.socket) -> None:  # pragma: no cover - abstract
        """Serve one client until it disconnects."""
        raise NotImplementedError

    @property
    def n_clients(self) -> int:
        """Number of connected clients."""
        with self._clients_lock:
            return len(self._clients)

    def clients(self) -> list[socket.socket]:
        """Return a snapshot of the connected client sockets."""
        with self._clients_lock:
            return list(self._clients)

    # --- faults -------------------------------------------------------------------------------
    def drop_connections(self) -> int:
        """Fault: close every client connection now (the server keeps listening).

        Returns
        -------
        int
            Connections dropped.
        """
        with self._clients_lock:
            clients = list(self._clients)
        for conn in clients:
            try:
                conn.shutdown(socket.SHUT_RDWR)
            except OSError:
                pass
        _LOG.info("%s: dropped %d connection(s)", self.name, len(clients))
        return len(clients)

    def close(self) -> None:
        """Stop listening, drop every client and join the threads (idempotent)."""
        if self._closed.is_set():
            return
        self._closed.set()
        self.drop_connections()
        self._listener.close()
        if self._accept_thread.is_alive():
            self._accept_thread.join(timeout=2.0)
        for thread in self._threads:
            thread.join(timeout=2.0)


class LineSimServer(SimServer):
    """A server that answers command lines ending in :attr:`terminator`.

    Subclasses implement :meth:`on_line`, returning the bytes to send back (or None).
    """

    terminator = b"\n"

    def __init__(self, name: str, rig: TwinRig, time_base: SimTimeBase, *, port: int = 0) -> None:
        super().__init__(name, port=port)
        self.rig = rig
        self.time_base = time_base
        self.lines_received = 0

    def handle(self, conn: socket.socket) -> None:
        """Read lines and answer each with :meth:`on_line`."""
        buf = b""
        while not self._closed.is_set():
            data = conn.recv(4096)
            if not data:
                return
            buf += data
            while self.terminator in buf:
                raw, buf = buf.split(self.terminator, 1)
                self.lines_received += 1
                reply = self.on_line(raw.decode("ascii", errors="replace").strip("\r\n"))
                if reply:
                    conn.sendall(reply)

    def on_line(self, line: str) -> bytes | None:  # pragma: no cover - abstract
        """Answer one command line."""
        raise NotImplementedError
