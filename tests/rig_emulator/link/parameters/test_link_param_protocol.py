"""The parameter microservice over a socket, and a parameter change that changes the flight."""

import time

import numpy as np

from protocol.dialect import mavlink as M
from rig_emulator.config.schema import STRATEGIES
from rig_emulator.link.parameters.table import ParamTable
from rig_emulator.testing.rig import RigThread, all_params, command, connect, recv, stamp_s, start_offboard


def test_list_is_complete_and_consistent(client):
    got = all_params(client)
    n = len(ParamTable())
    assert sorted(got) == list(range(n))
    assert {m.param_count for m in got.values()} == {n}
    assert {m.param_type for m in got.values()} == {M.MAV_PARAM_TYPE_REAL32}
    names = [m.param_id for m in got.values()]
    assert len(set(names)) == n and max(len(x) for x in names) <= 16


def test_read_by_name_and_index(client):
    client.mav.param_request_read_send(1, 1, b"WP_RADIUS", -1)
    m = recv(client, "PARAM_VALUE")
    assert m.param_id == "WP_RADIUS" and abs(m.param_value - 0.08) < 1e-6
    client.mav.param_request_read_send(1, 1, b"", m.param_index)
    assert recv(client, "PARAM_VALUE").param_id == "WP_RADIUS"
    client.mav.param_request_read_send(1, 1, b"NO_SUCH_PARAM", -1)
    assert "NO_SUCH_PARAM" in recv(client, "STATUSTEXT").text


def test_set_accepted_and_rejected(rig, client):
    client.mav.param_set_send(1, 1, b"SMC_K_PHI", 2.5, M.MAV_PARAM_TYPE_REAL32)
    m = recv(client, "PARAM_VALUE")
    assert m.param_id == "SMC_K_PHI" and m.param_value == 2.5
    assert rig.server.rig.cfg["smc.k"][0] == 2.5
    client.mav.param_set_send(1, 1, b"SMC_K_PHI", -1.0, M.MAV_PARAM_TYPE_REAL32)  # below the schema range
    m = recv(client, "PARAM_VALUE")
    assert m.param_id == "SMC_K_PHI" and m.param_value == 2.5  # unchanged value echoed
    assert "SMC_K_PHI rejected" in recv(client, "STATUSTEXT").text
    client.mav.param_set_send(1, 1, b"SIM_PHYS_HZ", 2000.0, M.MAV_PARAM_TYPE_REAL32)  # restart-only
    assert recv(client, "PARAM_VALUE").param_value == 1000.0
    client.mav.param_set_send(1, 1, b"CTL_STRATEGY", float("nan"), M.MAV_PARAM_TYPE_REAL32)
    assert recv(client, "PARAM_VALUE").param_value == 0.0
    assert rig.server.params.rejected == 3
    client.mav.param_set_send(1, 1, b"CTL_STRATEGY", 3.0, M.MAV_PARAM_TYPE_REAL32)
    assert recv(client, "PARAM_VALUE").param_value == 3.0
    state = recv(client, "HILMS_CONTROLLER_STATE", condition=lambda m: m.strategy == 3)
    assert state is not None and rig.server.rig.cfg["control.strategy"] == STRATEGIES[3]


def _fly_north(strategy_index: float | None) -> list[tuple[float, float]]:
    """Arm, ask for 1 m north at 1 m up, and record (t, north) for 4 simulated seconds. In the air: on
    the hardware rig a vehicle standing on the virtual ground keeps its place until its thrust lifts it
    (sim.ground_contact), so a target on the ground would measure when it took off, not the strategy."""
    # one set-point, not a stream: a set-point timeout longer than the flight (PX4's 1 s default would hold)
    with RigThread(speedup=4.0, overrides={"offboard.loss_timeout": 30.0}) as rig:
        c = connect(rig.tcp_url)
        if strategy_index is not None:
            c.mav.param_set_send(1, 1, b"CTL_STRATEGY", strategy_index, M.MAV_PARAM_TYPE_REAL32)
            assert recv(c, "PARAM_VALUE").param_value == strategy_index
        assert command(c, M.MAV_CMD_COMPONENT_ARM_DISARM, 1).result == M.MAV_RESULT_ACCEPTED
        assert start_offboard(c, lambda: c.mav.set_position_target_local_ned_send(
            0, 1, 1, M.MAV_FRAME_LOCAL_NED, 0b0000_1101_1111_1000, 1.0, 0.0, -1.0, 0, 0, 0, 0, 0, 0, 0, 0)).result == 0
        # one read loop for everything: waiting for one type would throw the other streams' messages away
        t0, mode, track = None, None, []
        deadline = time.monotonic() + 60
        while (not track or track[-1][0] < 4.0) and time.monotonic() < deadline:
            m = c.recv_match(blocking=True, timeout=0.2)
            kind = m.get_type() if m is not None else None
            if kind == "POSITION_TARGET_LOCAL_NED" and t0 is None and abs(m.x - 1.0) < 1e-6:
                t0 = stamp_s(m)
            elif kind == "HEARTBEAT" and m.get_srcComponent() == 1:
                mode = m.custom_mode
            elif kind == "LOCAL_POSITION_NED" and t0 is not None:
                track.append((stamp_s(m) - t0, m.x))
        c.close()
        assert t0 is not None and mode == 6 << 16, (t0, mode)  # the target taken, flown in OFFBOARD
        return track


def test_strategy_change_changes_the_flight():
    smc_flc = _fly_north(None)
    pid = _fly_north(3.0)
    assert max(x for track in (smc_flc, pid) for _, x in track) > 0.3  # the rig flies towards the target
    # the tracks compared on a 0.1 s grid over the whole flight: when in rig time the set-point lands
    # moves one strategy's track by up to 0.03 m (SMC-FLC against itself) and 0.1 m (PID), while
    # SMC-FLC and PID part by 0.12-0.23 m
    for track in (smc_flc, pid):
        assert track[0][0] < 0.5 and max(b[0] - a[0] for a, b in zip(track, track[1:])) < 0.2, "gaps in the track"
    grid = np.linspace(0.5, 4.0, 36)
    north = [np.interp(grid, [t for t, _ in track], [x for _, x in track]) for track in (smc_flc, pid)]
    assert np.abs(north[0] - north[1]).max() > 0.06, np.abs(north[0] - north[1]).max()
