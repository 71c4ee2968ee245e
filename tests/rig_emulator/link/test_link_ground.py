"""The default rig (``hilms``, the hardware rig) served over a real socket, flown from its tilted hang:
armed on the ground it stands still (onboard position and SIM_STATE); a mission take-off from the hang
keeps the virtual vehicle at home; the onboard position / SIM_STATE divergence report fires once above
EST_DIV_WARN and not below; MPC_THR_HOVER is served, learnt in the hover, and read-only."""

import math

import numpy as np
import pytest

from protocol.dialect import mavlink as M
from protocol.geodesy import global_to_local_ned
from protocol.mission_items import MissionItem
from rig_emulator.testing.rig import MissionClient, RigThread, command, connect, recv, stamp_s

ENU = M.MAV_FRAME_LOCAL_ENU
DIVERGENCE_TEXT = "onboard position and SIM_STATE"


class Flight:
    """Positions in NED from the rig's messages, against its simulated clock: LOCAL_POSITION_NED (the
    onboard position) and SIM_STATE (the physics vehicle, converted from its latitude and longitude)."""

    def __init__(self, rig, conn):
        self.rig, self.conn = rig, conn
        self.home = rig.server.ctx.home
        self.t = math.nan
        self.onboard = []  # (t, n, e, d)
        self.sim_state = []
        self.texts = []

    def fly(self, sim_seconds: float) -> None:
        """Record until the rig's clock has run ``sim_seconds`` further."""
        t_end = None
        n = 0
        while True:
            m = recv(self.conn, ["LOCAL_POSITION_NED", "SIM_STATE", "STATUSTEXT"], 30.0)
            assert m is not None, "the rig stopped streaming"
            n += 1
            if n % 200 == 0:  # a ground station's 1 Hz HEARTBEAT, roughly
                self.conn.mav.heartbeat_send(M.MAV_TYPE_GCS, M.MAV_AUTOPILOT_INVALID, 0, 0, 0)
            kind = m.get_type()
            if kind == "STATUSTEXT":
                self.texts.append((self.t, m.text))
            elif kind == "LOCAL_POSITION_NED":
                self.t = stamp_s(m)
                t_end = self.t + sim_seconds if t_end is None else t_end
                self.onboard.append((self.t, m.x, m.y, m.z))
                if self.t >= t_end:
                    return
            elif math.isfinite(self.t):  # SIM_STATE has no time stamp: the last LOCAL_POSITION_NED's
                self.sim_state.append((self.t, *global_to_local_ned(self.home, m.lat_int * 1e-7, m.lon_int * 1e-7,
                                                                    m.alt)))

    def since(self, which, t0: float) -> np.ndarray:
        a = np.array(getattr(self, which))
        return a[a[:, 0] >= t0]

    def param_set(self, name: str, value: float):
        self.conn.mav.param_set_send(1, 1, name.encode(), value, M.MAV_PARAM_TYPE_REAL32)
        return recv(self.conn, "PARAM_VALUE", 30.0, lambda m: m.param_id == name)


def _horizontal(a: np.ndarray) -> np.ndarray:
    return np.hypot(a[:, 1], a[:, 2])


@pytest.fixture(scope="module")
def flight():
    with RigThread(speedup=0.0, airframe="hilms") as rig:  # the default plant, hanging tilted at power-on
        conn = connect(rig.tcp_url)
        conn.mav.heartbeat_send(M.MAV_TYPE_GCS, M.MAV_AUTOPILOT_INVALID, 0, 0, 0)
        assert recv(conn, "HEARTBEAT", 60) is not None
        yield Flight(rig, conn)
        conn.close()


def test_arming_from_the_hang_the_vehicle_stands_still_then_takes_off_from_home(flight):
    assert flight.param_set("EST_DIV_WARN", 1000.0).param_value == 1000.0  # no divergence report here
    att = recv(flight.conn, "ATTITUDE", 30)
    assert math.degrees(abs(att.roll)) > 8.0 and math.degrees(abs(att.pitch)) > 8.0  # the hang
    flight.fly(0.5)  # the rig's clock
    # armed in the default mode, holding the initial position on the ground: the controllers level
    # the rig and run the motors near hover thrust; neither vehicle moves along the ground
    assert command(flight.conn, M.MAV_CMD_COMPONENT_ARM_DISARM, 1).result == M.MAV_RESULT_ACCEPTED
    t_arm = flight.t
    flight.fly(6.0)
    for which in ("onboard", "sim_state"):
        a = flight.since(which, t_arm)
        assert np.max(_horizontal(a)) < 0.05, (which, np.max(_horizontal(a)))
    # a mission take-off from there: the virtual vehicle climbs at home
    items = [MissionItem(seq=0, frame=ENU, command=M.MAV_CMD_NAV_TAKEOFF, current=1, z=2.5),
             MissionItem(seq=1, frame=ENU, command=M.MAV_CMD_NAV_WAYPOINT, x=0.0, y=0.0, z=2.5, param1=30.0)]
    assert MissionClient(flight.conn).upload(items) == M.MAV_MISSION_ACCEPTED
    assert command(flight.conn, M.MAV_CMD_DO_SET_MODE, M.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, 4, 4).result == \
        M.MAV_RESULT_ACCEPTED
    t_takeoff = flight.t
    flight.fly(10.0)
    onboard = flight.since("onboard", t_takeoff)
    assert onboard[-1, 3] < -2.0  # up
    assert np.max(_horizontal(onboard)) < 0.3, np.max(_horizontal(onboard))
    assert not any(DIVERGENCE_TEXT in text for _, text in flight.texts)


def test_the_divergence_report_fires_once_above_the_threshold(flight):
    onboard, sim = flight.onboard[-1], flight.sim_state[-1]
    apart = math.dist(onboard[1:], sim[1:])
    # the two vehicles parted in the take-off (the report was held off by EST_DIV_WARN): by 0.09-0.4 m,
    # depending on when in the rig's time the mission started; they part further as the hover goes on
    assert apart > 0.05
    t_set = flight.t
    assert flight.param_set("EST_DIV_WARN", 0.5 * apart).param_value == pytest.approx(0.5 * apart, rel=1e-6)
    flight.fly(5.0)
    said = [text for t, text in flight.texts if t >= t_set and DIVERGENCE_TEXT in text]
    assert len(said) == 1, flight.texts


def test_mpc_thr_hover_is_learnt_in_the_hover_and_read_only(flight):
    """PX4's hover throttle: after the hover above, what the position controller commanded on average
    (hilms: near 0.816, above the 0.781 that m g / u1_max gives: the hardware rig's thrust chain)."""
    flight.conn.mav.param_request_read_send(1, 1, b"MPC_THR_HOVER", -1)
    m = recv(flight.conn, "PARAM_VALUE", 30.0, lambda m: m.param_id == "MPC_THR_HOVER")
    assert 0.79 < m.param_value < 0.85
    refused = flight.param_set("MPC_THR_HOVER", 0.5)
    assert refused.param_value == pytest.approx(m.param_value, abs=0.01)
    assert recv(flight.conn, "STATUSTEXT", 30.0, lambda t: "MPC_THR_HOVER" in t.text and "read-only" in t.text)
