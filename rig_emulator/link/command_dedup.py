"""Commands that arrive twice act once: retries and duplicated frames of COMMAND_LONG/INT.

The command protocol (https://mavlink.io/en/services/command.html) has a sender resend a
command whose COMMAND_ACK it did not get, with ``confirmation`` incremented on each resend.
When the command arrived but its ACK was lost, the resend must not act again (a second
MAV_CMD_HILMS_SHOCK would push the arm twice). A lossy link can also deliver one frame twice.
So, per sender (system id, component id), the rig remembers the last command it received:

* **retry**: ``confirmation`` > 0, the same command with the same parameters, within
  :data:`WINDOW_S` of the previous transmission -> ACKed with the earlier result, not acted on;
  the two cases below are not acted on and not ACKed again (one ACK per transmission: a second
  ACK would arrive while the sender waits for the answer to its next command, and be taken for it);
* **late original**: ``confirmation`` 0 after a retry of the same command and parameters
  acted, with a sequence number before the retry's (a re-ordering link delivered the first
  transmission after the second);
* **duplicated frame**: the same peer (channel), MAVLink sequence number, command,
  parameters and ``confirmation`` within :data:`FRAME_WINDOW_S` (this also covers COMMAND_INT,
  which has no ``confirmation`` field). The window is short because
  sequence numbers restart with every new connection: two runs of a script through one
  router send identical frames, seconds apart, that are two commands.

Anything else acts. Reading: the protocol carries no command identifier, so the same command
sent twice on purpose within :data:`WINDOW_S`, whose first transmission was lost, looks like a
retry and acts once; a sender wanting the command twice sends it again after the window or
with ``confirmation`` 0 (which acts unless it is a duplicated frame).
"""

from __future__ import annotations

from dataclasses import dataclass

WINDOW_S = 10.0  # longer than ground stations retry a command (QGroundControl, MAVSDK, rig-gcs: <= 6 s)
FRAME_WINDOW_S = 1.0  # a link duplicates a frame within milliseconds (a relay's delay at most)


@dataclass
class _Last:
    key: tuple  # (command, params)
    result: int
    confirmation: int  # of the latest transmission of the command
    seq: int
    channel: int  # id() of the channel the latest transmission came on
    time: float  # when the latest transmission arrived


class CommandDedup:
    def __init__(self, window_s: float = WINDOW_S):
        self.window_s = window_s
        self._last: dict[tuple, _Last] = {}

    def repeat_of(self, cmd, channel, now: float) -> tuple[int, bool] | None:
        """(earlier result, answer it again?) if ``cmd`` from ``channel`` repeats the sender's last
        command, else None. A retry is answered (its sender missed the ACK); a duplicated frame or a
        late first transmission is not: its sender had, or will have, one ACK per transmission, and
        a second would arrive while it waits for the answer to its next command."""
        last = self._last.get(cmd.sender)
        if last is None or now - last.time > self.window_s or last.key != (cmd.command, cmd.params):
            return None
        if (cmd.seq == last.seq and cmd.confirmation == last.confirmation and id(channel) == last.channel
                and now - last.time <= FRAME_WINDOW_S):
            return last.result, False  # the same frame again
        if cmd.confirmation == 0 and last.confirmation > 0 and 0 < (last.seq - cmd.seq) % 256 < 128:
            return last.result, False  # the first transmission, overtaken by its retry
        if cmd.confirmation > 0:
            last.confirmation, last.seq, last.channel, last.time = cmd.confirmation, cmd.seq, id(channel), now
            return last.result, True
        return None

    def record(self, cmd, channel, result: int, now: float) -> None:
        self._last[cmd.sender] = _Last((cmd.command, cmd.params), result, cmd.confirmation, cmd.seq, id(channel), now)
        if len(self._last) > 1024:  # senders are a handful; bound the table against spoofed ids
            oldest = min(self._last, key=lambda k: self._last[k].time)
            del self._last[oldest]
