"""The hilms MAVLink 2 dialect: ``hilms.xml`` (which includes common.xml) and its generated
pymavlink module.

Use ``from protocol.dialect import mavlink`` (the generated module, also importable as
``protocol.dialect.hilms``) for encoding and decoding; pymavlink's generated code is the only
MAVLink encoding layer of the project.

``use_hilms_dialect()`` makes ``pymavlink.mavutil.mavlink_connection`` decode with this
dialect over MAVLink 2. mavutil selects dialects by importing
``pymavlink.dialects.v20.<name>`` and chooses v1/v2 from the process-wide ``MAVLINK20``
environment variable (pymavlink/mavutil.py, ``set_dialect``); we register our module under
that import name and set ``MAVLINK20`` so that mavutil never regenerates or reloads it.
"""

from __future__ import annotations

import os
import sys
from types import ModuleType

from protocol.dialect import hilms
from protocol.dialect import hilms as mavlink

DIALECT_NAME = "hilms"
_PYMAVLINK_MODULE_NAME = "pymavlink.dialects.v20." + DIALECT_NAME

__all__ = ["DIALECT_NAME", "hilms", "mavlink", "use_hilms_dialect"]


def use_hilms_dialect() -> ModuleType:
    """Select the hilms dialect, MAVLink 2, for pymavlink's ``mavutil`` in this process.

    Connections opened with ``mavutil.mavlink_connection`` afterwards encode and decode with
    ``protocol.dialect.hilms``. Idempotent. Returns the dialect module.
    """
    os.environ["MAVLINK20"] = "1"
    import pymavlink.dialects.v20 as v20_package
    from pymavlink import mavutil

    sys.modules[_PYMAVLINK_MODULE_NAME] = hilms
    setattr(v20_package, DIALECT_NAME, hilms)
    mavutil.set_dialect(DIALECT_NAME)
    if mavutil.mavlink is not hilms:
        raise RuntimeError("pymavlink.mavutil did not select the hilms dialect module")
    return hilms
