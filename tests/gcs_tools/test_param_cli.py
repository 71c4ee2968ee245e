"""rig-gcs param save/load/get against a rig over TCP: a saved file loads back without a change,
a file with an unknown name sets nothing, and values survive the file exactly (float32)."""

import numpy as np
import pytest

from gcs_tools.cli import main
from rig_emulator.testing.rig import RigThread, client_url


@pytest.fixture(scope="module")
def rig():
    with RigThread(speedup=4.0) as r:
        yield r


def test_save_then_load_changes_nothing(rig, capsys, tmp_path):
    url = client_url(rig.tcp_url)
    f = tmp_path / "all.params"
    assert main(["param", "set", url, "EST_TAU_RP", "0.7"]) == 0
    assert main(["param", "save", url, str(f)]) == 0
    n = len(rig.server.params.table)
    assert f"saved {n} parameters" in capsys.readouterr().out
    rows = [ln.split("\t") for ln in f.read_text().splitlines() if not ln.startswith("#")]
    assert len(rows) == n and all(r[0] == "1" and r[1] == "1" and r[4] == "9" for r in rows)
    assert ["1", "1", "EST_TAU_RP", "0.7", "9"] in rows
    assert main(["param", "set", url, "EST_TAU_RP", "0.9"]) == 0
    assert main(["param", "load", url, str(f)]) == 0
    assert capsys.readouterr().out.splitlines()[-2:] == ["EST_TAU_RP: 0.9 -> 0.7", f"loaded {f}: 1 set, {n - 1} already equal"]
    assert np.float32(rig.server.rig.cfg["estimation.tau_roll_pitch"]) == np.float32(0.7)


def test_unknown_name_sets_nothing(rig, capsys, tmp_path):
    url = client_url(rig.tcp_url)
    f = tmp_path / "typo.parm"
    f.write_text("EST_TAU_YAW 3\nEST_TAU_RPP 1\n")
    before = rig.server.rig.cfg["estimation.tau_yaw"]
    assert main(["param", "load", url, str(f)]) == 2
    assert "typo.parm:2: EST_TAU_RPP: no such parameter on the vehicle; nothing was set" in capsys.readouterr().err
    assert rig.server.rig.cfg["estimation.tau_yaw"] == before
    assert main(["param", "get", url, "NO_SUCH_PARAM", "--timeout", "0.2", "--retries", "1"]) == 1
    assert "NO_SUCH_PARAM: no PARAM_VALUE after 2 PARAM_REQUEST_READ" in capsys.readouterr().err


def test_rejected_set_prints_its_reason_once(rig, capsys):
    url = client_url(rig.tcp_url)
    before = rig.server.rig.cfg["smc.k"][0]
    assert main(["param", "set", url, "SMC_K_PHI", "1e9", "--timeout", "0.5"]) == 1
    err = capsys.readouterr().err
    assert f"SMC_K_PHI: the vehicle rejected 1e+09 and kept {before:g}" in err
    assert err.count("must be in [0, 10000]") == 1, err
    assert rig.server.rig.cfg["smc.k"][0] == before


def test_a_read_only_parameter_is_refused_by_set_and_left_by_load(rig, capsys, tmp_path):
    """MPC_THR_HOVER is derived by the rig: a set is refused with the reason; a file that holds another
    value of it (saved after another flight) loads without touching it."""
    url = client_url(rig.tcp_url)
    assert main(["param", "set", url, "MPC_THR_HOVER", "0.5", "--timeout", "0.5", "--retries", "1"]) == 1
    assert "read-only" in capsys.readouterr().err
    f = tmp_path / "hover.parm"
    f.write_text("MPC_THR_HOVER 0.5\nEST_TAU_YAW 2.5\n")
    assert main(["param", "load", url, str(f)]) == 0
    assert capsys.readouterr().out.splitlines()[-1] == f"loaded {f}: 1 set, 1 already equal"
    assert rig.server.rig.cfg["estimation.tau_yaw"] == 2.5
