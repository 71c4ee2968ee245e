"""The parameter microservice: the table (:mod:`.table`), PARAM_* messages (:mod:`.service`),
and the values set over MAVLink kept across restarts (:mod:`.store`)."""
