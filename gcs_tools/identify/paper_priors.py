"""The paper's physical priors for ``rig-gcs identify --paper`` (``paper_priors.toml``).

The paper says two things in words that bound values its numbers might otherwise pull anywhere:
the joint is "fully lubricated" (Coulomb friction near zero) and Eq. 40 was calibrated on the
same load cells that measure the running thrust (no common thrust bias). Each becomes a Gaussian
prior: the residual ``(value - mean) / sigma`` joins the fit's residual vector (the priors of
:class:`gcs_tools.identify.params.Param`, the same term ``--prior KEY=MEAN+-SIGMA`` adds).
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass, replace
from importlib import resources

PRIORS_FILE = "paper_priors.toml"


@dataclass(frozen=True)
class PaperPrior:
    key: str  # a schema key; it applies to the key and to any element of it (joint.coulomb[0,1])
    mean: float
    sigma: float
    source: str
    where: str = ""  # short: the paper's place and words


def load_priors(text: str | None = None) -> list[PaperPrior]:
    if text is None:
        text = (resources.files("gcs_tools.identify") / PRIORS_FILE).read_text(encoding="utf-8")
    out = []
    for i, p in enumerate(tomllib.loads(text).get("prior", [])):
        try:
            prior = PaperPrior(str(p["key"]), float(p["mean"]), float(p["sigma"]), str(p["source"]),
                               str(p.get("where", "")))
        except (KeyError, TypeError, ValueError) as exc:
            raise ValueError(f"{PRIORS_FILE}: prior[{i}]: needs key, mean, sigma, source ({exc})") from None
        if not prior.sigma > 0:
            raise ValueError(f"{PRIORS_FILE}: {prior.key}: sigma must be > 0")
        out.append(prior)
    return out


def prior_for(param, priors: list[PaperPrior]) -> PaperPrior | None:
    """The paper prior on ``param``'s key (its schema key, so any element of a list key), or None."""
    for p in priors:
        if param.key.base == p.key or param.name == p.key:
            return p
    return None


def apply(params: list, explicit: set | None = None, priors: list[PaperPrior] | None = None) -> tuple[list, list]:
    """(params with the paper's priors attached, the priors applied as ``(param name, PaperPrior)``).
    A parameter that already has a prior, or whose name is in ``explicit`` (given ``--prior``), keeps its own."""
    priors = load_priors() if priors is None else priors
    explicit = explicit or set()
    out, used = [], []
    for par in params:
        pp = prior_for(par, priors)
        if pp is not None and par.prior is None and par.name not in explicit:
            par = replace(par, prior=(pp.mean, pp.sigma))
            used.append((par.name, pp))
        out.append(par)
    return out, used
