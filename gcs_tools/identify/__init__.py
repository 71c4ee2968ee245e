"""Identification of the emulated rig's parameters from targets: ``rig-gcs identify``.

Fits chosen configuration parameters (any numeric key that ``--set KEY=VALUE`` accepts, or
one element of a list key, a field of a list of tables, a leaf of a sensor-model tree)
within bounds, optionally with Gaussian priors, to

* the paper's published numbers (:mod:`gcs_tools.identify.paper`: Table 4, Table 6 and
  Fig. 19's mean errors, ``paper_targets.toml``), optionally its qualitative claims;
* a user's own flight logs (:mod:`gcs_tools.identify.tlog_target`): the simulated
  ATTITUDE / LOCAL_POSITION_NED / load-cell series against the logged ones.

Every evaluation runs on the sweep engine (:mod:`rig_emulator.sweep`: local processes or a
Dask cluster) and is appended to a JSON-lines record, so a rerun resumes without
re-simulating (:mod:`gcs_tools.identify.record`). The optimiser is scipy's bounded
``least_squares`` (:mod:`gcs_tools.identify.fit`); the result is a TOML preset that
``--config`` accepts (:mod:`gcs_tools.identify.preset`). docs/how-to/identify.md describes it.
(Nothing is imported here, so ``rig-gcs --help`` stays fast.)
"""
