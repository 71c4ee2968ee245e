"""Faults from the config: the degradation docs/how-to/faults.md states, headless.

Each run injects its fault at t = 5 s through ``faults.events``; the bounds are the measured
figures of docs/how-to/faults.md (python -m gcs_tools.studies faults, seeds 0-2) with a margin.
"""

import functools
import numpy as np
import pytest

from rig_emulator.api import simulate as _simulate
from rig_emulator.config.loader import ConfigError, load_config
from rig_emulator.control.supervisor import ALERT_ATTITUDE, ALERT_ESTIMATE, ALERT_RATE
from rig_emulator.simulation.run import Simulation

# these tests pin the ideal plant's behaviour (the default airframe is now the hardware rig)
simulate = functools.partial(_simulate, airframe="hilms-ideal")

T0 = 5.0


def _events(device, indices, mode, magnitude=0.0, t=T0):
    return {"faults.events": [{"t": t, "sensor": device, "index": i, "mode": mode, "magnitude": magnitude}
                              for i in indices]}


def _roll_pitch_deg(a, b):
    return np.abs((np.degrees(a[:, :2] - b[:, :2]) + 180.0) % 360.0 - 180.0)


def _trip(result):
    """(time, cause) of the failsafe, or None."""
    fs = result.series["failsafe"]
    if fs.max() == 0:
        return None
    i = int(np.argmax(fs > 0))
    return float(result.series["t"][i]), int(fs[i])


@pytest.mark.parametrize("mode, magnitude", [("stuck", 0.0), ("dead", 0.0), ("bias", 3000.0), ("noise", 50.0)])
def test_one_bad_imu_module_robust_ensemble_keeps_attitude_while_moving(mode, magnitude):
    r = simulate("harmonic", overrides=_events("imu", [2], mode, magnitude))
    s = r.series
    m = s["t"] >= T0
    assert _roll_pitch_deg(s["euler"][m], s["euler_true"][m]).max() < 1.0  # measured <= 0.61
    assert _roll_pitch_deg(s["euler_des"][m], s["euler_true"][m]).max() < 1.5  # measured <= 0.91
    assert _trip(r) is None
    assert (s["health"][m, 0].astype(int) & (1 << 2)).any()  # the ensemble rejects module 2 (at times)


def test_three_dead_imu_modules_invalidate_the_estimate_and_trip_the_failsafe():
    r = simulate("hover", overrides=_events("imu", [0, 1, 2], "dead"))
    t, cause = _trip(r)
    assert cause == ALERT_ESTIMATE and T0 + 0.5 <= t <= T0 + 0.6  # hold_time 0.5 s
    s = r.series
    assert s["estimate_invalid"][s["t"] >= t + 0.5].astype(int).min() & 2  # the fused accel stays implausible
    assert np.all(s["v_cmd"][s["t"] > t + 0.01] == 0.0)  # motors cut: disarmed


@pytest.mark.parametrize("strategy", ["flc", "pid"])
def test_motor_losing_20_percent_still_holds_hover(strategy):
    r = simulate("hover", strategy=strategy, overrides=_events("motor", [1], "thrust_loss", 0.2))
    s = r.series
    m = s["t"] >= T0
    assert _trip(r) is None
    assert _roll_pitch_deg(s["euler_des"][m], s["euler_true"][m]).max() < 5.0  # measured <= 3.4
    assert np.degrees(np.abs(s["omega"][m, 2])).max() < 5.0  # yaw authority left


def test_motor_dead_trips_the_failsafe_and_the_rig_stops_diverging():
    r = simulate("hover", overrides=_events("motor", [1], "dead"))
    t, cause = _trip(r)
    assert T0 + 0.5 <= t <= T0 + 1.2 and cause & (ALERT_ATTITUDE | ALERT_RATE | ALERT_ESTIMATE)
    s = r.series
    after = s["t"] >= t + 0.5
    w = np.linalg.norm(s["omega"], axis=1)
    assert w[after].max() <= 1.01 * w[after][0]  # motors off: the rotation no longer grows
    assert np.all(s["thrust"][-1] < 1e-6)
    assert s["pos_true"][-1, 2] == 0.0  # fell to the virtual ground and rests there
    assert np.all(s["pos_true"][-1] == s["pos_true"][-50])
    off = simulate("hover", duration=8.0, overrides={**_events("motor", [1], "dead"), "failsafe.enabled": False})
    assert _trip(off) is None  # without the failsafe it diverges silently
    assert np.all(off.series["thrust"][-1, 1:] > 1.0)  # the other motors keep running
    assert _roll_pitch_deg(off.series["euler_des"], off.series["euler_true"]).max() > 90.0


