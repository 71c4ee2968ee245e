"""rig-gcs reproduce --controller: a plug-in's Table 6 row next to the paper's, in one command."""

import json

import pytest

from gcs_tools.errors import UsageError
from gcs_tools.reproduce.runner import reproduce

LQR = "rig_emulator.controllers.examples.lqr:LQRAttitude"


def test_controller_comparison_report(tmp_path):
    reproduce(tmp_path, quick=True, workers=1, show_progress=False, controller=LQR)
    report = (tmp_path / "report.md").read_text()
    assert f"| `{LQR}` (ours) |" in report and "| SMC-FLC (paper) | 0.5096 |" in report
    assert f"--controller {LQR}" in report
    me = json.loads((tmp_path / "results.json").read_text())["experiments"]["controller"]["numbers"]["mean_errors"]
    assert set(me) == {"helix/plugin", "helix/flc", "helix/smc-flc", "harmonic/plugin", "harmonic/smc", "harmonic/flc"}
    assert me["helix/plugin"]["x_m"] < 0.1


def test_unloadable_controller_is_a_usage_error(tmp_path):
    with pytest.raises(UsageError, match="--controller: controller nope.mod:X: cannot import"):
        reproduce(tmp_path, quick=True, workers=1, show_progress=False, controller="nope.mod:X")


def test_a_refused_plugin_parameter_is_a_usage_error_before_anything_runs(tmp_path):
    with pytest.raises(UsageError, match=r"--controller: .*unknown parameter 'controller.params.kq'"):
        reproduce(tmp_path, quick=True, workers=1, show_progress=False, controller=LQR,
                  overrides={"controller.params.kq": 1.0})
    assert not (tmp_path / "report.md").exists()
