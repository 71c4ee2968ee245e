"""A rig process flooded over real sockets (the in-suite cut of benchmarks/fuzz_link.py): 5,000 UDP
datagrams of garbage, truncated, oversized, bad-CRC, relabelled, bit-flipped and CRC-valid
random frames, and 500 frames as one TCP stream. The rig stays up, answers a command and a
parameter read, counts every datagram exactly as a fresh pymavlink parser says it must
(received, bad CRC, garbage runs, truncated, unknown ids, echoes, other systems/components,
unhandled, bytes), no handler raises, and its step counter matches its simulated time. The
rates before, during and after are printed (scripts measure speed, tests do not)."""

from rig_emulator.link.telemetry.link_status import status_values_names
from rig_emulator.testing.rig import RigProcess
from rig_emulator.testing.fuzz_session import fuzz_rig


def test_flood_over_udp_and_tcp_is_counted_exactly_and_the_rig_carries_on():
    with RigProcess(speedup=1.0, extra_endpoints=["udpin:127.0.0.1:0"]) as rig:
        udp = next(u for u in rig.urls if u.startswith("udpin:"))
        res = fuzz_rig(rig.tcp_url, udp, 5000, seed=3, window=100, baseline_s=0.5, tcp_frames=500, proc=rig.proc)
        print("\n" + res.report())
        assert res.alive and res.command_ack == 0 and res.param_answer == 1000.0
        assert res.mismatches == {}, res.mismatches
        assert res.handler_errors == 0
        assert res.expected["received"] > 1500 and res.expected["bad_crc"] > 300 and res.expected["truncated"] > 300
        assert res.step_time_error_s < 0.0025
        assert res.final["CTRL_STEPS"] == -(-res.final["STEPS"] // 2)  # control at 500 Hz of 1 kHz physics
        assert set(res.final) == {"time_s", *status_values_names()}  # every counter is on the wire
        assert rig.stop() == 0

