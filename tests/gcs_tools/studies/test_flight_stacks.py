"""The flight-stack studies (``px4-reposition``, ``ardupilot-move``): what they install and fly with,
the pages they write, and their refusals. The flights themselves need PX4 and ArduPilot builds made
outside the repository, so the suite checks everything around them; the rig's side of both protocols
is tested with the stand-ins (tests/rig_emulator/link/px4_simulator, .../ardupilot_json)."""

import pytest

from gcs_tools.studies import ardupilot_move as AP
from gcs_tools.studies import px4_reposition as PX4
from gcs_tools.studies.page import span
from gcs_tools.studies.sitl import tilt_deg, wrap
from rig_emulator.link.px4_simulator.serve_px4 import AIRFRAME_FILE


def table_rows(text: str) -> list[list[str]]:
    """The cells of every markdown table row of ``text`` but the separator."""
    return [[c.strip() for c in line.strip().strip("|").split("|")] for line in text.splitlines()
            if line.startswith("|") and not line.startswith("|---")]


def _params(text: str) -> dict[str, str]:
    out = {}
    for line in text.splitlines():
        f = line.split("#", 1)[0].split()
        if len(f) == 4 and f[:2] == ["param", "set-default"]:
            out[f[2]] = f[3]
        elif len(f) == 2 and f[0] != ".":
            out[f[0]] = f[1]
    return out


def test_the_geometry_airframe_is_the_shipped_geometry_on_px4_defaults():
    shipped = open(AIRFRAME_FILE).read()
    mine, theirs = _params(PX4.geometry_airframe(shipped)), _params(shipped)
    geometry = {k: v for k, v in theirs.items() if k.startswith(("CA_", "PWM_MAIN_FUNC"))}
    assert len(geometry) == 2 + 4 * 4 + 4
    assert mine == {**geometry, "THR_MDL_FAC": "0.0", "MPC_THR_HOVER": "0.78"}
    assert ". ${R}etc/init.d/rc.mc_defaults" in PX4.geometry_airframe(shipped)
    # the shipped airframe tunes more than that: the comparison has something to compare
    assert set(theirs) - set(geometry) >= {"THR_MDL_FAC", "MPC_THR_HOVER", "MPC_YAWRAUTO_MAX", "MPC_JERK_AUTO"}


def test_the_airframes_are_installed_where_px4_finds_them_by_name(tmp_path):
    folder = tmp_path / "etc" / "init.d-posix" / "airframes"
    with pytest.raises(SystemExit, match="--px4: .*airframes does not exist"):
        PX4.install_airframes(tmp_path)
    folder.mkdir(parents=True)
    PX4.install_airframes(tmp_path)
    assert sorted(p.name for p in folder.iterdir()) == sorted(f for f, _ in PX4.AIRFRAMES.values())
    assert (folder / "10090_none_hilms").read_text() == open(AIRFRAME_FILE).read()
    PX4.install_airframes(tmp_path, [{"MPC_JERK_AUTO": "1.5"}, {"MPC_YAWRAUTO_MAX": "45", "MPC_YAWRAUTO_ACC": "60"}])
    assert {"10092_none_hilmsv0", "10093_none_hilmsv1"} <= {p.name for p in folder.iterdir()}
    v1 = _params((folder / "10093_none_hilmsv1").read_text())
    assert v1 == {**_params(open(AIRFRAME_FILE).read()), "MPC_YAWRAUTO_MAX": "45", "MPC_YAWRAUTO_ACC": "60"}
    # PX4 keeps the last set-default of a name: the changed value comes after the shipped one
    text = (folder / "10092_none_hilmsv0").read_text()
    assert text.rindex("MPC_JERK_AUTO 1.5") > text.index("MPC_JERK_AUTO")
    for file, model in [*PX4.AIRFRAMES.values(), PX4.variant_names(0), PX4.variant_names(1)]:
        assert file.split("_", 1)[1] == model  # PX4_SIM_MODEL=MODEL finds NNNNN_MODEL


