"""``rig-emulator serve --ardupilot-json`` as a user runs it: a process, the stand-in ArduPilot,
a clean stop, and the options it refuses."""

from __future__ import annotations

import signal
import subprocess
import sys

import pytest

from gcs_tools.ardupilot_peer import JsonLink, fly
from rig_emulator.link.ardupilot_json.serve_ardupilot import PARAM_FILE, ground_endpoints, parse_spec
from rig_emulator.testing.rig import START_TIMEOUT_S, RigProcess


def test_serve_ardupilot_json_process():
    with RigProcess(speedup=1, args=["--ardupilot-json", "127.0.0.1:0", "--no-persist"]) as rig:
        line = rig.wait_line("rig-emulator: ardupilot json physics on udp:127.0.0.1:")
        assert line is not None, rig.output
        assert PARAM_FILE in line
        port = int(line.split("udp:127.0.0.1:", 1)[1].split()[0])
        link = JsonLink("127.0.0.1", port, timeout_s=START_TIMEOUT_S)  # a cold cache compiles at the first frame
        log = fly(link, 1.0)
        link.close()
        assert log.frames == 1001 and link.clock.advances == 1001
        assert rig.wait_line("rig-emulator: ArduPilot at udp:127.0.0.1:") is not None
        assert rig.stop(signal.SIGINT) == 0
        assert any(line.startswith("rig-emulator: stopped at t = 1.001") for line in rig.output), rig.output


def test_the_parameter_file_is_installed_and_names_the_frame():
    with open(PARAM_FILE) as f:
        params = dict(line.split()[:2] for line in f if line.strip() and not line.startswith("#"))
    assert params["FRAME_CLASS"] == "1" and params["FRAME_TYPE"] == "6"  # quad PLUSREV
    # outputs 1..4 = rig motors front, right, back, left = ArduCopter PLUSREV motors 3, 1, 4, 2
    assert [params[f"SERVO{i}_FUNCTION"] for i in range(1, 5)] == ["35", "33", "36", "34"]


def test_default_port_follows_the_instance():
    assert parse_spec("", 0) == ("127.0.0.1", 9002)
    assert parse_spec("", 2) == ("127.0.0.1", 9022)  # SITL -I 2 sends to 9022
    assert parse_spec("0.0.0.0:9100", 2) == ("0.0.0.0", 9100)
    # the rig's own ground link moves off ArduPilot SITL's TCP 5760 + 10 N when none is given
    assert ground_endpoints(0) == ["tcpin:127.0.0.1:5790"] and ground_endpoints(2) == ["tcpin:127.0.0.1:5810"]


@pytest.mark.parametrize("args,message", [
    (["--ardupilot-json", "nonsense"], "--ardupilot-json 'nonsense'"),
    (["--ardupilot-json", "--start-paused"], "--start-paused does not apply"),
    (["--ardupilot-json", "--px4-simulator"], "one flight stack at a time"),
    (["--ardupilot-rate", "500"], "--ardupilot-rate needs --ardupilot-json"),
    (["--ardupilot-json", "--ardupilot-rate", "0"], "--ardupilot-rate 0: must be > 0"),
])
def test_refused_options(args, message):
    proc = subprocess.run([sys.executable, "-m", "rig_emulator", "serve", "--no-persist", "--mavlink",
                           "tcpin:127.0.0.1:0", *args], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2, proc.stderr
    assert message in proc.stderr
