"""A controller's parameters read as plain attributes, and they follow every change."""

import copy
import pickle

import numpy as np
import pytest

from rig_emulator.controllers import Controller, ControllerParams, PluginError

DEFAULTS = {"kp": 2.0, "kd": [1.0, 1.0, 0.5], "set": 3.0}


def test_values_are_plain_attributes_not_looked_up_per_read():
    p = ControllerParams(DEFAULTS, {"kp": 4.0})
    assert type(vars(p)["kp"]) is float and p.kp == 4.0  # an instance attribute: no __getattr__ at each read
    assert isinstance(vars(p)["kd"], np.ndarray) and list(p.kd) == [1.0, 1.0, 0.5]
    with pytest.raises(ValueError):
        p.kd[0] = 9.0  # read-only view
    assert callable(p.set) and p.get("set") == 3.0  # a name of the class's own is read with get()


def test_values_follow_set_refresh_and_pickling():
    rng = np.random.default_rng()
    p = ControllerParams(DEFAULTS, owner="T", info={"kp": {"min": 0.0, "max": 10.0}})
    for _ in range(5):
        kp, kd = float(rng.uniform(0, 10)), rng.uniform(-5, 5, 3)
        p.set("kp", kp)
        p.set("kd", kd)
        assert p.kp == kp and np.array_equal(p.kd, kd) and p.array[0] == kp
    with pytest.raises(PluginError, match=r"controller.params.kp = 11.0: must be in \[0, 10\]"):
        p.set("kp", 11.0)
    assert p.kp == kp  # a refused value changes nothing
    p.array[:] = 7.0  # written in place (as a served rig does), then refreshed
    assert p.kp == kp and p.kd[0] == 7.0  # a vector is a view: it follows at once
    p.refresh()
    assert p.kp == 7.0
    for q in (pickle.loads(pickle.dumps(p)), copy.deepcopy(p)):
        q.set("kp", 1.5)
        q.set("kd", [3.0, 2.0, 1.0])
        assert q.kp == 1.5 and list(q.kd) == [3.0, 2.0, 1.0] and p.kp == 7.0
        assert np.shares_memory(vars(q)["kd"], q.array)


def test_a_served_parameter_change_reaches_the_running_controller():
    from rig_emulator.config.loader import load_config
    from rig_emulator.simulation.live import LiveRig

    class Gains(Controller):
        params = {"kz": 1.0, "k": [1.0, 2.0]}

        def update(self, t, obs):
            return (obs.mass * obs.gravity, 0.0, 0.0, 0.0)

    value = float(np.random.default_rng().uniform(2.0, 3.0))
    rig = LiveRig(load_config(scenario="hover"), controller=Gains())
    rig.set_params({"controller.params": {"kz": value, "k": [value, -value]}})
    assert rig.controller.params.kz == value and list(rig.controller.params.k) == [value, -value]


def test_cffi_and_ctypes_callbacks_fly_alike(monkeypatch):
    from rig_emulator.api import simulate
    from rig_emulator.controllers import runtime

    spec = "rig_emulator.controllers.examples.cascaded_pid:CascadedPID"
    seed = int(np.random.default_rng().integers(0, 1000))
    runs = []
    for how in ("cffi", "ctypes"):
        monkeypatch.setenv("HILMS_PLUGIN_CALLBACK", how)
        if how == "cffi" and runtime._FFI is None:
            pytest.skip("cffi is not installed")
        runs.append(simulate("helix", duration=1.0, seed=seed, controller=spec).series)
    for key in runs[0]:
        assert np.array_equal(runs[0][key], runs[1][key], equal_nan=True), key
