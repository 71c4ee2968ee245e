"""Flight tasks on a headless LiveRig (no MAVLink): take-off, fly-to, return with landing and
disarm, a delay leg, the motor test and reboot."""

import math

import numpy as np
import pytest

from rig_emulator.config.loader import load_config
from rig_emulator.guidance.flight_tasks import FlightTasks
from rig_emulator.link.serve import prepare_rig
from rig_emulator.simulation.prearm import prearm_failure


@pytest.fixture(scope="module")
def rig():
    return prepare_rig(load_config(airframe="hilms-ideal"))  # the task logic, on the ideal plant


def _run(rig, tasks, seconds, until=None):
    events = []
    for _ in range(int(round(seconds / 0.01))):
        rig.step(10)
        snap = rig.snapshot()
        events += [(snap.time_s, e) for e in tasks.poll(snap)]
        if until is not None and any(e == until for _t, e in events):
            break
    return events


def test_takeoff_goto_return_and_land_disarm(rig):
    rig.reboot()
    tasks = FlightTasks(rig)
    assert prearm_failure(rig.snapshot(), rig.cfg) is None
    # a take-off commanded while disarmed starts on arming
    tasks.takeoff(1.5, armed=False)
    assert _run(rig, tasks, 0.5) == [] and rig.snapshot().position[2] < 0.05
    rig.arm(True)
    ev = _run(rig, tasks, 15.0, until="takeoff complete")
    assert [e for _t, e in ev] == ["takeoff started", "takeoff complete"]
    assert abs(rig.snapshot().position[2] - 1.5) < 0.15
    tasks.goto([1.0, -0.5, 1.5])
    ev = _run(rig, tasks, 15.0, until="arrived")
    assert ev and ev[-1][1] == "arrived"
    p = rig.snapshot().position
    assert math.hypot(p[0] - 1.0, p[1] + 0.5) < 0.15
    alt = tasks.return_home()
    assert alt == pytest.approx(rig.cfg["guidance.return_altitude"])
    ev = _run(rig, tasks, 40.0, until="landed")
    assert ev and ev[-1][1] == "landed"
    snap = rig.snapshot()
    assert not snap.armed
    assert math.hypot(snap.position[0], snap.position[1]) < 0.15 and snap.position[2] < 0.1


def test_land_here_after_a_delay_leg(rig):
    rig.reboot()
    tasks = FlightTasks(rig)
    rig.arm(True)
    tasks.takeoff(1.0)
    _run(rig, tasks, 15.0, until="takeoff complete")
    # free_xy 2 (NAV_DELAY): the leg holds where the rig is, height included
    z0 = rig.snapshot().position[2]
    rig.fly_path([[5.0, 5.0, 0.0]], free_xy=[2.0], holds=[1.0])
    for _ in range(100):
        rig.step(10)
    assert abs(rig.snapshot().position[2] - z0) < 0.15  # the hardware-faithful plant holds height less tightly
    tasks.land()
    ev = _run(rig, tasks, 20.0, until="landed")
    assert ev[-1][1] == "landed" and not rig.snapshot().armed


def test_motor_test_spins_one_motor_disarmed_then_stops(rig):
    rig.reboot()
    volts = rig.motor_test(3, 0.4, 0.5)
    assert volts == pytest.approx(0.4 * rig.cfg["motors.voltage_max"])
    rig.step(300)
    f = rig.snapshot().thrusts
    assert f[2] > 1.0 and max(f[0], f[1], f[3]) < 0.05
    rig.step(500)
    assert max(rig.snapshot().thrusts) < 0.05
    rig.arm(True)
    with pytest.raises(ValueError, match="disarmed"):
        rig.motor_test(1, 0.1, 1.0)


def test_reboot_restarts_time_and_keeps_parameters_and_mission(rig):
    rig.set_param("guidance.speed", 0.7)
    rig.set_mission([[0.0, 0.0, 1.0], [1.0, 0.0, 1.0]])
    rig.arm(True)
    rig.step(1000)
    rig.reboot()
    assert rig.time_s == 0.0 and not rig.armed
    assert rig.cfg["guidance.speed"] == 0.7
    rig.arm(True)
    rig.start_mission()
    rig.step(100)
    assert rig.mission_status().flying
    np.testing.assert_allclose(rig.snapshot().position, 0.0, atol=0.05)
