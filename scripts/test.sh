#!/usr/bin/env bash
# One command: set up .venv with the test extras and run the whole test suite.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup-venv.sh test
# Real ground-station clients the integration tests drive. MAVProxy's declared dependencies
# pull a GUI stack (about 1 GB) that a console session does not use, hence --no-deps.
.venv/bin/python -m pip install -q --no-deps "MAVProxy==1.8.75"
# Compile the step loop once before the suite: the tests then load it from numba's on-disk
# cache instead of compiling it in many processes at once.
.venv/bin/python -m rig_emulator simulate --scenario hover --duration 0.1 > /dev/null
# Three workers on two cores: many integration tests wait on sockets and real clients' timeouts (wall
# time), so a third worker fills the cores they leave idle; the tests judge rates and waits in simulated
# time and pass with the cores shared (stress-ng --cpu 2 beside the suite).
exec .venv/bin/python -m pytest -n 3 -q "$@"
