"""The PX4 SITL airframe shipped for the rig (``rig_emulator/link/px4_simulator/10090_none_hilms``):
written as PX4's start-up script reads an airframe, its geometry the rig's, its tuning the one the
docs tabulate (each value inside the range given there), its thrust model fitted to the default
plant's motors. What the tuning does in flight was measured against a real PX4 SITL
(docs/how-to/flight-stacks.md); nothing here needs PX4."""

from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np
import pytest

from rig_emulator.config.loader import load_config
from rig_emulator.link.px4_simulator.serve_px4 import AIRFRAME_FILE
from rig_emulator.physics.hardware import motor_thrust
from rig_emulator.simulation.params import physics_params, supply_voltage
from rig_emulator.testing.docs import table_rows

DOCS = Path(__file__).resolve().parents[4] / "docs" / "how-to" / "flight-stacks.md"
TABLE_HEADING = "### PX4 parameters for the rig"
# the only lines PX4's rcS gets from the file besides comments: its multicopter defaults, then
# `param set-default NAME VALUE` (PX4 names: upper case, at most 16 characters)
MC_DEFAULTS = ". ${R}etc/init.d/rc.mc_defaults"
SET_DEFAULT = re.compile(r"param set-default ([A-Z][A-Z0-9_]{0,15}) (-?[0-9]+(?:\.[0-9]+)?)")
GEOMETRY = re.compile(r"CA_.*|PWM_MAIN_FUNC[0-9]+")


def read_airframe(path: str = AIRFRAME_FILE) -> dict[str, float]:
    with open(path) as f:
        lines = f.read().splitlines()
    assert lines[0] == "#!/bin/sh"
    params: dict[str, float] = {}
    for n, raw in enumerate(lines, start=1):
        line = raw.strip()
        if not line or line.startswith("#") or line == MC_DEFAULTS:
            continue
        m = SET_DEFAULT.fullmatch(line)
        assert m, f"{path}:{n}: not a PX4 'param set-default NAME VALUE' line: {line!r}"
        assert m[1] not in params, f"{path}:{n}: {m[1]} set twice"
        params[m[1]] = float(m[2])
    assert MC_DEFAULTS in lines  # PX4's multicopter defaults first, as its own SITL airframes
    return params


def docs_table() -> dict[str, tuple[float, float, float]]:
    """name -> (value, low, high) from the docs' table of the rig's PX4 parameters."""
    row = r"\| `([A-Z0-9_]+)` \| (-?[0-9.]+)[^|]* \| [^|]* \| (-?[0-9.]+)\.\.(-?[0-9.]+) \|"
    return {name: tuple(float(x) for x in groups) for name, groups in table_rows(DOCS, TABLE_HEADING, row).items()}


def test_px4_finds_the_airframe_by_its_file_name():
    # rcS runs airframes/<SYS_AUTOSTART>_* without a dot in the name; PX4_SIM_MODEL=none_hilms finds
    # it by the part after the number, and "none" is PX4's simulator_mavlink (the rig)
    name = os.path.basename(AIRFRAME_FILE)
    assert re.fullmatch(r"[0-9]+_none_hilms", name) and "." not in name
    assert read_airframe()


def test_the_geometry_is_the_rigs():
    """PX4's moment of rotor i per newton, CT (p x a) - CT KM a with a = (0, 0, -1), is the rig's:
    roll l (f4 - f2), pitch l (f1 - f3), yaw kM/kF (f1 - f2 + f3 - f4) (physics/rigid_body.py)."""
    p = read_airframe()
    cfg = load_config()
    arm, km = cfg["airframe.arm_length"], cfg["airframe.km_over_kf"]
    rig = {0: (0.0, arm, km), 1: (-arm, 0.0, -km), 2: (0.0, -arm, km), 3: (arm, 0.0, -km)}
    assert p["CA_AIRFRAME"] == 0 and p["CA_ROTOR_COUNT"] == 4
    for i, moment in rig.items():
        px, py, kmi = p[f"CA_ROTOR{i}_PX"], p[f"CA_ROTOR{i}_PY"], p[f"CA_ROTOR{i}_KM"]
        assert (-py, px, kmi) == pytest.approx(moment, abs=1e-9), f"rotor {i}"
        assert p[f"PWM_MAIN_FUNC{i + 1}"] == 101 + i  # output i+1 drives motor i+1


def test_every_tuned_parameter_is_in_the_docs_with_its_value_inside_the_range_given():
    tuned = {k: v for k, v in read_airframe().items() if not GEOMETRY.fullmatch(k)}
    table = docs_table()
    assert set(tuned) == set(table)
    for name, value in tuned.items():
        doc_value, low, high = table[name]
        assert value == doc_value, name
        assert low <= value <= high, f"{name} {value} outside {low}..{high}"


def test_the_thrust_model_fits_the_default_plants_motors():
    """THR_MDL_FAC f: PX4 takes the thrust as (1 - f) u + f u^2 of full thrust; the rig's motors
    (the hardware preset's curve, bias and gains, physics/hardware.py) follow it over the flying
    range, and MPC_THR_HOVER is their mean share of full thrust at hover."""
    p = read_airframe()
    cfg = load_config()
    assert cfg["airframe.name"] == "hilms"  # the default plant: its convex motors are what the factor fits
    pp = physics_params(cfg)
    v_max = supply_voltage(cfg)
    u = np.linspace(0.4, 1.0, 25)
    f = p["THR_MDL_FAC"]
    hover_share = []
    for i in range(4):
        thrust = np.array([motor_thrust(ui * v_max, i, pp.k_v, pp.f_ceiling, 1.0, pp.hw) for ui in u])
        rel = thrust / thrust[-1]
        assert np.max(np.abs((1.0 - f) * u + f * u * u - rel)) < 0.025, f"motor {i + 1}"
        assert np.max(np.abs(u - rel)) > 0.15  # the linear model PX4 assumes by default does not fit
        hover_share.append(cfg["airframe.mass"] * cfg["airframe.gravity"] / 4.0 / thrust[-1])
    assert p["MPC_THR_HOVER"] == pytest.approx(np.mean(hover_share), abs=0.02)
