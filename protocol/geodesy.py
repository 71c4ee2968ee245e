"""Local metres <-> geodetic latitude/longitude/altitude about a home point (WGS-84).

Implements the local tangent plane at ``home``: geodetic -> ECEF (closed form),
ECEF -> geodetic (Bowring's fixed-point iteration in the pole-safe form
lat = atan2(z + e^2 N sin(lat), p), h = p cos(lat) + (z + e^2 N sin(lat)) sin(lat) - N,
iterated to convergence), and ECEF <-> ENU by the rotation with rows
east = (-sin lon, cos lon, 0), north = (-sin lat cos lon, -sin lat sin lon, cos lat),
up = (cos lat cos lon, cos lat sin lon, sin lat). NED is ENU permuted (protocol/frames.py).
Constants: WGS-84 a = 6378137 m, 1/f = 298.257223563 (NIMA TR8350.2).

Altitudes are heights above the WGS-84 ellipsoid. The emulator has no geoid model: a home
altitude given as AMSL is treated as ellipsoidal, which shifts all points together and
keeps local <-> global conversions mutually exact.

Every (3,) input gives floats; every (N, 3) input (or arrays of lat/lon/alt) gives arrays.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from protocol.frames import enu_to_ned, ned_to_enu

WGS84_A_M = 6378137.0
WGS84_F = 1.0 / 298.257223563
WGS84_E2 = WGS84_F * (2.0 - WGS84_F)
WGS84_B_M = WGS84_A_M * (1.0 - WGS84_F)
_MAX_ITERATIONS = 10


@dataclass(frozen=True)
class Home:
    """Origin of the local frame: geodetic latitude, longitude (deg) and ellipsoidal
    altitude (m)."""

    lat_deg: float
    lon_deg: float
    alt_m: float = 0.0

    def __post_init__(self) -> None:
        for name, lo, hi in (
            ("lat_deg", -90.0, 90.0),
            ("lon_deg", -180.0, 180.0),
            ("alt_m", -math.inf, math.inf),
        ):
            value = getattr(self, name)
            if not (_is_real(value) and math.isfinite(value) and lo <= value <= hi):
                what = f"a number in [{lo:g}, {hi:g}]" if math.isfinite(lo) else "a finite number"
                raise ValueError(f"Home.{name} must be {what}, got {value!r}")


def _is_real(value) -> bool:
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool)


def _out(x: np.ndarray):
    return float(x) if np.ndim(x) == 0 else x


def geodetic_to_ecef(lat_deg, lon_deg, alt_m) -> np.ndarray:
    """ECEF position(s) (m), shape (..., 3), of geodetic lat/lon (deg) and height (m)."""
    lat = np.radians(np.asarray(lat_deg, dtype=float))
    lon = np.radians(np.asarray(lon_deg, dtype=float))
    h = np.asarray(alt_m, dtype=float)
    sin_lat = np.sin(lat)
    n = WGS84_A_M / np.sqrt(1.0 - WGS84_E2 * sin_lat * sin_lat)
    x = (n + h) * np.cos(lat) * np.cos(lon)
    y = (n + h) * np.cos(lat) * np.sin(lon)
    z = (n * (1.0 - WGS84_E2) + h) * sin_lat
    return np.stack(np.broadcast_arrays(x, y, z), axis=-1)


def ecef_to_geodetic(ecef):
    """(lat_deg, lon_deg, alt_m) of ECEF position(s) (m), shape (3,) or (N, 3)."""
    p_ecef = np.asarray(ecef, dtype=float)
    x, y, z = p_ecef[..., 0], p_ecef[..., 1], p_ecef[..., 2]
    p = np.hypot(x, y)
    lat = np.arctan2(z, p * (1.0 - WGS84_E2))
    for _ in range(_MAX_ITERATIONS):
        sin_lat = np.sin(lat)
        n = WGS84_A_M / np.sqrt(1.0 - WGS84_E2 * sin_lat * sin_lat)
        new_lat = np.arctan2(z + WGS84_E2 * n * sin_lat, p)
        converged = np.all(np.abs(new_lat - lat) < 1e-15)
        lat = new_lat
        if converged:
            break
    sin_lat, cos_lat = np.sin(lat), np.cos(lat)
    n = WGS84_A_M / np.sqrt(1.0 - WGS84_E2 * sin_lat * sin_lat)
    h = p * cos_lat + (z + WGS84_E2 * n * sin_lat) * sin_lat - n
    return _out(np.degrees(lat)), _out(np.degrees(np.arctan2(y, x))), _out(h)


def ecef_to_geodetic_xyz(x: float, y: float, z: float) -> tuple[float, float, float]:
    """:func:`ecef_to_geodetic` of one ECEF point given as three floats, in scalar math: the
    same operations in the same order, bit-identical where numpy's ``arctan2`` is libm's (hosts
    without AVX-512; with it numpy runs its own SIMD kernel and the two differ by an ulp or two,
    docs/explanation/conventions.md; the horizontal distance stays numpy's ``hypot``, which Python's
    ``math.hypot`` does not always match to the last bit; a test compares the two), about
    15x faster than numpy on 0-d arrays (the served rig converts positions for several
    messages a simulated second)."""
    p = float(np.hypot(x, y))
    lat = math.atan2(z, p * (1.0 - WGS84_E2))
    for _ in range(_MAX_ITERATIONS):
        sin_lat = math.sin(lat)
        n = WGS84_A_M / math.sqrt(1.0 - WGS84_E2 * sin_lat * sin_lat)
        new_lat = math.atan2(z + WGS84_E2 * n * sin_lat, p)
        converged = abs(new_lat - lat) < 1e-15
        lat = new_lat
        if converged:
            break
    sin_lat, cos_lat = math.sin(lat), math.cos(lat)
    n = WGS84_A_M / math.sqrt(1.0 - WGS84_E2 * sin_lat * sin_lat)
    h = p * cos_lat + (z + WGS84_E2 * n * sin_lat) * sin_lat - n
    return math.degrees(lat), math.degrees(math.atan2(y, x)), h


def ecef_to_enu_rotation(lat_deg: float, lon_deg: float) -> np.ndarray:
    """Rotation R_ENU_ECEF at a geodetic point: rows are east, north, up in ECEF."""
    lat, lon = math.radians(lat_deg), math.radians(lon_deg)
    sl, cl, so, co = math.sin(lat), math.cos(lat), math.sin(lon), math.cos(lon)
    return np.array([[-so, co, 0.0], [-sl * co, -sl * so, cl], [cl * co, cl * so, sl]])


def local_enu_to_global(home: Home, enu):
    """(lat_deg, lon_deg, alt_m) of local ENU offset(s) (m) from ``home``."""
    enu = np.asarray(enu, dtype=float)
    r = ecef_to_enu_rotation(home.lat_deg, home.lon_deg)
    ecef = geodetic_to_ecef(home.lat_deg, home.lon_deg, home.alt_m) + enu @ r
    return ecef_to_geodetic(ecef)


def global_to_local_enu(home: Home, lat_deg, lon_deg, alt_m) -> np.ndarray:
    """Local ENU offset(s) (m) from ``home`` of geodetic point(s); shape (3,) or (N, 3)."""
    r = ecef_to_enu_rotation(home.lat_deg, home.lon_deg)
    delta = geodetic_to_ecef(lat_deg, lon_deg, alt_m) - geodetic_to_ecef(
        home.lat_deg, home.lon_deg, home.alt_m
    )
    return delta @ r.T


def local_ned_to_global(home: Home, ned):
    """(lat_deg, lon_deg, alt_m) of local NED offset(s) (m) from ``home``."""
    return local_enu_to_global(home, ned_to_enu(ned))


def global_to_local_ned(home: Home, lat_deg, lon_deg, alt_m) -> np.ndarray:
    """Local NED offset(s) (m) from ``home`` of geodetic point(s); shape (3,) or (N, 3)."""
    return enu_to_ned(global_to_local_enu(home, lat_deg, lon_deg, alt_m))


class TangentPlane:
    """:func:`local_enu_to_global` for one home, one point at a time, in plain floats, bit for
    bit where :func:`ecef_to_geodetic_xyz` is: the home's frame computed once; ``origin + enu @ r`` summed as numpy's vector-matrix
    product does (the products in order from +0), then :func:`ecef_to_geodetic_xyz`. A few
    microseconds instead of tens: for messages sent every simulation step or chunk."""

    def __init__(self, home: Home):
        self.home = home
        self._origin = tuple(geodetic_to_ecef(home.lat_deg, home.lon_deg, home.alt_m).tolist())
        self._rows = tuple(tuple(row) for row in ecef_to_enu_rotation(home.lat_deg, home.lon_deg).tolist())

    def to_global(self, east: float, north: float, up: float) -> tuple[float, float, float]:
        """(lat_deg, lon_deg, alt_m) of a local ENU offset (m) from the home."""
        (e0, e1, e2), (n0, n1, n2), (u0, u1, u2) = self._rows
        o0, o1, o2 = self._origin
        return ecef_to_geodetic_xyz(o0 + (((0.0 + east * e0) + north * n0) + up * u0),
                                    o1 + (((0.0 + east * e1) + north * n1) + up * u1),
                                    o2 + (((0.0 + east * e2) + north * n2) + up * u2))


def _ecef_scalar(lat_deg: float, lon_deg: float, alt_m: float) -> tuple[float, float, float]:
    """:func:`geodetic_to_ecef` of one point in ``math`` (deterministic on every host)."""
    lat, lon = math.radians(lat_deg), math.radians(lon_deg)
    sin_lat, cos_lat = math.sin(lat), math.cos(lat)
    n = WGS84_A_M / math.sqrt(1.0 - WGS84_E2 * sin_lat * sin_lat)
    return ((n + alt_m) * cos_lat * math.cos(lon), (n + alt_m) * cos_lat * math.sin(lon),
            (n * (1.0 - WGS84_E2) + alt_m) * sin_lat)


def surface_offset(home: Home, lat_deg: float, lon_deg: float) -> tuple[float, float, float]:
    """(distance_m, east_m, north_m): how far a point at latitude/longitude is from ``home``
    horizontally, along the WGS-84 ellipsoid at home's altitude, whatever the two altitudes.

    ``distance_m`` is the arc of the normal section from home towards the point, 2 R asin(c / 2R)
    of the chord c between the two points at home's altitude, with Euler's radius of curvature
    R = M N / (N cos^2 a + M sin^2 a) (meridian M and prime-vertical N radii at home, plus home's
    altitude) of the azimuth a; within millimetres of the geodesic over tens of kilometres and
    equal to the tangent plane's horizontal distance near home. ``east_m``, ``north_m``: the
    chord's components along home's east and north (the direction of the offset). The altitude
    of neither point enters: the Earth's curvature (d^2 / 2R, 196 m at 50 km) is not read as a
    height. Scalar ``math`` only, so the figure is the same on every host."""
    h = home.alt_m
    x0, y0, z0 = _ecef_scalar(home.lat_deg, home.lon_deg, h)
    x1, y1, z1 = _ecef_scalar(float(lat_deg), float(lon_deg), h)
    dx, dy, dz = x1 - x0, y1 - y0, z1 - z0
    lat, lon = math.radians(home.lat_deg), math.radians(home.lon_deg)
    sl, cl, so, co = math.sin(lat), math.cos(lat), math.sin(lon), math.cos(lon)
    east = -so * dx + co * dy
    north = -sl * co * dx - sl * so * dy + cl * dz
    chord = math.sqrt(dx * dx + dy * dy + dz * dz)
    if chord == 0.0:
        return 0.0, 0.0, 0.0
    w = 1.0 - WGS84_E2 * sl * sl
    m = WGS84_A_M * (1.0 - WGS84_E2) / (w * math.sqrt(w)) + h
    n = WGS84_A_M / math.sqrt(w) + h
    az = math.atan2(east, north)
    ca, sa = math.cos(az), math.sin(az)
    radius = m * n / (n * ca * ca + m * sa * sa)
    return 2.0 * radius * math.asin(min(1.0, chord / (2.0 * radius))), east, north
