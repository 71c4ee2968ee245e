"""The rig's console: one readable line per event on stdout, as SITL consoles print them.

``rig-emulator: [   12.345] armed`` - the simulated time in brackets, then the event:
arming and disarming (with the reason when the rig did it itself), each mode change, each
mission item reached, and every STATUSTEXT the rig broadcasts (faults, failsafes, fences,
landings, refusals sent to every peer). :meth:`Console.poll` finds arming and mode changes
by comparing with the previous chunk, so none is missed whichever path caused it.
"""

from __future__ import annotations

import sys

from rig_emulator.link.commands.modes import FlightModes

SEVERITY = {0: "EMERGENCY", 1: "ALERT", 2: "CRITICAL", 3: "ERROR", 4: "WARNING", 5: "NOTICE", 6: "INFO", 7: "DEBUG"}


class Console:
    def __init__(self, stream=None, enabled: bool = True):
        self.stream = stream if stream is not None else sys.stdout
        self.enabled = enabled
        self._armed = None
        self._mode = None
        self.lines = 0

    def line(self, t: float, text: str) -> None:
        if not self.enabled:
            return
        print(f"rig-emulator: [{t:9.3f}] {text}", file=self.stream, flush=True)
        self.lines += 1

    def statustext(self, t: float, severity: int, text: str) -> None:
        self.line(t, f"{SEVERITY.get(severity, str(severity))}: {text}")

    def poll(self, t: float, armed: bool, main: int, sub: int) -> None:
        """Print arming and mode changes (PX4 main and sub mode) since the last call. Called
        after every chunk: with no change it returns at once (the mode's name is made only
        for the line that prints it)."""
        mode = (main, sub)
        if armed == self._armed and mode == self._mode:
            return
        if self._armed is not None and armed != self._armed:
            self.line(t, "armed" if armed else "disarmed")
        if self._mode is not None and mode != self._mode:
            self.line(t, f"mode {FlightModes.name_of(main, sub)}")
        self._armed, self._mode = armed, mode
