"""The rig on MAVLink: serves the running :class:`~rig_emulator.simulation.live.LiveRig` to
ground stations (QGroundControl, MAVProxy, MAVSDK, pymavlink scripts).

Layout (one concept per module):

* :mod:`endpoints` - sockets named by mavutil connection strings (udpout, udpin, tcpin, tcp);
  each remote peer becomes a :class:`~rig_emulator.link.channel.Channel`.
* :mod:`channel` - one peer: its MAVLink parser/encoder (pymavlink's generated dialect),
  its counters, its stream schedule and its transmit buffer.
* :mod:`mavlink_units` - the one place where SI numbers become MAVLink units (mm, cdeg,
  degE7, mG, ...); frames go through :mod:`protocol.frames` and :mod:`protocol.geodesy`.
* :mod:`ideal_sensors` - the sensor readings the streams publish (ideal until the sensor
  layer adds its fields to the snapshot).
* :mod:`telemetry_*` - one builder per streamed message: snapshot -> message.
* :mod:`streams` - which message goes out how often (per simulated time).
* :mod:`params` / :mod:`param_service` - the parameter table and protocol.
* :mod:`modes`, :mod:`commands`, :mod:`offboard_setpoints`, :mod:`ftp_server` (+ :mod:`component_metadata`),
  :mod:`flight_monitors` (set-point timeout, geofence) - the other microservices;
  :mod:`command_dedup` - a retried or duplicated command acts once.
* :mod:`counters` / :mod:`link_status` - what the link received, dropped and why, and the
  loop's step counters; sent to a client on request (NAMED_VALUE_INT).
* :mod:`signing` (:mod:`signing_key`, :mod:`signing_clock`) - MAVLink 2 signing on every link.
* :mod:`rig_state` (:mod:`state_dir`, :mod:`param_store`, :mod:`mission_store`) - what survives
  a restart: parameters, the mission, the signing clock, written atomically.
* :mod:`server` - wiring and the paced loop; :mod:`serve` (:mod:`serve_setup`) - the command line.
* :mod:`testing` - start a rig on free ports from tests and scripts; :mod:`testing_relay` - a
  lossy, laggy UDP relay; :mod:`testing_fuzz` / :mod:`testing_fuzz_session` - hostile frames,
  the oracle of how the rig counts them, and a flood-and-check session (scripts/fuzz_link.py).
"""
