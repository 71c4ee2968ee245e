"""Figs. 12 and 15's chattering verdicts read the angles the figures plot (the roll and pitch
errors above 5 Hz), not the motor commands, which the report gives next to them."""

from gcs_tools.reproduce import exp_masses, exp_shocks
from gcs_tools.reproduce.experiment import NOT_REPRODUCED, PARTLY, REPRODUCED


def _fig(deg, volts, diverged=None):
    return {"chattering_deg_rms": deg, "chattering_v_rms": volts, "diverged_at_s": diverged}


def test_fig12_reads_the_angles():
    # the FLC's motors busier than the SMC's, its angles a third as rough: the angles decide
    assert exp_shocks.chattering_verdict(_fig(0.18, 1.3), _fig(0.06, 2.4)).status == REPRODUCED
    assert exp_shocks.chattering_verdict(_fig(0.18, 2.4), _fig(0.12, 1.3)).status == PARTLY
    v = exp_shocks.chattering_verdict(_fig(0.18, 2.4), _fig(0.31, 0.2))
    assert v.status == NOT_REPRODUCED
    assert "0.180 deg" in v.evidence and "0.200 V" in v.evidence


def test_fig15_reads_the_angles():
    smoother = {"40g": {"smc": _fig(0.22, 1.6), "flc": _fig(0.10, 2.3)},
                "100g": {"smc": _fig(0.09, 1.2), "flc": _fig(0.06, 2.1)}}
    assert exp_masses._smoother_verdict(smoother).status == REPRODUCED
    rougher = dict(smoother, **{"100g": {"smc": _fig(0.09, 2.1), "flc": _fig(0.12, 1.2)}})
    assert exp_masses._smoother_verdict(rougher).status == PARTLY
    lost = dict(smoother, **{"100g": {"smc": _fig(0.5, 1.0, diverged=3.0), "flc": _fig(0.9, 2.0)}})
    assert exp_masses._smoother_verdict(lost).status == REPRODUCED  # the SMC lost it: the FLC is the smoother
