#!/usr/bin/env bash
# OpenCueDryRun: tools/farm/opencue_job.py compiles, and the commands its
# --dry-run prints (the frames OpenCue would run, in dependency order: 4 tile
# frames, then the merge) assemble an image bit-identical to one process.
# OpenCue itself is not run (no Cuebot here): docs/farm-schedulers.md.
#
#   bash tests/farm/test_opencue_dryrun.sh [PATH/TO/vdbmarch]
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
VDBMARCH=${1:-$ROOT/build/bin/vdbmarch}
[ -x "$VDBMARCH" ] || { echo "test_opencue_dryrun: no vdbmarch binary at $VDBMARCH" >&2; exit 1; }
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
SCENE=$ROOT/vdb_samples/cloud.json
OPTS=(--res 96x72 --spp 2 --seed 3)

python3 -m py_compile "$ROOT/tools/farm/opencue_job.py"
python3 "$ROOT/tools/farm/opencue_job.py" --dry-run --tiles 4 --vdbmarch "$VDBMARCH" \
  -o "$TMP/out dir/merged.exr" "$SCENE" -- "${OPTS[@]}" >"$TMP/job.sh"
cat "$TMP/job.sh"
[ "$(grep -c -- '--tile [0-3]/4' "$TMP/job.sh")" -eq 4 ] || { echo "FAIL: expected 4 tile commands"; exit 1; }
grep -q 'depend_all on render' "$TMP/job.sh" || { echo "FAIL: the merge layer does not depend on the render layer"; exit 1; }
sh "$TMP/job.sh"
"$VDBMARCH" render "$SCENE" "${OPTS[@]}" -q -o "$TMP/single.exr"
"$VDBMARCH" compare "$TMP/out dir/merged.exr" "$TMP/single.exr" --identical
# argument errors are refused before anything is scheduled
if python3 "$ROOT/tools/farm/opencue_job.py" --dry-run --frames 1-3 -o "$TMP/x.exr" "$SCENE" 2>/dev/null; then
  echo "FAIL: --frames without #### in the output was accepted"; exit 1
fi
echo "test_opencue_dryrun: PASS"
