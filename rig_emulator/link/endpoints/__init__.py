"""Where bytes come and go: sockets named by mavutil connection strings (:mod:`.sockets`),
one peer's parser, encoder and schedule (:mod:`.channel`), and the link counters (:mod:`.counters`)."""
