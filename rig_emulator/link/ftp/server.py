"""MAVFTP (FILE_TRANSFER_PROTOCOL), read-only: the rig serves a fixed set of files from memory.

Implements the MAVLink FTP microservice (https://mavlink.io/en/services/ftp.html) for a
read-only file system:

* ListDirectory (offset = index of the first entry; entries ``F<name>\\t<size>`` and
  ``D<name>``, NUL-separated, as many as fit in 239 bytes; NAK EOF past the last),
* OpenFileRO (ACK with the file size and the session to use: the one the request named when
  it is free, as ArduPilot does and MAVProxy expects, else a free one), ReadFile (at ``offset``, up to ``size``
  bytes; NAK EOF at or past the end), BurstReadFile (the rest of the file from ``offset`` in
  consecutive ACKs with consecutive seq numbers, the last flagged ``burst_complete``; the
  client asks again for gaps),
* TerminateSession, ResetSessions.

Everything else is NAK'd with the error the spec gives: the write operations (CreateFile,
WriteFile, RemoveFile, CreateDirectory, RemoveDirectory, OpenFileWO, TruncateFile, Rename)
FileProtected, other opcodes UnknownCommand; a path that is not served FileNotFound (so
MAVProxy's ``@PARAM/param.pck`` request fails at once and it falls back to the parameter
protocol), a read on a session not open InvalidSession, an opcode 0 or a size beyond the
payload InvalidDataSize, a fifth open session NoSessionsAvailable. The reply's ``seq`` is the
request's + 1; a repeated request (byte for byte the last one answered on this channel) gets
the same reply again without acting twice, so a lost reply costs nothing.

Paths: ``/`` and ``""`` are the root; leading slashes are ignored; directories are
``/``-separated. Files are ``name -> bytes`` (:class:`FileStore`).
"""

from __future__ import annotations

import struct
from dataclasses import dataclass

from protocol.dialect import mavlink as M

HEADER = struct.Struct("<HBBBBBBI")
MAX_DATA = 239
PAYLOAD_LEN = 251
MAX_SESSIONS = 4
BURST_PACKETS_PER_CALL = 64  # one BurstReadFile answers with at most this many packets; the client asks again

OP_NONE, OP_TERMINATE_SESSION, OP_RESET_SESSIONS, OP_LIST_DIRECTORY, OP_OPEN_FILE_RO, OP_READ_FILE = 0, 1, 2, 3, 4, 5
OP_CREATE_FILE, OP_WRITE_FILE, OP_REMOVE_FILE, OP_CREATE_DIRECTORY, OP_REMOVE_DIRECTORY = 6, 7, 8, 9, 10
OP_OPEN_FILE_WO, OP_TRUNCATE_FILE, OP_RENAME, OP_CALC_FILE_CRC32, OP_BURST_READ_FILE = 11, 12, 13, 14, 15
OP_ACK, OP_NAK = 128, 129
WRITE_OPS = frozenset({OP_CREATE_FILE, OP_WRITE_FILE, OP_REMOVE_FILE, OP_CREATE_DIRECTORY, OP_REMOVE_DIRECTORY,
                       OP_OPEN_FILE_WO, OP_TRUNCATE_FILE, OP_RENAME})
ERR_NONE, ERR_FAIL, ERR_FAIL_ERRNO, ERR_INVALID_DATA_SIZE, ERR_INVALID_SESSION = 0, 1, 2, 3, 4
ERR_NO_SESSIONS_AVAILABLE, ERR_EOF, ERR_UNKNOWN_COMMAND, ERR_FILE_EXISTS, ERR_FILE_PROTECTED = 5, 6, 7, 8, 9
ERR_FILE_NOT_FOUND = 10


@dataclass(frozen=True)
class Request:
    seq: int
    session: int
    opcode: int
    size: int
    req_opcode: int
    burst_complete: int
    offset: int
    data: bytes

    @classmethod
    def parse(cls, payload: bytes) -> "Request | None":
        if len(payload) < HEADER.size:
            return None
        seq, session, opcode, size, req, burst, _pad, offset = HEADER.unpack_from(payload)
        return cls(seq, session, opcode, size, req, burst, offset, bytes(payload[HEADER.size:]))

    def path(self) -> str:
        raw = self.data[: min(self.size, MAX_DATA)]
        return raw.split(b"\0", 1)[0].decode("ascii", "replace")


class FileStore:
    """A read-only tree of in-memory files: ``{"dir/name.json": b"..."}``."""

    def __init__(self, files: dict[str, bytes] | None = None):
        self.files: dict[str, bytes] = {}
        for name, data in (files or {}).items():
            self.add(name, data)

    def add(self, name: str, data: bytes) -> None:
        self.files[name.strip("/")] = bytes(data)

    @staticmethod
    def _norm(path: str) -> str:
        return path.strip().strip("/")

    def read(self, path: str) -> bytes | None:
        return self.files.get(self._norm(path))

    def listing(self, path: str) -> list[str] | None:
        """Entries of directory ``path`` (``F<name>\\t<size>`` / ``D<name>``), None if it is none."""
        d = self._norm(path)
        prefix = d + "/" if d else ""
        files, dirs = [], set()
        for name, data in self.files.items():
            if not name.startswith(prefix):
                continue
            rest = name[len(prefix):]
            if "/" in rest:
                dirs.add(rest.split("/", 1)[0])
            else:
                files.append(f"F{rest}\t{len(data)}")
        if not files and not dirs and d:
            return None
        return [f"D{x}" for x in sorted(dirs)] + sorted(files)


