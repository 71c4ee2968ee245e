"""Soak: one simulated hour of the rig with telemetry, a logger and repeated mission uploads.

Run from the repository root::

    .venv/bin/python -m benchmarks.soak                       # 3600 simulated s as fast as the host allows
    .venv/bin/python -m benchmarks.soak --sim-seconds 600 --speedup 20 --out /tmp/soak

Starts ``rig-emulator serve`` (a real process, TCP endpoint on a free port) and attaches:

* ``rig-gcs log`` (a real process) writing ``soak.tlog`` in ``--out``;
* a telemetry client (this script) reading every message and, every ``--sample`` wall
  seconds, the rig's counters (:mod:`rig_emulator.link.telemetry.link_status`) and its resident memory
  (``/proc/PID/status`` VmRSS);
* a ground station (a thread of this script, gcs_tools' mission client) uploading a mission
  every ``--upload-every`` wall seconds, alternating the rectangle and the helix, and
  downloading every fifth to compare it with what was sent.

Control steps. The served rig advances its physics in chunks paced against the wall clock;
a control update runs every ``physics rate / control rate`` physics steps inside the compiled
loop, so an update cannot be skipped: a step the loop is late for runs late. What can be
*missed* is real time: when the loop falls more than 0.25 s x speed-up behind its schedule it
gives up that lag (PACE_RESET, LAG_MS). The script reports, between the end of the warm-up and
the end: control steps expected from the wall time x speed-up x control rate, control steps
done (the rig's CTRL_STEPS), the difference (missed), the real time given up; and that the
step counter equals the simulated time x physics rate (no step lost by the chunk scheduler).
With ``--speedup max`` there is no schedule to miss; only the counter check applies.

Memory: RSS after the warm-up (``--warmup`` simulated seconds) and at the end, growth in %.
The .tlog is read back to its end with pymavlink's mavutil. Exit 0 when RSS grew less than
5 %, no control step was missed, the counter check holds, every upload succeeded and the log
is valid to its end; 1 otherwise.
"""

from __future__ import annotations

import argparse
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from rig_emulator.link.telemetry.link_status import read_link_status  # noqa: E402
from rig_emulator.link.serve_args import parse_speedup  # noqa: E402
from rig_emulator.testing.rig import RigProcess, client_url, connect  # noqa: E402


def rss_kib(pid: int) -> int:
    with open(f"/proc/{pid}/status") as f:
        return next(int(line.split()[1]) for line in f if line.startswith("VmRSS:"))


class Uploader(threading.Thread):
    """A ground station uploading missions in a loop (its own TCP connection)."""

    def __init__(self, url: str, every_s: float):
        super().__init__(daemon=True)
        self.url, self.every_s = url, every_s
        self.done = self.verified = 0
        self.failures: list[str] = []
        self.times: list[float] = []
        self._halt = threading.Event()

    def stop(self):
        self._halt.set()
        self.join(30)

    def run(self):
        from gcs_tools import mission_client
        from gcs_tools.link import Link
        from gcs_tools.missions import helix_points, mission_from_enu, rectangle_points

        missions = [mission_from_enu(rectangle_points(5, 3, 2)), mission_from_enu(helix_points(1.0))]
        with Link(self.url) as link:
            link.wait_vehicle(30)
            link.request_data_streams(0)  # a mission tool: no telemetry on this connection
            while not self._halt.wait(self.every_s):
                mission = missions[self.done % 2]
                t0 = time.monotonic()
                try:
                    mission_client.upload(link, mission)
                    self.done += 1
                    if self.done % 5 == 0:
                        back = mission_client.download(link).items
                        sent = mission.canonical().items
                        if len(back) == len(sent) and all(a.same_as(b) for a, b in zip(back, sent)):
                            self.verified += 1
                        else:
                            self.failures.append(f"download after upload {self.done} differs from the upload")
                except Exception as exc:  # noqa: BLE001 - reported in the figures
                    self.failures.append(f"upload {self.done + 1}: {exc}")
                self.times.append(time.monotonic() - t0)


