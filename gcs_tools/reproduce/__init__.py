"""Reproduce the paper's experiments: ``rig-gcs reproduce -o DIR``.

From Python: ``gcs_tools.reproduce.runner.reproduce(out_dir, seed=0, workers=None,
scheduler=None, only=None, quick=False)`` runs the experiments of
:mod:`gcs_tools.reproduce.experiments` and writes ``report.md``, ``results.json`` and the
figures. docs/how-to/reproduce.md describes what each experiment runs, measures and compares
with the paper. (Nothing is imported here, so ``rig-gcs --help`` stays fast.)
"""
