"""The experiments of the reproduction, in report order (``rig-gcs reproduce --only NAME``).

Each is a module with ``NAME``, ``TITLE``, ``PAPER``, ``jobs(ctx)``, optionally ``live(ctx)``
and ``analyse(ctx, results, live)`` (see :mod:`gcs_tools.reproduce.experiment`).
"""

from __future__ import annotations

from gcs_tools.reproduce import (exp_altitude, exp_harmonic, exp_helix, exp_masses, exp_rectangle, exp_shocks,
                                 exp_sweep)

EXPERIMENTS = (exp_shocks, exp_harmonic, exp_sweep, exp_masses, exp_helix, exp_altitude, exp_rectangle)
BY_NAME = {e.NAME: e for e in EXPERIMENTS}
STABILITY = "stability"  # the FLC stability analysis section (gcs_tools.stability), not a simulation
NAMES = tuple(BY_NAME) + (STABILITY,)
