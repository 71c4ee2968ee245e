"""A bad plug-in stops a headless run with a message naming the plug-in, the time and the problem."""

import math

import numba
import numpy as np
import pytest

from rig_emulator import cli
from rig_emulator.api import simulate
from rig_emulator.control import plugin_layout as L
from rig_emulator.controllers import CompiledController, Controller, PluginError, load_controller
from rig_emulator.controllers.examples.hover import LevelHover


class Hover(Controller):
    """u1 = m g, no torque: flies only a moment before the loss-of-control failsafe (enough for
    the failures at the first calls)."""

    def update(self, t, obs):
        return (obs.mass * obs.gravity, 0.0, 0.0, 0.0)


class RaisesAt3(LevelHover):  # holds the rig level until it fails
    def update(self, t, obs):
        if t >= 3.0:
            raise ZeroDivisionError("my gain schedule divided by zero")
        return super().update(t, obs)


class ThreeNumbers(Hover):
    def update(self, t, obs):
        return (1.0, 2.0, 3.0)


class NaNAt1(LevelHover):
    def update(self, t, obs):
        f = super().update(t, obs)
        return (math.nan if t >= 1.0 else f[0], f[1], f[2], f[3])


@numba.njit
def _failing_kernel(t, obs, params, state, out):
    out[L.C_CMD] = obs[L.O_MASS] * obs[L.O_G]
    for i in range(1, 4):
        out[L.C_CMD + i] = 0.0
    return 7 if t >= 0.5 else 0


class CompiledFails(CompiledController):
    kernel = _failing_kernel


def _fly(ctrl, duration=4.0):
    return simulate("hover", duration=duration, controller=ctrl, seed=1)


def test_exception_at_3s_names_plugin_time_and_problem():
    with pytest.raises(PluginError) as info:
        _fly(RaisesAt3)
    msg = str(info.value)
    assert "RaisesAt3" in msg and "t = 3.000 s" in msg
    assert "ZeroDivisionError: my gain schedule divided by zero" in msg and "test_plugin_errors.py" in msg
    assert info.value.time_s == pytest.approx(3.0)


def test_wrong_return_shape():
    with pytest.raises(PluginError, match=r"ThreeNumbers at t = 0\.000 s: ValueError: update\(\) must return 4 numbers"
                                          r".*, got 3 \(returned by ThreeNumbers\.update, .*test_plugin_errors\.py:\d+\)$"):
        _fly(ThreeNumbers, 0.5)


class Text(Hover):
    def update(self, t, obs):
        return ("a", "b", "c", "d")


def test_a_return_that_is_not_numbers_points_at_update_not_at_the_rig():
    with pytest.raises(PluginError) as info:
        _fly(Text, 0.5)
    msg = str(info.value)
    assert "Text at t = 0.000 s: ValueError" in msg and "returned by Text.update" in msg
    assert "runtime.py" not in msg


def test_nan_command():
    with pytest.raises(PluginError, match=r"NaNAt1 at t = 1\.000 s: returned a non-finite command \[nan, [0-9.]+, "
                                          r"[0-9.]+, [0-9.]+\] \(motor thrusts 1-4 \(N\)\)"):
        _fly(NaNAt1, 2.0)


def test_compiled_kernel_error_code():
    with pytest.raises(PluginError, match=r"CompiledFails at t = 0\.500 s: returned error code 7"):
        _fly(CompiledFails, 1.0)


def test_import_and_declaration_errors():
    with pytest.raises(PluginError, match=r"controller no_such_pkg\.mod:X: cannot import 'no_such_pkg\.mod'"):
        load_controller("no_such_pkg.mod:X")
    with pytest.raises(PluginError, match="must be written 'package.module:Name'"):
        load_controller("just_a_module")
    with pytest.raises(PluginError, match="has no 'Nope'"):
        load_controller("rig_emulator.controllers.examples.pid:Nope")
    with pytest.raises(PluginError, match="not a subclass"):
        load_controller("rig_emulator.controllers.base:PluginError")

    class Bad(Hover):
        commands = "attitude"

    with pytest.raises(PluginError, match="commands = 'attitude' does not go with replaces = 'both'"):
        _fly(Bad, 0.1)

    class OddRate(Hover):
        rate_hz = 300.0

    with pytest.raises(PluginError, match="rate_hz = 300: the physics rate .* whole multiple"):
        _fly(OddRate, 0.1)


def test_cli_exit_2_with_the_message(tmp_path, monkeypatch, capsys):
    (tmp_path / "my_bad_plugin.py").write_text(
        "from rig_emulator.controllers.examples.hover import LevelHover\n"
        "class Boom(LevelHover):\n"
        "    def update(self, t, obs):\n"
        "        if t >= 3.0:\n"
        "            raise RuntimeError('boom')\n"
        "        return super().update(t, obs)\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    code = cli.main(["simulate", "--scenario", "hover", "--duration", "4", "--seed", "1", "--controller",
                     "my_bad_plugin:Boom"])
    err = capsys.readouterr().err
    assert code == 2
    assert "controller my_bad_plugin:Boom at t = 3.000 s: RuntimeError: boom" in err
    code = cli.main(["simulate", "--scenario", "hover", "--duration", "1", "--controller", "my_missing_plugin:Boom"])
    assert code == 2 and "cannot import 'my_missing_plugin'" in capsys.readouterr().err


def test_failure_disarms_and_arming_clears_it():
    from rig_emulator.config.loader import load_config
    from rig_emulator.simulation.run import Simulation

    sim = Simulation(load_config(scenario="hover", overrides={"sim.duration": 4.0, "sim.seed": 1}), controller=NaNAt1)
    sim.advance(1500)
    assert not sim.armed and sim.plugin_failure is not None and sim.plugin_failure.time_s == pytest.approx(1.0)
    assert np.all(sim.v_cmd == 0.0)
    sim.armed = True
    assert sim.plugin_failure is None
