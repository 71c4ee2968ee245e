"""A velocity-only offboard set-point on the hardware plant: flown with no steady error, as PX4 flies
it, because the axis' position reference is the track the velocity carries (guidance/offboard.py);
a stream of set-points carries one track on, and the track never leads the vehicle by more than
VELOCITY_TRACK_LEAD_M. Without the track the rig climbed at 0.27 m/s when asked for 0.4."""

import math

import numpy as np

from rig_emulator.config.loader import load_config
from rig_emulator.control.controller import REF_POS
from rig_emulator.guidance.offboard import OFB_POS0, OFB_T0, VELOCITY_TRACK_LEAD_M
from rig_emulator.link.serve import prepare_rig

NAN = math.nan


def _rig():
    rig = prepare_rig(load_config(airframe="hilms"))
    rig.arm(True)
    return rig, int(round(0.1 / rig.dt))


def _stream(rig, n, seconds, velocity):
    """Velocity set-points at 10 Hz for ``seconds``; (time, up) after each."""
    out = []
    for _ in range(int(round(seconds / 0.1))):
        rig.set_offboard_setpoint(velocity=velocity, yaw=0.0)
        rig.step(n)
        out.append((rig.time_s, float(rig.snapshot().position[2])))
    return out


def test_a_stream_of_velocity_setpoints_climbs_at_the_rate_asked():
    rig, n = _rig()
    p0 = rig.position_now()
    rig.set_position_target([p0[0], p0[1], 1.0])
    rig.step(50 * n)  # 5 s: in the air
    track = _stream(rig, n, 6.0, [NAN, NAN, 0.4])
    (t1, z1), (t2, z2) = track[20], track[-1]  # after 2 s of the stream
    assert abs((z2 - z1) / (t2 - t1) - 0.4) < 0.02, (z2 - z1) / (t2 - t1)


def test_the_track_carries_on_across_setpoints_and_stays_near_the_vehicle():
    rig, n = _rig()
    start = rig.position_now()[2]  # no track flown yet: it starts where the vehicle is
    rig.set_offboard_setpoint(velocity=[NAN, NAN, 0.5], yaw=0.0)
    first = rig.sim.gp.offboard.copy()
    assert first[OFB_POS0 + 2] == start and np.isnan(first[OFB_POS0:OFB_POS0 + 2]).all()
    rig.step(n)
    rig.set_offboard_setpoint(velocity=[NAN, NAN, 0.5], yaw=0.0)  # the next of a stream, 0.1 s later
    second = rig.sim.gp.offboard
    carried = first[OFB_POS0 + 2] + 0.5 * (second[OFB_T0] - first[OFB_T0])
    assert abs(second[OFB_POS0 + 2] - carried) < 1e-12  # one track, not a restart from the vehicle
    rig.step(n)
    assert abs(rig.sim.ref[REF_POS + 2] - (carried + 0.5 * (rig.time_s - second[OFB_T0]))) < 0.5 * 0.02  # flown
    # down into the ground (the hardware rig stands on it): the track stops VELOCITY_TRACK_LEAD_M below
    _stream(rig, n, 3.0, [NAN, NAN, -1.0])
    here = rig.position_now()[2]
    rig.set_offboard_setpoint(velocity=[NAN, NAN, -1.0], yaw=0.0)
    assert rig.sim.gp.offboard[OFB_POS0 + 2] == here - VELOCITY_TRACK_LEAD_M
    # an axis with a position keeps it; an axis with neither stays free
    rig.set_offboard_setpoint(position=[1.0, NAN, NAN], velocity=[NAN, NAN, 0.2], yaw=0.0)
    rig.step(n)
    assert rig.sim.ref[REF_POS] == 1.0 and np.isnan(rig.sim.ref[REF_POS + 1])
