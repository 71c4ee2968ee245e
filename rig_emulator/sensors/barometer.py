"""The virtual barometer: static pressure and air temperature at the virtual altitude.

The rig cannot climb: its translation is virtual (Eq. 1), so a barometer on the frame
would read the room's pressure whatever the virtual altitude. A flight stack in the loop
(:mod:`rig_emulator.simulation.lockstep`) needs a barometer that follows the virtual
altitude, so the rig derives one from it with the International Standard Atmosphere's
troposphere (ISO 2533:1975, ICAO Doc 7488; valid below 11 km geopotential height):

``T(h) = T0 - L h``, ``p(h) = p0 (T(h) / T0) ^ (g0 M / (R L))``

with ``h`` the altitude above mean sea level (the ``--home`` altitude plus the virtual
height, geometric taken as geopotential: the difference is 0.03 % at 1 km). Reading: the
barometer is ideal (no noise, offset or lag); the flight stack sees exactly the standard
atmosphere at the virtual altitude, which is also what its own altitude conversion
assumes, so the barometric altitude it computes equals the virtual altitude.
"""

from __future__ import annotations

import math

ISA_P0_PA = 101325.0  # sea-level standard pressure
ISA_T0_K = 288.15  # sea-level standard temperature
ISA_LAPSE_K_PER_M = 0.0065  # troposphere temperature lapse rate
ISA_G0 = 9.80665  # standard gravity
ISA_R = 8.31446  # universal gas constant, J/(mol K)
ISA_M = 0.0289644  # molar mass of dry air, kg/mol
ISA_EXPONENT = ISA_G0 * ISA_M / (ISA_R * ISA_LAPSE_K_PER_M)  # 5.2559
ISA_TROPOPAUSE_M = 11000.0
ISA_FLOOR_M = -500.0
KELVIN_AT_0C = 273.15


def isa_pressure_temperature(altitude_amsl_m: float) -> tuple[float, float]:
    """Static pressure (Pa) and temperature (K) of the standard troposphere at an altitude
    above mean sea level (m). Like a real sensor at the end of its range, the reading
    saturates outside -500 m .. 11 km (a virtual runaway must not stop the rig)."""
    h = min(max(altitude_amsl_m, ISA_FLOOR_M), ISA_TROPOPAUSE_M) if math.isfinite(altitude_amsl_m) else 0.0
    t = ISA_T0_K - ISA_LAPSE_K_PER_M * h
    return ISA_P0_PA * (t / ISA_T0_K) ** ISA_EXPONENT, t


def isa_altitude(pressure_pa: float) -> float:
    """Altitude above mean sea level (m) of a static pressure in the standard troposphere
    (the inverse of :func:`isa_pressure_temperature`)."""
    return ISA_T0_K / ISA_LAPSE_K_PER_M * (1.0 - (pressure_pa / ISA_P0_PA) ** (1.0 / ISA_EXPONENT))
