"""Offboard guidance: an external set-point (PX4's offboard interface) turned into references.

The set-point lives in ``GuidanceParams.offboard`` (OFB_* layout below, world ENU, paper
angles, SI), written by :class:`~rig_emulator.simulation.live.LiveRig` from set-point
messages; the link layer converts MAVLink frames before (``protocol/setpoint_frames.py``).
Three kinds:

* OFB_KIND_POSITION: per world axis a position, velocity and acceleration, each NaN when
  not given. As in PX4's trajectory set-points a NaN is "not controlled": a velocity alone
  is velocity control, an acceleration alone is acceleration control, a position with no
  velocity holds it (velocity reference 0). A velocity alone is flown as PX4 flies it, with no
  steady error: the position reference of that axis is the track the velocity carries from
  OFB_POS0 (where the track stood when the set-point arrived, see
  :meth:`~rig_emulator.simulation.live.LiveRig.set_offboard_setpoint`), so the paper's position
  laws, which have no integral term, see the error a lag builds up and close it. Heading: the yaw when given, else the heading
  at the set-point's time turning at the yaw rate (NaN rate: held).
* OFB_KIND_ATTITUDE: paper Euler angles, Euler-angle rate feed-forward, and a collective
  thrust (N, NaN = hover thrust m g).
* OFB_KIND_RATES: body rates (FRD, rad/s) and a collective thrust; the angles are free.
"""

import math

from rig_emulator._jit import jit
from rig_emulator.control.controller import (
    MODE_ATTITUDE,
    MODE_POSITION,
    MODE_RATES,
    REF_ACC,
    REF_ACC_FF,
    REF_ATT,
    REF_ATT_ACC,
    REF_ATT_RATE,
    REF_MODE,
    REF_POS,
    REF_THRUST,
    REF_VEL,
    REF_YAW,
)

OFB_KIND = 0  # OFB_KIND_* below
OFB_POS = 1  # 3: world ENU (m), NaN per axis = not controlled
OFB_VEL = 4  # 3: m/s
OFB_ACC = 7  # 3: m/s^2
OFB_YAW = 10  # paper psi (rad), NaN = not given
OFB_YAW_RATE = 11  # paper psi rate (rad/s), NaN = not given
OFB_T0 = 12  # time the set-point arrived (s)
OFB_YAW0 = 13  # paper psi at that time (rad)
OFB_ATT = 14  # 3: paper phi, theta, psi (rad) for OFB_KIND_ATTITUDE
OFB_RATE = 17  # 3: Euler-angle rate feed-forward (attitude) or body rates FRD (rates), rad/s
OFB_THRUST = 20  # collective thrust (N), NaN = hover thrust
OFB_POS0 = 21  # 3: a velocity-only axis' position track at OFB_T0, world ENU (m); NaN = pure velocity error
OFB_SIZE = 24
#: How far a velocity track may lead the vehicle (m) when a new set-point carries it on: a vehicle held
#: back (on the ground, at a fence, at its thrust limit) does not wind the track up beyond this
VELOCITY_TRACK_LEAD_M = 1.0

OFB_KIND_POSITION = 0.0
OFB_KIND_ATTITUDE = 1.0
OFB_KIND_RATES = 2.0


@jit(inline="always")
def _wrap(a):
    return (a + math.pi) % (2.0 * math.pi) - math.pi


@jit(nrt=False)
def offboard_references(t, ofb, ref):
    """Fill ``ref`` (controller.REF_* layout) from the offboard set-point ``ofb`` at time t."""
    kind = ofb[OFB_KIND]
    ref[REF_THRUST] = ofb[OFB_THRUST]
    ref[REF_ACC_FF] = 0.0
    if kind == OFB_KIND_POSITION:
        ref[REF_MODE] = MODE_POSITION
        for k in range(3):
            p = ofb[OFB_POS + k]
            v = ofb[OFB_VEL + k]
            a = ofb[OFB_ACC + k]
            if math.isnan(p) and not math.isnan(v):  # velocity control: the track it carries
                p = ofb[OFB_POS0 + k] + v * (t - ofb[OFB_T0])
            ref[REF_POS + k] = p
            ref[REF_VEL + k] = 0.0 if (math.isnan(v) and not math.isnan(p)) else v
            ref[REF_ACC + k] = a
            if not math.isnan(a):
                ref[REF_ACC_FF] = 1.0
        ref[REF_THRUST] = math.nan
        if not math.isnan(ofb[OFB_YAW]):
            ref[REF_YAW] = ofb[OFB_YAW]
        elif not math.isnan(ofb[OFB_YAW_RATE]):
            ref[REF_YAW] = _wrap(ofb[OFB_YAW0] + ofb[OFB_YAW_RATE] * (t - ofb[OFB_T0]))
        else:
            ref[REF_YAW] = ofb[OFB_YAW0]
        return
    ref[REF_MODE] = MODE_ATTITUDE if kind == OFB_KIND_ATTITUDE else MODE_RATES
    for k in range(3):
        ref[REF_POS + k] = math.nan
        ref[REF_VEL + k] = math.nan
        ref[REF_ACC + k] = 0.0
        ref[REF_ATT + k] = ofb[OFB_ATT + k]
        ref[REF_ATT_RATE + k] = ofb[OFB_RATE + k]
        ref[REF_ATT_ACC + k] = 0.0
    ref[REF_YAW] = ofb[OFB_ATT + 2]
