"""What an identification compares: headless runs built from job templates, reduced to residuals.

A :class:`Problem` holds job templates (:class:`~rig_emulator.sweep.SimJob` with the
experiment's own overrides, e.g. a frequency of the sweep) and turns one parameter point into
the templates' jobs with the fitted parameters' overrides on top (:meth:`Problem.jobs`); its
``evaluate(results)`` (the results in job order) returns the residual vector and named
numbers. Targets are :mod:`gcs_tools.identify.paper` (the paper's numbers) and
:mod:`gcs_tools.identify.tlog_target` (a user's flight logs).

The base configuration of the fit (``--airframe``, ``--config FILE``, ``--set KEY=VALUE``)
goes into every job: configuration files become overrides (the loader's order: presets, then
files, then overrides, is kept), so a job stays a small picklable SimJob that a Dask worker
can run.
"""

from __future__ import annotations

import copy
import dataclasses
import tomllib
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from gcs_tools.errors import UsageError
from gcs_tools.identify.params import Param, overrides_for
from rig_emulator.config.loader import ConfigError, flatten
from rig_emulator.sweep import SimJob


@dataclasses.dataclass(frozen=True)
class Base:
    """The configuration every run of a fit starts from (before the fitted parameters)."""

    airframe: str = "hilms"
    files: tuple = ()  # paths of --config files, in order
    overrides: tuple = ()  # (key, value) of --set, in order

    def flat(self) -> dict:
        """The files' keys then the --set keys, as overrides."""
        out: dict = {}
        for path in self.files:
            p = Path(path)
            try:
                doc = tomllib.loads(p.read_text(encoding="utf-8"))
            except FileNotFoundError:
                raise ConfigError(f"--config {p}: file not found") from None
            except (OSError, UnicodeDecodeError) as exc:
                raise ConfigError(f"--config {p}: cannot read ({exc})") from None
            except tomllib.TOMLDecodeError as exc:
                raise ConfigError(f"--config {p}: not valid TOML ({exc})") from None
            layer = flatten(doc)
            cal = layer.get("sensors.calibration_file")
            if isinstance(cal, str) and cal and not Path(cal).is_absolute():
                layer["sensors.calibration_file"] = str(p.resolve().parent / cal)  # as the loader does
            out.update(layer)
        out.update(dict(self.overrides))
        return out

    def describe(self) -> dict:
        """JSON-able, with the files' contents (a changed file is another fit)."""
        return {"airframe": self.airframe, "files": {str(f): self.flat_file(f) for f in self.files},
                "set": [[k, v] for k, v in self.overrides]}

    @staticmethod
    def flat_file(path) -> dict:
        return Base(files=(path,)).flat()


class Problem:
    """Job templates and a reduction to residuals (subclasses: paper targets, flight logs)."""

    kind = "problem"

    def __init__(self, templates: list[SimJob], base: Base):
        self.base = base
        flat = base.flat()
        self.templates = [dataclasses.replace(t, airframe=base.airframe, overrides={**flat, **dict(t.overrides)})
                          for t in templates]
        self._cfgs: list | None = None

    def configs(self) -> list:
        """Each template's validated configuration (ConfigError naming the job when it is bad)."""
        if self._cfgs is None:
            self._cfgs = [t.config() for t in self.templates]
        return self._cfgs

    def jobs(self, params: list[Param], values: list[float]) -> list[SimJob]:
        out = []
        for t, cfg in zip(self.templates, self.configs()):
            try:
                ov = overrides_for(params, values, cfg)
            except ConfigError as exc:
                raise ConfigError(f"{t.describe()}: {exc}") from None
            out.append(dataclasses.replace(t, overrides={**dict(t.overrides), **copy.deepcopy(ov)}))
        return out

    def context(self) -> dict:
        """What the evaluations depend on besides the parameter point (for the record)."""
        raise NotImplementedError

    def evaluate(self, results: list) -> tuple[np.ndarray, dict]:
        raise NotImplementedError

    def residual_names(self) -> list[str] | None:
        """Names of the residuals when there are few (paper targets), else None (time series)."""
        return None

    def summary(self, residuals: np.ndarray, metrics: dict) -> dict:
        """Figures of the fit's quality for the report and the preset's header."""
        raise NotImplementedError


def check_strategy(strategy: str, where: str) -> str:
    from rig_emulator.config.schema import STRATEGIES

    if strategy not in STRATEGIES:
        raise UsageError(f"{where}: strategy {strategy!r}: must be one of {', '.join(STRATEGIES)}")
    return strategy


def jsonable_overrides(pairs: Mapping[str, Any]) -> list:
    return [[k, v] for k, v in sorted(pairs.items())]
