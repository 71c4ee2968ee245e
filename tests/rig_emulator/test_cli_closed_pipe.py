"""`rig-emulator params | head` ends quietly: no BrokenPipeError traceback, exit 141 (SIGPIPE)."""

import os
import subprocess
import sys


def test_params_into_a_closed_pipe_prints_no_traceback():
    read_end, write_end = os.pipe()
    os.close(read_end)  # the reader has gone away (as `head` does after its lines) before the list is written
    try:
        proc = subprocess.run([sys.executable, "-m", "rig_emulator", "params"], stdout=write_end,
                              stderr=subprocess.PIPE, timeout=120)
    finally:
        os.close(write_end)
    err = proc.stderr.decode()
    assert "Traceback" not in err and "BrokenPipeError" not in err, err
    assert proc.returncode == 141
