"""The command microservice: COMMAND_LONG / COMMAND_INT (:mod:`.command_long`), a retried
command acting once (:mod:`.dedup`), flight modes (:mod:`.modes`, :mod:`.standard_modes`), flight
commands, control and monitors, GCS loss, offboard set-points (:mod:`.offboard_setpoints`) and the
console (:mod:`.console`)."""
