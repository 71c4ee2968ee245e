"""MAVProxy 1.8.75 flies the rig as a PX4 vehicle: every mode name it lists, takeoff, guided,
return and land. MAVProxy is driven through its stdin and judged by its output (see
test_link_mavproxy.py); the rig runs as ``rig-emulator serve`` at 4x real time.

MAVProxy's own ``mode NAME`` cannot send a PX4 mode with pymavlink 2.4.50 (``set_mode_px4``
gets px4_map's tuple: struct.error, nothing is sent); the test records that for the first
name and sends each name's DO_SET_MODE the way a MAVProxy user can, ``long DO_SET_MODE
<base> <main> <sub>`` with the numbers of pymavlink's px4_map. The results (what the rig did
with every name) are printed."""

import re
import subprocess
import sys

import pytest
from pymavlink import mavutil

from protocol.geodesy import local_enu_to_global
from rig_emulator.testing.rig import RigProcess, connect, recv
from rig_emulator.link.serve_args import DEFAULT_HOME
from protocol.geodesy import Home

from .test_link_mavproxy import MAVPROXY, _Lines

pytestmark = [pytest.mark.slow]
FLOWN = {"POSCTL", "STABILIZED", "LOITER", "RTL", "LAND", "TAKEOFF", "OFFBOARD"}


def _seen_or_wait(out, pattern, mark, timeout=3.0):
    """A line matching ``pattern`` printed since line ``mark`` (already read or still to come)."""
    for line in out.all[mark:]:
        m = re.search(pattern, line)
        if m:
            return m
    return out.wait_for(pattern, timeout=timeout)


def _position(obs):
    """The rig's latest position (ENU): what queued up on the observer's socket is read first."""
    while obs.recv_match(blocking=False) is not None:
        pass
    m = recv(obs, "LOCAL_POSITION_NED", 5.0)
    return m.y, m.x, -m.z


def test_mavproxy_modes_takeoff_guided_rtl_land(tmp_path):
    home = Home(*(float(v) for v in DEFAULT_HOME.split(",")))
    results = {}
    with RigProcess(speedup=4.0) as rig:
        port = rig.tcp_url.rsplit(":", 1)[1]
        obs = connect(rig.tcp_url, source_system=254)
        proc = subprocess.Popen(
            [sys.executable, str(MAVPROXY), f"--master=tcp:127.0.0.1:{port}", f"--state-basedir={tmp_path}"],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, cwd=tmp_path)
        out = _Lines(proc)

        def send(line):
            proc.stdin.write(line + "\n")
            proc.stdin.flush()

        try:
            assert out.wait_for(r"Received \d+ parameters") is not None, "".join(out.all)
            send("mode")  # the list MAVProxy offers for this vehicle
            listed = out.wait_for(r"Available modes:\s+(.*)")
            assert listed is not None
            names = [n.strip() for n in listed.group(1).split(",")]
            assert set(names) == set(mavutil.px4_map)
            send("mode LOITER")  # MAVProxy's own path: fails inside pymavlink before sending
            err = out.wait_for(r"(required argument is not a float|struct\.error|Exception)", timeout=15)
            results["mode LOITER (MAVProxy's mode command)"] = "client error: " + (err.group(1) if err else "none?")
            for name in names:
                base, main, sub = mavutil.px4_map[name]
                mark = len(out.all)
                send(f"long DO_SET_MODE {base} {main} {sub}")
                ack = out.wait_for(r"Got COMMAND_ACK: DO_SET_MODE: (\w+)")
                assert ack is not None, (name, "".join(out.all[-20:]))
                text = None
                if ack.group(1) != "ACCEPTED":  # the reason may come just before or after the ACK
                    text = _seen_or_wait(out, r"AP: ((?:mode|mission) refused: .*)", mark)
                results[f"mode {name}"] = ack.group(1) + (f" ({text.group(1).strip()})" if text else "")
                if name in FLOWN:
                    assert ack.group(1) == "ACCEPTED", (name, results)
                else:
                    assert ack.group(1) == "DENIED" and text is not None, (name, results)
            send("long DO_SET_MODE 29 4 3")  # LOITER, then arm and take off to 2 m (AMSL for PX4: below home)
            send("arm throttle")
            assert out.wait_for(r"ARMED", timeout=20) is not None, "".join(out.all[-20:])
            send("takeoff 2")
            assert out.wait_for(r"Using minimum takeoff altitude") is not None
            assert out.wait_for(r"takeoff complete", timeout=60) is not None
            up = _position(obs)[2]
            assert abs(up - 2.5) < 0.2
            results["takeoff 2"] = f"climbed to {up:.2f} m (MIS_TAKEOFF_ALT; 2 m AMSL is below home)"
            lat, lon, _ = local_enu_to_global(home, [1.0, 1.0, 0.0])
            send(f"guided {lat:.7f} {lon:.7f} 2")
            assert out.wait_for(r"arrived", timeout=60) is not None
            e, n, u = _position(obs)
            assert abs(e - 1.0) < 0.15 and abs(n - 1.0) < 0.15 and abs(u - 2.0) < 0.15
            results["guided LAT LON 2"] = f"flew to E {e:.2f} N {n:.2f} U {u:.2f}"
            send("long NAV_RETURN_TO_LAUNCH")
            assert out.wait_for(r"landed: disarmed", timeout=90) is not None
            e, n, u = _position(obs)
            assert abs(e) < 0.15 and abs(n) < 0.15 and u < 0.1
            results["long NAV_RETURN_TO_LAUNCH"] = f"returned and landed at E {e:.2f} N {n:.2f}, disarmed"
            send("param set MIS_TAKEOFF_ALT 1.5")  # MAVProxy sends it from its idle loop: read it back until set
            for _ in range(10):
                send("param fetch MIS_TAKEOFF_ALT")
                got = out.wait_for(r"MIS_TAKEOFF_ALT = (\S+)", timeout=10)
                if got is not None and float(got.group(1)) == 1.5:
                    break
            else:
                raise AssertionError("MIS_TAKEOFF_ALT not set: " + "".join(out.all[-20:]))
            send("arm throttle")
            send("takeoff 0")
            assert out.wait_for(r"takeoff complete", timeout=60) is not None
            up = _position(obs)[2]
            assert abs(up - 1.5) < 0.2
            results["param set MIS_TAKEOFF_ALT 1.5 + takeoff 0"] = f"climbed to {up:.2f} m"
            send("long NAV_LAND")
            assert out.wait_for(r"landed: disarmed", timeout=90) is not None
            results["long NAV_LAND"] = f"landed at {_position(obs)[2]:.2f} m, disarmed"
            send("land")  # MAVProxy's land: DO_LAND_START
            land_start = out.wait_for(r"land start refused: (.*)")
            assert land_start is not None
            results["land (DO_LAND_START)"] = "FAILED: " + (land_start.group(1).strip() if land_start else "?")
            before_exit = "".join(out.all)
            send("exit")
            proc.stdin.close()
            proc.wait(30)
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
            obs.close()
        print("\nMAVProxy 1.8.75 on the rig:\n" + "\n".join(f"  {k}: {v}" for k, v in results.items()))
        assert "Traceback" not in before_exit
        assert rig.stop() == 0
