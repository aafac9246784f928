#!/usr/bin/env bash
# Equal-time noise of this build against a fixed yardstick build (a landed
# commit built with `git worktree`), for unbiased estimators: at each budget
# every binary renders the scene twice with different seeds, and the RMSE
# between the two renders is sqrt(2) times each one's RMSE against the truth
# (their bias is zero: the estimators are tested against quadrature and
# against each other). So MSE ratios need no converged truth; the ratio of
# squared pair-RMSEs is the ratio of MSEs against the truth at equal time.
# Usage: tools/bench_yardstick.sh YARDSTICK_BINARY OUT SCENE...
# Environment: RES (default 160x120), BUDGETS (seconds, default "4 16"),
# THREADS (default 2), NEW_BIN (this build's binary, default build/bin/vdbmarch:
# copy it aside to keep building while the benchmark runs), NEW_SET and
# OLD_SET (extra --set options of each side,
# default: render.method=reference on both).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
OLD="$1"; OUT="$2"; shift 2
NEW="${NEW_BIN:-$ROOT/build/bin/vdbmarch}"
RES="${RES:-160x120}"; BUDGETS="${BUDGETS:-4 16}"; THREADS="${THREADS:-2}"
NEW_SET="${NEW_SET:-render.method=reference}"; OLD_SET="${OLD_SET:-render.method=reference}"
mkdir -p "$OUT"
pair() {  # binary sets scene budget tag -> "spp rmse_pair"
    local bin="$1" sets="$2" scene="$3" budget="$4" tag="$5" args=() spp=""
    for s in $sets; do args+=(--set "$s"); done
    for seed in 11 23; do
        local log
        log=$("$bin" render "$scene" -o "$OUT/$tag.$seed.exr" --res "$RES" --time "$budget" --threads "$THREADS" \
            --set render.seed=$seed "${args[@]}" 2>&1 | tail -1)
        spp=$(echo "$log" | sed -n 's/.* \([0-9]*\) spp.*/\1/p')
    done
    echo "$spp $("$NEW" compare "$OUT/$tag.11.exr" "$OUT/$tag.23.exr" | awk '/^rmse /{print $2}')"
}
echo "| scene | budget s | yardstick spp / pair RMSE | this build spp / pair RMSE | MSE ratio (this / yardstick) |"
echo "|---|---|---|---|---|"
for scene in "$@"; do
    name=$(basename "$scene" .json)
    for b in $BUDGETS; do
        read -r so ro < <(pair "$OLD" "$OLD_SET" "$scene" "$b" "$name.old.$b")
        read -r sn rn < <(pair "$NEW" "$NEW_SET" "$scene" "$b" "$name.new.$b")
        echo "| $name | $b | $so / $ro | $sn / $rn | $(python3 -c "print(f'{($rn/$ro)**2:.3f}')") |"
    done
done
