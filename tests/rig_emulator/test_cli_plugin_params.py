"""A controller plug-in's own parameters from the command line: `rig-emulator params`
lists them, `--set controller.params.NAME=VALUE` sets them for simulate and serve (and the same
dotted key in the Python API and SimJob), checked against the plug-in's declaration."""

import json
import subprocess
import sys

import numpy as np
import pytest

from protocol.dialect import mavlink as M
from rig_emulator.api import simulate
from rig_emulator.config.loader import ConfigError, load_config
from rig_emulator.controllers import PluginError
from rig_emulator.controllers.examples.hover import LevelHover
from rig_emulator.sweep import SimJob
from rig_emulator.testing.rig import RigProcess, connect, recv

HOVER = "rig_emulator.controllers.examples.hover:LevelHover"
LQR = "rig_emulator.controllers.examples.lqr:LQRAttitude"
PID = "rig_emulator.controllers.examples.pid:PID"


def _run(*args):
    return subprocess.run([sys.executable, "-m", "rig_emulator", *args], capture_output=True, text=True, timeout=300)


def _listing(stdout: str) -> dict:
    """``key -> (first line, doc line)`` of a `rig-emulator params` listing."""
    lines = stdout.splitlines()
    return {line.split(" = ")[0]: (line, lines[i + 1].strip() if i + 1 < len(lines) else "")
            for i, line in enumerate(lines) if " = " in line and not line.startswith(" ")}


def test_params_lists_the_plugins_parameters_with_range_and_default():
    p = _run("params", "--controller", HOVER, "--set", "controller.params.kp_z=2.5")
    assert p.returncode == 0, p.stderr
    got = _listing(p.stdout)
    assert got["controller.params.kp_z"] == ("controller.params.kp_z = 2.5 [1/s^2]  (in [0, 50]; default 4.0)",
                                             "altitude stiffness; served as HOV_KP_Z")
    assert got["controller.params.kd_att"][0] == "controller.params.kd_att = 2.0 [N s/rad]  (in [0, 20]; default 2.0)"
    keys = list(got)  # next to the rig's own controller.params, in the rig's format
    assert keys.index("controller.params") + 1 == keys.index("controller.params.kp_att")
    assert "smc.k = [1.47, 1.47, 1.42]" in p.stdout


def test_params_of_the_configs_plugin_and_a_vector_parameter():
    p = _run("params", "--set", f"controller.plugin={LQR}")
    assert p.returncode == 0, p.stderr
    got = _listing(p.stdout)
    line, doc = got["controller.params.k"]
    assert "(9 finite numbers; default [" in line and doc.endswith("served as LQR_K1..LQR_K9")
    assert got["controller.params.i_limit"][1].endswith("served as LQR_I_LIMIT")
    assert not any(k.startswith("controller.params.") for k in _listing(_run("params").stdout))  # no plug-in: none


def test_params_with_a_plugin_that_cannot_load_exits_2():
    p = _run("params", "--controller", "no_such_module:X")
    assert p.returncode == 2 and "controller no_such_module:X: cannot import 'no_such_module'" in p.stderr


def test_simulate_sets_a_plugin_parameter_from_the_command_line():
    base = ["simulate", "--scenario", "hover", "--duration", "3", "--json", "--controller", HOVER]
    default, soft = _run(*base), _run(*base, "--set", "controller.params.kp_z=0.5", "--set", "controller.params.kd_z=0.5")
    assert default.returncode == 0 and soft.returncode == 0, (default.stderr, soft.stderr)
    z_default, z_soft = (json.loads(p.stdout)["mean_errors"]["z_m"] for p in (default, soft))
    assert z_soft != z_default  # the value reached the controller
    explicit = _run(*base, "--set", "controller.params.kp_z=4.0")
    assert json.loads(explicit.stdout)["mean_errors"] == json.loads(default.stdout)["mean_errors"]


@pytest.mark.parametrize("setting, message", [
    ("controller.params.kp_z=80", "controller.params.kp_z = 80.0: must be in [0, 50] 1/s^2"),
    ("controller.params.kp_z=-1.5", "controller.params.kp_z = -1.5: must be in [0, 50] 1/s^2"),
    ("controller.params.kp_z=nan", "controller.params.kp_z = nan: must be finite"),
    ("controller.params.kp_z=[1, 2]", "controller.params.kp_z = [1.0, 2.0]: must be a number in [0, 50] 1/s^2"),
    ("controller.params.kp_q=1", "unknown parameter 'controller.params.kp_q' (did you mean 'controller.params.kp_z'?)"
                                 "; its parameters: kp_att, kd_att, kp_z, kd_z"),
    ("controller.params.kp.z=1", "unknown parameter 'controller.params.kp.z'"),
])
def test_simulate_refuses_bad_plugin_parameters_naming_key_and_range(setting, message):
    p = _run("simulate", "--scenario", "hover", "--duration", "1", "--controller", HOVER, "--set", setting)
    assert p.returncode == 2 and message in p.stderr, p.stderr
    assert "compiling" not in p.stderr and "Traceback" not in p.stderr


