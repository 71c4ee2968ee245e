"""MAVProxy (PyPI) against the running rig: connects, fetches every parameter, shows attitude,
changes mode by name with ``--load-module=gcs_tools.mavproxy_px4modes``.

MAVProxy is driven through its stdin and judged by its output
(:class:`rig_emulator.testing.mavproxy.MAVProxySession`); the test fails without MAVProxy
rather than passing silently.
"""

import pytest

from rig_emulator.link.parameters.table import ParamTable
from rig_emulator.testing.mavproxy import MAVPROXY, MAVProxySession
from rig_emulator.testing.rig import RigProcess

pytestmark = [pytest.mark.slow]


def test_mavproxy_is_installed():
    assert MAVPROXY.exists(), "MAVProxy is a test requirement: run scripts/test.sh or pip install --no-deps MAVProxy"


def test_mavproxy_fetches_params_and_shows_attitude(tmp_path):
    with RigProcess(speedup=1.0) as rig:
        # with the project's mode module loaded at start (docs/how-to/ground-stations.md): it must take the
        # mode command over from MAVProxy's own, which loads after --load-module modules
        args = ["--load-module=gcs_tools.mavproxy_px4modes"]
        with MAVProxySession(rig.tcp_url, tmp_path, args) as mp:
            got = mp.wait_for(r"Received (\d+) parameters")
            assert got is not None, mp.transcript()
            assert int(got.group(1)) == len(ParamTable())
            mp.do("param show SMC_K_PHI", r"SMC_K_PHI\s+1\.47")
            mp.do("status ATTITUDE", r"ATTITUDE \{time_boot_ms : \d+, roll : (\S+),")
            mp.do("mode LOITER", r"Got COMMAND_ACK: DO_SET_MODE: ACCEPTED")
            mp.do("posctl", r"Got COMMAND_ACK: DO_SET_MODE: ACCEPTED")  # a bare name: the module answers first
            assert "ERROR in command" not in mp.transcript(), mp.transcript()
        # judged while connected: MAVProxy's own shutdown is outside the rig's control
        assert "Traceback" not in mp.before_exit and "Exception" not in mp.before_exit, mp.before_exit
        assert rig.stop() == 0
