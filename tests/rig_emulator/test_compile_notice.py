"""The first run after an install says on stderr that it compiles, and roughly for how long; later runs say nothing."""

import io
import os
import subprocess
import sys

from rig_emulator.compile_notice import compile_notice, step_loop_cached


def test_cold_cache_is_detected_and_announced(tmp_path):
    code = ("from rig_emulator.compile_notice import compile_notice, step_loop_cached\n"
            "print(step_loop_cached())\n"
            "with compile_notice():\n    pass\n")
    p = subprocess.run([sys.executable, "-c", code], env={**os.environ, "HILMS_NUMBA_CACHE": str(tmp_path)},
                       capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, p.stderr
    assert p.stdout.strip() == "False"
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 2 and "compiling the step loop" in lines[0] and " s on a quiet 2-core machine" in lines[0]
    assert lines[1].startswith("rig-emulator: step loop compiled in ")


def test_warm_cache_says_nothing():
    from rig_emulator.api import simulate

    simulate("hover", duration=0.01)  # compiles or loads the loop: the cache holds it now
    assert step_loop_cached()
    buf = io.StringIO()
    with compile_notice(stream=buf) as cold:
        pass
    assert cold is False and buf.getvalue() == ""
