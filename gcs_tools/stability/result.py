"""The outcome of the FLC stability analysis (Eq. 16-32) and its JSON form."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from gcs_tools.stability import paper_values
from gcs_tools.stability.form_check import FormResult
from gcs_tools.stability.paper_check import PaperPCheck
from gcs_tools.stability.planes import AxisPlane
from gcs_tools.stability.settings import Settings
from gcs_tools.stability.ultimate_bound import UltimateBound


def _mat(a) -> list | None:
    if a is None:
        return None
    a = np.asarray(a)
    if np.iscomplexobj(a):
        return [[float(z.real), float(z.imag)] for z in a.ravel()] if a.ndim == 1 else None
    return a.astype(float).tolist()


def _complex(z: complex) -> list[float]:
    return [float(z.real), float(z.imag)]


def _form_dict(f: FormResult) -> dict[str, Any]:
    return {
        "form": f.form,
        "verdict": f.verdict,
        "F": _mat(f.F),
        "F_eigenvalues": [_complex(z) for z in f.f_eigenvalues],
        "sdp": {
            "solver": f.sdp.solver,
            "status": f.sdp.status,
            "P": _mat(f.sdp.P),
            "P_eigenvalues": _mat(f.sdp.p_eigenvalues),
            "lmi_max_eigenvalue": f.sdp.lmi_max_eigenvalue,
            "verified": f.sdp.verified,
        },
        "scipy": {
            "feasible": f.scipy.feasible,
            "hurwitz": f.scipy.hurwitz,
            "P0": _mat(f.scipy.P0),
            "P0_eigenvalues": _mat(f.scipy.p0_eigenvalues),
            "residual": f.scipy.residual,
        },
        "unstable_modes": [
            {"axis": m.axis, "eigenvalue": _complex(m.eigenvalue), "vector": [_complex(z) for z in m.vector],
             "c1": m.c1, "c0": m.c0, "reason": m.reason}
            for m in f.unstable
        ],
        "explanation": f.explanation(),
    }


@dataclass(frozen=True)
class StabilityResult:
    """Everything :func:`gcs_tools.stability.analyse` computed; ``feasible`` is the derived LMI's verdict."""

    airframe: str
    inertia: tuple[float, float, float]  # Ixx, Iyy, Izz, kg m^2
    flc_geometry: str
    flc_r: tuple[float, ...]
    settings: Settings
    planes: tuple[AxisPlane, AxisPlane, AxisPlane]
    kappa: np.ndarray  # 3 x 6, Eq. 20 (N m/rad, N m s/rad)
    h: np.ndarray  # 6 x 3, Eq. A10
    derived: FormResult  # A^T P + P A < 0 with A = N - h kappa (from Eq. 19-25)
    printed: FormResult  # Eq. 32 as printed
    paper_derived: FormResult  # the paper's kappa (Eq. 42), derived form
    paper_printed: FormResult  # the paper's kappa, printed form
    paper_p: PaperPCheck  # the paper's P (Eq. 43) checked
    bound: UltimateBound | None  # Eq. 31, None when the derived LMI is not feasible

    @property
    def feasible(self) -> bool:
        return self.derived.feasible

    @property
    def P(self) -> np.ndarray | None:
        return self.derived.sdp.P

    def to_markdown(self) -> str:
        from gcs_tools.stability.report import markdown

        return markdown(self)

    def to_dict(self) -> dict[str, Any]:
        b = self.bound
        return {
            "feasible": self.feasible,
            "airframe": self.airframe,
            "inertia_kg_m2": list(self.inertia),
            "flc": {"geometry": self.flc_geometry, "r": list(self.flc_r)},
            "settings": self.settings.to_dict(),
            "planes": [
                {"axis": p.axis, "kp": p.kp, "kd": p.kd, "e_max_rad": p.e_max, "de_max_rad_s": p.de_max,
                 "residual_max": p.residual_max, "d_min": p.d_min, "d_negative_fraction": p.d_negative_fraction,
                 "grid_points": p.grid_points}
                for p in self.planes
            ],
            "kappa": _mat(self.kappa),
            "h": _mat(self.h),
            "lmi": {"derived": _form_dict(self.derived), "printed": _form_dict(self.printed)},
            "paper": {
                "kappa_eq42": _mat(paper_values.kappa_matrix()),
                "P_eq43": [list(r) for r in paper_values.P_PRINTED],
                "P_eigenvalues_eq43": list(paper_values.P_EIGENVALUES),
                "lmi_with_paper_kappa": {"derived": _form_dict(self.paper_derived),
                                         "printed": _form_dict(self.paper_printed)},
                "paper_P_check": {
                    "symmetric": self.paper_p.symmetric,
                    "eigenvalues_printed_matrix": _mat(self.paper_p.eig_printed),
                    "eigenvalues_symmetric_part": _mat(self.paper_p.eig_symmetric_part),
                    "positive_definite": self.paper_p.positive_definite,
                    "lmi_max_eigenvalue": dict(self.paper_p.lmi_max_eigenvalue),
                },
            },
            "ultimate_bound": None if b is None else {
                "g_max": _mat(b.g_max), "g_max_norm": b.g_max_norm, "d_star_norm": b.d_star_norm,
                "sigma_max_P": b.sigma_max_P, "sigma_max_Ph": b.sigma_max_Ph, "sigma_min_H": b.sigma_min_H,
                "r2_eq31": b.r2, "r2_derived": b.r2_derived, "ultimate_bound": b.ultimate_bound,
                "region_radius": b.region_radius, "inside_region": b.inside_region,
            },
        }
