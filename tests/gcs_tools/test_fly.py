"""gcs_tools.fly against a live rig (the default `hilms` plant) over loopback TCP: what the
ground-driven flight does when the vehicle leaves OFFBOARD."""

import pytest

import gcs_tools.fly as fly_module
from gcs_tools.api import RigSession
from gcs_tools.errors import OperationError
from gcs_tools.missions import rectangle_points
from protocol.dialect import mavlink as M


def test_fly_switches_back_to_offboard_after_its_own_stream_paused(monkeypatch):
    """The tool's set-point stream stops mid-flight until the rig's offboard-loss failsafe
    (COM_OF_LOSS_T) takes over: the tool is told, switches back to OFFBOARD, and every
    waypoint is still reached."""
    sent, tripped = [0], [False]
    send = fly_module.send_target

    def paused_stream(link, t_ms, enu):
        in_offboard = fly_module.vehicle_mode(link)[0] == fly_module.PX4_OFFBOARD
        sent[0] += in_offboard
        if sent[0] >= 100 and not tripped[0]:  # 5 s of rig time into the flight
            if in_offboard:
                return
            tripped[0] = True
        send(link, t_ms, enu)

    monkeypatch.setattr(fly_module, "send_target", paused_stream)
    notices = []
    with RigSession(speedup=20) as rig:
        reached = fly_module.fly(rig.link, rectangle_points(2, 1, 1), 0.08, notice=notices.append, timeout_s=240)
    assert [r.index for r in reached] == [0, 1, 2, 3, 4]
    assert len(notices) == 1 and fly_module.OFFBOARD_LOSS_TEXT in notices[0], (notices, sent, reached)


def test_fly_stops_at_once_when_the_fence_takes_over():
    """A fence hold is the vehicle's decision: the tool does not fight it, it stops with the
    mode and the rig's reason instead of streaming on until its timeout."""
    with RigSession(speedup=20, rig_args=["--set", "fence.radius=3"]) as rig:
        with pytest.raises(OperationError) as exc:
            fly_module.fly(rig.link, rectangle_points(5, 3, 1.5), 0.08, timeout_s=240)
    text = str(exc.value)
    assert "left OFFBOARD" in text and "fence breach" in text and "timeout" not in text, text


def test_fly_stops_at_once_when_the_vehicle_disarms_in_flight(monkeypatch):
    """Motors off mid-flight (here another command disarms the rig): the tool says so at
    once, instead of streaming set-points to a vehicle on the ground until its timeout."""
    sent = [0]
    send = fly_module.send_target

    def disarm_mid_flight(link, t_ms, enu):
        sent[0] += fly_module.vehicle_mode(link)[0] == fly_module.PX4_OFFBOARD
        if sent[0] == 100:  # 5 s of rig time into the flight
            link.mav.command_long_send(link.target_system, link.target_component,
                                       M.MAV_CMD_COMPONENT_ARM_DISARM, 0, 0.0, 0.0, 0, 0, 0, 0, 0)
        send(link, t_ms, enu)

    monkeypatch.setattr(fly_module, "send_target", disarm_mid_flight)
    with RigSession(speedup=20) as rig:
        with pytest.raises(OperationError) as exc:
            fly_module.fly(rig.link, rectangle_points(5, 3, 2), 0.08, timeout_s=240)
    assert "disarmed at waypoint" in str(exc.value) and "timeout" not in str(exc.value), exc.value
