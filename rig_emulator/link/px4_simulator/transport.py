"""Where the flight stack is: a TCP port it connects to (PX4 SITL) or a serial line (a
flight controller board in HIL). Nothing here parses MAVLink.

``--px4-simulator`` takes:

* ``[HOST:]PORT`` - listen on TCP (default ``127.0.0.1:4560``, the port PX4's
  ``simulator_mavlink`` connects to). One flight stack at a time: a second connection
  while one is served is closed at once (counted in ``refused``).
* ``serial:DEVICE[:BAUD]`` or a path starting with ``/dev/`` (``/dev/ttyACM0[:BAUD]``) - a
  serial line at BAUD (default 921600, what PX4 boards use for HITL on USB), opened with
  pyserial as pymavlink's serial connections are. The session lasts as long as the device
  stays open; a device that fails (unplugged, the other end of a pseudo-terminal closed) is
  reopened every second.
"""

from __future__ import annotations

import errno
import functools
import os
import socket
import time

DEFAULT_HOST = "127.0.0.1"
DEFAULT_PORT = 4560
DEFAULT_BAUD = 921600
SEND_TIMEOUT_S = 5.0  # a flight stack that takes nothing for this long is gone
REOPEN_S = 1.0
RECV_CHUNK = 65536


class TransportError(ValueError):
    """A ``--px4-simulator`` value that cannot be served."""


def parse_spec(text: str) -> tuple:
    """``('tcp', host, port)`` or ``('serial', device, baud)`` for a ``--px4-simulator`` value."""
    text = text.strip()
    if text.startswith("serial:") or text.startswith("/dev/"):
        rest = text[len("serial:"):] if text.startswith("serial:") else text
        device, sep, baud = rest.rpartition(":")
        if not sep or not baud.isdigit():
            device, baud = rest, str(DEFAULT_BAUD)
        if not device:
            raise TransportError(f"--px4-simulator {text!r}: expected serial:DEVICE[:BAUD]")
        return "serial", device, int(baud)
    host, sep, port = text.rpartition(":")
    if not sep:
        host = DEFAULT_HOST
    if not port.isdigit() or not 0 <= int(port) <= 65535 or (sep and not host):
        raise TransportError(f"--px4-simulator {text!r}: expected [HOST:]PORT (e.g. 4560) or serial:DEVICE[:BAUD]")
    return "tcp", host, int(port)


def open_transport(text: str):
    """The listener or serial line a ``--px4-simulator`` value names."""
    spec = parse_spec(text)
    try:
        if spec[0] == "tcp":
            return TcpListener(spec[1], spec[2])
        return SerialLine(spec[1], spec[2])
    except OSError as exc:
        raise TransportError(f"--px4-simulator {text!r}: {exc.strerror or exc}") from exc


class Connection:
    """One flight stack's byte stream."""

    def __init__(self, fd, recv, send, close, name: str):
        self.fd = fd
        self._recv, self._send, self._close = recv, send, close
        self.name = name
        self.open = True

    def fileno(self):
        return self.fd

    def read(self) -> bytes | None:
        """What is waiting, once ``select`` said the stream is readable (b'' if nothing after
        all); None once the stream is closed or broken (end of file, a hung-up line)."""
        try:
            data = self._recv()
        except (BlockingIOError, InterruptedError):
            return b""
        except OSError:
            data = b""
        if not data:
            self.close()
            return None
        return data

    def write(self, data: bytes) -> bool:
        """Send all of ``data`` (waits while the peer's buffer is full, up to SEND_TIMEOUT_S);
        False when the stream broke."""
        view = memoryview(data)
        deadline = None
        while view:
            try:
                n = self._send(view)
            except (BlockingIOError, InterruptedError):
                n = 0
            except OSError:
                self.close()
                return False
            view = view[n:]
            if view:
                deadline = deadline or time.monotonic() + SEND_TIMEOUT_S
                if time.monotonic() > deadline:
                    self.close()
                    return False
                time.sleep(0.0005)
        return True

    def close(self) -> None:
        if self.open:
            self.open = False
            try:
                self._close()
            except OSError:
                pass


class TcpListener:
    """Listen for the flight stack's TCP connection; one at a time."""

    kind = "tcp"

    def __init__(self, host: str, port: int):
        self._sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        self._sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        self._sock.bind((host, port))
        self._sock.listen(2)
        self._sock.setblocking(False)
        self.refused = 0

    @property
    def url(self) -> str:
        host, port = self._sock.getsockname()[:2]
        return f"tcpin:{host}:{port}"

    def filenos(self) -> list:
        return [self._sock]

    def accept(self, busy: bool) -> Connection | None:
        """The next flight stack's connection, if one is waiting; while ``busy`` it is closed
        at once (refused) and None returned. One connection per call."""
        try:
            sock, addr = self._sock.accept()
        except OSError:  # nothing waiting (BlockingIOError) or a connection gone before it was accepted
            return None
        if busy:
            sock.close()
            self.refused += 1
            return None
        sock.setblocking(False)
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        return Connection(sock.fileno(), functools.partial(sock.recv, RECV_CHUNK), sock.send, sock.close,
                          f"tcp:{addr[0]}:{addr[1]}")

    def close(self) -> None:
        self._sock.close()


class SerialLine:
    """A serial device (a HIL board on USB, or one end of a pseudo-terminal pair)."""

    kind = "serial"
    refused = 0

    def __init__(self, device: str, baud: int):
        self.device, self.baud = device, baud
        self._next_try = 0.0
        self._port = None
        self._open_port()  # fails loudly at start (wrong path, no permission)

    @property
    def url(self) -> str:
        return f"serial:{self.device}:{self.baud}"

    def _open_port(self):
        import serial  # pyserial, pymavlink's serial dependency

        try:
            port = serial.Serial(self.device, self.baud, timeout=0, write_timeout=SEND_TIMEOUT_S)
        except serial.SerialException as exc:
            raise OSError(errno.EIO, str(exc)) from exc
        self._port = port
        return port

    def filenos(self) -> list:
        return []

    def accept(self, busy: bool) -> Connection | None:
        """The line as a session once it is open (at start, and after a failure every REOPEN_S)."""
        if busy:
            return None
        port = self._port
        if port is None:
            now = time.monotonic()
            if now < self._next_try:
                return None
            self._next_try = now + REOPEN_S
            try:
                port = self._open_port()
            except OSError:
                return None
        self._port = None  # handed over to the session
        fd = port.fileno()

        def recv() -> bytes:
            return os.read(fd, RECV_CHUNK)

        return Connection(fd, recv, lambda data: os.write(fd, data), port.close, self.url)

    def close(self) -> None:
        if self._port is not None:
            self._port.close()
            self._port = None
