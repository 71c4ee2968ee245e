#!/usr/bin/env bash
# Creates .venv (Python >= 3.11) and installs hilms-sil with the given extras (editable).
# Usage: scripts/setup-venv.sh [EXTRAS]   e.g. scripts/setup-venv.sh test
#
# Installs only when something it installs from changed: a stamp in .venv records a hash of
# pyproject.toml, this script and the interpreter's version, and the extras installed with
# them; a later call with the same inputs and extras among those recorded returns at once
# (a warm `scripts/demo.sh` spends its time flying, not in pip). Delete .venv/.hilms-sil-install
# (or .venv) to force a reinstall.
set -euo pipefail
cd "$(dirname "$0")/.."
PY=${PYTHON:-python3}
if [ ! -x .venv/bin/python ]; then
    "$PY" -m venv .venv
fi
extras=${1:-}
stamp=.venv/.hilms-sil-install
key=$( { cat pyproject.toml scripts/setup-venv.sh; .venv/bin/python -VV; } | .venv/bin/python -c \
    "import hashlib, sys; print(hashlib.sha256(sys.stdin.buffer.read()).hexdigest())")

recorded_key="" recorded_extras=""
if [ -f "$stamp" ]; then
    recorded_key=$(sed -n 's/^key=//p' "$stamp")
    recorded_extras=$(sed -n 's/^extras=//p' "$stamp")
fi
installed=1
[ "$recorded_key" = "$key" ] && [ -x .venv/bin/rig-emulator ] || installed=0
for e in ${extras//,/ }; do
    case ",$recorded_extras," in *",$e,"*) ;; *) installed=0 ;; esac
done
[ "$installed" = 1 ] && exit 0

spec="."
[ -n "$extras" ] && spec=".[${extras}]"
.venv/bin/python -m pip install -q --upgrade pip >/dev/null 2>&1 || true
.venv/bin/python -m pip install -q -e "$spec"
# Byte-code of the sources once (the MAVLink dialect module alone is 1.9 MB of Python): the
# commands start fast even where Python may not write it (PYTHONDONTWRITEBYTECODE).
.venv/bin/python -m compileall -q -j 0 rig_emulator protocol gcs_tools >/dev/null || true
[ "$recorded_key" = "$key" ] && extras="${recorded_extras:+$recorded_extras,}$extras"
printf 'key=%s\nextras=%s\n' "$key" "$(printf '%s' "$extras" | tr ',' '\n' | sed '/^$/d' | sort -u | paste -sd, -)" \
    > "$stamp"
