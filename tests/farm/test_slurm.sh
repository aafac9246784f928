#!/usr/bin/env bash
# SlurmTiledRender (ctest -L slurm): a real Slurm scheduler on loopback
# (tools/farm/slurm_local.sh) runs a 4-tile render submitted by
# tools/farm/slurm_submit.sh; the merged image must be bit-identical to the same
# render in one process. Also: a tile task requeued mid-render resumes from
# its checkpoint and the merge stays bit-identical; a failing render task makes --wait fail, the
# merge is cancelled and no output is written; when vdbmarch has --frames, a
# 2-frame x 2-tile array over a shot whose frames are different volumes.
# Exit 77 (skipped) only when the Slurm or munge binaries are not installed.
# Each submission is bounded (timeout 120) so that the trap always brings the
# cluster down before CTest's TIMEOUT would kill the script.
#
#   bash tests/farm/test_slurm.sh [PATH/TO/vdbmarch]
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
VDBMARCH=${1:-$ROOT/build/bin/vdbmarch}
[ -x "$VDBMARCH" ] || { echo "test_slurm: no vdbmarch binary at $VDBMARCH" >&2; exit 1; }
VDBMARCH=$(cd "$(dirname "$VDBMARCH")" && pwd)/$(basename "$VDBMARCH")
export PATH="$PATH:/usr/sbin:/sbin"
for b in slurmctld slurmd sbatch squeue sinfo scontrol munged; do
  if ! command -v "$b" >/dev/null; then
    echo "test_slurm: SKIP: $b not installed (apt-get install slurmctld slurmd slurm-client munge)"
    exit 77
  fi
done

t_start=$EPOCHREALTIME
elapsed() { awk -v a="$t_start" -v b="$EPOCHREALTIME" 'BEGIN{printf "%.1f", b-a}'; }
step() { echo "[test_slurm $(elapsed)s] $*"; }

