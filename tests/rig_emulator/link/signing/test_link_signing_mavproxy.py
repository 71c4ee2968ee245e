"""MAVProxy (PyPI, its built-in signing module) against a rig started with ``--signing-key``:
unsigned, MAVProxy is ignored; after ``signing setup PASSPHRASE`` (the key is SHA-256 of the
passphrase on both sides) it fetches the parameters and sets one. Driven through its stdin and
judged by its output (rig_emulator.testing.mavproxy)."""

import hashlib
import re
import time

import pytest

from rig_emulator.link.parameters.table import ParamTable
from rig_emulator.testing.mavproxy import MAVProxySession
from rig_emulator.testing.rig import RigProcess, connect, recv

pytestmark = [pytest.mark.slow]
PASSPHRASE = "hilms-rig-42"


def test_mavproxy_signing_setup_then_params(tmp_path):
    with RigProcess(speedup=1.0, args=["--signing-key", PASSPHRASE]) as rig:
        with MAVProxySession(rig.tcp_url, tmp_path) as mp:
            # unsigned, MAVProxy sees the rig (its telemetry is signed, MAVProxy does not check it) but
            # its parameter requests are dropped
            assert mp.wait_for(r"signing: rejected \d+ unsigned", timeout=60) is not None, mp.transcript()
            assert not any(re.search(r"Received \d+ parameters", line) for line in mp.all)
            mp.send(f"signing setup {PASSPHRASE}")
            assert mp.wait_for(r"Setup signing key") is not None, mp.transcript()
            mp.send("param fetch")
            got = mp.wait_for(r"Received (\d+) parameters")
            assert got is not None and int(got.group(1)) == len(ParamTable()), mp.transcript()
            mp.send("param set SMC_K_PHI 2.25")
            shown = None
            deadline = time.monotonic() + 30
            while time.monotonic() < deadline:  # MAVProxy shows its cache: ask until the rig's echo updated it
                mp.send("param show SMC_K_PHI")
                shown = mp.wait_for(r"SMC_K_PHI\s+(\S+)", timeout=10)
                if shown is None or float(shown.group(1)) == 2.25:
                    break
                time.sleep(0.5)  # the echo follows the rig's durable write (fsync), slower on a busy machine
            assert shown is not None and float(shown.group(1)) == 2.25, mp.transcript()
        assert "Traceback" not in mp.before_exit, mp.before_exit
        check = connect(rig.tcp_url, signing_key=hashlib.sha256(PASSPHRASE.encode()).digest())
        check.mav.param_request_read_send(1, 1, b"SMC_K_PHI", -1)
        assert recv(check, "PARAM_VALUE", 5, lambda m: m.param_id == "SMC_K_PHI").param_value == 2.25
        check.close()
        assert rig.stop() == 0
        stopped = rig.output[-1]
        assert re.search(r"'unsigned': [1-9]", stopped) and "bad_signature" not in stopped, stopped
        assert PASSPHRASE not in "\n".join(rig.output)
