"""One flight stack's session on the Simulator MAVLink API, in lockstep.

The protocol (PX4 ``simulator_mavlink``; the rig is the simulator):

1. The flight stack connects (TCP) or the serial line opens. The plant starts afresh
   (:meth:`LockstepPlant.restart`): time 0, on the ground at its initial position, motors off.
2. Free run: until the first HIL_ACTUATOR_CONTROLS arrives the rig advances one step every
   step period of wall-clock time (x ``speedup``) with the motors off and sends the step's
   sensors, so a flight stack that is still booting sees its clock move.
3. Lockstep: every HIL_ACTUATOR_CONTROLS whose ``flags`` bit 0 (lockstep) is set applies
   ``controls[0..3]`` to motors 1..4, advances the plant exactly one step and sends that
   step's HIL_SENSOR (and HIL_GPS, HIL_STATE_QUATERNION when due). Nothing else moves the
   plant, so the run depends only on what the flight stack sends, and goes as fast as both
   sides allow. A message without the lockstep flag (a HITL board runs on its own clock)
   sets the motors and the rig keeps stepping in real time.
4. The session ends when the stream closes or breaks; the motors stop and the rig waits for
   the next flight stack (a new connection starts again at 1).

Per step the rig sends HIL_SENSOR (id 0), HIL_GPS every ``gps_div`` steps (10 Hz at 250 Hz),
and HIL_STATE_QUATERNION at the interval the flight stack asks with
``MAV_CMD_SET_MESSAGE_INTERVAL`` (every step until asked; PX4 asks for 5 ms).
"""

from __future__ import annotations

import math
import time

from protocol.dialect import mavlink
from protocol.geodesy import TangentPlane
from rig_emulator.link.endpoints.channel import saturate_floats
from rig_emulator.link.endpoints.counters import LinkCounters
from rig_emulator.link.px4_simulator import hil_messages, hil_units

SYSID = 1  # the simulator's MAVLink identity (PX4's simulator module ignores it)
COMPID = mavlink.MAV_COMP_ID_AUTOPILOT1
GPS_RATE_HZ = 10.0
MAX_FREE_RUN_BURST = 10  # steps run at once when the free run falls behind the wall clock
SILENT_START_S = 1.0  # the free run's start when the flight stack says nothing (s after it connected)


