"""Helpers for tests and scripts, kept out of the production :mod:`rig_emulator.link` package.

* :mod:`.rig` - start a MAVLink rig on free ports (a subprocess or a thread) and drive it
  with pymavlink clients (``connect``, ``recv``, ``command``, ``MissionClient``, ...).
* :mod:`.relay` - a lossy, laggy UDP relay between a ground station and a rig.
* :mod:`.fuzz` / :mod:`.fuzz_session` - hostile frames, the oracle of how the rig counts
  them, and a flood-and-check session over real sockets (``benchmarks/fuzz_link.py``).
"""
