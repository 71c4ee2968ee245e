"""Sockets named by mavutil connection strings; every remote peer is a key the server maps
to its own channel.

Supported strings (as ``mavutil.mavlink_connection`` spells them):

* ``udpout:HOST:PORT`` - send to HOST:PORT from an ephemeral port (what QGroundControl
  listens for on 14550); replies come back to that port. One peer, present from the start.
* ``udpin:HOST:PORT`` (also ``udp:HOST:PORT``) - listen; every source address that sends a
  datagram becomes a peer (up to :data:`MAX_UDP_PEERS`).
* ``tcpin:HOST:PORT`` - listen; every accepted client is a peer (several at once).
* ``tcp:HOST:PORT`` - connect to a listening ground station, reconnecting every second.

A port of 0 binds an ephemeral port; :attr:`Endpoint.local_address` tells which. All
sockets are non-blocking; nothing here parses MAVLink.

Datagrams: the frames handed to a UDP peer between two :meth:`Endpoint.flush` calls (the
server flushes once per tick: after servicing the link, and after the chunks of a tick with
their telemetry) are packed back to back into as few datagrams as fit in
:data:`MAX_DATAGRAM_BYTES`, as flight stacks send MAVLink over UDP (a frame never spans two
datagrams; pymavlink, MAVProxy, MAVSDK and QGroundControl parse every frame of a datagram).
One ``sendto`` per datagram instead of one per frame: at speed-ups above 1 the system calls
(and the receiver's wake-ups) were what limited the served rig.
"""

from __future__ import annotations

import errno
from abc import ABC, abstractmethod
import socket
import time

MAX_UDP_PEERS = 16
TCP_TX_LIMIT = 4 * 1024 * 1024  # bytes queued for one client before messages are dropped
RECV_CHUNK = 65536
MAX_READS_PER_POLL = 64  # bounded work per service round, so a flood cannot starve the loop
#: Largest datagram the rig sends: under the 1472-byte UDP payload of a 1500-byte Ethernet MTU (no IP
#: fragmentation on a real network) and under the 2048-byte receive buffer of MAVSDK's UDP connection.
#: A MAVLink 2 frame is at most 280 bytes, so a datagram holds at least 5 of them.
MAX_DATAGRAM_BYTES = 1400


class EndpointError(ValueError):
    """A connection string that cannot be served."""


def _host_port(spec: str, rest: str) -> tuple[str, int]:
    host, sep, port = rest.rpartition(":")
    if not sep or not host or not port.isdigit() or not 0 <= int(port) <= 65535:
        raise EndpointError(f"{spec!r}: expected KIND:HOST:PORT, e.g. udpout:127.0.0.1:14550")
    return host, int(port)


def open_endpoint(spec: str) -> "Endpoint":
    """Open the endpoint a connection string names; raises :class:`EndpointError`."""
    kind, sep, rest = spec.partition(":")
    classes = {"udpout": UdpOut, "udpin": UdpIn, "udp": UdpIn, "tcpin": TcpIn, "tcp": TcpOut}
    if not sep or kind not in classes:
        raise EndpointError(f"{spec!r}: unsupported connection string; use one of "
                            "udpout:HOST:PORT, udpin:HOST:PORT, tcpin:HOST:PORT, tcp:HOST:PORT")
    host, port = _host_port(spec, rest)
    try:
        return classes[kind](spec, host, port)
    except OSError as exc:
        raise EndpointError(f"{spec!r}: {exc.strerror or exc}") from exc


