"""Tests of protocol/geodesy.py: WGS-84 local tangent plane conversions about a home."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from protocol import geodesy as geo
from tests.float_bits import same_geodetic

homes = st.builds(
    geo.Home,
    lat_deg=st.floats(-90.0, 90.0),
    lon_deg=st.floats(-180.0, 180.0),
    alt_m=st.floats(-400.0, 9000.0),
)
# offsets within a 10 km box, altitude within the rig's envelope and then some
offsets = hnp.arrays(
    np.float64,
    3,
    elements=st.floats(-7000.0, 7000.0, allow_nan=False),
).map(lambda v: np.array([v[0], v[1], v[2] / 7.0]))
MM = 1e-3


def _haversine_m(lat1, lon1, lat2, lon2, radius_m):
    p1, p2 = math.radians(lat1), math.radians(lat2)
    dp, dl = p2 - p1, math.radians(lon2 - lon1)
    a = math.sin(dp / 2) ** 2 + math.cos(p1) * math.cos(p2) * math.sin(dl / 2) ** 2
    return 2 * radius_m * math.asin(math.sqrt(a))


# ----------------------------------------------------------------------------- Home


@pytest.mark.parametrize(
    "kwargs, field",
    [
        (dict(lat_deg=90.5, lon_deg=0.0), "lat_deg"),
        (dict(lat_deg=-91.0, lon_deg=0.0), "lat_deg"),
        (dict(lat_deg=0.0, lon_deg=180.01), "lon_deg"),
        (dict(lat_deg=0.0, lon_deg=-200.0), "lon_deg"),
        (dict(lat_deg=math.nan, lon_deg=0.0), "lat_deg"),
        (dict(lat_deg=0.0, lon_deg=0.0, alt_m=math.inf), "alt_m"),
        (dict(lat_deg="47", lon_deg=0.0), "lat_deg"),
        (dict(lat_deg=0.0, lon_deg=True), "lon_deg"),
    ],
)
def test_home_validation_names_the_field(kwargs, field):
    with pytest.raises(ValueError, match=f"Home.{field}"):
        geo.Home(**kwargs)


def test_home_accepts_the_bounds():
    geo.Home(90.0, 180.0, 0.0)
    geo.Home(-90.0, -180.0, -100.0)
    assert geo.Home(1, 2).alt_m == 0.0


# ----------------------------------------------------------------------------- ECEF


def test_ecef_known_points():
    np.testing.assert_allclose(geo.geodetic_to_ecef(0.0, 0.0, 0.0), [geo.WGS84_A_M, 0, 0], atol=1e-9)
    np.testing.assert_allclose(geo.geodetic_to_ecef(0.0, 90.0, 100.0), [0, geo.WGS84_A_M + 100, 0], atol=1e-9)
    np.testing.assert_allclose(geo.geodetic_to_ecef(90.0, 0.0, 0.0), [0, 0, geo.WGS84_B_M], atol=1e-9)
    lat, lon, alt = geo.ecef_to_geodetic([0.0, 0.0, -geo.WGS84_B_M - 5.0])
    assert (lat, alt) == (pytest.approx(-90.0), pytest.approx(5.0, abs=1e-9))
    assert geo.WGS84_B_M == pytest.approx(6356752.314245, abs=1e-6)  # WGS-84 semi-minor axis


@given(
    st.floats(-90.0, 90.0), st.floats(-180.0, 180.0), st.floats(-1000.0, 50000.0)
)
def test_geodetic_ecef_roundtrip(lat, lon, alt):
    lat2, lon2, alt2 = geo.ecef_to_geodetic(geo.geodetic_to_ecef(lat, lon, alt))
    back = geo.geodetic_to_ecef(lat2, lon2, alt2)
    np.testing.assert_allclose(back, geo.geodetic_to_ecef(lat, lon, alt), rtol=0, atol=1e-6)
    assert lat2 == pytest.approx(lat, abs=1e-10)
    assert alt2 == pytest.approx(alt, abs=1e-6)
    if abs(lat) < 89.999:
        assert math.remainder(lon2 - lon, 360.0) == pytest.approx(0.0, abs=1e-9)


@given(st.floats(-89.0, 89.0), st.floats(-180.0, 180.0))
def test_enu_rotation_is_orthonormal_with_up_along_the_normal(lat, lon):
    r = geo.ecef_to_enu_rotation(lat, lon)
    np.testing.assert_allclose(r @ r.T, np.eye(3), atol=1e-14)
    assert np.linalg.det(r) == pytest.approx(1.0)
    up = geo.geodetic_to_ecef(lat, lon, 1.0) - geo.geodetic_to_ecef(lat, lon, 0.0)
    np.testing.assert_allclose(r[2], up, atol=1e-8)
    north = geo.geodetic_to_ecef(lat + 1e-6, lon, 0.0) - geo.geodetic_to_ecef(lat, lon, 0.0)
    assert north @ r[1] > 0.999 * np.linalg.norm(north)


# ----------------------------------------------------------------------------- local <-> global


@settings(max_examples=300)
@given(homes, offsets)
def test_local_enu_roundtrip_within_a_millimetre(home, enu):
    lat, lon, alt = geo.local_enu_to_global(home, enu)
    assert all(isinstance(x, float) for x in (lat, lon, alt))
    back = geo.global_to_local_enu(home, lat, lon, alt)
    assert np.abs(back - enu).max() < MM


@settings(max_examples=100)
@given(homes, hnp.arrays(np.float64, (5, 3), elements=st.floats(-5000.0, 5000.0)))
def test_local_ned_roundtrip_batch(home, ned):
    lat, lon, alt = geo.local_ned_to_global(home, ned)
    assert lat.shape == lon.shape == alt.shape == (5,)
    back = geo.global_to_local_ned(home, lat, lon, alt)
    assert back.shape == (5, 3)
    assert np.abs(back - ned).max() < MM


@given(homes, offsets)
def test_ned_is_enu_permuted(home, enu):
    a = geo.local_enu_to_global(home, enu)
    b = geo.local_ned_to_global(home, [enu[1], enu[0], -enu[2]])
    np.testing.assert_allclose(a, b, rtol=0, atol=1e-12)


@given(homes)
def test_home_maps_to_origin(home):
    np.testing.assert_allclose(
        geo.global_to_local_enu(home, home.lat_deg, home.lon_deg, home.alt_m), 0.0, atol=1e-9
    )
    lat, lon, alt = geo.local_enu_to_global(home, [0.0, 0.0, 0.0])
    assert lat == pytest.approx(home.lat_deg, abs=1e-12)
    assert alt == pytest.approx(home.alt_m, abs=1e-6)


def test_known_directions():
    home = geo.Home(47.0, 8.0, 500.0)
    lat, lon, alt = geo.local_enu_to_global(home, [0.0, 1000.0, 0.0])
    assert lat > home.lat_deg and lon == pytest.approx(8.0, abs=1e-12)
    lat, lon, alt = geo.local_enu_to_global(home, [1000.0, 0.0, 0.0])
    assert lon > home.lon_deg
    _, _, alt = geo.local_ned_to_global(home, [0.0, 0.0, -8.0])  # 8 m up (paper Z = 8 m)
    assert alt == pytest.approx(508.0, abs=1e-6)


@settings(max_examples=200)
@given(
    st.floats(-85.0, 85.0),
    st.floats(-180.0, 180.0),
    st.floats(0.0, 2 * math.pi),
    st.floats(1.0, 10000.0),
)
def test_horizontal_offsets_match_haversine(lat0, lon0, bearing, dist):
    """The sphere is not the ellipsoid: radii of curvature differ from the mean radius by
    < 0.6 %; over 10 km the tangent plane departs from the surface by < 8 m (negligible)."""
    home = geo.Home(lat0, lon0, 0.0)
    enu = [dist * math.sin(bearing), dist * math.cos(bearing), 0.0]
    lat, lon, _ = geo.local_enu_to_global(home, enu)
    d = _haversine_m(lat0, lon0, lat, lon, 6371008.8)
    assert d == pytest.approx(dist, rel=0.006)


@given(st.floats(-85.0, 85.0), st.floats(-180.0, 180.0), st.floats(-100.0, 100.0), st.floats(-100.0, 100.0))
def test_small_offsets_match_radii_of_curvature(lat0, lon0, east, north):
    """To first order dn = M dlat and de = N cos(lat) dlon, with the WGS-84 meridian
    radius M = a (1 - e2) / w^3 and prime-vertical radius N = a / w, w = sqrt(1 - e2 sin^2).
    The second-order terms (e^2 tan(lat) / 2N north, e n tan(lat) / N east) are bounded by
    the tolerance; a spherical radius would be off by ~0.3 % (0.3 m at 100 m)."""
    home = geo.Home(lat0, lon0, 0.0)
    lat, lon, _ = geo.local_enu_to_global(home, [east, north, 0.0])
    phi = math.radians(lat0)
    w = math.sqrt(1 - geo.WGS84_E2 * math.sin(phi) ** 2)
    m_radius, n_radius = geo.WGS84_A_M * (1 - geo.WGS84_E2) / w**3, geo.WGS84_A_M / w
    tol = 2.0 * (east**2 + abs(east * north) + north**2) * (1.0 + abs(math.tan(phi))) / geo.WGS84_A_M
    assert math.radians(lat - lat0) * m_radius == pytest.approx(north, abs=tol + 1e-7)
    dlon = math.radians(math.remainder(lon - lon0, 360.0))
    assert dlon * n_radius * math.cos(phi) == pytest.approx(east, abs=tol + 1e-7)


@given(st.floats(-89.0, 89.0), st.floats(-180.0, 180.0), st.floats(-400.0, 5000.0),
       hnp.arrays(np.float64, 3, elements=st.floats(-5000.0, 5000.0)))
def test_tangent_plane_matches_local_enu_to_global(lat, lon, alt, enu):
    home = geo.Home(lat, lon, alt)
    got = geo.TangentPlane(home).to_global(*enu)
    want = geo.local_enu_to_global(home, enu)
    assert abs(got[0] - want[0]) < 1e-11 and abs(got[2] - want[2]) < 1e-6
    assert abs(math.remainder(got[1] - want[1], 360.0)) < 1e-11


@settings(max_examples=500)
@given(homes, offsets)
def test_scalar_ecef_to_geodetic_matches_numpy(home, enu):
    """The served rig's scalar conversion gives numpy's numbers: to the bit where numpy calls libm
    (tests/float_bits.py), else within 4 ulps (the height: of the Earth's radius, the size of the
    terms it is the difference of)."""
    ecef = geo.geodetic_to_ecef(home.lat_deg, home.lon_deg, home.alt_m) + np.asarray(enu) @ geo.ecef_to_enu_rotation(
        home.lat_deg, home.lon_deg)
    assert same_geodetic(geo.ecef_to_geodetic_xyz(*ecef.tolist()), geo.ecef_to_geodetic(ecef))


def test_scalar_ecef_to_geodetic_matches_numpy_on_many_points():
    rng = np.random.default_rng(11)
    for home in (geo.Home(35.7, 51.4, 1200.0), geo.Home(-33.9, 151.2, 10.0), geo.Home(89.9, -179.0, -50.0)):
        origin = geo.geodetic_to_ecef(home.lat_deg, home.lon_deg, home.alt_m)
        r = geo.ecef_to_enu_rotation(home.lat_deg, home.lon_deg)
        for _ in range(3000):
            ecef = origin + rng.normal(0.0, 10.0 ** float(rng.integers(-2, 5)), 3) @ r
            assert same_geodetic(geo.ecef_to_geodetic_xyz(*ecef.tolist()), geo.ecef_to_geodetic(ecef))
