"""The command microservice: COMMAND_LONG / COMMAND_INT (:mod:`.command_long`), a retried
command acting once (:mod:`.dedup`), flight modes (:mod:`.modes`) and offboard set-points (:mod:`.offboard`)."""
