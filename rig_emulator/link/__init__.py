"""The rig on MAVLink: serves the running :class:`~rig_emulator.simulation.live.LiveRig` to
ground stations (QGroundControl, MAVProxy, MAVSDK, pymavlink scripts).

One folder per MAVLink microservice (as PX4's ``src/modules/mavlink/`` keeps one file per
service), so where a message is handled follows from the folder names:

* :mod:`~rig_emulator.link.endpoints.sockets` - sockets named by mavutil connection strings
  (``sockets``), one peer's parser/encoder, stream schedule and transmit buffer (``channel``),
  and what each link received, handled and dropped (``counters``).
* :mod:`~rig_emulator.link.telemetry` - streamed messages: the stream table and per-peer
  schedules, one builder module per message family (attitude, position, sensors, status),
  SI -> MAVLink units (``units``), the link counters sent on request (``link_status``),
  power (``power``), fault STATUSTEXT (``fault_report``) and a headless run written as a .tlog (``tlog_export``).
* :mod:`~rig_emulator.link.parameters` - the parameter table, its protocol and its store.
* :mod:`~rig_emulator.link.mission` - mission upload/download, the stored mission, execution.
* :mod:`~rig_emulator.link.commands.command_long` - COMMAND_LONG / COMMAND_INT (``command_long``),
  retries acting once (``dedup``), flight modes (``modes``, ``standard_modes``), flight
  commands and monitors, GCS loss, offboard set-points (``offboard_setpoints``), the console.
* :mod:`~rig_emulator.link.ftp` - MAVFTP (FILE_TRANSFER_PROTOCOL) and the component metadata it serves.
* :mod:`~rig_emulator.link.px4_simulator` - PX4's simulator API (lockstep).
* :mod:`~rig_emulator.link.signing.policy` - MAVLink 2 signing: policy, key, timestamp clock.
* :mod:`~rig_emulator.link.state` - what survives a restart: the state directory and the
  documents it holds (parameters, mission, signing clock), written atomically.

At the top: :mod:`~rig_emulator.link.server` (wiring and the paced loop),
:mod:`~rig_emulator.link.loop_timing` (its wall-clock record), and the command line
:mod:`~rig_emulator.link.serve` (:mod:`~rig_emulator.link.serve_args`,
:mod:`~rig_emulator.link.serve_setup`).

Helpers that start a rig from tests and scripts, a lossy relay and the fuzzer live outside
this package, in :mod:`rig_emulator.testing`.
"""
