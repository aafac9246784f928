#!/usr/bin/env bash
# The checkpoint fault catalogue (docs/robustness.md, "Interrupted renders"):
# renders SCENE once without interruption, then N_TERM renders stopped by
# SIGTERM and N_KILL by SIGKILL at random moments (a fixed seed), each run
# again with the same command until it completes. Every final image must be
# bit-identical to the uninterrupted one, and every checkpoint left behind
# must be readable (the resumed run refuses an unreadable one: exit 1).
# Prints one line per trial and a summary; exits 1 on any failure.
#
#   tools/checkpoint_faults.sh [OUTDIR]
# Environment: SCENE (default vdb_samples/cloud.json), RES (160x120), SPP
# (200), EVERY (checkpoint interval, 0.5 s), N_TERM (20), N_KILL (5), SEED (1).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BIN="${VDBMARCH:-$ROOT/build/bin/vdbmarch}"
OUT="${1:-$(mktemp -d /tmp/vdbmarch-faults.XXXXXX)}"
SCENE="${SCENE:-$ROOT/vdb_samples/cloud.json}" RES="${RES:-160x120}" SPP="${SPP:-200}" EVERY="${EVERY:-0.5}"
N_TERM="${N_TERM:-20}" N_KILL="${N_KILL:-5}" SEED="${SEED:-1}"
mkdir -p "$OUT"
args=(render "$SCENE" --res "$RES" --spp "$SPP" -q)

t0=$EPOCHREALTIME
"$BIN" "${args[@]}" -o "$OUT/whole.exr"
full=$(awk -v a="$t0" -v b="$EPOCHREALTIME" 'BEGIN{printf "%.3f", b-a}')
echo "uninterrupted render: $full s ($SCENE, $RES, $SPP spp)"

# The kill moments: uniform in [0.1, 0.95] of the uninterrupted time.
mapfile -t moments < <(awk -v n=$((N_TERM + N_KILL)) -v s="$SEED" -v t="$full" \
    'BEGIN{srand(s); for (i = 0; i < n; i++) printf "%.3f\n", t * (0.1 + 0.85 * rand())}')
ok=0 bad=0 unreadable=0 leftovers=0 saved=0
for ((i = 0; i < N_TERM + N_KILL; i++)); do
    sig=TERM; [ "$i" -lt "$N_TERM" ] || sig=KILL
    ck="$OUT/trial$i.ckpt" img="$OUT/trial$i.exr"
    rm -f "$ck" "$img"
    "$BIN" "${args[@]}" -o "$img" --checkpoint "$ck" --checkpoint-every "$EVERY" & pid=$!
    sleep "${moments[$i]}"
    kill -"$sig" "$pid" 2>/dev/null || true
    set +e; wait "$pid"; rc=$?; set -e
    had=no; [ -f "$ck" ] && { had=yes; saved=$((saved + 1)); }
    tmp=$(find "$OUT" -maxdepth 1 -name ".trial$i.ckpt.tmp-*" | wc -l)
    leftovers=$((leftovers + tmp)); rm -f "$OUT"/.trial$i.ckpt.tmp-*
    # Resume (or, without a checkpoint, render from the start) until done.
    set +e; "$BIN" "${args[@]}" -o "$img" --checkpoint "$ck" --checkpoint-every "$EVERY" 2>"$OUT/trial$i.err"; rrc=$?; set -e
    if [ "$rrc" -ne 0 ]; then
        if grep -q "checkpoint" "$OUT/trial$i.err"; then unreadable=$((unreadable + 1)); fi
        bad=$((bad + 1)); verdict="FAIL (resume exit $rrc: $(tail -1 "$OUT/trial$i.err"))"
    elif "$BIN" compare --identical "$img" "$OUT/whole.exr" >/dev/null; then
        ok=$((ok + 1)); verdict="identical"
    else
        bad=$((bad + 1)); verdict="FAIL (differs)"
    fi
    printf 'trial %2d: SIG%-4s at %6.3f s: exit %3d, checkpoint %-3s -> %s\n' "$i" "$sig" "${moments[$i]}" "$rc" "$had" "$verdict"
done
echo "summary: $ok of $((N_TERM + N_KILL)) identical; $saved stopped runs left a checkpoint; $unreadable unreadable; $leftovers temporary file(s) left by SIGKILL"
[ "$bad" -eq 0 ]
