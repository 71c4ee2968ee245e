"""Process and machine figures read from Linux's /proc (no psutil): memory, CPU time, load.

* :func:`memory_kib` - ``VmRSS`` (resident now) and ``VmHWM`` (peak resident) of a process;
* :func:`reset_peak` - restart ``VmHWM`` from the current RSS (``/proc/PID/clear_refs``,
  Linux >= 4.0), so a peak can be measured over one phase of a process's life;
* :func:`cpu_seconds` - user + system CPU time a process has used;
* :class:`MachineLoad` - how busy all CPUs were between two instants (``/proc/stat``), and
  the load averages: what other work the machine was doing while a figure was measured.
"""

from __future__ import annotations

import os
import time
from pathlib import Path

_CLK_TCK = os.sysconf("SC_CLK_TCK") if hasattr(os, "sysconf") else 100


def _status(pid: int | str) -> dict[str, str]:
    out = {}
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        key, _, value = line.partition(":")
        out[key] = value.strip()
    return out


def memory_kib(pid: int | str = "self") -> dict[str, int]:
    """``{"rss": VmRSS, "hwm": VmHWM}`` of process ``pid`` in KiB."""
    st = _status(pid)
    try:
        return {"rss": int(st["VmRSS"].split()[0]), "hwm": int(st["VmHWM"].split()[0])}
    except KeyError as exc:
        raise RuntimeError(f"/proc/{pid}/status has no {exc} (a kernel thread or a zombie?)") from None


def reset_peak(pid: int | str = "self") -> bool:
    """Reset ``VmHWM`` of ``pid`` to its current RSS; False where the kernel does not allow it."""
    try:
        Path(f"/proc/{pid}/clear_refs").write_text("5")
    except OSError:
        return False
    return True


def cpu_seconds(pid: int | str = "self") -> float:
    """User + system CPU seconds process ``pid`` has used (its threads included)."""
    text = Path(f"/proc/{pid}/stat").read_text()
    fields = text[text.rindex(")") + 2:].split()  # after "pid (comm) "
    utime, stime = int(fields[11]), int(fields[12])
    return (utime + stime) / _CLK_TCK


def _cpu_jiffies() -> tuple[int, int]:
    """(busy, total) jiffies over all CPUs since boot."""
    first = Path("/proc/stat").read_text().splitlines()[0].split()
    vals = [int(v) for v in first[1:]]
    idle = vals[3] + (vals[4] if len(vals) > 4 else 0)  # idle + iowait
    total = sum(vals[:8])  # user nice system idle iowait irq softirq steal
    return total - idle, total


class MachineLoad:
    """All-CPU busy fraction between :meth:`start` and :meth:`stop` (every process, ours too)."""

    def __init__(self) -> None:
        self._t0 = self._busy0 = self._total0 = None
        self.busy_fraction = float("nan")
        self.loadavg_1min = float("nan")
        self.wall_s = 0.0

    def start(self) -> "MachineLoad":
        self._busy0, self._total0 = _cpu_jiffies()
        self._t0 = time.monotonic()
        return self

    def stop(self) -> "MachineLoad":
        if self._t0 is None:
            raise RuntimeError("MachineLoad.stop() before start()")
        busy, total = _cpu_jiffies()
        self.wall_s = time.monotonic() - self._t0
        if total > self._total0:
            self.busy_fraction = (busy - self._busy0) / (total - self._total0)
        self.loadavg_1min = os.getloadavg()[0]
        return self

    def figures(self, prefix: str = "machine") -> dict[str, float]:
        """``{prefix}_busy_cores`` (busy fraction x CPU count) and ``{prefix}_loadavg_1min``."""
        return {f"{prefix}_busy_cores": self.busy_fraction * (os.cpu_count() or 1),
                f"{prefix}_loadavg_1min": self.loadavg_1min}
