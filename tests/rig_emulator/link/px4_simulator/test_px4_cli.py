"""``rig-emulator serve --px4-simulator`` as a user runs it: a process, a flight stack, a clean stop,
and the options it refuses."""

from __future__ import annotations

import os
import signal
import subprocess
import sys

import pytest

from gcs_tools.px4_peer import StreamLink, fly
from rig_emulator.link.px4_simulator.serve_px4 import AIRFRAME_FILE
from rig_emulator.testing.rig import START_TIMEOUT_S, RigProcess


def test_serve_px4_simulator_process():
    with RigProcess(speedup=1, args=["--px4-simulator", "127.0.0.1:0", "--no-persist"]) as rig:
        line = rig.wait_line("rig-emulator: px4 simulator on tcpin:127.0.0.1:")
        assert line is not None, rig.output
        port = int(line.rsplit(":", 1)[1])
        airframe = rig.wait_line("rig-emulator: PX4 SITL airframe for the rig: ")
        assert airframe is not None and AIRFRAME_FILE in airframe and "PX4_SIM_MODEL=none_hilms" in airframe
        assert os.path.isfile(AIRFRAME_FILE)
        link = StreamLink.tcp("127.0.0.1", port, timeout_s=START_TIMEOUT_S)  # a cold cache compiles at connect
        log = fly(link, 1.0)
        link.close()
        assert log.steps >= 250 and log.gps >= 9
        assert rig.wait_line("rig-emulator: flight stack gone") is not None
        assert rig.stop(signal.SIGINT) == 0
        assert any(line.startswith("rig-emulator: stopped at t = ") for line in rig.output)


@pytest.mark.parametrize("args,message", [
    (["--px4-simulator", "nonsense"], "--px4-simulator 'nonsense'"),
    (["--px4-simulator", "4560", "--start-paused"], "--start-paused does not apply"),
    (["--px4-simulator", "4560", "--px4-rate", "0"], "--px4-rate 0: must be > 0"),
])
def test_refused_options(args, message):
    proc = subprocess.run([sys.executable, "-m", "rig_emulator", "serve", "--no-persist", "--mavlink",
                           "tcpin:127.0.0.1:0", *args], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2, proc.stderr
    assert message in proc.stderr