def tlog_check(path: Path) -> dict:
    """Read the log to its end with mavutil: messages, types, bytes read vs file size, time stamps in order."""
    from pymavlink import mavutil

    from protocol.dialect import use_hilms_dialect

    use_hilms_dialect()
    log = mavutil.mavlogfile(str(path))
    n, bad, backwards, last_ts = 0, 0, 0, 0.0
    att = []
    while True:
        msg = log.recv_msg()
        if msg is None:
            break
        if msg.get_type() == "BAD_DATA":
            bad += 1
            continue
        n += 1
        ts = getattr(msg, "_timestamp", 0.0)
        backwards += ts < last_ts
        last_ts = max(last_ts, ts)
        if msg.get_type() == "ATTITUDE":
            att.append(msg.time_boot_ms / 1000.0)
    size = path.stat().st_size
    return {"messages": n, "bad_data": bad, "timestamps_backwards": backwards, "bytes_read": log.f.tell(),
            "size": size, "valid_to_end": log.f.tell() == size and bad == 0,
            "attitude_sim_span": (att[0], att[-1]) if att else None}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--sim-seconds", type=float, default=3600.0)
    p.add_argument("--speedup", default="max", help="the rig's --speedup (a number or max): %(default)s")
    p.add_argument("--warmup", type=float, default=120.0, help="simulated seconds before the first RSS figure")
    p.add_argument("--upload-every", type=float, default=3.0, help="wall seconds between mission uploads")
    p.add_argument("--sample", type=float, default=10.0, help="wall seconds between samples")
    p.add_argument("--out", default="soak-out", help="directory for soak.tlog")
    args = p.parse_args(argv)
    speedup = parse_speedup(args.speedup)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    tlog = out / "soak.tlog"
    with RigProcess(speedup=args.speedup) as rig:
        pid = rig.proc.pid
        url = client_url(rig.tcp_url)
        logger = subprocess.Popen([sys.executable, "-m", "gcs_tools", "log", url, "-o", str(tlog)],
                                  stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        tel = connect(rig.tcp_url)
        uploader = Uploader(url, args.upload_every)
        uploader.start()
        print(f"rig pid {pid}, speed-up {args.speedup}, {args.sim_seconds:g} simulated s; logger pid {logger.pid} "
              f"-> {tlog}", flush=True)
        samples = []
        start = None
        wall0 = time.monotonic()
        n_msgs = 0
        while True:
            t_next = time.monotonic() + args.sample
            while time.monotonic() < t_next:
                if tel.recv_match(blocking=True, timeout=0.2) is not None:
                    n_msgs += 1
            st = read_link_status(tel, timeout=10)
            if st is None:
                print("no answer to a counter request", flush=True)
                continue
            now = time.monotonic()
            rss = rss_kib(pid)
            samples.append((now, st, rss))
            if start is None and st["time_s"] >= args.warmup:
                start = samples[-1]
            print(f"  wall {now - wall0:6.0f} s  sim {st['time_s']:7.1f} s  RSS {rss / 1024:6.1f} MiB  uploads "
                  f"{uploader.done}  pacing resets {st['PACE_RESET']}", flush=True)
            if st["time_s"] >= args.sim_seconds or rig.proc.poll() is not None:
                break
        end = samples[-1]
        uploader.stop()
        tel.close()
        logger.send_signal(signal.SIGINT)
        try:
            log_out, log_err = logger.communicate(timeout=60)
        except subprocess.TimeoutExpired:
            logger.kill()
            log_out, log_err = logger.communicate()
        code = rig.stop()
    check = tlog_check(tlog)
    (w0, s0, r0), (w1, s1, r1) = start or samples[0], end
    growth = 100.0 * (r1 - r0) / r0
    rss_max = max(r for w, _, r in samples if w >= w0)
    phys_hz = round(s1["STEPS"] / s1["time_s"]) if s1["time_s"] else 0
    ctrl_div = round(s1["STEPS"] / max(s1["CTRL_STEPS"], 1))
    counter_err_ms = abs(s1["STEPS"] / phys_hz - s1["time_s"]) * 1e3 if phys_hz else float("nan")
    ctrl_done = s1["CTRL_STEPS"] - s0["CTRL_STEPS"]
    wall = w1 - w0
    print()
    print(f"simulated {s1['time_s']:.1f} s in {w1 - wall0:.1f} wall s (overall {s1['time_s'] / (w1 - wall0):.1f}x); "
          f"window after warm-up: {s1['time_s'] - s0['time_s']:.1f} simulated s in {wall:.1f} wall s")
    print(f"RSS after warm-up {r0 / 1024:.1f} MiB, at the end {r1 / 1024:.1f} MiB, max {rss_max / 1024:.1f} MiB: "
          f"growth {growth:+.2f} %")
    print(f"physics {phys_hz} Hz, control every {ctrl_div} steps; step counter {s1['STEPS']} vs simulated time "
          f"{s1['time_s']:.3f} s: |STEPS / rate - t| = {counter_err_ms:.2f} ms")
    missed = 0
    if speedup > 0:
        expected = speedup * wall * phys_hz / ctrl_div
        missed = max(0, round(expected - ctrl_done))
        print(f"control steps in the window: expected {expected:.0f} (wall x speed-up x rate), done {ctrl_done}, "
              f"missed {missed} ({missed / expected:.3%}); pacing resets {s1['PACE_RESET'] - s0['PACE_RESET']}, "
              f"real time given up {s1['LAG_MS'] - s0['LAG_MS']} ms")
    else:
        print(f"control steps in the window: done {ctrl_done} (speed-up max: no schedule to miss)")
    ups = uploader.times
    print(f"mission uploads: {uploader.done} done, {uploader.verified} verified by download, failures "
          f"{len(uploader.failures)} {uploader.failures[:3]}; upload time median "
          f"{sorted(ups)[len(ups) // 2] if ups else float('nan'):.3f} s, max {max(ups) if ups else float('nan'):.3f} s")
    print(f"telemetry client read {n_msgs} messages; rig counters at the end: received {s1['RX_MSGS']}, sent "
          f"{s1['TX_MSGS']}, dropped {s1['DROPPED']} (tx_overflow {s1['D_TXFULL']})")
    print(f"logger: {log_out.strip().splitlines()[-1] if log_out.strip() else ''} {log_err.strip()[-200:]}")
    print(f"tlog {tlog}: {check['messages']} messages, {check['bytes_read']} of {check['size']} bytes read, "
          f"BAD_DATA {check['bad_data']}, time stamps going backwards {check['timestamps_backwards']}, ATTITUDE "
          f"simulated time span {check['attitude_sim_span']}; valid to its end: {check['valid_to_end']}")
    print(f"rig exit code {code}")
    ok = (growth < 5.0 and missed == 0 and counter_err_ms < 2.5 and not uploader.failures and uploader.done > 0
          and check["valid_to_end"] and code == 0)
    print("RESULT:", "all checks hold" if ok else "FAILED")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
