"""MAVProxy 1.8.75 flies the rig as a PX4 vehicle: every mode name it lists, takeoff, guided,
return and land. MAVProxy is driven through its stdin and judged by its output
(rig_emulator.testing.mavproxy); the rig runs as ``rig-emulator serve`` at 4x real time.

MAVProxy's own ``mode NAME`` cannot send a PX4 mode with pymavlink 2.4.50 (``set_mode_px4``
gets px4_map's tuple: struct.error, nothing is sent); the test records that for the first
name, loads the project's MAVProxy module ``gcs_tools.mavproxy_px4modes`` and sends every
listed name with ``mode NAME``; one bare name (``posctl``) and the hand-typed fallback
``long DO_SET_MODE <base> <main> <sub>`` are checked too. The results (what the rig did with
every name) are printed; docs/how-to/ground-stations.md quotes them."""

import math

import pytest
from pymavlink import mavutil

from protocol.geodesy import Home, local_enu_to_global
from rig_emulator.link.serve_args import DEFAULT_HOME
from rig_emulator.testing.mavproxy import MAVProxySession
from rig_emulator.testing.rig import RigProcess, connect, recv

pytestmark = [pytest.mark.slow]
FLOWN = {"POSCTL", "STABILIZED", "LOITER", "RTL", "LAND", "TAKEOFF"}  # OFFBOARD: refused without a set-point stream
ACK = r"Got COMMAND_ACK: DO_SET_MODE: (\w+)"


def _position(obs):
    """The rig's latest position (ENU): what queued up on the observer's socket is read first."""
    while obs.recv_match(blocking=False) is not None:
        pass
    m = recv(obs, "LOCAL_POSITION_NED", 5.0)
    return m.y, m.x, -m.z


def _wait_still(obs, rate_deg_s=5.0, still_s=1.0, guard_s=60.0):
    """Wait until the rig's body rates (ATTITUDE) stay below ``rate_deg_s`` for ``still_s`` of
    simulated time; returns the simulated time waited. Judged on the messages' own stamps."""
    while obs.recv_match(blocking=False) is not None:
        pass
    t0 = since = None
    while True:
        m = recv(obs, "ATTITUDE", 5.0)
        assert m is not None, "no ATTITUDE from the rig"
        t = m.time_boot_ms * 1e-3
        t0 = t if t0 is None else t0
        rate = math.degrees(math.sqrt(m.rollspeed ** 2 + m.pitchspeed ** 2 + m.yawspeed ** 2))
        if rate < rate_deg_s:
            since = t if since is None else since
            if t - since >= still_s:
                return t - t0
        else:
            since = None
        assert t - t0 < guard_s, f"the rig still turns at {rate:.0f} deg/s {guard_s:g} s after the landing"


def _reported_mode(obs):
    """The mode the rig's next HEARTBEAT reports (pymavlink's PX4 names)."""
    while obs.recv_match(blocking=False) is not None:
        pass
    return mavutil.mode_string_v10(recv(obs, "HEARTBEAT", 5.0, lambda m: m.get_srcComponent() == 1))


def _mode_result(out, mark, ack):
    """ACCEPTED, or DENIED with the rig's reason (the STATUSTEXT may come just before or after the ACK)."""
    text = None
    if ack.group(1) != "ACCEPTED":
        text = out.seen_or_wait(r"AP: ((?:mode|mission) refused: .*)", mark)
    return ack.group(1) + (f" ({text.group(1).strip()})" if text else ""), text


def test_mavproxy_modes_takeoff_guided_rtl_land(tmp_path):
    home = Home(*(float(v) for v in DEFAULT_HOME.split(",")))
    results = {}
    with RigProcess(speedup=4.0) as rig:
        obs = connect(rig.tcp_url, source_system=254)
        with MAVProxySession(rig.tcp_url, tmp_path) as out:
            send = out.send
            assert out.wait_for(r"Received \d+ parameters") is not None, out.transcript()
            send("mode")  # the list MAVProxy offers for this vehicle
            listed = out.wait_for(r"Available modes:\s+(.*)")
            assert listed is not None
            names = [n.strip() for n in listed.group(1).split(",")]
            assert set(names) == set(mavutil.px4_map)
            send("mode LOITER")  # MAVProxy's own path: fails inside pymavlink before sending
            err = out.wait_for(r"(required argument is not a float|struct\.error|Exception)", timeout=15)
            results["mode LOITER (MAVProxy's own mode command)"] = "client error: " + (err.group(1) if err else "none?")
            out.do("module load gcs_tools.mavproxy_px4modes", r"Loaded module gcs_tools\.mavproxy_px4modes")
            before = _reported_mode(obs)
            for name in names:
                mark = len(out.all)
                ack = out.do(f"mode {name}", ACK)
                results[f"mode {name}"], text = _mode_result(out, mark, ack)
                reported = _reported_mode(obs)
                results[f"mode {name}"] += f" -> HEARTBEAT {reported}"
                if name in FLOWN:
                    assert ack.group(1) == "ACCEPTED" and reported == name, (name, results)
                else:  # refused with the reason, the mode flown before kept
                    assert ack.group(1) == "DENIED" and text is not None and reported == before, (name, results)
                before = reported
            mark = len(out.all)
            out.do("posctl", r"Got COMMAND_ACK: DO_SET_MODE: ACCEPTED")  # a bare name, as MAVProxy offers it
            assert _reported_mode(obs) == "POSCTL"
            # MAVProxy's mode module (loaded before ours here) tries the name first and fails as above
            own = out.seen_or_wait(r"ERROR in command: (.*)", mark, timeout=1.0)
            assert own is not None
            results["posctl (bare name)"] = f"ACCEPTED -> HEARTBEAT POSCTL (after MAVProxy's own '{own.group(1).strip()}')"
            base, main, sub = mavutil.px4_map["LOITER"]
            out.do(f"long DO_SET_MODE {base} {main} {sub}", r"Got COMMAND_ACK: DO_SET_MODE: ACCEPTED")
            results[f"long DO_SET_MODE {base} {main} {sub} (LOITER by hand)"] = "ACCEPTED"
            # in LOITER: arm and take off to 2 m (AMSL for PX4: below home)
            send("arm throttle")
            assert out.wait_for(r"ARMED", timeout=20) is not None, out.transcript(20)
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
            mark = len(out.all)
            assert out.wait_for(r"landed: disarmed", timeout=90) is not None
            # the operator's cue to arm again: MAVProxy has seen a disarmed HEARTBEAT (it prints
            # "ARMED" only on a change it saw, so an arm sent before that would never print it)
            assert out.seen_or_wait(r"\bDISARMED\b", mark, timeout=20) is not None, out.transcript(20)
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
                raise AssertionError("MIS_TAKEOFF_ALT not set: " + out.transcript(20))
            # The hardware rig disarmed on landing swings down to its hanging tilt on the joint
            # (joint.cog_offset) and its pre-arm check refuses arming while it still turns ("Arming
            # denied: still rotating"), which is what the rig should do: wait for the swing to die out,
            # as an operator does, then arm and check that it armed.
            swing = _wait_still(obs)
            send("arm throttle")
            assert out.wait_for(r"\bARMED\b", timeout=20) is not None, out.transcript(20)
            results["arm throttle after the landing"] = f"ARMED after {swing:.1f} s (simulated) waiting for the rig to hang still"
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
        obs.close()
        print("\nMAVProxy 1.8.75 on the rig:\n" + "\n".join(f"  {k}: {v}" for k, v in results.items()))
        assert "Traceback" not in out.before_exit
        assert rig.stop() == 0