def test_a_variant_is_px4_parameters_and_numbers():
    assert PX4.parse_variant("mpc_jerk_auto=1.5, MPC_XY_VEL_MAX=3") == {"MPC_JERK_AUTO": "1.5", "MPC_XY_VEL_MAX": "3"}
    for bad in ("MPC_JERK_AUTO", "MPC_JERK_AUTO=fast", "=1", "A B=1"):
        with pytest.raises(ValueError, match="--variant"):
            PX4.parse_variant(bad)


def _session(alt, tilt, landed=True):
    rep = {"alt_dev_m": alt, "rig_alt_dev_m": alt * 2, "tilt_deg": tilt, "rig_tilt_deg": tilt + 0.1,
           "yaw_dev_deg": 97.0, "arrive_s": None, "end_err_m": 0.01}
    return {"hover_alt_m": (2.45, 2.49), "hover_tilt_deg": 1.04, "repositions": [rep, dict(rep, arrive_s=12.25)],
            "landed": landed}


def test_the_px4_table_gives_each_figure_as_its_range_over_sessions_and_repositions():
    rows = PX4.table({"`10091_none_hilmsgeom`": [_session(0.5, 19.0), _session(2.1, 17.3, landed=False)],
                      "`10090_none_hilms`": [_session(0.012, 7.0), _session(0.034, 6.6)]})
    cells = {r[0]: r[1:] for r in table_rows("\n".join(rows))}
    assert rows[0] == "| 5 m reposition | `10091_none_hilmsgeom` | `10090_none_hilms` |"
    assert cells["altitude deviation, PX4's estimate"] == ["0.500-2.100 m", "0.012-0.034 m"]
    assert cells["altitude deviation, the rig's SIM_STATE"] == ["1.000-4.200 m", "0.024-0.068 m"]
    assert cells["largest tilt, PX4's estimate"] == ["17.3-19.0 deg", "6.6-7.0 deg"]
    assert cells["time to within 0.3 m of the target"] == ["12.2 s", "12.2 s"]  # the None (never) is left out
    assert cells["sessions landed and disarmed"] == ["1 of 2", "2 of 2"]
    assert cells["hover before, PX4's estimate"] == ["2.45-2.49 m, tilt within 1.0 deg"] * 2


def test_ardupilot_variants_change_only_what_they_name():
    from rig_emulator.link.ardupilot_json import __file__ as package
    from pathlib import Path

    shipped = (Path(package).parent / "hilms.parm").read_text()
    base = _params(shipped)
    assert _params(AP.variant_parm(shipped, "shipped")) == base
    fitted = _params(AP.variant_parm(shipped, "fitted"))
    assert fitted == {**base, "MOT_SPIN_MIN": "0.19", "MOT_SPIN_MAX": "1", "MOT_THST_EXPO": "0.5",
                      "MOT_BAT_VOLT_MAX": "0"}
    assert set(base) - set(_params(AP.variant_parm(shipped, "yaw-default"))) == set(AP.YAW_LIMITS)
    assert set(base) - set(_params(AP.variant_parm(shipped, "move-default"))) == set(AP.MOVE_LIMITS)
    mine = _params(AP.variant_parm(shipped, "move-default", {"WPNAV_JERK": 2, "ATC_SLEW_YAW": 1000}))
    assert mine == {**{k: v for k, v in base.items() if k not in AP.MOVE_LIMITS}, "WPNAV_JERK": "2",
                    "ATC_SLEW_YAW": "1000"}
    # each value the study sets is the one the guide's table of the fitted curve gives
    guide = {r[0].strip("`"): r[1] for r in table_rows(open("docs/how-to/flight-stacks.md").read()) if len(r) > 1}
    for key in ("MOT_SPIN_MIN", "MOT_SPIN_MAX", "MOT_THST_EXPO"):
        assert float(guide[key]) == AP.FITTED[key]


