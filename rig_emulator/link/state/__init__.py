"""What a rig keeps across restarts: the state directory (:mod:`.directory`) and the open
state with its documents (:mod:`.rig_state`)."""
