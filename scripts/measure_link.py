"""The MAVLink link figures: ``python -m benchmarks --only mavlink-link,jitter`` (extra arguments pass through).

Run from the repository root: ``.venv/bin/python scripts/measure_link.py [--quick] [--repeat N]``.
The measurements this script used to make (telemetry messages per second at speed-up 1,
COMMAND_LONG -> COMMAND_ACK latency, the real-time factor of ``--speedup max`` with a
client) are now probes of the benchmark suite (``benchmarks/mavlink_link.py``,
``benchmarks/jitter.py``; see benchmarks/README.md), measured in fresh processes against a
reference of the same run and written to ``bench-results.json``.
"""

import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

if __name__ == "__main__":
    sys.exit(subprocess.call([sys.executable, "-m", "benchmarks", "--only", "mavlink-link,jitter", *sys.argv[1:]],
                             cwd=ROOT))
