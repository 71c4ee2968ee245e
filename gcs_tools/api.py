"""Scripted experiments in a few lines: start a rig, fly, log, get the figures.

>>> from gcs_tools.api import RigSession
>>> from gcs_tools.missions import rectangle_points
>>> with RigSession(speedup=20, log_path="run.tlog") as rig:      # a rig on free ports, logging
...     reached = rig.fly(rectangle_points(5, 3, 2))              # guided 8 cm switching (Sec. 4-4)
...     result = rig.finish()                                      # stop logging, read the log
>>> result.mean_errors["x_m"], result.tlog, result.arrays("LOCAL_POSITION_NED", "x")

:class:`RigSession` runs ``rig-emulator serve`` in a subprocess on free ports
(:class:`rig_emulator.testing.rig.RigProcess`), connects a ground link for commands and a
second one that records everything to a .tlog in a thread (:class:`gcs_tools.logger.Recorder`).
:meth:`RigSession.upload` / :meth:`download` run the mission protocol; :meth:`link` is the
:class:`gcs_tools.link.Link` for anything else. :func:`headless_tlog` writes a headless run
as a .tlog, so the same checks run on live and headless runs.
"""

from __future__ import annotations

import tempfile
import warnings
from dataclasses import dataclass, field
from pathlib import Path

from gcs_tools import mission_client
from gcs_tools.fly import DEFAULT_MIN_LEG_TIME, DEFAULT_SPEED, Reached, fly
from gcs_tools.link import Link
from gcs_tools.logger import Recorder, request_rates
from gcs_tools.tlog_errors import tlog_mean_errors
from gcs_tools.tlog_read import read_fields

#: rates the session's logger asks for (Hz of rig time): targets as often as the actuals
LOG_RATES = {"ATTITUDE": 25.0, "ATTITUDE_TARGET": 25.0, "LOCAL_POSITION_NED": 25.0,
             "POSITION_TARGET_LOCAL_NED": 25.0}


@dataclass
class RunResult:
    """A finished run: the .tlog, its mean errors (Eq. 45, :func:`tlog_mean_errors`) and the waypoints reached."""

    tlog: Path
    mean_errors: dict
    samples: dict
    reached: list = field(default_factory=list)

    def arrays(self, message: str, *fields: str):
        """Arrays of ``fields`` of ``message`` in the log (one array, or a tuple for several)."""
        data, _ = read_fields(self.tlog, {message: list(fields)})
        cols = tuple(data[message].get(f) for f in fields)
        return cols[0] if len(cols) == 1 else cols


class RigSession:
    """A live rig on free ports with a ground link and a running logger (see the module doc)."""

    def __init__(self, speedup: float = 20.0, log_path=None, rig_args=(), log_rates=None):
        from rig_emulator.testing.rig import RigProcess, client_url

        self._tmp = None
        if log_path is None:
            self._tmp = tempfile.TemporaryDirectory(prefix="hilms-run-")
            log_path = Path(self._tmp.name) / "run.tlog"
        self.tlog = Path(log_path)
        self.rig = RigProcess(speedup=speedup, args=list(rig_args))
        self.url = client_url(self.rig.tcp_url)
        self.reached: list[Reached] = []
        try:
            self._log_link = Link(self.url, source_component=191)
            self._log_link.wait_vehicle()
            request_rates(self._log_link, LOG_RATES if log_rates is None else log_rates, None)
            self.recorder = Recorder(self._log_link, self.tlog).start()
            self.link = Link(self.url)
            self.link.wait_vehicle()
        except BaseException:
            self.rig.stop()
            raise

    def fly(self, points_enu, radius: float = 0.08, speed: float = DEFAULT_SPEED,
            min_leg_time: float = DEFAULT_MIN_LEG_TIME, timeout_s: float = 300.0) -> list[Reached]:
        """Ground-driven waypoint flight (:func:`gcs_tools.fly.fly`); returns the waypoints reached."""
        import numpy as np

        pts = np.asarray(points_enu, dtype=float).reshape(-1, 3)
        got = fly(self.link, pts, np.full(pts.shape[0], radius), speed=speed, min_leg_time=min_leg_time,
                  timeout_s=timeout_s, notice=lambda text: warnings.warn(text, RuntimeWarning, stacklevel=3))
        self.reached.extend(got)
        return got

    def upload(self, mission) -> None:
        mission_client.upload(self.link, mission)

    def download(self):
        return mission_client.download(self.link)

    def finish(self, t_from: float | None = None, t_to: float | None = None) -> RunResult:
        """Stop logging and return the run's figures (the rig keeps running until :meth:`close`)."""
        self.recorder.join()
        res = tlog_mean_errors(self.tlog, t_from, t_to)
        return RunResult(self.tlog, res["mean_errors"], res["samples"], list(self.reached))

    def close(self) -> int:
        self.recorder.stop()
        try:
            self.recorder.join()
        except Exception:  # noqa: BLE001 - closing: the log is already complete up to here
            pass
        for ln in (self.link, self._log_link):
            ln.close()
        code = self.rig.stop()
        return code

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def headless_tlog(path, scenario: str, **simulate_kwargs):
    """Run a scenario headless (:func:`rig_emulator.api.simulate`), write it as a .tlog; returns (SimResult, RunResult)."""
    from rig_emulator.api import simulate
    from rig_emulator.link.telemetry.tlog_export import export_tlog

    from protocol.run_label import run_label

    result = simulate(scenario, **simulate_kwargs)
    cfg = result.config
    export_tlog(result, path, label=run_label(scenario, cfg["control.strategy"], cfg["airframe.name"], cfg["sim.seed"]))
    res = tlog_mean_errors(path)
    return result, RunResult(Path(path), res["mean_errors"], res["samples"])
