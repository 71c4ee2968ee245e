"""Fuzz a real rig process over real sockets and print the figures.

Run from the repository root::

    .venv/bin/python -m benchmarks.fuzz_link                       # 100,000 UDP datagrams + 10,000 frames on TCP
    .venv/bin/python -m benchmarks.fuzz_link --frames 20000 --tcp-frames 0 --seed 7

Starts ``rig-emulator serve --speedup 1`` with a ``tcpin`` and a ``udpin`` endpoint on free
ports (:class:`rig_emulator.testing.rig.RigProcess`), then
:func:`rig_emulator.testing.fuzz_session.fuzz_rig`: garbage, truncated, oversized,
bad-CRC, relabelled and bit-flipped frames and CRC-valid messages of every handled type with
random field values (:class:`rig_emulator.testing.fuzz.FrameFactory`), each datagram's
expected counting computed by a fresh pymavlink parser. Afterwards the rig must be alive,
ACK a command, answer a parameter read, have counted exactly what the oracle predicts with
no handler error, and its step counter must agree with its simulated time. Prints the
simulated-time rate before, during and after the flood and the control steps run. Exit 0
when every check holds, 1 otherwise.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from rig_emulator.testing.rig import RigProcess  # noqa: E402
from rig_emulator.testing.fuzz_session import fuzz_rig  # noqa: E402


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--frames", type=int, default=100_000, help="UDP datagrams (one frame or blob each): %(default)s")
    p.add_argument("--tcp-frames", type=int, default=10_000, help="frames sent as one TCP byte stream: %(default)s")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--window", type=int, default=100,
                   help="datagrams in flight before waiting for the rig to have read them: %(default)s")
    p.add_argument("--speedup", default="1", help="the rig's --speedup: %(default)s")
    args = p.parse_args(argv)
    t0 = time.monotonic()
    with RigProcess(speedup=args.speedup, extra_endpoints=["udpin:127.0.0.1:0"]) as rig:
        udp = next(u for u in rig.urls if u.startswith("udpin:"))
        print(f"rig pid {rig.proc.pid} at speed-up {args.speedup}: {rig.tcp_url} (control), {udp} (fuzz)", flush=True)

        def progress(done, total):
            if done % 20_000 == 0 or done == total:
                print(f"  {done}/{total} datagrams, {time.monotonic() - t0:.0f} s", flush=True)

        res = fuzz_rig(rig.tcp_url, udp, args.frames, seed=args.seed, window=args.window, tcp_frames=args.tcp_frames,
                       progress=progress, proc=rig.proc)
        code = rig.stop()
    print(res.report())
    print(f"rig exit code after SIGTERM: {code}; last line: {rig.output[-1] if rig.output else ''}")
    ok = res.ok and code == 0
    print("RESULT:", "all checks hold" if ok else "FAILED")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
