#!/usr/bin/env bash
# One command: set up .venv, then fly the paper's line-then-helix (Eq. 46) headless
# with the SMC-FLC strategy and print the mean errors (Table 6 layout).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup-venv.sh
exec .venv/bin/rig-emulator simulate --scenario helix --strategy smc-flc --seed 1 "$@"
