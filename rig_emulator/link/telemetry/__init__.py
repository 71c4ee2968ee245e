"""Streamed telemetry: which message goes out how often (:mod:`.stream_table`, :mod:`.streams`),
one builder per message (:mod:`.attitude`, :mod:`.position`, :mod:`.sensors`, :mod:`.status`) with
what they need (:mod:`.context`, :mod:`.ideal_sensors`, :mod:`.units`), the link counters on request
(:mod:`.link_status`), fault STATUSTEXT (:mod:`.fault_report`) and headless .tlog files (:mod:`.tlog_export`)."""
