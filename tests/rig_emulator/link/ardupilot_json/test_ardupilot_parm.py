"""The ArduCopter parameter file shipped for the rig (``rig_emulator/link/ardupilot_json/hilms.parm``):
read as ArduPilot reads a defaults file, its motor values fitted to the default plant's motors with
the rig's own motor function, and tabulated in the docs with the same values. What the values do in
flight was measured against a real ArduCopter SITL (docs/how-to/flight-stacks.md); nothing here
needs ArduPilot."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from rig_emulator.config.loader import load_config
from rig_emulator.link.ardupilot_json.motor_map import PWM_MAX_US, PWM_MIN_US
from rig_emulator.link.ardupilot_json.serve_ardupilot import PARAM_FILE
from rig_emulator.physics.hardware import motor_thrust
from rig_emulator.simulation.params import physics_params, supply_voltage

DOCS = Path(__file__).resolve().parents[4] / "docs" / "how-to" / "flight-stacks.md"
TABLE_HEADING = "### ArduCopter parameters for the rig"
# ArduPilot's defaults files: NAME VALUE (separated by spaces, a tab or a comma), '#' comments;
# names upper case, at most 16 characters (AP_Param)
LINE = re.compile(r"([A-Z][A-Z0-9_]{0,15})[ \t,]+(-?[0-9]+(?:\.[0-9]+)?)")
# AP_MotorsMulticopter.h: the hover thrust ArduCopter uses and learns is kept within these
THST_HOVER_MIN, THST_HOVER_MAX = 0.125, 0.6875
GEOMETRY = re.compile(r"FRAME_CLASS|FRAME_TYPE|SERVO[0-9]+_FUNCTION")  # test_json_cli.py checks these


def read_parm(path: str = PARAM_FILE) -> dict[str, float]:
    params: dict[str, float] = {}
    with open(path) as f:
        for n, raw in enumerate(f, start=1):
            line = raw.strip()
            if not line or line.startswith("#"):
                continue
            m = LINE.fullmatch(line)
            assert m, f"{path}:{n}: not an ArduPilot 'NAME VALUE' line: {line!r}"
            assert m[1] not in params, f"{path}:{n}: {m[1]} set twice"
            params[m[1]] = float(m[2])
    return params


def docs_table() -> dict[str, float]:
    """name -> value from the docs' table of the rig's ArduCopter parameters."""
    text = DOCS.read_text()
    section = text[text.index(TABLE_HEADING):]
    end = section.find("\n#", len(TABLE_HEADING))
    section = section if end < 0 else section[:end]
    rows = {}
    for line in section.splitlines():
        m = re.match(r"\| `([A-Z0-9_]+)` \| (-?[0-9.]+) \|", line)
        if m:
            assert m[1] not in rows, f"{m[1]} twice in the docs' table"
            rows[m[1]] = float(m[2])
    return rows


def hilms_motors(u: np.ndarray) -> tuple[np.ndarray, float]:
    """Thrust (N) of the default plant's motors 1..4 at commands ``u`` (rows), and the weight
    each carries at hover (N)."""
    cfg = load_config()
    assert cfg["airframe.name"] == "hilms"  # the default plant: its convex motors are what the values fit
    pp = physics_params(cfg)
    v_max = supply_voltage(cfg)
    thrust = np.array([[motor_thrust(ui * v_max, i, pp.k_v, pp.f_ceiling, 1.0, pp.hw) for ui in u]
                       for i in range(4)])
    return thrust, cfg["airframe.mass"] * cfg["airframe.gravity"] / 4.0


def test_every_tuned_parameter_is_in_the_docs_with_its_value():
    tuned = {k: v for k, v in read_parm().items() if not GEOMETRY.fullmatch(k)}
    table = docs_table()
    assert set(tuned) == set(table)
    for name, value in tuned.items():
        assert table[name] == value, name


def test_the_pwm_range_is_the_one_the_rig_reads():
    p = read_parm()
    assert (p["MOT_PWM_MIN"], p["MOT_PWM_MAX"]) == (PWM_MIN_US, PWM_MAX_US)


def test_the_thrust_curve_fits_the_default_plants_motors():
    """ArduCopter (AP_Motors_Thrust_Linearization) outputs u = SPIN_MIN + (SPIN_MAX - SPIN_MIN) r
    for a thrust (1 - e) r + e r^2 of the thrust at SPIN_MAX; the rig's motors (the hardware
    preset's curve, bias and gains, physics/hardware.py) follow it from where their thrust starts
    to full command."""
    p = read_parm()
    s_min, s_max, e = p["MOT_SPIN_MIN"], p["MOT_SPIN_MAX"], p["MOT_THST_EXPO"]
    u = np.linspace(0.0, 1.0, 1001)
    thrust, _ = hilms_motors(u)
    for i in range(4):
        # SPIN_MIN is where the thrust starts (within 0.01 of the command)
        assert thrust[i][u <= s_min - 0.01].max() == 0.0 and thrust[i][u >= s_min + 0.01].min() > 0.0
        # SPIN_MAX: the thrust still grows to full command (no flat top to leave out)
        assert s_max == 1.0 and np.all(np.diff(thrust[i][u >= s_min + 0.01]) > 0.0)
        flying = (u >= s_min) & (u <= s_max)
        r = (u[flying] - s_min) / (s_max - s_min)
        rel = thrust[i][flying] / np.interp(s_max, u, thrust[i])
        assert np.max(np.abs((1.0 - e) * r + e * r * r - rel)) < 0.005, f"motor {i + 1}"
        # ArduCopter's linear model over the whole output range does not fit
        assert np.max(np.abs(u[flying] - rel)) > 0.15


def test_the_hover_thrust_is_the_rigs_within_arducopters_range():
    p = read_parm()
    u = np.linspace(0.0, 1.0, 1001)
    thrust, weight = hilms_motors(u)
    share = np.mean([weight / np.interp(p["MOT_SPIN_MAX"], u, t) for t in thrust])
    assert share == pytest.approx(0.70, abs=0.01)  # the value the docs quote
    # the rig's hover share is above ArduCopter's cap: the file asks for the cap, no more
    assert THST_HOVER_MIN <= p["MOT_THST_HOVER"] <= THST_HOVER_MAX
    assert p["MOT_THST_HOVER"] == pytest.approx(min(share, THST_HOVER_MAX), abs=1e-9)


def test_no_battery_voltage_compensation():
    # the rig's motor supply does not sag: MOT_BAT_VOLT_MAX 0 switches the compensation off
    assert read_parm()["MOT_BAT_VOLT_MAX"] == 0.0


def test_the_yaw_acceleration_asked_is_a_fraction_of_the_rigs_yaw_authority():
    """The rig's only yaw torque is the rotors' reaction, kM/kF (f1 - f2 + f3 - f4)
    (physics/rigid_body.py): at hover two motors can rise to full thrust while the other two fall
    as much, so the collective holds. ArduCopter's yaw acceleration limit (cdeg/s^2) asks a
    quarter of that at most, leaving the rest to roll, pitch and altitude."""
    p = read_parm()
    cfg = load_config()
    u = np.linspace(0.0, 1.0, 1001)
    thrust, weight = hilms_motors(u)
    headroom = np.mean(thrust[:, -1]) - weight  # N a motor, on average
    yaw_acc_deg = np.degrees(cfg["airframe.km_over_kf"] * 4.0 * headroom / cfg["airframe.izz"])
    assert yaw_acc_deg == pytest.approx(74.0, abs=3.0)  # the value the docs quote
    assert 0.0 < p["ATC_ACCEL_Y_MAX"] / 100.0 <= 0.3 * yaw_acc_deg
    # ArduCopter's defaults, 270 deg/s^2 and 60 deg/s, are far beyond it
    assert 27000 / 100.0 > 3.0 * yaw_acc_deg
    assert 500 <= p["ATC_SLEW_YAW"] <= 6000 / 2  # a slower heading change; its range starts at 5 deg/s