def test_dead_load_cell_is_rejected_and_its_thrust_held():
    r = simulate("hover", overrides=_events("load_cell", [2], "dead"))
    s = r.series
    m = s["t"] >= T0 + 0.05
    assert np.all(s["health"][m, 1].astype(int) & 0b10)  # cell 2 rejected by the guards throughout
    held = s["thrust_meas"][m, 1]
    assert held.max() - held.min() < 0.05  # frozen at its last accepted reading ...
    assert abs(held.mean() - s["thrust"][m, 1].mean()) < 0.3  # ... near the motor's mean thrust (chattering SMC)
    assert _trip(r) is None
    assert np.linalg.norm(s["pos"][-1] - s["pos_true"][-1]) < 15.0  # drift measured <= 6.2 m beyond fault-free


def test_spiking_load_cell_is_caught_by_the_jump_guard():
    """Spikes of 200 counts (~490 grF) on cell 3, no smoothing filter: the guard alone keeps them out."""
    ov = {**_events("load_cell", [3], "spike", 200.0), "estimation.load_cell_filter": "none"}
    unguarded = {"sensor_models.estimation": {"load_cell_filter": {"jump_threshold_grf": 1e4}}}

    def worst_error_ratio(result):
        s = result.series
        m = s["t"] >= T0
        e = np.abs(s["thrust_meas"][m] - s["thrust"][m]).max(axis=0)
        return e[2] / np.delete(e, 2).max()  # cell 3 against the worst healthy cell

    guarded = simulate("hover", overrides=ov)
    assert worst_error_ratio(guarded) < 1.2  # measured 0.65-0.95
    assert (guarded.series["health"][:, 1].astype(int) & 0b100).sum() > 20  # the guard rejected the spikes
    assert worst_error_ratio(simulate("hover", overrides={**ov, **unguarded})) > 3.0  # measured 5.6-6.9


def test_faults_from_config_are_deterministic():
    ov = {"faults.events": [{"t": 1.0, "sensor": "imu", "index": 4, "mode": "noise", "magnitude": 20.0},
                            {"t": 1.5, "sensor": "load_cell", "index": 1, "mode": "spike", "magnitude": 150.0},
                            {"t": 2.0, "sensor": "motor", "index": 3, "mode": "thrust_loss", "magnitude": 0.1}]}
    a = simulate("hover", duration=4.0, seed=3, overrides=ov)
    b = simulate("hover", duration=4.0, seed=3, overrides=ov)
    c = simulate("hover", duration=4.0, seed=3)
    assert np.array_equal(a.log, b.log, equal_nan=True)
    assert not np.array_equal(a.log, c.log, equal_nan=True)


@pytest.mark.parametrize("event, message", [
    ({"sensor": "imu", "index": 5, "mode": "dead"}, "IMU module 5: must be 0..4"),
    ({"sensor": "load_cell", "index": 0, "mode": "dead"}, "load cell 0: must be 1..4"),
    ({"sensor": "motor", "index": 1, "mode": "thrust_loss", "magnitude": 1.5}, "must be in [0, 1]"),
    ({"sensor": "imu", "index": 1, "mode": "spike", "magnitude": 10.0}, "does not apply to an IMU module"),
    ({"sensor": "motor", "index": 2, "mode": "noise", "magnitude": 1.0}, "does not apply to a motor"),
])
def test_bad_fault_events_are_config_errors(event, message):
    ev = {"t": 1.0, "magnitude": 0.0, **event}
    with pytest.raises(ConfigError, match=r"faults\.events\[0\]") as err:
        Simulation(load_config(overrides={"faults.events": [ev]}))
    assert message in str(err.value)


def test_sensor_faults_need_the_sensor_models():
    with pytest.raises(ConfigError, match="sensor models are off"):
        Simulation(load_config(overrides={"sensors.simulate": False, "faults.events": [
            {"t": 1.0, "sensor": "imu", "index": 1, "mode": "dead", "magnitude": 0.0}]}))
