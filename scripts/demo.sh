#!/usr/bin/env bash
# One command: set up .venv, then fly the paper's line-then-helix (Eq. 46) headless
# with the SMC-FLC strategy on the hardware rig (airframe hilms, the default) and print its
# mean errors next to the paper's Table 6 row (`--airframe hilms-ideal`: the ideal plant).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup-venv.sh
exec .venv/bin/rig-emulator simulate --scenario helix --strategy smc-flc --seed 1 "$@"
