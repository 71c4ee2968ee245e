"""The supervisor: debounced sensor flags, estimate validity, the loss-of-control latch."""

import math

import numpy as np

from rig_emulator.config.loader import load_config
from rig_emulator.control import supervisor as SV
from rig_emulator.control.controller import OUT_ATT_DES, OUT_SIZE

G = 9.81
FIELD = 50e-6
DT = 0.002


def _setup(**overrides):
    cfg = load_config("hilms-ideal", overrides={"failsafe.hold_time": 0.1, "health.reject_window": 0.05,
                                 "health.update_rate_hz": 1.0 / DT, **overrides})
    return SV.supervisor_params(cfg, 5, G, FIELD, DT), SV.supervisor_state(5, 4)


def _fused(accel=G, mag=FIELD):
    f = np.zeros((3, 3))
    f[1, 2] = -accel
    f[2, 0] = mag
    return f


def _step(t, up, us, phi=0.0, rejected=(0, 0, 0), fused=None, cells=0, armed=True, rate=0.0, estimated=True):
    cout = np.zeros(OUT_SIZE)
    return SV.supervise(t, armed, True, estimated, phi, 0.0, 0.0, 0.0, rate, cout,
                        np.array(rejected, dtype=np.int64), _fused() if fused is None else fused, cells, up, us)


def test_units_rejected_most_of_the_time_are_flagged_with_hysteresis():
    up, us = _setup()
    t = 0.0
    for i in range(200):  # isolated rejections (every tenth update) never flag
        every10 = i % 10 == 0
        _step(t, up, us, rejected=(0, (1 << 2) if every10 else 0, (1 << 2) if every10 else 0),
              cells=(1 << 1) if every10 else 0)
        t += DT
    assert us.flags[SV.F_ACCEL] == 0 and us.flags[SV.F_CELLS] == 0
    n = 0
    while not us.flags[SV.F_ACCEL]:  # rejected all the time: flagged after ~ window ln 2
        _step(t, up, us, rejected=(0, 1 << 2, 1 << 2), cells=1 << 1)
        t += DT
        n += 1
    assert 0.02 < n * DT < 0.05
    assert list(us.flags[SV.F_GYRO : SV.F_MAG + 1]) == [0, 4, 4] and us.flags[SV.F_CELLS] == 2
    for _ in range(5):  # a few accepted samples do not clear it (hysteresis) ...
        _step(t, up, us)
        t += DT
    assert us.flags[SV.F_ACCEL] == 4 and us.flags[SV.F_CELLS] == 2
    for _ in range(100):  # ... a clean stretch does
        _step(t, up, us)
        t += DT
    assert us.flags[SV.F_ACCEL] == 0 and us.flags[SV.F_CELLS] == 0
    assert us.flags[SV.F_INVALID] == 0


def test_estimate_invalid_without_majority_or_with_implausible_magnitudes():
    cases = ((dict(rejected=(0b00111, 0b00011, 0)), SV.INVALID_GYRO),  # 3 of 5 gyros rejected: no majority
             (dict(fused=_fused(accel=0.1 * G)), SV.INVALID_ACCEL),  # e.g. three dead accelerometers outvoting two
             (dict(fused=_fused(mag=2.0 * FIELD)), SV.INVALID_MAG))
    for kwargs, bit in cases:
        up, us = _setup()
        _step(0.0, up, us, **kwargs)
        assert us.flags[SV.F_INVALID] == 0  # a moment is not reported (manoeuvres) ...
        for i in range(1, 50):
            _step(i * DT, up, us, **kwargs)
        assert us.flags[SV.F_INVALID] == bit  # ... a lasting inconsistency is


def test_loss_of_control_must_hold_then_latches_until_rearmed():
    up, us = _setup()
    big = math.radians(60.0)
    assert not _step(0.0, up, us, phi=big)
    assert us.flags[SV.F_ALERTS] == SV.ALERT_ATTITUDE
    assert not _step(0.05, up, us, phi=0.0)  # a break restarts the hold time
    t = 0.1
    while not _step(t, up, us, phi=big):
        t += DT
        assert t < 0.3
    assert abs(t - 0.2) < 1e-6  # held from 0.1 s for hold_time = 0.1 s
    assert us.flags[SV.F_FAILSAFE] == SV.ALERT_ATTITUDE
    assert math.isclose(us.values[SV.V_TRIP_T], t) and math.isclose(us.values[SV.V_TRIP_ATT], big)
    assert not _step(t + 1.0, up, us, phi=0.0)  # latched: nothing more to do, stays tripped
    assert us.flags[SV.F_FAILSAFE] == SV.ALERT_ATTITUDE
    SV.reset_failsafe(us)  # arming again
    assert us.flags[SV.F_FAILSAFE] == 0 and not _step(t + 2.0, up, us)


def test_rate_and_estimate_causes_report_action_and_off_switch():
    up, us = _setup(**{"failsafe.action": "report"})
    for i in range(60):
        tripped = _step(i * DT, up, us, rate=math.radians(400.0), fused=_fused(accel=0.0))
    assert not tripped  # 'report' never cuts the motors ...
    assert us.flags[SV.F_FAILSAFE] == SV.ALERT_RATE | SV.ALERT_ESTIMATE  # ... but latches the cause
    up, us = _setup(**{"failsafe.on_estimate_invalid": False})
    for i in range(60):
        _step(i * DT, up, us, fused=_fused(accel=0.0))
    assert us.flags[SV.F_FAILSAFE] == 0 and us.flags[SV.F_INVALID] == SV.INVALID_ACCEL
    up, us = _setup(**{"failsafe.enabled": False})
    for i in range(60):
        assert not _step(i * DT, up, us, phi=3.0, rate=100.0)
    assert us.flags[SV.F_FAILSAFE] == 0
    up, us = _setup()
    for i in range(60):  # disarmed: no loss of control
        assert not _step(i * DT, up, us, phi=3.0, armed=False)
    assert us.flags[SV.F_FAILSAFE] == 0 and us.flags[SV.F_ALERTS] == 0


def test_attitude_error_is_against_the_desired_attitude():
    up, us = _setup()
    cout = np.zeros(OUT_SIZE)
    cout[OUT_ATT_DES + 1] = math.radians(40.0)
    rej = np.zeros(3, dtype=np.int64)
    SV.supervise(0.0, True, True, True, 0.0, math.radians(35.0), 0.0, 0.0, 0.0, cout, rej, _fused(), 0, up, us)
    assert us.flags[SV.F_ALERTS] == 0
    assert math.isclose(us.values[SV.V_ATT_ERR], math.radians(5.0), rel_tol=1e-9)


def test_update_rate_is_a_whole_number_of_control_periods():
    cfg = load_config("hilms-ideal", overrides={"health.update_rate_hz": 120.0})
    up = SV.supervisor_params(cfg, 5, G, FIELD, 0.002, 2)  # 500 Hz control at 1 kHz physics
    assert up.div == 8  # 1 / (120 Hz x 2 ms) = 4.2 -> 4 control periods of 2 steps
    assert math.isclose(up.share_alpha, 1.0 - math.exp(-0.008 / cfg["health.reject_window"]))
