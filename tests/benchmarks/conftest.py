"""Make the repository-root ``benchmarks`` directory importable under any pytest runner.

``benchmarks/`` is a plain directory at the repository root, not part of the
installed distribution, so it is on ``sys.path`` only when Python starts in the
repository root (``python -m pytest``); the bare ``pytest`` script needs this.
"""

import sys
from pathlib import Path

_ROOT = str(Path(__file__).resolve().parents[2])
if _ROOT not in sys.path:
    sys.path.insert(0, _ROOT)
