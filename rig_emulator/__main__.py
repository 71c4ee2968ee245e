"""``python -m rig_emulator`` is the ``rig-emulator`` command."""

import sys

from rig_emulator.cli import main

sys.exit(main())
