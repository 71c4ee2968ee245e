"""The position builders' cached-home conversion is protocol.geodesy's: to the last bit where this
host's numpy calls libm, within a few ulps where it does not (tests/float_bits.py)."""

import numpy as np

from protocol.geodesy import Home, local_enu_to_global
from rig_emulator.link.telemetry.position import enu_to_global
from tests.float_bits import same_geodetic


def test_enu_to_global_is_local_enu_to_global():
    rng = np.random.default_rng(3)
    for home in (Home(35.7, 51.4, 1200.0), Home(-12.5, 130.8, 30.0)):
        for _ in range(2000):
            enu = rng.normal(0.0, 10.0 ** float(rng.integers(-3, 4)), 3)
            assert same_geodetic(enu_to_global(home, enu), local_enu_to_global(home, enu))
            assert enu_to_global(home, tuple(enu.tolist())) == enu_to_global(home, enu)


def test_enu_to_global_at_the_origin_and_on_the_axes():
    home = Home(35.7, 51.4, 1200.0)
    for enu in ((0.0, 0.0, 0.0), (-0.0, -0.0, -0.0), (3.0, 0.0, -0.0), (0.0, -2.5, 0.0), (0.0, 0.0, 1e-9)):
        assert same_geodetic(enu_to_global(home, enu), local_enu_to_global(home, np.array(enu)))
