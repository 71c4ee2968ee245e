"""MAVLink 2 message signing: what is accepted (:mod:`.policy`), the key (:mod:`.key`) and
the timestamp clock (:mod:`.clock`)."""
