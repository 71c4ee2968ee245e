"""The ArduCopter parameter file shipped for the rig (``rig_emulator/link/ardupilot_json/hilms.parm``):
read as ArduPilot reads a defaults file, its values tabulated in the docs, and the thrust-model
figures the docs and the file give (ArduCopter's curve fitted to the default plant's motors, the
error of the straight line it flies with, the hover share, the yaw authority) recomputed from the
rig's own motor function. What the values do in flight was measured against a real ArduCopter
SITL (docs/how-to/flight-stacks.md); nothing here needs ArduPilot."""

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
from rig_emulator.testing.docs import table_rows

DOCS = Path(__file__).resolve().parents[4] / "docs" / "how-to" / "flight-stacks.md"
SHIPPED_HEADING = "### ArduCopter parameters for the rig"
FITTED_HEADING = "#### ArduCopter's thrust curve fitted to the rig"
# ArduPilot's defaults files: NAME VALUE (separated by spaces, a tab or a comma), '#' comments;
# names upper case, at most 16 characters (AP_Param)
LINE = re.compile(r"([A-Z][A-Z0-9_]{0,15})[ \t,]+(-?[0-9]+(?:\.[0-9]+)?)")
GEOMETRY = re.compile(r"FRAME_CLASS|FRAME_TYPE|SERVO[0-9]+_FUNCTION")  # test_json_cli.py checks these
# AP_MotorsMulticopter.h: the hover thrust ArduCopter uses and learns is kept within these;
# MOT_SPIN_MIN / MOT_SPIN_MAX as copter.parm leaves them (the file does not set them)
THST_HOVER_MIN, THST_HOVER_MAX = 0.125, 0.6875
SPIN_MIN_DEFAULT, SPIN_MAX_DEFAULT = 0.15, 0.95


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


def docs_table(heading: str) -> dict[str, float]:
    """name -> value from the table of ArduCopter parameters under ``heading`` in the docs."""
    return {name: float(v) for name, (v,) in
            table_rows(DOCS, heading, r"\| `([A-Z0-9_]+)` \| (-?[0-9.]+) \|").items()}


def hilms_motors(u: np.ndarray) -> tuple[np.ndarray, float]:
    """Thrust (N) of the default plant's motors 1..4 (rows) at commands ``u``, and the weight
    each carries at hover (N)."""
    cfg = load_config()
    assert cfg["airframe.name"] == "hilms"  # the default plant: its convex motors are what is fitted
    pp = physics_params(cfg)
    v_max = supply_voltage(cfg)
    thrust = np.array([[motor_thrust(ui * v_max, i, pp.k_v, pp.f_ceiling, 1.0, pp.hw) for ui in u]
                       for i in range(4)])
    return thrust, cfg["airframe.mass"] * cfg["airframe.gravity"] / 4.0


def model_error(u, thrust_row, spin_min, spin_max, expo) -> float:
    """Largest gap, in shares of the thrust at ``spin_max``, between ArduCopter's thrust model
    (AP_Motors_Thrust_Linearization: (1 - e) r + e r^2, r = (u - SPIN_MIN) / (SPIN_MAX -
    SPIN_MIN)) and a motor, from ``spin_min`` to ``spin_max``."""
    flying = (u >= spin_min) & (u <= spin_max)
    r = (u[flying] - spin_min) / (spin_max - spin_min)
    rel = thrust_row[flying] / np.interp(spin_max, u, thrust_row)
    return float(np.max(np.abs((1.0 - expo) * r + expo * r * r - rel)))


U = np.linspace(0.0, 1.0, 1001)


def test_every_tuned_parameter_is_in_the_docs_with_its_value():
    tuned = {k: v for k, v in read_parm().items() if not GEOMETRY.fullmatch(k)}
    table = docs_table(SHIPPED_HEADING)
    assert set(tuned) == set(table)
    for name, value in tuned.items():
        assert table[name] == value, name


def test_the_pwm_range_is_the_one_the_rig_reads():
    p = read_parm()
    assert (p["MOT_PWM_MIN"], p["MOT_PWM_MAX"]) == (PWM_MIN_US, PWM_MAX_US)


