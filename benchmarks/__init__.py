"""Benchmark suite of hilms-sil.

Run from the repository root::

    python -m benchmarks                 # everything, 5 repetitions, writes bench-results.json
    python -m benchmarks --quick         # short smoke run
    python -m benchmarks --only rig-core

Every figure is a ratio against a reference measured in the same run on the same
machine (or a raw figure with its unit), the median over ``--repeat`` fresh
subprocesses. See ``docs/explanation/performance.md`` and :mod:`benchmarks.harness`.
"""