class FtpServer:
    """The vehicle side of MAVFTP for one rig; :meth:`handle` answers one request."""

    def __init__(self, store: FileStore):
        self.store = store
        self.sessions: dict[int, bytes] = {}
        self._last: dict = {}  # channel key -> (request seq, replies), to answer a repeat identically

    # --- replies -------------------------------------------------------------------------------
    @staticmethod
    def _pack(req: Request, opcode: int, data: bytes = b"", offset: int | None = None, burst_complete: int = 0,
              session: int | None = None, index: int = 0) -> bytes:
        """A reply: seq is the request's + 1 (+ ``index`` for the index-th packet of a burst)."""
        return HEADER.pack((req.seq + 1 + index) % 65536, req.session if session is None else session, opcode,
                           len(data), req.opcode, burst_complete, 0, req.offset if offset is None else offset) + data

    def _nak(self, req: Request, error: int) -> list[bytes]:
        return [self._pack(req, OP_NAK, bytes([error]))]

    # --- operations --------------------------------------------------------------------------------
    def _list(self, req: Request) -> list[bytes]:
        entries = self.store.listing(req.path())
        if entries is None:
            return self._nak(req, ERR_FILE_NOT_FOUND)
        if req.offset >= len(entries):
            return self._nak(req, ERR_EOF)
        out = b""
        for entry in entries[req.offset:]:
            raw = entry.encode("ascii", "replace") + b"\0"
            if len(out) + len(raw) > MAX_DATA:
                break
            out += raw
        return [self._pack(req, OP_ACK, out)]

    def _open(self, req: Request) -> list[bytes]:
        data = self.store.read(req.path())
        if data is None:
            return self._nak(req, ERR_FILE_NOT_FOUND)
        if len(self.sessions) >= MAX_SESSIONS:
            return self._nak(req, ERR_NO_SESSIONS_AVAILABLE)
        # the session the client named when it is free (ArduPilot's reading, which MAVProxy relies on),
        # else the lowest free one (the spec: the ACK's session is the one to use)
        session = req.session if req.session not in self.sessions else next(
            s for s in range(256) if s not in self.sessions)
        self.sessions[session] = data
        return [self._pack(req, OP_ACK, struct.pack("<I", len(data)), offset=0, session=session)]

    def _read(self, req: Request) -> list[bytes]:
        data = self.sessions.get(req.session)
        if data is None:
            return self._nak(req, ERR_INVALID_SESSION)
        if req.offset >= len(data):
            return self._nak(req, ERR_EOF)
        n = min(req.size or MAX_DATA, MAX_DATA)
        return [self._pack(req, OP_ACK, data[req.offset:req.offset + n])]

    def _burst(self, req: Request) -> list[bytes]:
        data = self.sessions.get(req.session)
        if data is None:
            return self._nak(req, ERR_INVALID_SESSION)
        if req.offset >= len(data):
            return self._nak(req, ERR_EOF)
        n = min(req.size or MAX_DATA, MAX_DATA)
        out = []
        offset = req.offset
        while offset < len(data) and len(out) < BURST_PACKETS_PER_CALL:
            chunk = data[offset:offset + n]
            last = offset + len(chunk) >= len(data) or len(out) == BURST_PACKETS_PER_CALL - 1
            out.append(self._pack(req, OP_ACK, chunk, offset=offset, burst_complete=1 if last else 0, index=len(out)))
            offset += len(chunk)
        return out

    def _dispatch(self, req: Request) -> list[bytes]:
        op = req.opcode
        if req.size > MAX_DATA:
            return self._nak(req, ERR_INVALID_DATA_SIZE)
        if op == OP_TERMINATE_SESSION:
            if self.sessions.pop(req.session, None) is None:
                return self._nak(req, ERR_INVALID_SESSION)
            return [self._pack(req, OP_ACK)]
        if op == OP_RESET_SESSIONS:
            self.sessions.clear()
            return [self._pack(req, OP_ACK)]
        if op == OP_LIST_DIRECTORY:
            return self._list(req)
        if op == OP_OPEN_FILE_RO:
            return self._open(req)
        if op == OP_READ_FILE:
            return self._read(req)
        if op == OP_BURST_READ_FILE:
            return self._burst(req)
        if op in WRITE_OPS:
            return self._nak(req, ERR_FILE_PROTECTED)
        if op == OP_NONE:
            return self._nak(req, ERR_INVALID_DATA_SIZE)
        return self._nak(req, ERR_UNKNOWN_COMMAND)

    def handle(self, payload: bytes, channel_key=None) -> list[bytes] | None:
        """Reply payloads (unpadded) for one request payload; None when it cannot be parsed.

        A request identical to the last one answered for ``channel_key`` is a retry: the same
        replies are sent again and nothing is done twice (a second open would leak a session)."""
        req = Request.parse(payload)
        if req is None:
            return None
        wire = bytes(payload[:HEADER.size + min(req.size, MAX_DATA)])
        last = self._last.get(channel_key)
        if last is not None and last[0] == wire:
            return last[1]
        replies = self._dispatch(req)
        self._last[channel_key] = (wire, replies)
        return replies

    def forget(self, channel_key) -> None:
        self._last.pop(channel_key, None)


def reply_message(payload: bytes, to_msg):
    """FILE_TRANSFER_PROTOCOL carrying reply ``payload`` to the sender of ``to_msg``."""
    return M.MAVLink_file_transfer_protocol_message(
        target_network=0, target_system=to_msg.get_srcSystem(), target_component=to_msg.get_srcComponent(),
        payload=list(payload.ljust(PAYLOAD_LEN, b"\0")))
