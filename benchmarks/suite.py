"""The suite: importing this module registers every benchmark in ``harness.REGISTRY``.

To add a benchmark, write its probe function(s) and one summarising function in a
module of this package (see ``rig_core.py``), decorate them with
``@probe(...)`` / ``@benchmark(...)`` from :mod:`benchmarks.harness`, and import the
module here.
"""

from . import rotorpy_reference, rig_core  # noqa: F401  (registration side effects)
from . import hardware_rig  # noqa: F401
from . import flc_vs_skfuzzy  # noqa: F401
from . import cf_vs_ahrs  # noqa: F401
from . import mavlink_link, jitter, memory  # noqa: F401
from . import many_rigs  # noqa: F401
from . import plugins  # noqa: F401
from . import px4_lockstep, ardupilot_json  # noqa: F401
from . import served_max  # noqa: F401
from . import sysid_fit  # noqa: F401
from .harness import REGISTRY

__all__ = ["REGISTRY"]
