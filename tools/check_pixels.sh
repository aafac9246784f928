#!/usr/bin/env bash
# Renders every sample scene with every method at 64x48 and 4 spp with two
# vdbmarch binaries and says, per render, whether the pixels are
# bit-identical (vdbmarch compare --identical): the check for a change that
# must not move pixels (a refactor), against a landed commit's binary. A
# render that differs is also checked for agreement (compare --paired: the
# mean per-pixel difference within 4 standard errors over the image and
# each quadrant, per channel), for changes that reorder random numbers.
# Usage: tools/check_pixels.sh BASE_VDBMARCH NEW_VDBMARCH [METHODS...]
#   (default methods: auto uniform transmittance guided reference;
#    SPP=64 in the environment for a sharper agreement check)
# Exit status 0 when every render matched bit for bit.
set -uo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BASE="$1"; NEW="$2"; shift 2
METHODS="${*:-auto uniform transmittance guided reference}"
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT
fail=0
for scene in "$ROOT"/vdb_samples/*.json "$ROOT"/vdb_samples/scenes/*.json; do
    name=$(basename "$scene" .json)
    for m in $METHODS; do
        args=(render "$scene" --res 64x48 --spp "${SPP:-4}" --threads 2 --seed 7 --method "$m" -q --no-denoise)
        "$BASE" "${args[@]}" -o "$OUT/a.exr" 2>"$OUT/a.err" || { echo "$name $m: base failed: $(tail -1 "$OUT/a.err")"; fail=1; continue; }
        "$NEW" "${args[@]}" -o "$OUT/b.exr" 2>"$OUT/b.err" || { echo "$name $m: new failed: $(tail -1 "$OUT/b.err")"; fail=1; continue; }
        if "$NEW" compare "$OUT/a.exr" "$OUT/b.exr" --identical >/dev/null 2>&1; then
            echo "$name $m: identical"
        else
            paired=$("$NEW" compare --paired "$OUT/b.exr" "$OUT/a.exr" 2>&1 | grep max_abs_z)
            if "$NEW" compare --paired "$OUT/b.exr" "$OUT/a.exr" >/dev/null 2>&1; then
                echo "$name $m: different, agree ($paired)"
            else
                echo "$name $m: DIFFERENT, DISAGREE ($paired)"
            fi
            fail=1
        fi
    done
done
exit $fail
