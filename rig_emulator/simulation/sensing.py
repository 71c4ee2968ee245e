"""Build the rig's sensing chain (Sec. 4-1) from a config: sensor models, calibration, estimators.

Random streams are split from the run's seed with ``numpy.random.SeedSequence`` so that
the drawn sensor errors, the calibration procedure and the run-time noise are independent
and each reproducible: the same seed gives bit-identical runs.
"""

from __future__ import annotations

import json
import os
from collections import namedtuple
from pathlib import Path

import numpy as np

from rig_emulator.build_cache import BuildCache
from rig_emulator.config.loader import ConfigError, RigConfig
from rig_emulator.fast_copy import fast_deepcopy
from rig_emulator.estimation.attitude_pipeline import make_attitude_chain
from rig_emulator.estimation.calibration_file import load_calibration
from rig_emulator.estimation.complementary import complementary_params
from rig_emulator.estimation.ensemble import ensemble_params
from rig_emulator.estimation.estimation_config import load_estimation_config
from rig_emulator.estimation.imu_calibration import ImuCalibration, calibrate_imu_modules, nominal_calibration
from rig_emulator.estimation.load_cell_calibration import calibrate_load_cells
from rig_emulator.estimation.load_cell_filter import load_cell_filter_params, load_cell_filter_state
from rig_emulator.sensors.imu_module import draw_imu_modules, load_imu_config
from rig_emulator.sensors.load_cell import draw_load_cells, load_load_cell_config
from rig_emulator.sensors.sensor_step import allocate_raw, make_sensor_suite

# what the compiled loop receives
SensingParams = namedtuple("SensingParams", "simulate estimated suite chain lcp")
SensingState = namedtuple(
    "SensingState",
    "sstate awork lcs imu_raw cell_raw att_est thrust_est onboard health thrust_true rotor_speed",
)
# onboard: the rig's own virtual translation (Eq. 1 from load cells and estimated attitude):
# position (0:3), velocity (3:6). health: (0) rejected IMU modules mask, (1) rejected cells mask.


#: The config keys a rig's sensing depends on (a test checks that building a Sensing reads
#: no other key): equal values of these, with the same seed and step, build equal Sensings.
SENSING_KEYS = ("sim.seed", "sensors.", "sensor_models.", "estimation.")
_BUILT = BuildCache(8, copy=lambda sensing: _copy_sensing(sensing))  # build key -> Sensing


def _build_key(cfg: RigConfig, dt: float):
    """What a Sensing is built from, as hashable text (None when it cannot be written)."""
    picked = {k: v for k, v in cfg.items() if k.startswith(SENSING_KEYS)}
    cal = cfg.get("sensors.calibration_file")
    if cal:
        try:
            st = os.stat(cal)  # a rewritten calibration file (new inode, size or time) is read again
        except OSError:
            return None  # the build reports the missing file
        picked["__calibration_file_stat"] = [st.st_ino, st.st_size, st.st_mtime_ns]
    try:
        return (float(dt), json.dumps(picked, sort_keys=True, allow_nan=True))
    except (TypeError, ValueError):
        return None


def build_sensing(cfg: RigConfig, dt: float) -> "Sensing":
    """The rig's sensing for ``cfg`` (seeded by ``sim.seed``), built once per process for
    each distinct sensing configuration: a sweep of one rig over control or guidance
    parameters draws its sensors and runs its calibrations once, and every run gets its own
    copy (with a fresh run-time random stream in the same state), bit-identical to a
    Sensing built from scratch (tested)."""
    return _BUILT.get_or_build(_build_key(cfg, dt),
                               lambda: Sensing(cfg, dt, np.random.SeedSequence(cfg["sim.seed"])))


def _copy_sensing(sensing: "Sensing") -> "Sensing":
    out = object.__new__(Sensing)
    out.__dict__.update(fast_deepcopy(sensing.__dict__))
    return out


