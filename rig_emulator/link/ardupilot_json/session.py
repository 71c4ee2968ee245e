"""One ArduPilot SITL's session on the JSON simulator interface, in lockstep on its frame counter.

ArduPilot (``libraries/SITL/SIM_JSON.cpp``) sends a servo packet for every frame and waits
for the physics' answer before it moves its clock; the physics owns the clock (the answer's
``timestamp``). The rig:

* a **new frame** (``frame_count`` above the last one): the servo outputs go to the motors
  (:mod:`~rig_emulator.link.ardupilot_json.motor_map`), the plant advances exactly one step and
  the step's state is the answer (:mod:`~rig_emulator.link.ardupilot_json.state_json`). A gap
  in the count (a lost packet) still moves one step; it is counted in ``missed``;
* a **repeated frame** (the same ``frame_count``: ArduPilot re-sends a frame it got no answer
  to after 1 s) is answered with the last answer again, without stepping: ArduPilot only moves
  its clock when ``timestamp`` grows, so the plant and ArduPilot stay on the same step;
* nothing else moves the plant: the run depends only on what ArduPilot sends and goes as fast
  as both sides allow.

The session starts the plant afresh (:meth:`LockstepPlant.restart`: time 0, motors off, the
same seed), so two sessions with the same ArduPilot behaviour are the same run. The rig's
arming follows ArduPilot's outputs: armed while any of the four motors is commanded above
``PWM_MIN_US`` (ArduCopter outputs ``MOT_SPIN_ARM`` when armed, 1000 us when disarmed).
"""

from __future__ import annotations

from rig_emulator.link.ardupilot_json.motor_map import motor_voltages
from rig_emulator.link.ardupilot_json.state_json import state_line


class JsonSession:
    """The exchange with one ArduPilot (one UDP address) in lockstep."""

    def __init__(self, addr, plant, counters, log=print):
        self.addr = addr
        self.plant = plant
        self.counters = counters
        self._log = log
        self.last_frame = -1  # frame_count of the last frame answered
        self.reply = b""  # the last answer, sent again for a repeated frame
        self.steps = 0  # new frames answered (= plant steps)
        self.repeats = 0  # repeated frames answered without stepping
        self.missed = 0  # frame numbers skipped (frames ArduPilot sent that never arrived)
        self.frame_rate_hz = 0  # what the last packet asked for
        self.last_heard = 0.0  # wall-clock time of the last packet (the server's clock)
        self._voltage_max = plant.voltage_max_v
        plant.restart()
        plant.command([0.0] * 4, False)

    def answer(self, packet) -> bytes:
        """The answer to one servo packet of this session's ArduPilot (frame_count >= the last)."""
        count = packet.frame_count
        if count == self.last_frame:
            self.repeats += 1
            return self.reply
        if count > self.last_frame + 1 and self.last_frame >= 0:
            self.missed += count - self.last_frame - 1
        self.last_frame = count
        self.frame_rate_hz = packet.frame_rate_hz
        voltages = motor_voltages(packet.pwm_us, self._voltage_max)
        plant = self.plant
        plant.command(voltages, max(voltages) > 0.0)
        readout = plant.advance()
        self.steps += 1
        self.counters.steps += plant.steps_per_update
        self.reply = state_line(readout)
        return self.reply

    def close(self) -> None:
        """End the session: motors off."""
        self.plant.command([0.0] * 4, False)
