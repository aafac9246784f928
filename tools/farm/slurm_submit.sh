#!/usr/bin/env bash
# Submits a vdbmarch render to Slurm: one job array of tile (and frame) renders
# and one merge job that depends on it (docs/farm.md).
#
#   tools/farm/slurm_submit.sh [OPTIONS] SCENE [-- RENDER_OPTIONS...]
#
#   -o, --output OUT.exr   the merged image (required); with --frames it contains
#                          a run of '#' (OUT.####.exr), replaced by the frame number
#   --tiles N              split each frame into N tiles (vdbmarch render --tile I/N);
#                          default 1 (no tiling, no merge job)
#   --frames A-B[:STEP]    render frames A..B every STEP (the scene path, or paths
#                          inside the scene, may contain ####: vdbmarch --frames)
#   --workdir DIR          where the tiles, job scripts and logs go (default:
#                          OUTDIR/NAME.farm); must be visible to every node
#   --vdbmarch PATH        the binary the nodes run (default: build/bin/vdbmarch of
#                          this repository, else vdbmarch on PATH)
#   --partition P          Slurm partition (default: the cluster's default)
#   --cpus-per-task C      CPUs of each render task (default 1; passed as --threads
#                          unless RENDER_OPTIONS set --threads)
#   --max-running K        at most K array tasks at once (--array=...%K)
#   --job-name NAME        default vdbmarch-NAME (NAME: OUT's file name without
#                          .exr and the frame token)
#   --sbatch ARG           one more sbatch argument for both jobs (repeatable),
#                          e.g. --sbatch --time=1:00:00 --sbatch --account=fx
#   --checkpoint-every S   each task saves its render's state every S seconds
#                          (default 300) to its output + .ckpt, and when Slurm
#                          signals it: a preempted or requeued task resumes
#                          where it stopped (vdbmarch render --checkpoint)
#   --signal-before S      ask for SIGUSR1 S seconds before a task's time
#                          limit (default 60): the task saves and requeues itself
#   --wait                 wait for the jobs; exit 1, showing the logs of the
#                          failed jobs, unless every task and the merge succeeded
#   --dry-run              write the job scripts, print the sbatch commands, submit nothing
#
# Array task T renders frame index T / N, tile T % N, into
#   WORKDIR/NAME.tile_<I>of<N>[.<frame>].exr
# and its log goes to WORKDIR/logs/NAME.render.<jobid>_<T>.log; the merge job
# (sbatch --dependency=afterok:<array> --kill-on-invalid-dep=yes) runs
# `vdbmarch merge` once per frame into OUT, logging to WORKDIR/logs/NAME.merge.<jobid>.log.
# Prints render_job=<id> and merge_job=<id> (none without tiling) on stdout.
# Render tasks are submitted with --requeue and --signal=B:USR1@S: on SIGUSR1
# (the time limit is near) a task forwards it to vdbmarch, which saves its
# checkpoint and exits 75, and the task requeues itself; on SIGTERM (Slurm
# preempting or requeuing it; Slurm signals every process of the task) the
# task waits for vdbmarch to save. The requeued task resumes from the
# checkpoint; the merged image is bit-identical to an uninterrupted render.
set -euo pipefail

prog=$(basename "$0")
die() { echo "$prog: error: $*" >&2; exit 2; }
fail() { echo "$prog: $*" >&2; exit 1; }
say() { echo "$prog: $*" >&2; }
usage() { sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//' >&2; exit "${1:-2}"; }

TILES=1 FRAMES="" OUT="" WORKDIR="" VDBMARCH="" PARTITION="" CPT=1 MAXRUN="" JOBNAME="" CKPT_EVERY=300 SIGNAL_BEFORE=60
WAIT=0 DRY=0 SCENE=""
SBATCH_EXTRA=() RENDER_EXTRA=()

need() { if [ $# -lt 2 ] || [ -z "$2" ]; then die "$1 needs a value"; fi; }
while [ $# -gt 0 ]; do
  case "$1" in
    -h|--help) usage 0 ;;
    -o|--output) need "$@"; OUT=$2; shift 2 ;;
    --tiles) need "$@"; TILES=$2; shift 2 ;;
    --frames) need "$@"; FRAMES=$2; shift 2 ;;
    --workdir) need "$@"; WORKDIR=$2; shift 2 ;;
    --vdbmarch) need "$@"; VDBMARCH=$2; shift 2 ;;
    --partition) need "$@"; PARTITION=$2; shift 2 ;;
    --cpus-per-task) need "$@"; CPT=$2; shift 2 ;;
    --max-running) need "$@"; MAXRUN=$2; shift 2 ;;
    --job-name) need "$@"; JOBNAME=$2; shift 2 ;;
    --checkpoint-every) need "$@"; CKPT_EVERY=$2; shift 2 ;;
    --signal-before) need "$@"; SIGNAL_BEFORE=$2; shift 2 ;;
    --sbatch) need "$@"; SBATCH_EXTRA+=("$2"); shift 2 ;;
    --wait) WAIT=1; shift ;;
    --dry-run) DRY=1; shift ;;
    --) shift; RENDER_EXTRA=("$@"); break ;;
    -*) die "unknown option '$1' (render options go after --; see --help)" ;;
    *) [ -z "$SCENE" ] || die "one SCENE only ('$SCENE' and '$1'); render options go after --"
       SCENE=$1; shift ;;
  esac
