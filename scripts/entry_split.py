"""Thread CPU of one chunk's compiled call with 0 steps (unboxing, the GIL held) and with 20 (the difference runs without the GIL)."""
import time
from rig_emulator.config.loader import load_config
from rig_emulator.link.serve import prepare_rig
rig = prepare_rig(load_config(airframe="hilms-ideal")); rig.arm(True)
sim = rig.sim
for n in (0, 20, 0, 20):
    best = 1e9
    for rep in range(7):
        t0 = time.thread_time()
        for _ in range(500):
            sim.log_row = 0
            entry, args = sim.advance_call(n); sim.advance_done(n, entry(*args))
        best = min(best, (time.thread_time() - t0) / 500 * 1e6)
    print(f"advance_call + entry + advance_done, {n:2d} steps: {best:.1f} us thread CPU (best of 7 x 500)")
