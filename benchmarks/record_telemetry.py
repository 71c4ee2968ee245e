"""Record the telemetry a served rig sends, deterministically, to compare two versions byte for byte.

Run from the repository root: ``.venv/bin/python -m benchmarks.record_telemetry OUT.txt [--sim-s S]``,
then ``cmp`` two outputs (or ``--compare A B``). Used to show that a change of the serve
loop's speed (a lazy snapshot, scalar builders, ...) left every message as it was.

In this process, with no socket and no wall clock: a :class:`~rig_emulator.link.server.RigServer`
at speed-up 0 in the serve loop's chunks at ``--speedup max`` (``chunk_seconds(5 ms, 0)``),
two peers on a recording endpoint (one at the default stream rates, one that asked for every
stream at 50 Hz with REQUEST_DATA_STREAM ALL), and the loop's own steps called in its order
(``step_chunk``, ``emit_streams``, ``flush``) chunk after chunk. A scripted flight drives it
through the commands a ground station sends (arm, take-off, reposition, a
shock, a sensor fault, STABILIZED (attitude mode: no position target), return, land), per
configuration: ``hilms-ideal`` (what the benchmark serves), ``hilms`` (the hardware rig) and
``hilms-ideal`` with ``sensors.simulate = false`` (the ideal sensor readings). The only
wall-clock inputs of the telemetry are fixed: ``SYSTEM_TIME``'s Unix time (the ``time`` module
its builder reads is replaced by a fixed clock) and ``SYS_STATUS``'s load (``run`` is not called,
so it stays 0). HEARTBEAT goes out only on the peers' opening
(its 1 Hz is wall-clock time).

Every frame is written as one line: airframe, chunk index, peer, message name and the frame's
bytes in hex (pymavlink's encoding: the same bytes a client receives), then a SHA-256 of all.
"""

from __future__ import annotations

import argparse
import hashlib
import math
import os
import sys
import types

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from protocol.dialect import mavlink as M  # noqa: E402
from rig_emulator.config.loader import load_config  # noqa: E402
from rig_emulator.link import server as srv  # noqa: E402
from rig_emulator.link.endpoints.sockets import Endpoint  # noqa: E402
from rig_emulator.link.serve import chunk_seconds, prepare_rig  # noqa: E402
from rig_emulator.link.telemetry import status as status_mod  # noqa: E402

BOOT_UNIX_S = 1.7e9
PX4_STABILIZED = 7  # PX4's custom main mode STABILIZED


class RecordingEndpoint(Endpoint):
    """An endpoint with no socket: it keeps every frame handed to it."""

    kind = "record"
    datagram = True

    def __init__(self):
        super().__init__("record:")
        self.frames: list[tuple] = []  # (key, bytes)

    def poll(self) -> list[tuple]:
        return []

    def send(self, key, data: bytes) -> bool:
        self.frames.append((key, bytes(data)))
        return True

    def filenos(self) -> list:
        return []

    def close(self) -> None:
        pass


def _gcs():
    return M.MAVLink(None, srcSystem=255, srcComponent=190)


def _decode(gcs, msg):
    """``msg`` as the rig receives it (packed and parsed), so handlers see real field types."""
    return gcs.decode(bytearray(msg.pack(gcs)))


def _command(server, channel, gcs, cmd, *params):
    p = list(params) + [0.0] * (7 - len(params))
    msg = M.MAVLink_command_long_message(1, M.MAV_COMP_ID_AUTOPILOT1, cmd, 0, *p)
    server.handle(_decode(gcs, msg), channel)


def _config(spec: str):
    """``airframe`` or ``airframe:key=value`` (one override: ``true``/``false`` or a number)."""
    airframe, _, override = spec.partition(":")
    overrides = {}
    if override:
        key, _, value = override.partition("=")
        overrides[key] = {"true": True, "false": False}.get(value.lower(), value)
        if isinstance(overrides[key], str):
            overrides[key] = float(value)
    return load_config(airframe=airframe, overrides=overrides or None)


