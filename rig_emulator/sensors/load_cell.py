"""ZEMIC L6D load cells behind the rig's 10-bit ADC (paper Sec. 4-1, Fig. 9, Fig. 10).

One cell per arm measures its motor's thrust. The reading in counts is
``S = b + F_grf / C + n`` rounded and clipped to 0..1023, the inverse of the paper's
calibration ``F[grF] = C (S - b)``: ``b`` is the unloaded reading (about 350, Fig. 9) and
``C`` the smallest readable step (2.44 grF per count, Sec. 4-1).

Reading (per-cell spread): ``b`` is drawn normal around ``zero_reading_counts`` with
``zero_reading_spread_counts`` sigma, clipped at 3 sigma; ``C`` normal around
``step_grf`` with sigma ``step_tolerance / 3``, clipped at the tolerance.
Reading (noise, Fig. 9): the raw output is quiet with the motor off and noisy with it
running because the arm vibrates; the noise sigma is
``sigma_grf = noise_floor_grf + vibration_grf_at_hover * (Omega / Omega_hover)^2``,
i.e. it grows with the rotor's centrifugal excitation (proportional to thrust).
Gram-force uses standard gravity: 1 grF = 9.80665e-3 N.
"""

from __future__ import annotations

import math
from collections import namedtuple
from dataclasses import dataclass

import numpy as np

from rig_emulator._jit import jit
from rig_emulator.sensors.faults import FAULT_BIAS, FAULT_DEAD, FAULT_NOISE, FAULT_SPIKE, FAULT_STUCK
from rig_emulator.sensors.presets import load_sensor_preset

GRF_N = 9.80665e-3  # newton per gram-force

LoadCellKernel = namedtuple(
    "LoadCellKernel",
    [
        "n_cells",                  # int
        "decim",                    # int: sampled when step % decim == 0
        "zero_counts",              # (n,) true unloaded reading b
        "counts_per_newton",        # (n,) 1 / (C grF/count * GRF_N)
        "noise_floor_N",            # float
        "vibration_N_at_hover",     # float
        "rotor_speed_hover_rad_s",  # float
        "count_max",                # float (1023)
        "spike_probability",        # float
    ],
)


@dataclass(frozen=True)
class LoadCellTruth:
    """The injected per-cell calibration truth and the kernel."""

    zero_counts: np.ndarray       # (n,) b
    c_grf_per_count: np.ndarray   # (n,) C
    kernel: LoadCellKernel


def load_load_cell_config(overrides: dict | None = None) -> dict:
    """Datasheet defaults (``zemic_l6d.toml``) with nested ``overrides`` applied."""
    return load_sensor_preset("zemic_l6d", overrides)


def draw_load_cells(cfg: dict, rng: np.random.Generator) -> LoadCellTruth:
    """Draw each cell's zero reading and step once from ``rng`` -> truth + kernel."""
    lc = cfg["load_cell"]
    n = lc["n_cells"]
    spread = lc["zero_reading_spread_counts"]
    zero = lc["zero_reading_counts"] + np.clip(rng.normal(0.0, spread, n), -3 * spread, 3 * spread)
    tol = lc["step_tolerance"]
    c = lc["step_grf"] * (1.0 + np.clip(rng.normal(0.0, tol / 3.0, n), -tol, tol))
    count_max = float(2 ** lc["adc_bits"] - 1)
    kernel = LoadCellKernel(
        n_cells=n,
        decim=lc["decimation"],
        zero_counts=zero,
        counts_per_newton=1.0 / (c * GRF_N),
        noise_floor_N=lc["noise_floor_grf"] * GRF_N,
        vibration_N_at_hover=lc["vibration_grf_at_hover"] * GRF_N,
        rotor_speed_hover_rad_s=lc["rotor_speed_hover_rad_s"],
        count_max=count_max,
        spike_probability=lc["spike_probability"],
    )
    return LoadCellTruth(zero, c, kernel)


@jit(inline="always")
def sample_load_cells(thrust_N, rotor_speed_rad_s, k, fault_mode, fault_magnitude, rng, raw_out):
    """Raw counts of every cell for the motors' thrusts [N] and rotor speeds [rad/s].

    Writes float64 integer counts into ``raw_out`` (n,). Faults: stuck holds the last
    value, dead reads 0, bias adds counts, noise adds ``magnitude`` x sigma, spike adds
    +-``magnitude`` counts with probability ``spike_probability`` per sample.
    """
    for i in range(k.n_cells):
        mode = fault_mode[i]
        if mode == FAULT_STUCK:
            continue
        r = rotor_speed_rad_s[i] / k.rotor_speed_hover_rad_s
        sig = (k.noise_floor_N + k.vibration_N_at_hover * r * r) * k.counts_per_newton[i]
        s = k.zero_counts[i] + thrust_N[i] * k.counts_per_newton[i] + sig * rng.standard_normal()
        if mode == FAULT_NOISE:
            s += fault_magnitude[i] * sig * rng.standard_normal()
        c = math.floor(s + 0.5)
        if mode == FAULT_BIAS:
            c += fault_magnitude[i]
        elif mode == FAULT_SPIKE:
            if rng.random() < k.spike_probability:
                if rng.random() < 0.5:
                    c += fault_magnitude[i]
                else:
                    c -= fault_magnitude[i]
        elif mode == FAULT_DEAD:
            c = 0.0
        if c < 0.0:
            c = 0.0
        elif c > k.count_max:
            c = k.count_max
        raw_out[i] = c
