#!/usr/bin/env bash
# Issue 12's proof in one command: the damaged-file catalogue of the real
# assets (needs ../shared/assets; skipped without), the ASan+UBSan unit and
# stress suites, and the libFuzzer runs of every reader. docs/robustness.md
# records the figures.
# Usage: tools/robustness.sh [FUZZ_RUNS]   (default 1000000 per harness;
#        MAX_SECONDS caps each harness, default 3600)
set -uo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
status=0
echo "== damaged-file catalogue"
bash "$ROOT/tools/setup.sh" >/dev/null || exit 1
python3 "$ROOT/tools/damage_catalogue.py" --copies 20 || status=1
echo "== sanitizers"
bash "$ROOT/tools/sanitize.sh" "unit|stress" || status=1
echo "== fuzzing"
bash "$ROOT/tools/fuzz.sh" "${1:-1000000}" || status=1
exit $status
