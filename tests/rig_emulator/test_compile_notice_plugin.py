"""A plug-in's first run says what it compiles (the step loop on a new install, its kernel), once; the
loop is the one every controller flies, so a built-in run compiles it for the plug-ins too."""

import os
import subprocess
import sys

_CHILD = r"""
import numpy as np
from numba.core import types
import rig_emulator.compile_notice as cn
from rig_emulator.control import plugin_layout as L
from rig_emulator.control.plugin_step import PLUGIN_SIG
from rig_emulator.controllers.examples.pid import PID, pid_kernel

PID_SPEC = "rig_emulator.controllers.examples.pid:PID"
PY_SPEC = "rig_emulator.controllers.examples.hover:LevelHover"
print("empty:", cn.what_compiles(PID_SPEC))
print("python, empty:", cn.what_compiles(PY_SPEC, "python"))
plain = (types.float64,)
with_plugin = (types.float64, types.FunctionType(PLUGIN_SIG))
cn._loop_signatures = lambda: [plain]  # only the lockstep loop (no controller) in the cache
print("lockstep loop only:", cn.what_compiles(PID_SPEC))
print("built-in, lockstep loop only:", cn.what_compiles())
cn._loop_signatures = lambda: [plain, with_plugin]  # and the loop every controller flies
print("built-in:", cn.what_compiles())
print("plug-in path:", cn.what_compiles(PID_SPEC))
print("python:", cn.what_compiles(PY_SPEC, "python"))
print("kernel as python:", cn.what_compiles(PID_SPEC, "python"))
obs = np.zeros(L.OBS_SIZE); obs[L.O_DT] = 0.002; obs[L.O_MASS] = 2.0; obs[L.O_G] = 9.8; obs[L.O_MAX_TILT] = 0.5
pid_kernel(0.0, obs, PID().params.array, np.zeros(PID.state_size), np.zeros(L.OUT_SIZE))  # compiles the kernel
print("kernel compiled:", cn.what_compiles(PID_SPEC))
"""


def test_notice_names_what_compiles_once_per_plugin(tmp_path):
    p = subprocess.run([sys.executable, "-c", _CHILD], env={**os.environ, "HILMS_NUMBA_CACHE": str(tmp_path)},
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    said = dict(line.split(": ", 1) for line in p.stdout.strip().splitlines())
    pid = "controller rig_emulator.controllers.examples.pid:PID"
    assert said["empty"].startswith(f"compiling the step loop and the kernel of {pid} (first run of this install")
    assert " s on a quiet 2-core machine" in said["empty"] and str(tmp_path) in said["empty"]
    assert said["python, empty"].startswith("compiling the step loop (first run of this install")
    assert said["lockstep loop only"].startswith(f"compiling the step loop and the kernel of {pid} (")
    assert said["built-in, lockstep loop only"].startswith("compiling the step loop (")
    assert said["built-in"] == "None"
    assert said["plug-in path"].startswith(f"compiling the kernel of {pid} (first run of this plug-in")
    assert said["python"] == "None" and said["kernel as python"] == "None"
    assert said["kernel compiled"] == "None"  # once: the kernel is in the cache now


def test_a_plugin_flies_the_loop_a_builtin_run_compiled():
    from rig_emulator.api import simulate
    from rig_emulator.compile_notice import compile_notice, step_loop_cached, what_compiles

    simulate("hover", duration=0.01)  # the built-in strategy: compiles or loads the loop
    assert step_loop_cached()
    assert what_compiles("rig_emulator.controllers.examples.hover:LevelHover", "python") is None
    import io

    buf = io.StringIO()
    with compile_notice(stream=buf, plugin="rig_emulator.controllers.examples.hover:LevelHover", call="python") as said:
        pass
    assert said is False and buf.getvalue() == ""
