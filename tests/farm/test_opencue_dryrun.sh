#!/usr/bin/env bash
# OpenCueDryRun: tools/farm/opencue_job.py compiles, and the commands its
# --dry-run prints (the frames OpenCue would run, in dependency order: 4 tile
# frames, then the merge; then 2 frames x 2 tiles) assemble images
# bit-identical to one process.
# OpenCue itself is not run (no Cuebot here): docs/farm.md.
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

# compiles (as python3 -m py_compile would, without writing __pycache__ into the tree)
python3 -c 'import sys; compile(open(sys.argv[1]).read(), sys.argv[1], "exec")' "$ROOT/tools/farm/opencue_job.py"
python3 "$ROOT/tools/farm/opencue_job.py" --dry-run --tiles 4 --vdbmarch "$VDBMARCH" \
  -o "$TMP/out dir/merged.exr" "$SCENE" -- "${OPTS[@]}" >"$TMP/job.sh"
cat "$TMP/job.sh"
[ "$(grep -c -- '--tile [0-3]/4' "$TMP/job.sh")" -eq 4 ] || { echo "FAIL: expected 4 tile commands"; exit 1; }
grep -q 'depend_all on render' "$TMP/job.sh" || { echo "FAIL: the merge layer does not depend on the render layer"; exit 1; }
sh "$TMP/job.sh"
"$VDBMARCH" render "$SCENE" "${OPTS[@]}" -q -o "$TMP/single.exr"
"$VDBMARCH" compare "$TMP/out dir/merged.exr" "$TMP/single.exr" --identical
# frames x tiles (layers render_t0, render_t1 over the frames, merge frame by
# frame), on a shot whose frames are different volumes
mkdir -p "$TMP/shot"
ln -s "$ROOT/vdb_samples/cloud.vdb" "$TMP/shot/vol.0001.vdb"
ln -s "$ROOT/vdb_samples/plume.vdb" "$TMP/shot/vol.0003.vdb"
python3 "$ROOT/tools/farm/opencue_job.py" --dry-run --tiles 2 --frames 1-3:2 --vdbmarch "$VDBMARCH" \
  -o "$TMP/anim/a.####.exr" "$TMP/shot/vol.####.vdb" -- "${OPTS[@]}" >"$TMP/frames.sh"
grep -q 'frame-by-frame on render_t1' "$TMP/frames.sh" || { echo "FAIL: no frame-by-frame depend"; exit 1; }
sh "$TMP/frames.sh"
for f in 1 3; do
  "$VDBMARCH" render "$TMP/shot/vol.####.vdb" "${OPTS[@]}" --frames "$f" -q -o "$TMP/single.$f.exr"
  "$VDBMARCH" compare "$TMP/anim/a.000$f.exr" "$TMP/single.$f.exr" --identical
done
# argument errors are refused before anything is scheduled
if python3 "$ROOT/tools/farm/opencue_job.py" --dry-run --frames 1-3 -o "$TMP/x.exr" "$SCENE" 2>/dev/null; then
  echo "FAIL: --frames without #### in the output was accepted"; exit 1
fi
echo "test_opencue_dryrun: PASS"
