#!/usr/bin/env bash
# The cost of splitting one render across machines (docs/farm.md): the CPU
# time (user + sys) of N tiles rendered one after another, each a separate
# process as on a farm, against one process rendering the whole frame; and
# for a progressive guided render, the same for parts by photon passes and
# for tiles sharing one baked cache. Each split is merged and checked
# bit-identical to the one-process image (`compare --identical`; the baked
# cache variant is checked against a one-process render with that cache).
# Prints a markdown table; medians over REPEATS runs (default 1).
# Usage: [SECTIONS="cloud glass heavy cache"] tools/bench_farm.sh [OUT_DIR] [REPEATS] [THREADS]
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
out=${1:-$root/bench_out/farm}
repeats=${2:-1}
threads=${3:-2}
bin=$root/build/bin/vdbmarch
mkdir -p "$out"
sections=" ${SECTIONS:-cloud glass heavy cache} "
want() { [[ $sections == *" $1 "* ]]; }
median() { sort -g | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}'; }

# cpu CMD...: runs CMD quietly, prints "cpu_seconds wall_seconds".
cpu() {
  /usr/bin/time -f '%U %S %e' -o "$out/time.txt" "$@" -q >/dev/null
  awk '{printf "%.3f %.3f\n", $1 + $2, $3}' "$out/time.txt"
}

# run_split NAME SCENE SPLIT_OPTIONS... -- RENDER_OPTIONS...: renders every
# part (SPLIT_OPTIONS are the per-part options, e.g. "--tile 0/4"), merges
# them, checks identity against $out/NAME.single.exr, prints "cpu wall".
declare -A single_cpu
row() {  # row LABEL SCENE_KEY PARTS CPU WALL IDENTICAL
  local base=${single_cpu[$2]}
  printf '| %s | %s | %.2f | %.2f | %.3f | %s |\n' "$1" "$3" "$4" "$5" "$(echo "$4 / $base" | bc -l)" "$6"
}

printf '| render | parts | CPU s (all parts) | wall s (parts one after another) | CPU / one process | merged = one process |\n'
printf '|---|---|---|---|---|---|\n'

measure_single() {  # measure_single KEY SCENE OPTIONS...
  local key=$1 scene=$2; shift 2
  local c=() w=()
  for r in $(seq "$repeats"); do
    read -r ci wi < <(cpu "$bin" render "$scene" --threads "$threads" -o "$out/$key.single.exr" "$@")
    c+=("$ci"); w+=("$wi")
  done
  single_cpu[$key]=$(printf '%s\n' "${c[@]}" | median)
  printf '| %s, one process | 1 | %.2f | %.2f | 1 | - |\n' "$key" "${single_cpu[$key]}" "$(printf '%s\n' "${w[@]}" | median)"
}

# measure_parts KEY SCENE LABEL "PART_OPTS_1" "PART_OPTS_2" ... -- OPTIONS...
measure_parts() {
  local key=$1 scene=$2 label=$3; shift 3
  local parts=()
  while [ "$1" != "--" ]; do parts+=("$1"); shift; done
  shift
  local c=() w=() ident=""
  for r in $(seq "$repeats"); do
    local ct=0 wt=0 files=()
    for i in "${!parts[@]}"; do
      # shellcheck disable=SC2086
      read -r ci wi < <(cpu "$bin" render "$scene" --threads "$threads" ${parts[$i]} -o "$out/$key.part$i.exr" "$@")
      ct=$(echo "$ct + $ci" | bc -l); wt=$(echo "$wt + $wi" | bc -l)
      files+=("$out/$key.part$i.exr")
    done
    "$bin" merge "${files[@]}" -o "$out/$key.merged.exr" -q
    if "$bin" compare "$out/$key.merged.exr" "$out/$key.single.exr" --identical >/dev/null; then ident=yes; else ident=NO; fi
    rm -f "${files[@]}"
    c+=("$ct"); w+=("$wt")
  done
  row "$key, $label" "$key" "${#parts[@]}" "$(printf '%s\n' "${c[@]}" | median)" "$(printf '%s\n' "${w[@]}" | median)" "$ident"
}

tiles() { local n=$1; for i in $(seq 0 $((n - 1))); do printf -- '--tile %d/%d\n' "$i" "$n"; done; }

# 1. The README's cloud (auto: the path tracer, no photons): a tile repeats
#    only the loading.
cloud=$root/vdb_samples/cloud.json
if want cloud; then
  measure_single cloud "$cloud" --spp 16
  for n in 2 4 8; do
    mapfile -t opts < <(tiles "$n")
    measure_parts cloud "$cloud" "$n tiles" "${opts[@]}" -- --spp 16
  done
fi

# 2. The glass scene with the automatic method (guided: progressive photon
#    passes and a cache; the scene file itself asks for uniform marching):
#    every tile traces the photon passes and builds the cache again.
glass=$root/vdb_samples/glass.json
gopts=(--method auto --res 320x240 --spp 16 --set photons.spp_per_pass=4)
# split_glass KEY OPTIONS...: tiles and parts by passes of the glass scene.
split_glass() {
  local key=$1; shift
  measure_single "$key" "$glass" "$@"
  for n in 2 4 8; do
    mapfile -t opts < <(tiles "$n")
    measure_parts "$key" "$glass" "$n tiles" "${opts[@]}" -- "$@"
  done
  # Parts by photon passes (4 passes of 4 samples): each part traces its own
  # passes' photons and the cache refinements before it.
  measure_parts "$key" "$glass" "4 parts by passes" "--passes 0-1" "--passes 1-2" "--passes 2-3" "--passes 3-4" -- "$@"
  measure_parts "$key" "$glass" "2 parts by passes" "--passes 0-2" "--passes 2-4" -- "$@"
}
want glass && split_glass glass "${gopts[@]}"
# 2b. The same with 10^6 photons per pass (glass.json has 10^5), where the
#     photons and the cache are a tenth of a one-process render.
want heavy && split_glass glass_1M_photons "${gopts[@]}" --set photons.count=1000000

# 3. One baked cache (10^6 photons) shared by the tiles (bake once, render --cache): the
#    bake is counted once, in the CPU of the split.
want cache || exit 0
heavy=(--set photons.count=1000000)
read -r bake_cpu _ < <(cpu "$bin" bake "$glass" --threads "$threads" "${heavy[@]}" -o "$out/glass.cache.vdb")
measure_single glass_1M_cache "$glass" "${gopts[@]}" "${heavy[@]}" --cache "$out/glass.cache.vdb"
single_cpu[glass_1M_cache]=$(echo "${single_cpu[glass_1M_cache]} + $bake_cpu" | bc -l)
printf '| (bake of 10^6 photons, once: %.2f s CPU, counted in the row above and the rows below) | | | | | |\n' "$bake_cpu"
for n in 4 8; do
  mapfile -t opts < <(tiles "$n")
  line=$(measure_parts glass_1M_cache "$glass" "$n tiles, one baked cache" "${opts[@]}" -- "${gopts[@]}" "${heavy[@]}" --cache "$out/glass.cache.vdb")
  # The bake is part of the split's CPU too.
  echo "$line" | awk -F'|' -v b="$bake_cpu" -v s="${single_cpu[glass_1M_cache]}" 'BEGIN{OFS="|"} {c=$4+b; printf "|%s|%s| %.2f |%s| %.3f |%s|\n", $2, $3, c, $5, c/s, $7}'
done