def test_the_ardupilot_row_gives_ranges_and_the_landings():
    s = {"hover_alt_m": [1.995, 2.008], "hover_rig_alt_m": [1.991, 2.025], "hover_tilt_deg": 1.46,
         "hover_xy_span_m": 0.07, "move_alt_m": [1.98, 2.02], "move_alt_dev_m": 0.02, "move_rig_alt_dev_m": 0.03,
         "move_tilt_deg": 18.3, "move_rig_tilt_deg": 18.5, "arrive_s": 2.75, "overshoot_m": 0.35, "landed": True,
         **AP.lockstep(["rig-emulator: ArduPilot at udp:127.0.0.1:5501 stopped at t = 140.1 s after 140080 frames "
                        "(0 repeated, 0 missed); motors off", "rig-emulator: stopped at t = 140.1 s; received 1, "
                        "sent 2, dropped {}"])}
    row = AP.row("fitted", [s, dict(s, move_tilt_deg=18.7, hover_xy_span_m=0.12, arrive_s=None, landed=False)])
    cells = table_rows(row)[0]
    assert cells[0] == "`fitted`"
    assert cells[1:] == ["1.995-2.008 m (1.991-2.025 m)", "<= 1.5 deg, 0.07-0.12 m", "1.98-2.02 m (0.03 m)",
                         "18.3-18.7 deg (18.5 deg)", "2.75 s, 0.35 m", "1 of 2", "140080 (0, 0), {}"]
    assert len(cells) == 1 + len(AP.COLUMNS)


@pytest.mark.parametrize("module, argv, message", [
    (PX4, ["--px4", "{tmp}"], "--px4: .*bin/px4 does not exist"),
    (PX4, ["--px4", "{tmp}", "--airframes", "hilms,iris"], "--airframes: iris"),
    (PX4, ["--px4", "{tmp}", "--sessions", "0"], "--sessions: must be at least 1"),
    (PX4, ["--px4", "{tmp}", "--variant", "MPC_JERK_AUTO"], "--variant 'MPC_JERK_AUTO': must be NAME=NUMBER"),
    (AP, ["--ardupilot", "{tmp}"], "--ardupilot: .*arducopter does not exist"),
    (AP, ["--ardupilot", "{tmp}", "--variants", "fast"], "--variants: fast"),
    (AP, ["--ardupilot", "{tmp}", "--speedup", "0"], "--speedup: must be positive"),
    (AP, ["--ardupilot", "{tmp}", "--set", "WPNAV_ACCEL"], "--set 'WPNAV_ACCEL': must be NAME=NUMBER"),
])
def test_bad_arguments_are_refused_naming_the_option(module, argv, message, tmp_path, capsys):
    with pytest.raises(SystemExit) as exc:
        module.main([a.format(tmp=tmp_path) for a in argv])
    assert exc.value.code == 2
    import re

    assert re.search(message, capsys.readouterr().err), message


def test_each_variant_is_said_in_words():
    assert AP.describe("shipped") == "`hilms.parm` as shipped"
    assert AP.describe("move-default", {"WPNAV_JERK": 2.0}) == (
        "`hilms.parm` with `WPNAV_JERK 2`; without `WPNAV_ACCEL`, `WPNAV_SPEED` (ArduCopter's defaults)")
    assert AP.describe("fitted").startswith("`hilms.parm` with `MOT_SPIN_MIN 0.19`, `MOT_SPIN_MAX 1`")


def test_the_shared_figures():
    assert tilt_deg(0.0, 0.0) == 0.0
    assert abs(tilt_deg(0.1, 0.0) - 5.729578) < 1e-5
    assert abs(wrap(3.5) - (3.5 - 2 * 3.141592653589793)) < 1e-12
    assert span([0.0123, 0.0349], 3) == "0.012-0.035"
    assert span([7.01, 6.98], 1) == "7.0"
    assert span([-0.14, 2.02], 2) == "-0.14 to 2.02"
