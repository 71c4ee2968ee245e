"""Bit-identical PNG figures: matplotlib's Agg backend, fixed style, no time stamps.

A PNG written by matplotlib carries a ``Software`` text chunk and nothing time-dependent;
:func:`save` drops even that (``metadata={"Software": None}``), renders into memory and
writes the bytes atomically (:func:`protocol.atomic_file.atomic_path`), so the same data
give the same file byte for byte with the same matplotlib.
"""

from __future__ import annotations

import io
from pathlib import Path

from gcs_tools.errors import UsageError
from protocol.atomic_file import atomic_path

DPI = 100
STYLE = {
    "figure.dpi": DPI,
    "savefig.dpi": DPI,
    "font.size": 9,
    "axes.grid": True,
    "grid.alpha": 0.3,
    "lines.linewidth": 1.0,
    "legend.fontsize": 8,
    "path.simplify": True,  # dense 500 Hz chattering lines render in a fraction of the time (deterministic)
    "agg.path.chunksize": 20000,
}
COLORS = {"smc": "tab:red", "flc": "tab:blue", "smc-flc": "tab:green", "desired": "black",
          "iir": "tab:orange", "kalman": "tab:purple", "none": "tab:gray"}


def pyplot():
    """matplotlib.pyplot on the Agg backend with the report's style."""
    try:
        import matplotlib
    except ImportError:
        raise UsageError("the reproduction's figures need matplotlib: pip install matplotlib") from None
    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    plt.rcParams.update(STYLE)
    return plt


def save(fig, out_dir: Path, name: str) -> str:
    """Write ``fig`` as ``out_dir/name`` (PNG, no metadata) atomically and close it; returns ``name``."""
    plt = pyplot()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=DPI, metadata={"Software": None})
    plt.close(fig)
    with atomic_path(Path(out_dir) / name) as tmp:
        Path(tmp).write_bytes(buf.getvalue())
    return name
