"""The evaluation record (resume, other contexts, interrupted writes) and the preset writer."""

import math
import tomllib

import numpy as np
import pytest

from gcs_tools.identify.paper import load_data
from gcs_tools.identify.preset import toml_body
from gcs_tools.identify.record import Evaluation, Record, pack, unpack
from gcs_tools.reproduce import paper_data
from rig_emulator.config.loader import load_config


def test_record_resumes_bit_exact_and_ignores_other_contexts(tmp_path):
    path = tmp_path / "fit.jsonl"
    rec = Record(path, "ctx-a")
    r = np.array([0.1, -2.5e-300, np.pi, 1 / 3])
    rec.add(Evaluation({"smc.k[0]": 1.2345678901234567}, r, {"m": 0.5, "bad": math.nan}))
    Record(path, "ctx-b").add(Evaluation({"smc.k[0]": 1.0}, r, {}))
    again = Record(path, "ctx-a")
    assert len(again) == 1 and again.other_context == 1
    ev = again.get({"smc.k[0]": 1.2345678901234567})
    assert ev.cached and ev.residuals.tobytes() == r.tobytes() and math.isnan(ev.metrics["bad"])
    assert again.get({"smc.k[0]": float(np.nextafter(1.2345678901234567, 2.0))}) is None  # the next float: another point
    # an interrupted write leaves a partial last line: skipped, and the next line starts on its own
    with open(path, "a") as f:
        f.write('{"context": "ctx-a", "point": {"smc.k[0]": 2.0}, "metr')
    third = Record(path, "ctx-a")
    assert third.skipped == 1 and len(third) == 1
    third.add(Evaluation({"smc.k[0]": 3.0}, r, {}))
    assert len(Record(path, "ctx-a")) == 2


def test_pack_round_trips_every_float():
    a = np.array([0.0, -0.0, 1e-310, np.inf, -np.inf, np.nan, 123456.789])
    b = unpack(pack(a))
    assert a.tobytes() == b.tobytes()


def test_preset_body_loads_as_a_config_file(tmp_path):
    flat = {"motors.time_constant": 0.0625, "smc.k": [1.5, 1.5, 1.42],
            "sensor_models.mpu6050": {"gyro": {"noise_dps_per_rthz": 0.006}},
            "disturbance.extra_masses": [{"arm": 1, "mass": 0.07, "distance": 0.33}], "airframe.ixx": 0.07}
    text = toml_body(flat)
    assert tomllib.loads(text)["smc"]["k"] == [1.5, 1.5, 1.42]
    f = tmp_path / "fit.toml"
    f.write_text("# header\n" + text)
    cfg = load_config(files=[f])
    assert cfg["motors.time_constant"] == 0.0625 and cfg["airframe.ixx"] == 0.07
    assert cfg["disturbance.extra_masses"][0]["mass"] == 0.07
    assert cfg["sensor_models.mpu6050"]["gyro"]["noise_dps_per_rthz"] == 0.006


def test_shipped_paper_targets_agree_with_paper_data():
    targets, claims = load_data()
    got = {t.metric: t.value for t in targets}
    want = {f"table4.{s}.{k}": v for s, row in paper_data.TABLE_4.items() for k, v in row.items()}
    want.update({f"table6.{s}.{k}": v for s, row in paper_data.TABLE_6.items() for k, v in row.items()})
    want.update({f"fig19.{k}": v for k, v in paper_data.RECTANGLE_ME.items()})
    assert got == want and len(targets) == 18
    assert all(t.source for t in targets) and {c.claim for c in claims} <= set(paper_data.CLAIMS)
