"""ArduPilot SITL's servo packet: what its JSON simulator interface sends the physics.

ArduPilot ``libraries/SITL/SIM_JSON.h`` (``servo_packet_16`` / ``servo_packet_32``), one UDP
datagram per frame, little-endian, no padding:

=========  ======  =================================================================
field      type    meaning
=========  ======  =================================================================
magic      uint16  18458 (16 channels) or 29569 (32 channels, ``SERVO_32_ENABLE 1``)
frame_rate uint16  the frame rate ArduPilot asks for (Hz; ``SIM_RATE_HZ``, adjusted to
                   the physics' own step when it keeps time sync)
frame_count uint32 +1 per frame answered; the same number again when ArduPilot re-sends
                   a frame it got no answer to (after 1 s); 0 after ArduPilot restarts
pwm        uint16  the servo outputs in microseconds, ``SERVOn`` at index n - 1 (16 or 32)
=========  ======  =================================================================
"""

from __future__ import annotations

import struct
from typing import NamedTuple

MAGIC_16 = 18458
MAGIC_32 = 29569
_HEADER = struct.Struct("<HHI")
CHANNELS = {MAGIC_16: 16, MAGIC_32: 32}
_PWM = {magic: struct.Struct(f"<{n}H") for magic, n in CHANNELS.items()}
SIZES = {magic: _HEADER.size + s.size for magic, s in _PWM.items()}  # 40 and 72 bytes


class ServoPacket(NamedTuple):
    frame_rate_hz: int
    frame_count: int
    pwm_us: tuple  # 16 or 32 servo outputs, microseconds


class PacketError(ValueError):
    """A datagram that is not an ArduPilot servo packet (the message says why)."""


def decode(data: bytes) -> ServoPacket:
    """The servo packet in one datagram; :class:`PacketError` naming what is wrong otherwise."""
    if len(data) < _HEADER.size:
        raise PacketError(f"{len(data)} bytes: shorter than a servo packet's header ({_HEADER.size})")
    magic, rate, count = _HEADER.unpack_from(data)
    pwm = _PWM.get(magic)
    if pwm is None:
        raise PacketError(f"magic {magic}: expected {MAGIC_16} (16 channels) or {MAGIC_32} (32 channels)")
    if len(data) != SIZES[magic]:
        raise PacketError(f"{len(data)} bytes with magic {magic}: a {CHANNELS[magic]}-channel packet "
                          f"is {SIZES[magic]} bytes")
    return ServoPacket(rate, count, pwm.unpack_from(data, _HEADER.size))


def encode(frame_rate_hz: int, frame_count: int, pwm_us) -> bytes:
    """The datagram ArduPilot would send (16 or 32 outputs): the stand-in flight stack's, tests'."""
    pwm_us = tuple(int(p) for p in pwm_us)
    magic = MAGIC_16 if len(pwm_us) == 16 else MAGIC_32 if len(pwm_us) == 32 else None
    if magic is None:
        raise PacketError(f"{len(pwm_us)} servo outputs: a packet holds 16 or 32")
    return _HEADER.pack(magic, frame_rate_hz, frame_count) + _PWM[magic].pack(*pwm_us)