def record(airframe: str, sim_s: float, out: list) -> None:
    status_mod.time = types.SimpleNamespace(time=lambda: BOOT_UNIX_S)  # SYSTEM_TIME's wall clock, fixed
    rig = prepare_rig(_config(airframe))
    server = srv.RigServer(rig, [], speedup=0.0, chunk_s=chunk_seconds(5.0, 0.0))
    ep = RecordingEndpoint()
    server.endpoints.append(ep)
    server._open_channel(ep, ("default", 1))
    server._open_channel(ep, ("all", 2))
    ch_default, ch_all = server.channels[(id(ep), ("default", 1))], server.channels[(id(ep), ("all", 2))]
    gcs = _gcs()
    server.handle(_decode(gcs, M.MAVLink_request_data_stream_message(1, 1, M.MAV_DATA_STREAM_ALL, 50, 1)), ch_all)
    home = server.ctx.home
    n_chunks = int(round(sim_s / server.chunk_s))
    script = {  # chunk -> what the ground station sends before it (seconds at 50 chunks per s)
        25: lambda: _command(server, ch_default, gcs, M.MAV_CMD_COMPONENT_ARM_DISARM, 1.0),
        30: lambda: _command(server, ch_default, gcs, M.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, math.nan, math.nan, math.nan,
                             home.alt_m + 3.0),
        200: lambda: _command(server, ch_default, gcs, M.MAV_CMD_DO_REPOSITION, -1.0,
                              M.MAV_DO_REPOSITION_FLAGS_CHANGE_MODE, 0, math.nan,
                              home.lat_deg + 2e-5, home.lon_deg + 3e-5, home.alt_m + 4.0),
        320: lambda: _command(server, ch_default, gcs, M.MAV_CMD_HILMS_SHOCK, 2, 0.5, 0.2),
        360: lambda: _command(server, ch_default, gcs, M.MAV_CMD_HILMS_SENSOR_FAULT, 0, 1, 1, 0.05),
        400: lambda: _command(server, ch_default, gcs, M.MAV_CMD_DO_SET_MODE, M.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED,
                              PX4_STABILIZED),  # attitude mode: no position target
        440: lambda: _command(server, ch_default, gcs, M.MAV_CMD_NAV_RETURN_TO_LAUNCH),
        520: lambda: _command(server, ch_default, gcs, M.MAV_CMD_NAV_LAND),
    }
    for k in range(n_chunks):
        if k in script:
            script[k]()
        server.step_chunk()
        server.emit_streams()
        server.flush()
        for key, data in ep.frames:
            msg = gcs.decode(bytearray(data))
            out.append(f"{airframe.replace(' ', '')} {k} {key[0]} {msg.get_type()} {data.hex()}")
        ep.frames.clear()
    server.close()


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out", nargs="?", help="file to write the frames to")
    ap.add_argument("--sim-s", type=float, default=12.0, help="simulated seconds per airframe (default 12)")
    ap.add_argument("--airframes", default="hilms-ideal,hilms,hilms-ideal:sensors.simulate=false",
                    help="comma-separated: airframe or airframe:key=value (default: %(default)s)")
    ap.add_argument("--compare", nargs=2, metavar=("A", "B"), help="compare two recordings instead")
    args = ap.parse_args()
    if args.compare:
        a, b = (open(p).read().splitlines() for p in args.compare)
        for i, (x, y) in enumerate(zip(a, b)):
            if x != y:
                print(f"first difference at line {i + 1}:\n  {x}\n  {y}")
                return 1
        if len(a) != len(b):
            print(f"lengths differ: {len(a)} vs {len(b)} lines")
            return 1
        print(f"identical: {len(a)} frames")
        return 0
    out: list[str] = []
    for airframe in args.airframes.split(","):
        record(airframe, args.sim_s, out)
    digest = hashlib.sha256("\n".join(out).encode()).hexdigest()
    counts: dict = {}
    for line in out:
        name = line.split()[3]
        counts[name] = counts.get(name, 0) + 1
    if args.out:
        with open(args.out, "w") as f:
            f.write("\n".join(out) + "\n")
    print(f"{len(out)} frames, {len(counts)} message types, sha256 {digest}")
    print(", ".join(f"{k} {v}" for k, v in sorted(counts.items())))
    return 0


if __name__ == "__main__":
    sys.exit(main())
