"""``analyse``: the FLC stability analysis of Eq. 16-32 for a rig configuration.

Steps, each in its own module:

1. Eq. 16-17, 20 (:mod:`.planes`): fit ``u_est = kp e + kd de`` to the FLC surface the rig
   flies (its axes from :func:`rig_emulator.simulation.params.control_params`), per axis.
2. Eq. 18-24, A10 (:mod:`.error_dynamics`): ``h`` from the inertia, ``A = N - h kappa``.
3. Eq. 32 (:mod:`.form_check`): the LMI solved with cvxpy and cross-checked with scipy, in
   the form derived from Eq. 19-25 and in the form printed; also for the paper's kappa
   (Eq. 42), and the paper's P (Eq. 43) checked (:mod:`.paper_check`).
4. Eq. 27-31 (:mod:`.ultimate_bound`): R2 from the derived LMI's P, ``g_max`` of the
   gyroscopic terms and the plane-fit residual bound.
"""

from __future__ import annotations

import numpy as np

from gcs_tools.stability import paper_values
from gcs_tools.stability.error_dynamics import dynamics, g_max, h_matrix
from gcs_tools.stability.form_check import check_form
from gcs_tools.stability.paper_check import check_paper_p
from gcs_tools.stability.planes import AXES, fit_axis, kappa_of
from gcs_tools.stability.result import StabilityResult
from gcs_tools.stability.settings import Settings, load_settings
from gcs_tools.stability.ultimate_bound import ultimate_bound


def analyse(config=None, settings: Settings | None = None) -> StabilityResult:
    """Stability analysis of the configured FLC attitude gains (Eq. 16-32).

    ``config``: a :class:`~rig_emulator.config.loader.RigConfig` (default: the rig preset,
    ``load_config()``). ``settings``: a :class:`~gcs_tools.stability.settings.Settings`
    (default: ``settings.toml``). Raises :class:`~gcs_tools.stability.lmi.AnalysisUnavailable`
    when cvxpy or the solver is missing.
    """
    from rig_emulator.config.loader import load_config
    from rig_emulator.simulation.params import control_params

    cfg = load_config() if config is None else config
    st = load_settings() if settings is None else settings
    cp = control_params(cfg)
    planes = tuple(
        fit_axis(name, axis, st.fit_scale, st.fit_grid_points)
        for name, axis in zip(AXES, (cp.flc_phi, cp.flc_theta, cp.flc_psi))
    )
    kappa = kappa_of(planes)
    h = h_matrix(cp.ixx, cp.iyy, cp.izz)

    def form(name, gains):
        return check_form(name, h, gains, st)

    derived = form("derived", kappa)
    bound = None
    if derived.feasible:
        gm = g_max(cp.ixx, cp.iyy, cp.izz, st.desired_rate_max, [p.de_max for p in planes])
        region = min(min(p.e_max, p.de_max) for p in planes)
        bound = ultimate_bound(
            derived.sdp.P, dynamics("derived", h, kappa), h, gm, [p.residual_max for p in planes], region
        )
    paper_kappa = paper_values.kappa_matrix()
    return StabilityResult(
        airframe=str(cfg["airframe.name"]),
        inertia=(float(cp.ixx), float(cp.iyy), float(cp.izz)),
        flc_geometry=str(cfg["flc.geometry"]),
        flc_r=tuple(float(x) for x in cfg["flc.r"]),
        settings=st,
        planes=planes,
        kappa=kappa,
        h=h,
        derived=derived,
        printed=form("printed", kappa),
        paper_derived=form("derived", paper_kappa),
        paper_printed=form("printed", paper_kappa),
        paper_p=check_paper_p(h),
        bound=bound,
    )


def analyse_gains(kappa, inertia, settings: Settings | None = None):
    """Eq. 32 for given gains and inertia alone: ``(derived, printed)`` :class:`FormResult` pair.

    ``kappa`` is a 3 x 6 matrix of Eq. 20 (N m/rad, N m s/rad), ``inertia`` ``(Ixx, Iyy, Izz)``.
    """
    st = load_settings() if settings is None else settings
    h = h_matrix(*inertia)
    kappa = np.asarray(kappa, dtype=np.float64)
    return tuple(check_form(f, h, kappa, st) for f in ("derived", "printed"))
