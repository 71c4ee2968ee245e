"""In-process A/B of the --speedup max tick: serial (step_chunk + emit_streams per chunk) against the
step-worker pipeline (RigServer._unpaced_tick) at several GIL switch intervals; wall and process CPU ms
per simulated second, best and median of 5 alternated rounds of TICKS ticks of 10 chunks (hilms-ideal,
armed, one peer at the default rates on a discarding endpoint). Usage: scripts/ab_step_worker.py [TICKS] [sw,sw,...]"""
import math, sys, time
sys.path.insert(0, __import__("os").path.dirname(__import__("os").path.abspath(__file__)))
from record_telemetry import RecordingEndpoint, _gcs, _decode, _command
from protocol.dialect import mavlink as M
from rig_emulator.config.loader import load_config
from rig_emulator.link import server as srv
from rig_emulator.link.serve import chunk_seconds, prepare_rig
from rig_emulator.link.step_worker import short_switch_interval

class Discard(RecordingEndpoint):
    def send(self, key, data): return True

rig = prepare_rig(load_config(airframe="hilms-ideal"))
server = srv.RigServer(rig, [], speedup=0.0, chunk_s=chunk_seconds(5.0, 0.0))
ep = Discard(); server.endpoints.append(ep); server._open_channel(ep, ("gcs", 1))
ch = server.channels[(id(ep), ("gcs", 1))]
gcs = _gcs()
_command(server, ch, gcs, M.MAV_CMD_COMPONENT_ARM_DISARM, 1.0)
TICKS = int(sys.argv[1]) if len(sys.argv) > 1 else 100
sws = [float(x) for x in sys.argv[2].split(",")] if len(sys.argv) > 2 else [2e-5]

def serial():
    for _ in range(TICKS):
        for _ in range(10):
            server.step_chunk(); server.emit_streams()
        server.flush()

def piped():
    for _ in range(TICKS):
        server._unpaced_tick(10, math.inf, math.inf, 0.0, 0.0)
        server.flush()

res = {}
modes = [("serial", None, serial)] + [("pipelined", sw, piped) for sw in sws]
for rep in range(5):
    for name, sw, fn in modes:
        sim0 = rig.time_s; t0 = time.perf_counter(); c0 = time.process_time()
        if sw is None: fn()
        else:
            with short_switch_interval(sw): fn()
        sim = rig.time_s - sim0; w = (time.perf_counter() - t0) / sim * 1e3; c = (time.process_time() - c0) / sim * 1e3
        k = (name, sw); res.setdefault(k, []).append((w, c))
for (name, sw), v in res.items():
    ws = sorted(x[0] for x in v); cs = sorted(x[1] for x in v)
    print(f"{name:9s} sw={sw}: wall ms/sim-s best {ws[0]:.2f} median {ws[2]:.2f}; cpu best {cs[0]:.2f} median {cs[2]:.2f} -> best {1000/ws[0]:.0f}x")
server.close()
