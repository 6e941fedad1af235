#!/usr/bin/env bash
# Installs what the tests need (scripts/setup.sh --test), runs ruff and the import-linter layers
# contract, then the tests.  Under CI=true a missing validator fails the run.
#   bash scripts/test.sh          everything (the README's command; .ci/run calls it)
#   bash scripts/test.sh --fast   the inner loop: no slow, consumers, ros or browser test (under 90 s)
# Other arguments go to pytest.
set -euo pipefail
cd "$(dirname "$0")/.."
fast=()
if [ "${1:-}" = "--fast" ]; then
  shift
  fast=(-m "not slow and not consumers and not ros and not browser")
fi
bash scripts/setup.sh --test
.venv/bin/ruff check --quiet robotkit tests benchmarks scripts dodo.py
.venv/bin/lint-imports --no-cache >/dev/null || { .venv/bin/lint-imports --no-cache; exit 1; }
exec .venv/bin/python -m pytest "${fast[@]}" "$@"