def test_the_fitted_thrust_curve_follows_the_default_plants_motors():
    """The docs' fitted values: SPIN_MIN where the thrust starts, SPIN_MAX at full command (the
    thrust grows to the end), the curve within 0.004 of full thrust in between, as quoted."""
    fit = docs_table(FITTED_HEADING)
    s_min, s_max, e = fit["MOT_SPIN_MIN"], fit["MOT_SPIN_MAX"], fit["MOT_THST_EXPO"]
    thrust, _ = hilms_motors(U)
    for i in range(4):
        assert thrust[i][U <= s_min - 0.01].max() == 0.0 and thrust[i][U >= s_min + 0.01].min() > 0.0
        assert s_max == 1.0 and np.all(np.diff(thrust[i][U >= s_min + 0.01]) > 0.0)
        assert model_error(U, thrust[i], s_min, s_max, e) < 0.0045, f"motor {i + 1}"
        # a straight line from u = 0 does not fit (the docs quote 0.24)
        assert model_error(U, thrust[i], 0.0, 1.0, 0.0) > 0.2


def test_the_straight_line_flown_is_off_by_what_the_docs_say():
    """The file keeps ArduCopter's straight line (MOT_THST_EXPO 0 over copter.parm's 0.15..0.95):
    off by up to 0.15 of full thrust, and about a quarter more thrust per unit of ArduCopter's
    thrust at hover than the fitted curve (9.7-10.1 N against 7.6-8.1 N), as quoted."""
    p = read_parm()
    assert p["MOT_THST_EXPO"] == 0.0 and "MOT_SPIN_MIN" not in p and "MOT_SPIN_MAX" not in p
    thrust, weight = hilms_motors(U)
    worst = max(model_error(U, t, SPIN_MIN_DEFAULT, SPIN_MAX_DEFAULT, 0.0) for t in thrust)
    assert worst == pytest.approx(0.15, abs=0.005)
    for t in thrust:
        u_hover = np.interp(weight, t, U)
        slope = np.interp(u_hover + 0.005, U, t) - np.interp(u_hover - 0.005, U, t)
        line_gain = (SPIN_MAX_DEFAULT - SPIN_MIN_DEFAULT) * slope / 0.01  # N per unit of thrust asked
        fitted_gain = t[-1]  # the fitted curve is exact: full thrust per unit
        assert 9.6 <= line_gain <= 10.2 and 7.5 <= fitted_gain <= 8.2
        assert line_gain / fitted_gain == pytest.approx(1.25, abs=0.04)


def test_the_hover_thrust_is_the_rigs_within_arducopters_range():
    p = read_parm()
    thrust, weight = hilms_motors(U)
    share = np.mean([weight / t[-1] for t in thrust])
    assert share == pytest.approx(0.70, abs=0.01)  # the value the docs quote
    # the rig's hover share is above ArduCopter's cap: the file asks for the cap, no more
    assert THST_HOVER_MIN <= p["MOT_THST_HOVER"] <= THST_HOVER_MAX
    assert p["MOT_THST_HOVER"] == pytest.approx(min(share, THST_HOVER_MAX), abs=1e-9)


def test_the_yaw_acceleration_asked_is_a_fraction_of_the_rigs_yaw_authority():
    """The rig's only yaw torque is the rotors' reaction, kM/kF (f1 - f2 + f3 - f4)
    (physics/rigid_body.py): at hover two motors can rise to full thrust while the other two fall
    as much, so the collective holds. ArduCopter's yaw acceleration limit (cdeg/s^2) asks a
    quarter of that at most, leaving the rest to roll, pitch and altitude."""
    p = read_parm()
    cfg = load_config()
    thrust, weight = hilms_motors(U)
    headroom = np.mean(thrust[:, -1]) - weight  # N a motor, on average
    yaw_acc_deg = np.degrees(cfg["airframe.km_over_kf"] * 4.0 * headroom / cfg["airframe.izz"])
    assert yaw_acc_deg == pytest.approx(74.0, abs=3.0)  # the value the docs quote
    assert 0.0 < p["ATC_ACCEL_Y_MAX"] / 100.0 <= 0.3 * yaw_acc_deg
    # ArduCopter's default, 270 deg/s^2, is far beyond it
    assert 27000 / 100.0 > 3.0 * yaw_acc_deg
    assert 500 <= p["ATC_SLEW_YAW"] <= 6000 / 2  # a slower heading change; its range starts at 5 deg/s
