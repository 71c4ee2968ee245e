"""The scalar frame functions (the served rig's per-chunk messages) give bit for bit
what their array forms give: random attitudes, attitudes with exact and signed zeros, NaN."""

import itertools
import math

import numpy as np
import pytest

from protocol import frames as F
from tests.float_bits import bits, same_or_within_ulps


def _quaternions():
    rng = np.random.default_rng(14)
    out = [tuple(q / np.linalg.norm(q)) for q in rng.normal(size=(3000, 4))]
    special = (0.0, -0.0, 1.0, -1.0, 0.5, -0.5, 2 ** -0.5)
    out += [q for q in itertools.product(special, repeat=4)]  # exact zeros, signed zeros, non-unit
    out += [(math.nan, 0.0, 0.0, 0.0), (1.0, math.inf, 0.0, 0.0), (0.0, 0.0, 0.0, 0.0)]
    return out


def _rwb(q) -> np.ndarray:
    from rig_emulator.physics.rotation import quat_to_rot

    r = np.zeros((3, 3))
    quat_to_rot(*q, r)
    return r


@pytest.fixture(scope="module")
def cases():
    return [(q, _rwb(q)) for q in _quaternions()]


def test_rotation_matches_the_compiled_quat_to_rot(cases):
    for q, r in cases:
        assert bits(F.rwb_from_quaternion_xyz(*q)) == bits(r.ravel()), q


def test_ned_rotation_matches_the_matmul(cases):
    for q, r in cases:
        assert bits(F.rwb_to_r_ned_frd_xyz(tuple(r.ravel().tolist()))) == bits(F.rwb_to_r_ned_frd(r).ravel()), q


@pytest.mark.filterwarnings("ignore::RuntimeWarning")
def test_euler_and_quaternion_match_the_array_forms(cases):
    for q, r in cases:
        r9 = tuple(r.ravel().tolist())
        assert bits(F.mavlink_euler_from_rwb_xyz(r9)) == bits(F.mavlink_euler_from_rwb(r)), q
        assert bits(F.mavlink_quaternion_from_rwb_xyz(r9)) == bits(F.mavlink_quaternion_from_rwb(r)), q


def test_paper_yaw_matches_the_array_form():
    rng = np.random.default_rng(15)
    values = list(rng.normal(size=20000) * 4.0) + [0.0, -0.0, math.pi, -math.pi, math.pi / 2, 3 * math.pi / 2,
                                                   -math.pi / 2, 2 * math.pi, 1e-300, math.nan]
    for psi in values:
        assert bits([F.paper_yaw_to_mavlink_xyz(float(psi))]) == bits([F.paper_euler_to_mavlink(0.0, 0.0, psi)[2]]), psi


def test_the_scalar_trig_is_numpys_to_the_bit_or_within_an_ulp():
    """The scalar forms call math's atan2, asin, sqrt, cos and sin; the array forms of one attitude
    call math's too (protocol/frames.py _zyx_angles), numpy's where they are vectorised. numpy's
    are libm's to the bit on hosts without AVX-512 and within one ulp on all (tests/float_bits.py)."""
    rng = np.random.default_rng(16)
    for x, y in zip(rng.normal(size=20000) * 3.0, rng.normal(size=20000)):
        x, y = float(x), float(y)
        c = min(max(x / 3.0, -1.0), 1.0)
        assert same_or_within_ulps([math.atan2(x, y), math.asin(c), math.sqrt(abs(x)), math.cos(x), math.sin(x)],
                                   [np.arctan2(x, y), np.arcsin(c), np.sqrt(abs(x)), np.cos(x), np.sin(x)], ulps=1), x
        assert bits([math.sqrt(abs(x))]) == bits([np.sqrt(abs(x))]), x  # correctly rounded in both


def test_rotation_zyx_matches_numpy_trig():
    rng = np.random.default_rng(17)
    for z, y, x in rng.normal(size=(3000, 3)) * 2.0:
        ref = _rz_np(z) @ _ry_np(y) @ _rx_np(x)
        assert bits(F.rotation_zyx(z, y, x).ravel()) == bits(ref.ravel())


def _rx_np(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _ry_np(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def _rz_np(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
