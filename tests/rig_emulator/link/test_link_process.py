"""The `rig-emulator` command: starts serving, stops cleanly on signals, refuses bad options."""

import signal
import subprocess
import sys

from protocol.dialect import mavlink as M
from rig_emulator.testing.rig import RigProcess, command, connect, recv, udp_listener


def test_sigterm_and_sigint_exit_zero():
    for sig in (signal.SIGTERM, signal.SIGINT):
        with RigProcess(speedup=2.0) as rig:
            c = connect(rig.tcp_url)
            assert recv(c, "HEARTBEAT") is not None
            assert command(c, 31999).result == M.MAV_RESULT_UNSUPPORTED
            c.close()
            assert rig.stop(sig) == 0
            assert any("stopped at" in line for line in rig.output)


def test_default_command_serves_and_duration_stops_it():
    udp_client, udp_url = udp_listener()
    proc = subprocess.run(
        [sys.executable, "-m", "rig_emulator", "--mavlink", udp_url, "--speedup", "max", "--duration", "3",
         "--sysid", "7", "--set", "control.strategy=pid", "--no-persist"],
        capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert f"serving {udp_url}" in proc.stdout
    hb = recv(udp_client, "HEARTBEAT", timeout=5)
    assert hb is not None and hb.get_srcSystem() == 7
    att = recv(udp_client, "ATTITUDE", timeout=5)
    assert att is not None and att.get_srcSystem() == 7
    udp_client.close()


def test_bad_options_exit_two():
    for args in (["--mavlink", "serial:/dev/null"], ["--speedup", "-1"], ["--sysid", "0"], ["--set", "smc.k=5"]):
        proc = subprocess.run([sys.executable, "-m", "rig_emulator", "serve", *args, "--duration", "1", "--no-persist"],
                              capture_output=True, text=True, timeout=120)
        assert proc.returncode == 2, (args, proc.stdout, proc.stderr)
        assert "error" in proc.stderr


def test_serve_strategy_option_sets_the_running_strategy():
    from rig_emulator.config.schema import STRATEGIES

    with RigProcess(speedup=2, args=["--strategy", "flc", "--no-persist"]) as rig:
        conn = connect(rig.tcp_url)
        conn.mav.param_request_read_send(1, 1, b"CTL_STRATEGY", -1)
        pv = recv(conn, "PARAM_VALUE", 10, lambda m: m.param_id == "CTL_STRATEGY")
        assert pv is not None and int(pv.param_value) == STRATEGIES.index("flc")
