"""Load-cell calibration with the 370 g and 685 g masses (paper Sec. 4-1)."""

import numpy as np

from rig_emulator.estimation.calibration_file import load_calibration, save_calibration
from rig_emulator.estimation.estimation_config import load_estimation_config
from rig_emulator.estimation.load_cell_calibration import calibrate_load_cells
from rig_emulator.sensors.load_cell import draw_load_cells, load_load_cell_config


def test_b_and_c_recovered_within_the_quantisation(tmp_path):
    for seed in (1, 2, 3):
        truth = draw_load_cells(load_load_cell_config(), np.random.default_rng(seed))
        cal = calibrate_load_cells(load_estimation_config(), truth, np.random.default_rng(seed + 10))
        assert np.abs(cal.zero_counts - truth.zero_counts).max() < 0.5          # half a count
        span = 685.0 / truth.c_grf_per_count                                      # counts at 685 g
        # the force error at 685 g stays below one count (one step C)
        assert np.all(np.abs(cal.c_grf_per_count - truth.c_grf_per_count) * span < truth.c_grf_per_count)
    back = load_calibration(save_calibration(tmp_path / "cells.json", cal))
    assert np.array_equal(back.c_grf_per_count, cal.c_grf_per_count)
    assert back.procedure["masses_g"] == [370.0, 685.0]