class Endpoint(ABC):
    """One socket (or listening socket and its clients). Subclasses fill in the transport."""

    kind = ""
    datagram = False  # True: every read is one datagram holding whole frames

    def __init__(self, spec: str):
        self.spec = spec
        self.dropped_peers = 0
        self.tx_dropped = 0  # frames a flush could not send (the server moves them to its counters)

    @property
    def local_address(self) -> tuple[str, int]:
        return self._sock.getsockname()[:2]

    @property
    def url(self) -> str:
        """The connection string with the bound port (useful when the port was 0)."""
        host, port = self.local_address
        return f"{self.kind}:{host}:{port}"

    def filenos(self) -> list:
        return [self._sock]

    @abstractmethod
    def poll(self) -> list[tuple]:
        """Read what is waiting: ``[(event, key, data)]`` with event 'open', 'data' or 'closed'."""

    @abstractmethod
    def send(self, key, data: bytes) -> bool:
        """Queue one MAVLink frame for a peer; False when it had to be dropped."""

    def flush(self) -> None:
        """Push queued bytes: TCP clients' buffers, UDP peers' packed datagrams. Frames that
        could not go out are added to :attr:`tx_dropped`."""

    def close(self) -> None:
        self._sock.close()


def _udp_socket() -> socket.socket:
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.setblocking(False)
    return sock


class _Udp(Endpoint):
    datagram = True

    def __init__(self, spec: str):
        super().__init__(spec)
        self._pending: dict = {}  # peer -> [bytearray of whole frames, number of frames]
        self.datagrams_sent = 0
        self.frames_sent = 0

    def _read(self) -> list[tuple]:
        out = []
        for _ in range(MAX_READS_PER_POLL):
            try:
                data, addr = self._sock.recvfrom(RECV_CHUNK)
            except (BlockingIOError, InterruptedError):
                break
            except ConnectionRefusedError:
                continue  # ICMP port unreachable from an earlier send: nobody listens yet
            except OSError:
                break
            out.append((addr[:2], data))
        return out

    def send(self, key, data: bytes) -> bool:
        """Append the frame to the peer's datagram; a full datagram goes out first."""
        pending = self._pending.get(key)
        if pending is None:
            self._pending[key] = [bytearray(data), 1]
            return True
        if len(pending[0]) + len(data) > MAX_DATAGRAM_BYTES:
            self._send_datagram(key, pending)
            pending[0] = bytearray(data)
            pending[1] = 1
            return True
        pending[0] += data
        pending[1] += 1
        return True

    def _send_datagram(self, key, pending) -> None:
        try:
            self._sock.sendto(pending[0], key)
        except OSError:  # a full socket buffer (BlockingIOError), nobody listening yet, an unreachable peer
            self.tx_dropped += pending[1]
            return
        self.datagrams_sent += 1
        self.frames_sent += pending[1]

    def flush(self) -> None:
        if not self._pending:
            return
        pending, self._pending = self._pending, {}
        for key, p in pending.items():
            self._send_datagram(key, p)


class UdpOut(_Udp):
    kind = "udpout"

    def __init__(self, spec: str, host: str, port: int):
        super().__init__(spec)
        self.remote = (socket.gethostbyname(host), port)
        self._sock = _udp_socket()
        self._sock.bind(("0.0.0.0" if host != "127.0.0.1" else "127.0.0.1", 0))
        self._opened = False

    @property
    def url(self) -> str:
        return f"udpout:{self.remote[0]}:{self.remote[1]}"

    def poll(self) -> list[tuple]:
        events = []
        if not self._opened:
            self._opened = True
            events.append(("open", self.remote, b""))
        for addr, data in self._read():
            events.append(("data", self.remote, data))
        return events


class UdpIn(_Udp):
    kind = "udpin"

    def __init__(self, spec: str, host: str, port: int):
        super().__init__(spec)
        self._sock = _udp_socket()
        self._sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        self._sock.bind((host, port))
        self.peers: set = set()

    def poll(self) -> list[tuple]:
        events = []
        for addr, data in self._read():
            if addr not in self.peers:
                if len(self.peers) >= MAX_UDP_PEERS:
                    self.dropped_peers += 1
                    continue
                self.peers.add(addr)
                events.append(("open", addr, b""))
            events.append(("data", addr, data))
        return events


class _TcpClient:
    def __init__(self, sock: socket.socket):
        self.sock = sock
        self.tx = bytearray()


