"""MAVFTP (FILE_TRANSFER_PROTOCOL): the rig has no file system to serve, so every request
is answered at once with a NAK, which makes MAVProxy and QGroundControl fall back to the
parameter protocol instead of waiting for a timeout.

The FTP payload layout (MAVLink FTP spec): seq u16, session u8, opcode u8, size u8,
req_opcode u8, burst_complete u8, padding u8, offset u32, data[239]. The reply's seq is
the request's + 1; its single data byte is the error code.
"""

from __future__ import annotations

import struct

from protocol.dialect import mavlink as M

OP_NAK = 129
ERR_FAIL = 1
ERR_UNKNOWN_COMMAND = 7
ERR_FILE_NOT_FOUND = 10
OP_TERMINATE_SESSION, OP_RESET_SESSIONS, OP_OPEN_FILE_RO = 1, 2, 4
HEADER = struct.Struct("<HBBBBBBI")
PAYLOAD_LEN = 251


def nak_for(msg):
    """The FILE_TRANSFER_PROTOCOL NAK answering ``msg``, or None if its payload is unreadable."""
    payload = bytes(msg.payload)
    if len(payload) < HEADER.size:
        return None
    seq, session, opcode, _size, _req, _burst, _pad, _offset = HEADER.unpack_from(payload)
    error = ERR_FILE_NOT_FOUND if opcode == OP_OPEN_FILE_RO else ERR_UNKNOWN_COMMAND
    if opcode in (OP_TERMINATE_SESSION, OP_RESET_SESSIONS):
        error = ERR_FAIL
    reply = HEADER.pack((seq + 1) % 65536, session, OP_NAK, 1, opcode, 0, 0, 0) + bytes([error])
    return M.MAVLink_file_transfer_protocol_message(
        target_network=0, target_system=msg.get_srcSystem(), target_component=msg.get_srcComponent(),
        payload=list(reply.ljust(PAYLOAD_LEN, b"\0")))
