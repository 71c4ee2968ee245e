"""The bench supply's side of the motors: the current the four motor drivers draw.

Where it acts: telemetry only (SYS_STATUS / BATTERY_STATUS); the motors' thrust follows
Eq. 40 from the commanded voltage whatever this model says, as on the rig, whose drivers
are fed by a 0..15 V bench supply (Fig. 11) that holds its voltage.

Model (one function, :func:`supply_current`), from what the paper gives of the hardware
(Sec. 4, Fig. 8: "four 750 KV brushless DC motors with associated 6 amperes drivers") and
the rotor model (Eq. 38-39):

* each rotor's reaction moment is ``M_i = (kM/kF) F_i`` (Eq. 39 over Eq. 38), which the motor
  balances with its current: ``I_i = M_i / K_t``, where a BLDC's torque constant equals its
  back-EMF constant, ``K_t = 60 / (2 pi KV)`` N m/A for KV in rpm/V (the standard DC-motor
  relation; 750 KV gives 0.0127 N m/A);
* the driver switches the supply onto the motor for the fraction ``V_i / V_supply`` of the
  time (an ideal, lossless chopper), so the supply delivers ``I_i V_i / V_supply``.

No-load current, winding and driver losses are left out (the paper gives none of them):
the figure is a lower bound of what the bench supply's ammeter would show. At hover
(5.5 N a motor, 11.7 V commands) it gives about 6.9 A a motor, 21 A from the supply.
"""

from __future__ import annotations

import math

import numpy as np

KV_RPM_PER_V = 750.0  # Sec. 4: "four 750 KV brushless DC motors"


def torque_constant(kv_rpm_per_v: float) -> float:
    """K_t (N m/A) of a BLDC motor of ``kv_rpm_per_v``: equal to its back-EMF constant in SI."""
    return 60.0 / (2.0 * math.pi * kv_rpm_per_v)


def supply_current(thrusts_n, voltages_v, supply_v: float, km_over_kf: float,
                   kv_rpm_per_v: float = KV_RPM_PER_V) -> np.ndarray:
    """Current (A) the bench supply delivers for motor thrusts ``thrusts_n`` (N) and commanded
    voltages ``voltages_v`` (V), summed over the last axis (shape (..., 4) -> (...)).

    Per motor ``I_i = (kM/kF) F_i / K_t`` (Eq. 39, 750 KV, see the module doc) drawn for the
    duty ``V_i / V_supply`` of an ideal chopper driver."""
    f = np.clip(np.asarray(thrusts_n, dtype=float), 0.0, None)
    v = np.clip(np.asarray(voltages_v, dtype=float), 0.0, supply_v)
    motor_current = km_over_kf * f / torque_constant(kv_rpm_per_v)
    return np.sum(motor_current * v, axis=-1) / supply_v


#: Up to this many rows numpy sums a short reduction front to back, and
#: :func:`supply_current_sum` reproduces it bit for bit; longer ones use numpy's pairwise sum.
SEQUENTIAL_SUM_MAX = 7


def supply_current_sum(thrust_rows: list, voltage_rows: list, supply_v: float, km_over_kf: float,
                       kv_rpm_per_v: float = KV_RPM_PER_V) -> float:
    """``float(np.sum(supply_current(thrust_rows, voltage_rows, ...)))`` for at most
    :data:`SEQUENTIAL_SUM_MAX` rows of four motors (lists of floats), in plain Python.

    The same operations in the same order as the numpy expression (clip, ``kM/kF F / K_t``,
    times the clipped voltage, the four motors summed front to back, divided by the supply
    voltage, the rows summed front to back), so the result is bit-identical; numpy's calls
    cost ~20 us a chunk of the served rig, this ~2 us (a test compares the two)."""
    kt = torque_constant(kv_rpm_per_v)
    total = 0.0
    for i, (fs, vs) in enumerate(zip(thrust_rows, voltage_rows)):
        row = 0.0
        for j in range(4):
            f = fs[j]
            if f < 0.0:  # np.clip(f, 0, None): NaN stays NaN
                f = 0.0
            v = vs[j]
            if v < 0.0:
                v = 0.0
            elif v > supply_v:
                v = supply_v
            term = km_over_kf * f / kt * v
            row = term if j == 0 else row + term
        row /= supply_v
        total = row if i == 0 else total + row
    return total
