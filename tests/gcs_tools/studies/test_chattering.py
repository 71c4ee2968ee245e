"""gcs_tools.studies.chattering: the effects it toggles are exactly where hilms and hilms-ideal differ,
and its band shares put a sine's power in its band."""

import numpy as np

from rig_emulator.config.loader import load_config
from gcs_tools.studies import chattering as study


def test_the_effects_are_the_keys_the_two_airframes_differ_on():
    hw, ideal = load_config("hilms"), load_config("hilms-ideal")
    fx = study.effects()
    keys = sorted(k for e in fx.values() for k in e["hilms"])
    assert keys == sorted(k for k in hw if k != "airframe.name" and hw[k] != ideal[k])
    for entry in fx.values():
        assert all(entry["hilms"][k] == hw[k] and entry["ideal"][k] == ideal[k] for k in entry["hilms"])
    assert set(study.CUMULATIVE) <= set(fx)


def test_the_cumulative_plant_ends_with_every_effect_of_the_list():
    last = study.plants()[-1]
    fx = study.effects()
    assert last[1] == "hilms-ideal"
    assert last[2] == {k: v for name in study.CUMULATIVE for k, v in fx[name]["hilms"].items()}


def test_band_shares_put_a_sine_in_its_band():
    t = np.arange(0.0, 20.0, 1.0 / 500.0)
    x = 3.0 + np.sin(2 * np.pi * 7.0 * t) + 0.5 * np.sin(2 * np.pi * 30.0 * t) + np.sin(2 * np.pi * 1.0 * t)
    shares = study.band_shares(t, x)
    assert np.allclose(shares, [0.8, 0.0, 0.2, 0.0], atol=1e-6)
