"""rig-gcs over a lossy, laggy, duplicating, re-ordering link, repeated, with figures.

Run from the repository root::

    .venv/bin/python -m benchmarks.lossy_link                    # 20 % loss each way, 10 % duplicated, 10 % re-ordered, 20-50 ms
    .venv/bin/python -m benchmarks.lossy_link --rounds 5 --drop 0.3 --retries 5

A rig (:class:`rig_emulator.testing.rig.RigThread`, speed-up 1, a ``udpin`` endpoint) behind
:class:`rig_emulator.testing.relay.LossyRelay`; each round, with gcs_tools' clients and
the retry counts given (default: QGroundControl's 5):

* the whole parameter list, compared value by value with the rig's table;
* a parameter set per round, checked in the rig;
* ``--commands`` MAV_CMD_HILMS_SHOCK commands with distinct torques; the rig's shock calls are
  counted, so each must act exactly once when ACKed and at most once when not;
* a ``--items``-item mission upload and download, compared item by item.

Every operation either completes exactly or raises a clear error; the script prints the
completion times (median, max), the errors by kind, and the number of wrong results, which
must be 0 (exit 1 otherwise).
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from collections import Counter
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np  # noqa: E402

from gcs_tools import mission_client  # noqa: E402
from gcs_tools.errors import OperationError  # noqa: E402
from gcs_tools.link import Link  # noqa: E402
from gcs_tools.missions import mission_from_enu  # noqa: E402
from gcs_tools.params_client import ParamClient  # noqa: E402
from protocol.dialect import mavlink as M  # noqa: E402
from rig_emulator.testing.rig import RigThread  # noqa: E402
from rig_emulator.testing.relay import LossyRelay  # noqa: E402


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--drop", type=float, default=0.2)
    p.add_argument("--duplicate", type=float, default=0.1)
    p.add_argument("--reorder", type=float, default=0.1)
    p.add_argument("--delay", type=float, default=0.02, help="s")
    p.add_argument("--jitter", type=float, default=0.03, help="s")
    p.add_argument("--timeout", type=float, default=0.5, help="s per answer")
    p.add_argument("--retries", type=int, default=5)
    p.add_argument("--commands", type=int, default=40)
    p.add_argument("--items", type=int, default=30)
    args = p.parse_args(argv)
    times: dict[str, list] = {"param list": [], "param set": [], "command": [], "mission upload": [],
                              "mission download": []}
    errors: Counter = Counter()
    wrong: list[str] = []
    with RigThread(speedup=1.0, extra_endpoints=["udpin:127.0.0.1:0"]) as rig:
        srv = rig.server
        calls = []
        original = srv.rig.apply_shock
        srv.rig.apply_shock = lambda *a: (calls.append(a[1]), original(*a))[1]
        relay = LossyRelay.to_rig(rig.urls, drop=args.drop, duplicate=args.duplicate, reorder=args.reorder,
                                  delay_s=args.delay, jitter_s=args.jitter)
        print(f"relay: drop {args.drop}, duplicate {args.duplicate}, reorder {args.reorder}, delay {args.delay} s "
              f"+ jitter {args.jitter} s; timeout {args.timeout} s, retries {args.retries}", flush=True)
        with Link(relay.client_url) as link:
            link.wait_vehicle(30)
            client = ParamClient(link, args.timeout, args.retries)

            def timed(kind, fn):
                t0 = time.monotonic()
                try:
                    out = fn()
                except OperationError as exc:
                    errors[f"{kind}: {str(exc).split(':')[0]}"] += 1
                    print(f"  {kind}: clear error: {exc}", flush=True)
                    return None
                times[kind].append(time.monotonic() - t0)
                return True if out is None else out  # None is kept for a failure

            torque = 0.0
            acked: dict = {}  # torque -> ACKed ACCEPTED
            for r in range(args.rounds):
                got = timed("param list", client.fetch_all)
                if got is not None:
                    for prm in srv.params.table.params:
                        want = np.float32(prm.value(srv.rig.cfg))
                        if prm.name not in got or np.float32(got[prm.name].value) != want:
                            wrong.append(f"round {r}: {prm.name} listed wrong")
                value = 1.0 + 0.25 * r
                if timed("param set", lambda: client.set("SMC_K_PSI", value)) is not None:
                    if np.float32(srv.rig.cfg["smc.k"][2]) != np.float32(value):
                        wrong.append(f"round {r}: SMC_K_PSI set but the rig holds {srv.rig.cfg['smc.k'][2]}")
                for i in range(args.commands):
                    torque = round(torque + 0.01, 2)
                    acked[torque] = timed("command", lambda: link.command(
                        M.MAV_CMD_HILMS_SHOCK, 1 + i % 4, torque, 0.05, timeout=args.timeout,
                        retries=args.retries)) == M.MAV_RESULT_ACCEPTED
                pts = [[0.1 * k, 0.05 * k, 1.0 + 0.01 * r] for k in range(args.items)]
                mission = mission_from_enu(pts)
                if timed("mission upload", lambda: mission_client.upload(link, mission, args.timeout,
                                                                         args.retries)) is not None:
                    back = timed("mission download", lambda: mission_client.download(link, args.timeout, args.retries))
                    if back is not None and not (len(back.items) == len(mission.items) and all(
                            a.same_as(b) for a, b in zip(back.items, mission.canonical().items))):
                        wrong.append(f"round {r}: downloaded mission differs")
                print(f"round {r + 1}/{args.rounds} done; relay {relay.counts}", flush=True)
            time.sleep(1.0)  # late duplicates and retries still in the relay arrive
        for t, ok in acked.items():
            n = sum(np.float32(c) == np.float32(t) for c in calls)  # the torque travelled as a float32
            if (ok and n != 1) or (not ok and n > 1):
                wrong.append(f"shock {t}: {'ACKed' if ok else 'not ACKed'}, applied {n} times")
        relay.close()
        total_calls = len(calls)
        dup = srv.counters.dropped["duplicate_command"]
    print()
    for kind, ts in times.items():
        if ts:
            print(f"{kind:17s} {len(ts):4d} completed: median {statistics.median(ts):.3f} s, max {max(ts):.3f} s")
    print(f"clear errors after the retries: {dict(errors) or 'none'}")
    print(f"shock commands acted on by the rig: {total_calls}; repeats answered without acting: {dup}")
    print(f"wrong results: {len(wrong)} {wrong[:5]}")
    return 0 if not wrong else 1


if __name__ == "__main__":
    sys.exit(main())