class _Tcp(Endpoint):
    def __init__(self, spec: str):
        super().__init__(spec)
        self.clients: dict = {}
        self._lost: list = []  # clients a flush found broken, reported 'closed' by the next poll

    def _report_lost(self, events: list) -> None:
        """'closed' for the clients a flush dropped (first in a poll: a client reconnecting under
        the same key opens after it). Without this the server would keep their channels and
        count everything it queued for them as dropped (``tx_overflow``), session after session."""
        if self._lost:
            events.extend(("closed", key, b"") for key in self._lost)
            self._lost = []

    def _read_clients(self, events: list) -> None:
        for key, client in list(self.clients.items()):
            for _ in range(MAX_READS_PER_POLL):
                try:
                    data = client.sock.recv(RECV_CHUNK)
                except (BlockingIOError, InterruptedError):
                    break
                except OSError:
                    data = b""
                if not data:
                    self._drop(key)
                    events.append(("closed", key, b""))
                    break
                events.append(("data", key, data))

    def _drop(self, key) -> None:
        client = self.clients.pop(key, None)
        if client is not None:
            client.sock.close()

    def send(self, key, data: bytes) -> bool:
        client = self.clients.get(key)
        if client is None or len(client.tx) + len(data) > TCP_TX_LIMIT:
            return False
        client.tx += data
        return True

    def flush(self) -> None:
        for key, client in list(self.clients.items()):
            if not client.tx:
                continue
            try:
                n = client.sock.send(client.tx)
            except (BlockingIOError, InterruptedError):
                continue
            except OSError:  # the ground station is gone (reset, broken pipe)
                self._drop(key)
                self._lost.append(key)
                continue
            del client.tx[:n]

    def filenos(self) -> list:
        return [self._sock] + [c.sock for c in self.clients.values()]

    def close(self) -> None:
        for key in list(self.clients):
            self._drop(key)
        super().close()


def _tcp_socket() -> socket.socket:
    sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    return sock


class TcpIn(_Tcp):
    kind = "tcpin"

    def __init__(self, spec: str, host: str, port: int):
        super().__init__(spec)
        self._sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        self._sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        self._sock.bind((host, port))
        self._sock.listen(8)
        self._sock.setblocking(False)

    def poll(self) -> list[tuple]:
        events = []
        self._report_lost(events)
        while True:
            try:
                sock, addr = self._sock.accept()
            except (BlockingIOError, InterruptedError):
                break
            except OSError:
                break
            sock.setblocking(False)
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            key = addr[:2]
            self.clients[key] = _TcpClient(sock)
            events.append(("open", key, b""))
        self._read_clients(events)
        return events


class TcpOut(_Tcp):
    """A TCP client to a listening ground station; reconnects every second while down."""

    kind = "tcp"
    RETRY_S = 1.0

    def __init__(self, spec: str, host: str, port: int):
        super().__init__(spec)
        self.remote = (socket.gethostbyname(host), port)
        self._sock = _tcp_socket()
        self._next_try = 0.0
        self._connecting = None

    @property
    def url(self) -> str:
        return f"tcp:{self.remote[0]}:{self.remote[1]}"

    def _try_connect(self, events: list) -> None:
        now = time.monotonic()
        if self._connecting is None:
            if now < self._next_try:
                return
            self._connecting = _tcp_socket()
            self._connecting.setblocking(False)
            self._connecting.connect_ex(self.remote)
        err = self._connecting.getsockopt(socket.SOL_SOCKET, socket.SO_ERROR)
        if err == 0:
            try:
                self._connecting.getpeername()
            except OSError:
                return  # still connecting
            self.clients[self.remote] = _TcpClient(self._connecting)
            self._connecting = None
            events.append(("open", self.remote, b""))
        elif err not in (errno.EINPROGRESS, errno.EALREADY):
            self._connecting.close()
            self._connecting = None
            self._next_try = now + self.RETRY_S

    def poll(self) -> list[tuple]:
        events = []
        self._report_lost(events)
        if not self.clients:
            self._try_connect(events)
        self._read_clients(events)
        return events

    def filenos(self) -> list:
        return [c.sock for c in self.clients.values()]

    def close(self) -> None:
        if self._connecting is not None:
            self._connecting.close()
        super().close()
