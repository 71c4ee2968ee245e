#!/usr/bin/env bash
# Build the documentation site into site/ (MkDocs, strict: a broken link, reference or
# include fails). First regenerates the reference pages made from the code (docs/generated/:
# command-line help, parameters, telemetry streams, the dialect).
# Usage: scripts/docs.sh            regenerate docs/generated/ and build site/
#        scripts/docs.sh --check    fail if a generated file differs from the committed one, then build (CI)
#        scripts/docs.sh --serve    regenerate and preview on http://127.0.0.1:8000
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup-venv.sh docs
mode=${1:-}
if [ "$mode" = "--check" ]; then
    .venv/bin/python scripts/docs_gen.py --check
else
    .venv/bin/python scripts/docs_gen.py
fi
if [ "$mode" = "--serve" ]; then
    NO_MKDOCS_2_WARNING=1 exec .venv/bin/mkdocs serve
fi
NO_MKDOCS_2_WARNING=1 .venv/bin/mkdocs build --strict --quiet
echo "docs: site/index.html"
