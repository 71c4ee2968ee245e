"""The identification flight on a served rig (LiveRig.start_sysid), on the default `hilms` plant: the headless
programme's set-points and arming on the programme's own clock from the step it starts at, and a programme
that stops for good when anything else disarms the rig or steers it."""

import math

import numpy as np
import pytest

from rig_emulator.config.loader import load_config
from rig_emulator.guidance.offboard import OFB_ATT, OFB_THRUST
from rig_emulator.guidance.sysid import DURATION_S, HOLD_THRUST_MAX, HOLD_TILT_MAX, UPDATE_S, setpoint
from rig_emulator.link.serve import prepare_rig
from rig_emulator.simulation.live import LiveRig

CHUNK_STEPS = 5  # the served rig's 5 ms chunks at 1 kHz


def _run(rig, seconds):
    for _ in range(int(round(seconds / (CHUNK_STEPS * rig.dt)))):
        rig.step(CHUNK_STEPS)


@pytest.fixture(scope="module")
def cfg():
    return load_config("hilms")


def test_the_programme_flies_on_its_own_clock_from_where_it_starts(cfg):
    rig = prepare_rig(cfg)
    with pytest.raises(ValueError, match="disarmed"):
        rig.start_sysid()
    rig.arm(True)
    _run(rig, 1.237)  # an odd start: the programme's updates follow its own clock, not the rig's
    t0 = rig.time_s
    rig.start_sysid()
    hover = rig.sim.pp.mass * rig.sim.pp.g
    prog = rig.sim.programme
    # roll chirp, pitch chirp, a thrust step, the hover, the roll swing armed and disarmed
    for t_prog in (5.0, 20.0, 47.3, 70.0, 87.0, 90.0):
        _run(rig, t0 + t_prog - rig.time_s)
        st = rig.sysid_status()
        assert st.elapsed_s == pytest.approx(t_prog, abs=1e-9) and st.stopped is None and not st.done
        # the set-point applied last: at the last update instant before now (the one at now comes with the next
        # step), plus the position hold's correction, small and, in the thrust steps, leaving the collective alone
        t_update = (math.ceil(st.elapsed_s / UPDATE_S - 1e-6) - 1) * UPDATE_S
        armed, att, _rate, thrust = setpoint(t_update)
        assert rig.armed == armed, t_prog
        dphi, dtheta, dthrust = prog.hold
        assert math.hypot(dphi, dtheta) <= HOLD_TILT_MAX + 1e-12 and abs(dthrust) <= HOLD_THRUST_MAX
        if not armed:
            assert (dphi, dtheta, dthrust) == (0.0, 0.0, 0.0)
        if t_prog == 47.3:
            assert dthrust == 0.0
        ofb = rig.sim.gp.offboard
        np.testing.assert_allclose(ofb[OFB_ATT:OFB_ATT + 3], [att[0] + dphi, att[1] + dtheta, att[2]], atol=1e-12)
        assert ofb[OFB_THRUST] == pytest.approx((thrust + dthrust) * hover)
    assert not rig.armed and rig.sysid_status().part == "roll swing"  # disarmed: swinging on the joint
    _run(rig, t0 + DURATION_S - rig.time_s)
    st = rig.sysid_status()
    assert st.done and st.part == "after the programme" and not rig.armed
    rig.stop_sysid()
    assert rig.sysid_status() is None


def test_a_disarm_or_another_guidance_stops_it_for_good(cfg):
    rig = prepare_rig(cfg)
    rig.arm(True)
    rig.start_sysid()
    _run(rig, 4.0)
    rig.arm(False)  # e.g. a terminate action, or the failsafe inside the loop
    _run(rig, DURATION_S - 3.0)  # past the swings, where the programme would arm the rig again
    assert "disarmed by something else" in rig.sysid_status().stopped
    assert not rig.armed

    rig.stop_sysid()
    rig.arm(True)
    rig.start_sysid()
    _run(rig, 2.0)
    rig.hold_position()  # another guidance
    _run(rig, 0.1)
    st = rig.sysid_status()
    assert st.stopped == "another guidance took over" and st.replaced
    assert rig.sim.gp.offboard is not None and rig.armed
    _run(rig, DURATION_S - 20.0)
    assert rig.armed  # the programme never disarmed it for its swings


def test_refused_where_a_flight_stack_drives_the_motors(cfg):
    rig = LiveRig(cfg, external_motors=True)  # PX4 or ArduPilot in the loop
    rig.arm(True)
    with pytest.raises(ValueError, match="flight stack"):
        rig.start_sysid()
    assert rig.sysid_status() is None