class Sensing:
    """The drawn sensors, their calibration and the compiled chain's arguments."""

    def __init__(self, cfg: RigConfig, dt: float, seed_sequence: np.random.SeedSequence):
        draw_seq, cal_seq, run_seq = seed_sequence.spawn(3)
        draw_rng = np.random.default_rng(draw_seq)
        cal_rng = np.random.default_rng(cal_seq)
        self.run_rng = np.random.default_rng(run_seq)
        models = {name.split(".", 1)[1]: cfg[name] for name in cfg if name.startswith("sensor_models.")}
        imu_cfg = load_imu_config({k: models[k] for k in ("mpu6050", "hmc5883l", "imu_array") if models[k]})
        est_over = dict(models["estimation"])
        est_over.setdefault("ensemble", {})["mode"] = cfg["estimation.ensemble"]
        comp = est_over.setdefault("complementary", {})
        comp["tau_roll_pitch_s"] = cfg["estimation.tau_roll_pitch"]
        comp["tau_yaw_s"] = cfg["estimation.tau_yaw"]
        comp["accel_lowpass_hz"] = cfg["estimation.accel_lowpass_hz"]
        lcf = est_over.setdefault("load_cell_filter", {})
        lcf["mode"] = cfg["estimation.load_cell_filter"]
        lcf["iir_cutoff_hz"] = cfg["estimation.iir_cutoff_hz"]
        self.est_cfg = load_estimation_config(est_over)
        self.imu_truth = draw_imu_modules(imu_cfg, draw_rng, physics_dt_s=dt)
        self.cell_truth = draw_load_cells(load_load_cell_config(models["zemic_l6d"] or None), draw_rng)
        suite, sstate = make_sensor_suite(self.imu_truth, self.cell_truth)
        imu_raw, cell_raw = allocate_raw(suite)
        self.imu_calibration = self._imu_calibration(cfg, cal_rng)
        self.cell_calibration = calibrate_load_cells(self.est_cfg, self.cell_truth, cal_rng)
        k = suite.imu
        cf = complementary_params(self.est_cfg, k.decim_inertial * k.dt_s, k.decim_mag * k.dt_s, k.gravity_m_s2)
        chain, awork = make_attitude_chain(self.imu_calibration.arrays(), ensemble_params(self.est_cfg), cf, k.n_modules)
        lcp = load_cell_filter_params(self.est_cfg, self.cell_calibration, suite.cells.decim * k.dt_s)
        simulate = bool(cfg["sensors.simulate"])
        self.params = SensingParams(
            simulate=simulate,
            estimated=simulate and cfg["sensors.feedback"] == "estimated",
            suite=suite,
            chain=chain,
            lcp=lcp,
        )
        self.state = SensingState(
            sstate=sstate,
            awork=awork,
            lcs=load_cell_filter_state(suite.cells.n_cells),
            imu_raw=imu_raw,
            cell_raw=cell_raw,
            att_est=np.zeros(6),
            thrust_est=np.zeros(suite.cells.n_cells),
            onboard=np.zeros(6),
            health=np.zeros(2, dtype=np.int64),
            thrust_true=np.zeros(4),
            rotor_speed=np.zeros(4),
        )

    def recalibrate_imu(self, cfg: RigConfig, rng) -> None:
        """Run the IMU calibration procedure again and apply the result in place."""
        cal = calibrate_imu_modules(self.est_cfg, self.imu_truth, rng)
        cal.procedure["seed"] = cfg["sim.seed"]
        arrays = cal.arrays()
        self.params.chain.cal.gain[...] = arrays.gain
        self.params.chain.cal.offset_counts[...] = arrays.offset_counts
        self.imu_calibration = cal

    def _imu_calibration(self, cfg: RigConfig, rng) -> ImuCalibration:
        if cfg["sensors.calibration"] == "none":
            return nominal_calibration(self.imu_truth)
        path = cfg["sensors.calibration_file"]
        if path:
            try:
                cal = load_calibration(Path(path))
            except (OSError, ValueError) as exc:
                raise ConfigError(f"sensors.calibration_file = {path!r}: {exc}") from None
            if not isinstance(cal, ImuCalibration):
                raise ConfigError(f"sensors.calibration_file = {path!r}: holds a load-cell calibration, not an IMU one")
            if cal.arrays().gain.shape[0] != self.imu_truth.kernel.n_modules:
                raise ConfigError(f"sensors.calibration_file = {path!r}: made for a different number of IMU modules")
            made_for = cal.procedure.get("seed")
            if made_for is not None and made_for != cfg["sim.seed"]:
                raise ConfigError(
                    f"sensors.calibration_file = {path!r}: made for the rig of seed {made_for}, this run has "
                    f"sim.seed = {cfg['sim.seed']} (its sensors carry other turn-on errors); recalibrate"
                )
            return cal
        cal = calibrate_imu_modules(self.est_cfg, self.imu_truth, rng)
        cal.procedure["seed"] = cfg["sim.seed"]
        return cal