class SimulatorSession:
    """The lockstep exchange with one flight stack over one :class:`Connection`."""

    def __init__(self, conn, plant, home, speedup: float = 1.0, all_fields: bool = False,
                 counters: LinkCounters | None = None, log=print):
        self.conn = conn
        self.plant = plant
        self.home = home
        self.plane = TangentPlane(home)
        self.speedup = speedup if speedup > 0.0 else 1.0  # free-run pace; lockstep ignores it
        self.all_fields = all_fields
        self.counters = counters or LinkCounters()
        self._log = log
        self.mav = mavlink.MAVLink(None, srcSystem=SYSID, srcComponent=COMPID)
        self.mav.robust_parsing = True
        self.gps_div = max(1, int(round(1.0 / (GPS_RATE_HZ * plant.period_s))))
        self.state_interval_us = 0  # HIL_STATE_QUATERNION: 0 every step; < 0 off; else its grid (_state_due)
        self._period_us = hil_units.step_usec(plant.period_s)
        self.lockstep = False
        self.actuator_messages = 0
        self.steps = 0
        self.peer_heartbeat = None  # (sysid, compid, autopilot) of the flight stack
        self._voltages = [0.0] * 4
        self._armed = False
        plant.restart()
        plant.command(self._voltages, False)
        # the free run starts when the flight stack first speaks (PX4 sends SET_MESSAGE_INTERVAL
        # as soon as it is connected), or SILENT_START_S after it connected if it says nothing
        self._heard = False
        self._wall0 = time.monotonic() + SILENT_START_S
        self._sim0 = 0.0

    # --- receiving ----------------------------------------------------------------------------
    def on_readable(self) -> bool:
        """Read and act on what the flight stack sent; False once the session is over."""
        data = self.conn.read()
        if data is None:
            return False
        if not data:
            return True
        if not self._heard:  # the free run's clock starts now (before these messages are acted on)
            self._heard = True
            self._wall0 = min(self._wall0, time.monotonic())
        self.counters.rx_bytes += len(data)
        try:
            msgs = self._parse(data)
        except Exception:  # noqa: BLE001 - hostile bytes must never stop the rig
            self.counters.drop("bad_data")
            self.mav = mavlink.MAVLink(None, srcSystem=SYSID, srcComponent=COMPID)
            self.mav.robust_parsing = True
            return True
        for msg in msgs:
            kind = msg.get_type()
            if kind == "BAD_DATA" or kind.startswith("UNKNOWN"):
                self.counters.drop("bad_data")
                continue
            self.counters.received += 1
            if kind == "HIL_ACTUATOR_CONTROLS":
                self._actuators(msg)
            elif kind == "COMMAND_LONG":
                self._command(msg)
            elif kind == "HEARTBEAT":
                self.peer_heartbeat = (msg.get_srcSystem(), msg.get_srcComponent(), msg.autopilot)
            else:
                self.counters.drop("unhandled")
            if not self.conn.open:
                return False
        return self.conn.open

    def _parse(self, data: bytes) -> list:
        """The messages in ``data`` (and in what earlier reads left unfinished): pymavlink's
        ``parse_buffer`` without its last call, which only finds the buffer empty (one call
        to pymavlink's ``parse_char`` per message; in lockstep a read holds one message)."""
        mav = self.mav
        msg = mav.parse_char(data)
        msgs = []
        while msg is not None:
            msgs.append(msg)
            if not mav.buf_len():
                break
            msg = mav.parse_char(b"")
        return msgs

    def _actuators(self, msg) -> None:
        voltages = hil_units.motor_voltages(msg.controls, self.plant.voltage_max_v)
        armed = bool(msg.mode & hil_units.MODE_FLAG_SAFETY_ARMED) or max(voltages) > 0.0  # never NaN
        self.actuator_messages += 1
        self.plant.command(voltages, armed)
        if msg.flags & hil_units.FLAG_LOCKSTEP:
            if not self.lockstep:
                self.lockstep = True
                self._log(f"flight stack in lockstep from t = {self.plant.time_s:.3f} s")
            self.step()
        elif self.lockstep:  # the flight stack left lockstep: real time from here
            self.lockstep = False
            self._wall0, self._sim0 = time.monotonic(), self.plant.time_s

    def _command(self, msg) -> None:
        result = mavlink.MAV_RESULT_UNSUPPORTED
        if msg.command == mavlink.MAV_CMD_SET_MESSAGE_INTERVAL and int(msg.param1) == \
                mavlink.MAVLINK_MSG_ID_HIL_STATE_QUATERNION:
            interval_us = float(msg.param2)
            if math.isfinite(interval_us) and (interval_us in (-1.0, 0.0) or interval_us > 0.0):
                if interval_us <= 0.0:
                    self.state_interval_us = int(interval_us)  # -1 off, 0 every step
                else:
                    self.state_interval_us = max(int(round(interval_us)), 1)
                result = mavlink.MAV_RESULT_ACCEPTED
            else:
                result = mavlink.MAV_RESULT_DENIED
        self.send(mavlink.MAVLink_command_ack_message(command=msg.command, result=result, progress=0,
                                                      result_param2=0, target_system=msg.get_srcSystem(),
                                                      target_component=msg.get_srcComponent()))

    # --- stepping and sending ------------------------------------------------------------------
    def free_run_due(self, now: float) -> int:
        """Steps due in real time (free run before lockstep, or a board without lockstep)."""
        if self.lockstep:
            return 0
        behind = self._sim0 + (now - self._wall0) * self.speedup - self.plant.time_s
        n = int(behind / self.plant.period_s + 1e-9)
        if n > MAX_FREE_RUN_BURST:  # far behind (a pause, a slow host): re-anchor, do not burst
            self._wall0, self._sim0 = now, self.plant.time_s
            n = 1
        return max(n, 0)

    def next_free_run_in(self, now: float) -> float | None:
        """Wall seconds until the next free-run step (None in lockstep)."""
        if self.lockstep:
            return None
        target = self.plant.time_s + self.plant.period_s
        return max((target - self._sim0) / self.speedup - (now - self._wall0), 0.0)

    def step(self) -> None:
        """Advance the plant one step and send that step's messages (in one write)."""
        plant, pack = self.plant, self._pack
        readout = plant.advance()
        self.steps = steps = self.steps + 1
        self.counters.steps += plant.steps_per_update
        dither = hil_messages.BARO_DITHER_PA if steps % 2 else -hil_messages.BARO_DITHER_PA
        out = [pack(hil_messages.hil_sensor(readout, 0, self.all_fields, dither))]
        gps = steps % self.gps_div == 0
        state = self._state_due(hil_units.step_usec(readout.time_s))
        geo = hil_messages.geodetic(readout, self.plane) if gps and state else None  # once for both
        if gps:
            out.append(pack(hil_messages.hil_gps(readout, self.plane, geo)))
        if state:
            out.append(pack(hil_messages.hil_state_quaternion(readout, self.plane, geo)))
        self._write(out)

    def _state_due(self, t_us: int) -> bool:
        """Whether the step ending at ``t_us`` sends HIL_STATE_QUATERNION: at an interval, when a
        multiple of it (simulated time from the session's start) falls in the step ``(t - T, t]``.
        A grid fixed in simulated time, not anchored where the command arrived (which depends on
        the wall clock), so that two sessions in lockstep send it at the same steps."""
        interval = self.state_interval_us
        if interval <= 0:
            return interval == 0
        return t_us // interval > (t_us - self._period_us) // interval

    def _pack(self, msg) -> bytes:
        try:
            buf = msg.pack(self.mav)
        except OverflowError:  # a diverged plant: beyond float32 goes as +-inf
            buf = saturate_floats(msg).pack(self.mav)
        self.mav.seq = (self.mav.seq + 1) % 256
        return buf

    def _write(self, packed: list) -> None:
        if self.conn.open and self.conn.write(b"".join(packed)):
            self.counters.sent += len(packed)

    def send(self, msg) -> None:
        self._write([self._pack(msg)])

    def close(self) -> None:
        """End the session: motors off, stream closed."""
        self.plant.command([0.0] * 4, False)
        self.conn.close()