def test_api_and_simjob_take_the_dotted_key():
    kw = dict(duration=0.5, controller=HOVER, sensors__calibration="none")
    dotted = simulate("hover", overrides={"controller.params.kp_z": 2.5}, **kw)
    table = simulate("hover", overrides={"controller.params": {"kp_z": 2.5}}, **kw)
    assert np.array_equal(dotted.log, table.log, equal_nan=True)
    with pytest.raises(PluginError, match=r"controller.params.kp_z = 99.0: must be in \[0, 50\]"):
        simulate("hover", overrides={"controller.params.kp_z": 99.0}, **kw)
    job = SimJob("hover", controller=HOVER, overrides={"controller.params.kp_z": 2.5, "controller.params.kd_z": 1.0})
    job.check()
    assert job.config()["controller.params"] == {"kp_z": 2.5, "kd_z": 1.0}


def test_dotted_keys_go_over_the_table_of_a_file(tmp_path):
    f = tmp_path / "my.toml"
    f.write_text('[controller]\nplugin = "%s"\n[controller.params]\nkp_z = 3.0\nkd_z = 2.0\n' % HOVER)
    cfg = load_config(scenario="hover", files=[f], overrides={"controller.params.kp_z": 1.0})
    assert cfg["controller.params"] == {"kp_z": 1.0, "kd_z": 2.0}
    assert cfg.with_overrides({"controller.params.kd_att": 1.5})["controller.params"] == {
        "kp_z": 1.0, "kd_z": 2.0, "kd_att": 1.5}
    with pytest.raises(ConfigError, match="controller.params.kp_z = 'x': must be a number"):
        load_config(scenario="hover", overrides={"controller.params.kp_z": "x"})


def test_live_rig_set_params_takes_the_dotted_key():
    from rig_emulator.simulation.live import LiveRig

    rig = LiveRig(load_config(scenario="hover", overrides={"sensors.calibration": "none"}), chunk_steps_max=100,
                  controller=LevelHover())
    rig.set_params({"controller.params.kp_z": 2.5})
    assert rig.controller.params.kp_z == 2.5 and rig.cfg["controller.params"] == {"kp_z": 2.5}
    with pytest.raises(PluginError, match=r"controller.params.kp_z = 60.0: must be in \[0, 50\]"):
        rig.set_params({"controller.params.kp_z": 60.0})
    assert rig.controller.params.kp_z == 2.5


def test_serve_sets_a_plugin_parameter_from_the_command_line():
    with RigProcess(speedup=4.0, args=["--controller", HOVER, "--set", "controller.params.kp_z=2.5"]) as rig:
        conn = connect(rig.tcp_url)
        try:
            conn.mav.heartbeat_send(M.MAV_TYPE_GCS, M.MAV_AUTOPILOT_INVALID, 0, 0, 0)
            conn.mav.param_request_read_send(1, 1, b"HOV_KP_Z", -1)
            assert recv(conn, "PARAM_VALUE", 10.0, lambda m: m.param_id == "HOV_KP_Z").param_value == 2.5
        finally:
            conn.close()
    with pytest.raises(RuntimeError, match=r"exited with 2.*controller.params.kp_z = 80.0: must be in \[0, 50\]"):
        RigProcess(args=["--controller", HOVER, "--set", "controller.params.kp_z=80"])


def test_every_shipped_example_can_be_served():
    from rig_emulator.controllers import load_controller
    from rig_emulator.link.parameters.plugin_params import plugin_params

    for spec in (HOVER, LQR, PID):
        assert plugin_params(load_controller(spec), 0, set())  # names fit MAVLink's 16 characters


def test_plugin_parameters_without_a_plugin_are_refused():
    p = _run("simulate", "--scenario", "hover", "--duration", "1", "--set", "controller.params.kp_z=2")
    assert p.returncode == 2 and "controller.params.kp_z: no controller plug-in flies to take it" in p.stderr, p.stderr
    p = _run("serve", "--no-persist", "--mavlink", "tcpin:127.0.0.1:0", "--set", "controller.params.kp_z=2")
    assert p.returncode == 2 and "controller.params.kp_z: no controller plug-in flies to take it" in p.stderr, p.stderr