# Short path: the munge and slurmstepd sockets live under it.
TMP=$(mktemp -d /tmp/vdbmarch-slurm.XXXXXX)
STATE=$TMP/cluster
cleanup() {
  local rc=$?
  bash "$ROOT/tools/farm/slurm_local.sh" down "$STATE" || true
  if [ $rc -ne 0 ] && [ -d "$STATE/log" ]; then
    for f in "$STATE"/log/*.log; do echo "----- tail $f"; tail -n 15 "$f"; done
  fi
  rm -rf "$TMP"
  exit $rc
}
trap cleanup EXIT
trap 'exit 130' INT TERM

SCENE=$ROOT/vdb_samples/cloud.json
RENDER_OPTS=(--res 96x72 --spp 4 --seed 7)

step "bringing up the loopback cluster in $STATE"
t_up=$EPOCHREALTIME
# `eval "$(... up)"` would swallow a failed bring-up (the substitution's
# status is lost) and die later on an unset SLURM_CONF: name the failure.
# One retry: the loopback daemons occasionally lose a start-up race.
bring_up() { bash "$ROOT/tools/farm/slurm_local.sh" up "$STATE"; }
if ! cluster_env=$(bring_up); then
  echo "test_slurm: the loopback cluster did not come up; retrying once"
  bash "$ROOT/tools/farm/slurm_local.sh" down "$STATE" || true
  cluster_env=$(bring_up) || { echo "test_slurm: FAIL: tools/farm/slurm_local.sh up $STATE failed twice"; exit 1; }
fi
eval "$cluster_env"
step "cluster up in $(awk -v a="$t_up" -v b="$EPOCHREALTIME" 'BEGIN{printf "%.1f", b-a}') s: SLURM_CONF=$SLURM_CONF"
sinfo

# --- 4 tiles, merged, against one process
step "submitting 4 tiles of $SCENE"
sub=$(timeout 120 bash "$ROOT/tools/farm/slurm_submit.sh" --tiles 4 --wait --vdbmarch "$VDBMARCH" \
  --workdir "$TMP/work" -o "$TMP/out/merged.exr" "$SCENE" -- "${RENDER_OPTS[@]}")
echo "$sub"
if ! grep -q '^render_job=[0-9]*$' <<<"$sub" || ! grep -q '^merge_job=[0-9]*$' <<<"$sub"; then
  echo "test_slurm: FAIL: job ids not printed"; exit 1
fi
for i in 0 1 2 3; do
  [ -f "$TMP/work/merged.tile_${i}of4.exr" ] || { echo "test_slurm: FAIL: tile $i missing"; exit 1; }
done
ls "$TMP/work/logs"
[ "$(find "$TMP/work/logs" -name 'merged.render.*.log' | wc -l)" -eq 4 ] \
  || { echo "test_slurm: FAIL: expected 4 render task logs"; exit 1; }
step "tiled render merged; rendering the same scene in one process"
"$VDBMARCH" render "$SCENE" "${RENDER_OPTS[@]}" -q -o "$TMP/single.exr"
"$VDBMARCH" compare "$TMP/out/merged.exr" "$TMP/single.exr" --identical \
  || { echo "test_slurm: FAIL: the merged Slurm render differs from the single-process render"; exit 1; }
step "merged == single: bit-identical"

# --- a tile task requeued mid-render (as preemption does) saves its state on
# SIGTERM, and the requeued task resumes from it: the merge is still
# bit-identical to one process. The tile must outlast the requeue's delivery
# (scontrol to SIGTERM): at 300 spp a tile took 0.8 s on a fast machine and
# finished before the signal came.
RQ_OPTS=(--res 96x72 --spp 1500 --seed 7)
step "submitting 2 tiles at ${RQ_OPTS[*]}, checkpointing every 0.3 s"
sub=$(timeout 60 bash "$ROOT/tools/farm/slurm_submit.sh" --tiles 2 --checkpoint-every 0.3 --vdbmarch "$VDBMARCH" \
  --workdir "$TMP/rq" -o "$TMP/out/rq.exr" "$SCENE" -- "${RQ_OPTS[@]}")
rq_job=$(sed -n 's/^render_job=//p' <<<"$sub")
ck="$TMP/rq/rq.tile_0of2.exr.ckpt"
for i in $(seq 600); do [ -f "$ck" ] && break; sleep 0.1; done
[ -f "$ck" ] || { echo "test_slurm: FAIL: task 0 wrote no checkpoint"; exit 1; }
step "task ${rq_job}_0 has a checkpoint: requeuing it"
scontrol requeue "${rq_job}_0"
for i in $(seq 1200); do [ -f "$TMP/out/rq.exr" ] && break; sleep 0.1; done
[ -f "$TMP/out/rq.exr" ] || { tail -n 20 "$TMP"/rq/logs/*.log; echo "test_slurm: FAIL: no merged image after the requeue"; exit 1; }
log0=$(ls "$TMP"/rq/logs/rq.render.*_0.log)
cat "$log0"
grep -q 'stopped with its state' "$log0" || { echo "test_slurm: FAIL: task 0 did not save its state when requeued"; exit 1; }
grep -q '(restart 1)' "$log0" || { echo "test_slurm: FAIL: task 0 did not run again"; exit 1; }
grep -q 'resuming from .*rq.tile_0of2.exr.ckpt' "$log0" || { echo "test_slurm: FAIL: task 0 started again from nothing"; exit 1; }
[ ! -e "$ck" ] || { echo "test_slurm: FAIL: the checkpoint was not removed after the resumed task completed"; exit 1; }
"$VDBMARCH" render "$SCENE" "${RQ_OPTS[@]}" -q -o "$TMP/rq_single.exr"
"$VDBMARCH" compare "$TMP/out/rq.exr" "$TMP/rq_single.exr" --identical \
  || { echo "test_slurm: FAIL: the render with a requeued task differs from the single-process render"; exit 1; }
step "requeued task resumed; merged == single: bit-identical"

# --- a failing task: --wait must fail, show the log, cancel the merge, write nothing
step "submitting a render whose tasks fail"
if timeout 120 bash "$ROOT/tools/farm/slurm_submit.sh" --tiles 2 --wait --vdbmarch "$VDBMARCH" \
    --workdir "$TMP/bad" -o "$TMP/out/bad.exr" "$SCENE" -- "${RENDER_OPTS[@]}" --method no-such-method \
    >"$TMP/bad.out" 2>&1; then
  cat "$TMP/bad.out"; echo "test_slurm: FAIL: --wait succeeded although every task failed"; exit 1
fi
cat "$TMP/bad.out"
if ! grep -q 'FAILED' "$TMP/bad.out" || ! grep -q 'no-such-method' "$TMP/bad.out"; then
  echo "test_slurm: FAIL: the failure report does not show the task's log"; exit 1
fi
grep -q 'merge job [0-9]*: CANCELLED' "$TMP/bad.out" \
  || { echo "test_slurm: FAIL: the merge job was not cancelled"; exit 1; }
[ ! -e "$TMP/out/bad.exr" ] || { echo "test_slurm: FAIL: an output was written"; exit 1; }
step "failing tasks reported, merge cancelled"

# --- frames x tiles, when vdbmarch renders frame ranges: a shot whose frames
# are different volumes (frame 1 the cloud, frame 3 the plume), so a tile of
# one frame merged into another would show
if "$VDBMARCH" render --help | grep -q -- '--frames'; then
  mkdir -p "$TMP/shot"
  ln -s "$ROOT/vdb_samples/cloud.vdb" "$TMP/shot/vol.0001.vdb"
  ln -s "$ROOT/vdb_samples/plume.vdb" "$TMP/shot/vol.0003.vdb"
  step "submitting frames 1-3:2 x 2 tiles of $TMP/shot/vol.####.vdb"
  timeout 120 bash "$ROOT/tools/farm/slurm_submit.sh" --tiles 2 --frames 1-3:2 --wait --vdbmarch "$VDBMARCH" \
    --workdir "$TMP/fr" -o "$TMP/out/anim.####.exr" "$TMP/shot/vol.####.vdb" -- "${RENDER_OPTS[@]}"
  for f in 1 3; do
    "$VDBMARCH" render "$TMP/shot/vol.####.vdb" "${RENDER_OPTS[@]}" --frames "$f" -q -o "$TMP/single.000$f.exr"
    "$VDBMARCH" compare "$TMP/out/anim.000$f.exr" "$TMP/single.000$f.exr" --identical \
      || { echo "test_slurm: FAIL: frame $f differs from its single-process render"; exit 1; }
  done
  if "$VDBMARCH" compare "$TMP/out/anim.0001.exr" "$TMP/out/anim.0003.exr" --identical >/dev/null 2>&1; then
    echo "test_slurm: FAIL: frames 1 and 3 are the same image"; exit 1
  fi
  [ ! -e "$TMP/out/anim.0002.exr" ] || { echo "test_slurm: FAIL: frame 2 rendered with step 2"; exit 1; }
  step "frames 1 and 3 (2 tiles each) bit-identical to single-process renders"
else
  step "vdbmarch has no --frames: frame arrays not tested"
fi

step "PASS"
