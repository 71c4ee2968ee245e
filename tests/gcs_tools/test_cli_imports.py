"""`rig-gcs --help` and `rig-gcs errors` load only what they use (every call took about
2 s of imports): no numba, scipy, matplotlib or rig emulator; --help not even numpy or the dialect."""

import subprocess
import sys

HEAVY = ("numba", "scipy", "matplotlib", "rig_emulator", "cvxpy", "dask")

PROBE = """
import sys
from gcs_tools.cli import main
try:
    main(sys.argv[1:])
except SystemExit:
    pass
print(sorted({m.split('.')[0] for m in sys.modules}))
"""


def _modules(*args):
    p = subprocess.run([sys.executable, "-c", PROBE, *args], capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    return eval(p.stdout.strip().splitlines()[-1])  # noqa: S307 - our own printed list


def test_help_imports_no_heavy_module():
    loaded = _modules("--help")
    assert not set(loaded) & set(HEAVY + ("numpy", "pymavlink")), loaded


def test_errors_imports_no_heavy_module(tmp_path):
    from protocol.dialect import mavlink as M

    mav = M.MAVLink(None, srcSystem=1, srcComponent=1)
    log = tmp_path / "a.tlog"
    log.write_bytes(b"".join((i * 1000).to_bytes(8, "big") + m.pack(mav) for i, m in enumerate(
        [M.MAVLink_attitude_message(0, 0.1, 0.0, 0.0, 0, 0, 0),
         M.MAVLink_attitude_target_message(0, 0, [1.0, 0.0, 0.0, 0.0], 0, 0, 0, 0)])))
    loaded = _modules("errors", str(log))
    assert not set(loaded) & set(HEAVY), loaded