done

posint() { [[ "$1" =~ ^[0-9]+$ ]] && [ "$((10#$1))" -ge 1 ]; }
[ -n "$SCENE" ] || die "no SCENE given (see --help)"
[ -n "$OUT" ] || die "no output given: -o OUT.exr"
posint "$TILES" || die "--tiles wants a positive integer, not '$TILES'"
posint "$CPT" || die "--cpus-per-task wants a positive integer, not '$CPT'"
[ -z "$MAXRUN" ] || posint "$MAXRUN" || die "--max-running wants a positive integer, not '$MAXRUN'"
[[ "$CKPT_EVERY" =~ ^[0-9]*\.?[0-9]+$ ]] && awk -v s="$CKPT_EVERY" 'BEGIN{exit !(s > 0)}' \
  || die "--checkpoint-every wants a positive number of seconds, not '$CKPT_EVERY'"
posint "$SIGNAL_BEFORE" || die "--signal-before wants a positive integer number of seconds, not '$SIGNAL_BEFORE'"
TILES=$((10#$TILES))

# --- frames: A-B[:STEP] (or a single frame A)
NFRAMES=0 FIRST=0 STEP=1 LAST=0
if [ -n "$FRAMES" ]; then
  [[ "$FRAMES" =~ ^([0-9]+)(-([0-9]+))?(:([0-9]+))?$ ]] \
    || die "--frames wants A-B[:STEP] (e.g. 1-24 or 1-24:2), not '$FRAMES'"
  FIRST=$((10#${BASH_REMATCH[1]}))
  LAST=$((10#${BASH_REMATCH[3]:-${BASH_REMATCH[1]}}))
  STEP=$((10#${BASH_REMATCH[5]:-1}))
  [ "$LAST" -ge "$FIRST" ] || die "--frames $FRAMES: the last frame is before the first"
  [ "$STEP" -ge 1 ] || die "--frames $FRAMES: STEP must be at least 1"
  NFRAMES=$(( (LAST - FIRST) / STEP + 1 ))
fi

# --- the output and its frame token (a run of '#' in the file name)
case "$OUT" in *.exr) ;; *) die "the output must be an .exr file, not '$OUT'" ;; esac
OUTBASE=$(basename "$OUT")
TOKEN=""
if [[ "$OUTBASE" =~ (#+) ]]; then TOKEN=${BASH_REMATCH[1]}; fi
if [ "$NFRAMES" -gt 0 ]; then
  [ -n "$TOKEN" ] || die "with --frames the output needs a frame token, e.g. -o ${OUT%.exr}.####.exr"
else
  [ -z "$TOKEN" ] || die "the output '$OUT' has a frame token ($TOKEN) but no --frames was given"
fi
PAD=${#TOKEN}
NAME=${OUTBASE%.exr}
[ -z "$TOKEN" ] || { NAME=${NAME//$TOKEN/}; NAME=${NAME%.}; NAME=${NAME%_}; }
[ -n "$NAME" ] || NAME=render
case "$NAME" in *[!A-Za-z0-9._+-]*) NAME=$(printf %s "$NAME" | tr -c 'A-Za-z0-9._+-' _) ;; esac
JOBNAME=${JOBNAME:-vdbmarch-$NAME}

abspath() { # absolute path of $1 without requiring it to exist
  case "$1" in /*) printf %s "$1" ;; *) printf %s "$PWD/$1" ;; esac
}
OUT=$(abspath "$OUT")
OUTDIR=$(dirname "$OUT")
WORKDIR=$(abspath "${WORKDIR:-$OUTDIR/$NAME.farm}")

# --- the scene: must exist at submit time (its first frame, with --frames)
frame_path() { # frame_path PATH FRAME: every run of '#' in PATH replaced by FRAME, zero-padded to the run
  local p=$1 f=$2 out=""
  while [[ "$p" =~ ^([^#]*)(#+)(.*)$ ]]; do
    out+=$(printf '%s%0*d' "${BASH_REMATCH[1]}" "${#BASH_REMATCH[2]}" "$f")
    p=${BASH_REMATCH[3]}
  done
  printf %s "$out$p"
}
SCENE=$(abspath "$SCENE")
if [ "$NFRAMES" -gt 0 ]; then first_scene=$(frame_path "$SCENE" "$FIRST"); else first_scene=$SCENE; fi
[ -f "$first_scene" ] || die "scene not found: $first_scene"

# --- the binary the nodes run
if [ -z "$VDBMARCH" ]; then
  here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
  if [ -x "$here/../../build/bin/vdbmarch" ]; then
    VDBMARCH=$(cd "$here/../../build/bin" && pwd)/vdbmarch
  elif command -v vdbmarch >/dev/null; then
    VDBMARCH=$(command -v vdbmarch)
  else
    die "no vdbmarch binary: build it (tools/setup.sh) or give --vdbmarch PATH"
  fi
fi
VDBMARCH=$(abspath "$VDBMARCH")
[ -x "$VDBMARCH" ] || die "--vdbmarch $VDBMARCH is not an executable file"

# --threads from --cpus-per-task unless the render options choose
THREADS_ARGS=(--threads "$CPT")
for a in "${RENDER_EXTRA[@]+"${RENDER_EXTRA[@]}"}"; do
  case "$a" in --threads|--threads=*) THREADS_ARGS=() ;; -o|--output|--output=*|--tile|--tile=*|--crop|--crop=*|--frames|--frames=*|--checkpoint*|--resume*)
    die "RENDER_OPTIONS must not set $a: $prog sets it" ;; esac
done

NTASKS=$(( TILES * (NFRAMES > 0 ? NFRAMES : 1) ))
command -v sbatch >/dev/null || [ "$DRY" -eq 1 ] || die "sbatch not found (is this a Slurm submit host? apt-get install slurm-client)"
if [ "$DRY" -eq 0 ]; then
  maxarray=$(scontrol show config 2>/dev/null | sed -n 's/^MaxArraySize *= *\([0-9]*\).*/\1/p')
  if [ -n "$maxarray" ] && [ "$NTASKS" -gt "$maxarray" ]; then
    die "$NTASKS tasks exceed the cluster's MaxArraySize ($maxarray): fewer tiles or frames per submission"
  fi
fi

mkdir -p "$WORKDIR/logs" "$OUTDIR"

q() { printf '%q' "$1"; }
qa() { local x s=""; for x in "$@"; do s+=" $(printf '%q' "$x")"; done; printf '%s' "${s# }"; }
TILE_PREFIX="$WORKDIR/$NAME.tile_"

# --- the array task script
RENDER_SCRIPT="$WORKDIR/$NAME.render.sh"
cat >"$RENDER_SCRIPT" <<EOF
#!/usr/bin/env bash
# Generated by $prog: one task of the render array (task T: frame index T / TILES, tile T % TILES).
set -euo pipefail
VDBMARCH=$(q "$VDBMARCH")
SCENE=$(q "$SCENE")
OUT=$(q "$OUT")
TILE_PREFIX=$(q "$TILE_PREFIX")
TOKEN=$(q "$TOKEN")
TILES=$TILES NFRAMES=$NFRAMES FIRST=$FIRST STEP=$STEP PAD=$PAD CKPT_EVERY=$CKPT_EVERY
EXTRA=($(qa "${THREADS_ARGS[@]+"${THREADS_ARGS[@]}"}" "${RENDER_EXTRA[@]+"${RENDER_EXTRA[@]}"}"))
T=\${1:-\${SLURM_ARRAY_TASK_ID:?not an array task: give the task index}}
tile=\$((T % TILES))
args=()
if [ "\$NFRAMES" -gt 0 ]; then
  frame=\$((FIRST + (T / TILES) * STEP))
  args+=(--frames "\$frame-\$frame")
  ftag=\$(printf '%0*d' "\$PAD" "\$frame")
fi
if [ "\$TILES" -gt 1 ]; then
  args+=(--tile "\$tile/\$TILES")
  out="\${TILE_PREFIX}\${tile}of\${TILES}\${ftag:+.\$ftag}.exr"
elif [ "\$NFRAMES" -gt 0 ]; then
  out=\${OUT//"\$TOKEN"/\$ftag}
else
  out=\$OUT
fi
ckpt="\$out.ckpt"
echo "[\$(date +%T)] task \$T on \$(hostname)\${SLURM_RESTART_COUNT:+ (restart \$SLURM_RESTART_COUNT)}: \$VDBMARCH render \$SCENE \${args[*]} -o \$out --checkpoint \$ckpt \${EXTRA[*]}"
# vdbmarch runs in the background so this shell can forward SIGUSR1 (sent to
# it alone, before the time limit); SIGTERM reaches vdbmarch from Slurm
# directly, so here it only keeps the shell waiting while vdbmarch saves.
"\$VDBMARCH" render "\$SCENE" "\${args[@]}" -o "\$out" --checkpoint "\$ckpt" --checkpoint-every "\$CKPT_EVERY" "\${EXTRA[@]}" &
pid=\$!
trap 'kill -USR1 \$pid 2>/dev/null || true' USR1
trap ':' TERM
set +e
while :; do
  wait \$pid; rc=\$?
  kill -0 \$pid 2>/dev/null || break  # else wait returned for a trapped signal
done
set -e
if [ \$rc -eq 75 ]; then
  echo "[\$(date +%T)] task \$T stopped with its state in \$ckpt; requeued to resume"
  task=\${SLURM_ARRAY_JOB_ID:+\${SLURM_ARRAY_JOB_ID}_\${SLURM_ARRAY_TASK_ID}}
  scontrol requeue "\${task:-\$SLURM_JOB_ID}" 2>/dev/null || true  # already requeued when Slurm stopped it
  exit 75
fi
[ \$rc -eq 0 ] || exit \$rc
echo "[\$(date +%T)] task \$T done"
EOF

# --- the merge script (one vdbmarch merge per frame)
MERGE_SCRIPT="$WORKDIR/$NAME.merge.sh"
rm -f "$MERGE_SCRIPT"
[ "$TILES" -eq 1 ] || cat >"$MERGE_SCRIPT" <<EOF
#!/usr/bin/env bash
# Generated by $prog: merges the tiles of every frame once the render array succeeded.
set -uo pipefail
VDBMARCH=$(q "$VDBMARCH")
OUT=$(q "$OUT")
TILE_PREFIX=$(q "$TILE_PREFIX")
TOKEN=$(q "$TOKEN")
TILES=$TILES NFRAMES=$NFRAMES FIRST=$FIRST STEP=$STEP PAD=$PAD
rc=0
n=\$(( NFRAMES > 0 ? NFRAMES : 1 ))
for ((k = 0; k < n; k++)); do
  ftag="" out=\$OUT
  if [ "\$NFRAMES" -gt 0 ]; then
    ftag=\$(printf '%0*d' "\$PAD" "\$((FIRST + k * STEP))")
    out=\${OUT//"\$TOKEN"/\$ftag}
  fi
  tiles=()
  for ((i = 0; i < TILES; i++)); do tiles+=("\${TILE_PREFIX}\${i}of\${TILES}\${ftag:+.\$ftag}.exr"); done
  echo "[\$(date +%T)] \$VDBMARCH merge \${tiles[*]} -o \$out"
  if ! "\$VDBMARCH" merge "\${tiles[@]}" -o "\$out"; then
    echo "merge failed for \$out" >&2; rc=1
  fi
done
exit \$rc
EOF
chmod +x "$RENDER_SCRIPT"; [ "$TILES" -eq 1 ] || chmod +x "$MERGE_SCRIPT"

# --- submission
common=(--parsable --job-name="$JOBNAME" --chdir="$WORKDIR")
[ -z "$PARTITION" ] || common+=(--partition="$PARTITION")
common+=("${SBATCH_EXTRA[@]+"${SBATCH_EXTRA[@]}"}")
array="0-$((NTASKS - 1))${MAXRUN:+%$MAXRUN}"
render_cmd=(sbatch "${common[@]}" --array="$array" --cpus-per-task="$CPT" --requeue --signal="B:USR1@$SIGNAL_BEFORE"
  --open-mode=append --output="$WORKDIR/logs/$NAME.render.%A_%a.log" "$RENDER_SCRIPT")
merge_cmd=(sbatch "${common[@]}" --cpus-per-task=1 --kill-on-invalid-dep=yes
  --output="$WORKDIR/logs/$NAME.merge.%j.log")  # + --dependency and the script, below

if [ "$DRY" -eq 1 ]; then
  qa "${render_cmd[@]}"; echo
  [ "$TILES" -gt 1 ] && echo "$(qa "${merge_cmd[@]}") --dependency=afterok:<render job id> $(q "$MERGE_SCRIPT")"
  exit 0
fi

sub_out=$("${render_cmd[@]}" 2>&1) || fail "sbatch of the render array failed: $sub_out"
RENDER_JOB=${sub_out%%;*}
[[ "$RENDER_JOB" =~ ^[0-9]+$ ]] || fail "unexpected sbatch output: $sub_out"
say "render array job $RENDER_JOB: $NTASKS tasks ($TILES tile(s) x $(( NFRAMES > 0 ? NFRAMES : 1 )) frame(s)); logs in $WORKDIR/logs"
echo "render_job=$RENDER_JOB"
MERGE_JOB=""
if [ "$TILES" -gt 1 ]; then
  sub_out=$("${merge_cmd[@]}" --dependency="afterok:$RENDER_JOB" "$MERGE_SCRIPT" 2>&1) \
    || { scancel "$RENDER_JOB" 2>/dev/null || true; fail "sbatch of the merge job failed (render array $RENDER_JOB cancelled): $sub_out"; }
  MERGE_JOB=${sub_out%%;*}
  say "merge job $MERGE_JOB (after $RENDER_JOB succeeds) -> $OUT"
fi
echo "merge_job=${MERGE_JOB:-none}"
[ "$WAIT" -eq 1 ] || exit 0

# --- --wait: poll until neither job is queued or running, then read their states
jobs_ids=$RENDER_JOB${MERGE_JOB:+,$MERGE_JOB}
errs=0
while :; do
  if left=$(squeue -h -j "$jobs_ids" -t pending,running,completing,configuring,suspended,requeued,resizing \
              -o %i 2>"$WORKDIR/logs/.squeue.err"); then
    errs=0
    [ -z "$left" ] && break
  elif grep -qi 'invalid job id' "$WORKDIR/logs/.squeue.err"; then
    break  # both jobs already purged from the controller: done
  elif [ $((errs += 1)) -ge 60 ]; then
    fail "squeue keeps failing: $(cat "$WORKDIR/logs/.squeue.err")"
  fi
  sleep 1
done
rm -f "$WORKDIR/logs/.squeue.err"

# JobState of each job (array tasks: one line each) from scontrol while the
# controller still remembers them (MinJobAge); logs from the paths above.
bad=0
states=$(scontrol -o show job "$RENDER_JOB" 2>/dev/null || true)
[ -n "$states" ] || say "warning: slurmctld no longer knows job $RENDER_JOB (MinJobAge); judging by the output files"
while read -r line; do
  [ -n "$line" ] || continue
  st=$(sed -n 's/.*JobState=\([A-Z_]*\).*/\1/p' <<<"$line")
  task=$(sed -n 's/.*ArrayTaskId=\([0-9]*\).*/\1/p' <<<"$line")
  [ "$st" = COMPLETED ] && continue
  bad=1
  ec=$(sed -n 's/.* ExitCode=\([0-9:]*\).*/\1/p' <<<"$line")
  log="$WORKDIR/logs/$NAME.render.${RENDER_JOB}_${task:-?}.log"
  say "render task ${task:-?} of job $RENDER_JOB: $st (exit $ec); log $log:"
  if [ -f "$log" ]; then tail -n 30 "$log" >&2; else say "(no log)"; fi
done <<<"$states"
if [ -n "$MERGE_JOB" ]; then
  mline=$(scontrol -o show job "$MERGE_JOB" 2>/dev/null || true)
  mst=$(sed -n 's/.*JobState=\([A-Z_]*\).*/\1/p' <<<"$mline")
  if [ -n "$mline" ] && [ "$mst" != COMPLETED ]; then
    bad=1
    mlog="$WORKDIR/logs/$NAME.merge.$MERGE_JOB.log"
    say "merge job $MERGE_JOB: $mst ($(sed -n 's/.*Reason=\([^ ]*\).*/\1/p' <<<"$mline")); log $mlog:"
    if [ -f "$mlog" ]; then tail -n 30 "$mlog" >&2; else say "(no log: it did not run)"; fi
  fi
fi
# whatever scontrol said, the outputs must be there
n=$(( NFRAMES > 0 ? NFRAMES : 1 ))
for ((k = 0; k < n; k++)); do
  o=$OUT
  [ "$NFRAMES" -eq 0 ] || o=${OUT//"$TOKEN"/$(printf '%0*d' "$PAD" "$((FIRST + k * STEP))")}
  [ -f "$o" ] || { bad=1; say "missing output $o"; }
done
[ "$bad" -eq 0 ] || fail "FAILED (render job $RENDER_JOB${MERGE_JOB:+, merge job $MERGE_JOB}; logs in $WORKDIR/logs)"
say "done: $OUT"
