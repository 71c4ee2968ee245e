"""Commands that arrive twice act once: retries and duplicated frames of COMMAND_LONG/INT.

The command protocol (https://mavlink.io/en/services/command.html) has a sender resend a
command whose COMMAND_ACK it did not get, with ``confirmation`` incremented on each resend.
When the command arrived but its ACK was lost, the resend must not act again (a second
MAV_CMD_HILMS_SHOCK would push the arm twice). A lossy link can also deliver one frame twice,
or late: after the sender has moved on to its next command. So, per sender (system id,
component id), the rig remembers the commands it acted on in the last :data:`WINDOW_S`
seconds (command and parameters, the result, the latest transmission's ``confirmation``,
sequence number and channel), and a command matching one of them is:

* a **retry** when ``confirmation`` > 0 -> ACKed with the earlier result, not acted on (not
  ACKed when the sender has sent another command since: it had its answer and moved on);
* a **duplicated frame** when it has the same channel, MAVLink sequence number and
  ``confirmation`` as that command's latest transmission, within :data:`FRAME_WINDOW_S` (this
  also covers COMMAND_INT, which has no ``confirmation`` field);
* a **late original** when ``confirmation`` is 0, a retry of it already came and its sequence
  number is before that retry's (a re-ordering link delivered the first transmission last).

The last two neither act nor get a second ACK: one ACK per transmission, because a second one
would reach the sender while it waits for the answer to its next command and be taken for it.
Anything else acts. The frame window is short because sequence numbers restart with every new
connection: two runs of a script through one router send identical frames, seconds apart,
that are two commands.

Reading: the protocol carries no command identifier, so a retry that a link holds back until
just after the sender's next command, and that arrives first, is ACKed and that ACK can be
taken for the next command's (rig-gcs also filters stale ACKs, :mod:`gcs_tools.stale_acks`);
the same command sent twice on
purpose within :data:`WINDOW_S`, whose first transmission was lost, looks like a retry and
acts once; and a sender that sends more than 128 messages between a retried command and the
same command sent again on purpose can make the second look like a late original. A sender
wanting a command twice sends it with ``confirmation`` 0 after the first was answered.
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass

WINDOW_S = 10.0  # longer than ground stations retry a command (QGroundControl, MAVSDK, rig-gcs: <= 6 s)
FRAME_WINDOW_S = 1.0  # a link duplicates a frame within milliseconds (a relay's delay at most)
PER_SENDER = 16  # commands remembered per sender
SENDERS = 256  # senders remembered (bounded against spoofed ids)


@dataclass
class _Seen:
    result: int
    confirmation: int  # of the latest transmission of the command
    seq: int
    channel: int  # id() of the channel the latest transmission came on
    time: float  # when the latest transmission arrived


class CommandDedup:
    def __init__(self, window_s: float = WINDOW_S):
        self.window_s = window_s
        self._senders: OrderedDict = OrderedDict()  # sender -> OrderedDict((command, params) -> _Seen)

    def repeat_of(self, cmd, channel, now: float) -> tuple[int, bool] | None:
        """(earlier result, answer it again?) if ``cmd`` from ``channel`` repeats a command the
        sender sent recently, else None (act on it)."""
        seen = self._senders.get(cmd.sender, {}).get((cmd.command, cmd.params))
        if seen is None or now - seen.time > self.window_s:
            return None
        if (cmd.seq == seen.seq and cmd.confirmation == seen.confirmation and id(channel) == seen.channel
                and now - seen.time <= FRAME_WINDOW_S):
            return seen.result, False  # the same frame again
        if cmd.confirmation == 0 and seen.confirmation > 0 and 0 < (seen.seq - cmd.seq) % 256 < 128:
            return seen.result, False  # the first transmission, overtaken by its retry
        if cmd.confirmation > 0:
            commands = self._senders[cmd.sender]
            latest = next(reversed(commands)) == (cmd.command, cmd.params)
            seen.confirmation, seen.seq, seen.channel, seen.time = cmd.confirmation, cmd.seq, id(channel), now
            return seen.result, latest  # a retry of an older command: its sender has moved on, got its ACK
        return None

    def record(self, cmd, channel, result: int, now: float) -> None:
        commands = self._senders.pop(cmd.sender, None) or OrderedDict()
        self._senders[cmd.sender] = commands  # most recent sender last
        key = (cmd.command, cmd.params)
        commands.pop(key, None)
        commands[key] = _Seen(result, cmd.confirmation, cmd.seq, id(channel), now)
        while len(commands) > PER_SENDER or (commands and now - next(iter(commands.values())).time > self.window_s):
            commands.popitem(last=False)
        while len(self._senders) > SENDERS:
            self._senders.popitem(last=False)
