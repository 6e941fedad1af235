#!/usr/bin/env bash
# Installs what the tests need (scripts/setup.sh --test) and runs them all.
# Extra arguments go to pytest.  Under CI=true a missing validator fails the run.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh --test
exec .venv/bin/python -m pytest "$@"
