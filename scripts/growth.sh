#!/usr/bin/env bash
# Issue 18's growth criterion: how much the time per vertex per step grows from spin-129 to
# spin-290 (the rotating sphere at two resolutions), measured on whole runs of the command.
#
#   scripts/growth.sh [PAIRS] [DRAPERY]
#
# Writes both scenes (100 frames, `drapery bench --write-scenes`), then runs them PAIRS times
# (default 3), alternating the sizes so that both see the machine in the same state, each as
# `drapery run SCENE --output DIR --format ply --quiet` (the frames are deleted after each run).
# Prints each run's wall time, seconds per step and peak memory, each pair's growth
#
#   (t_290 / 290²) / (t_129 / 129²)
#
# the median of the pairs, and the growth between the two sizes' median runs (how the runs are
# combined moves the answer by a few per cent: BENCHMARKS.md, thirty-fifth session). DRAPERY
# defaults to target/release/drapery; FRAMES in the environment runs fewer frames (4 steps
# each), THREADS another number of solver threads than the cores (`drapery run --threads`: on
# one core the growth is smaller, BENCHMARKS.md, thirty-sixth session), and SELF_COLLISION=off
# runs both scenes with `self_collision = false` (obstacle contact and friction as before: where
# the growth comes from, BENCHMARKS.md, thirty-eighth session). The machine should be
# otherwise idle: a single pair can be off by 10 %, which is why the pairs are alternated and
# their median is printed.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
pairs=${1:-3}
drapery=${2:-$root/target/release/drapery}
frames=${FRAMES:-100}
case $frames in
'' | *[!0-9]* | 0) echo "growth.sh: FRAMES must be a positive whole number, not '$frames'" >&2; exit 2 ;;
esac
case $pairs in
'' | *[!0-9]* | 0) echo "growth.sh: PAIRS must be a positive whole number, not '$pairs'" >&2; exit 2 ;;
esac
threads=${THREADS:-$(nproc)}
case $threads in
'' | *[!0-9]* | 0) echo "growth.sh: THREADS must be a positive whole number, not '$threads'" >&2; exit 2 ;;
esac
[ -x "$drapery" ] || { echo "growth.sh: $drapery is not an executable (build it: cargo build --release -p drapery-cli)" >&2; exit 2; }
work=$(mktemp -d "${TMPDIR:-/tmp}/drapery-growth.XXXXXX")
trap 'rm -rf "$work"' EXIT
if ! "$drapery" bench --scenes spin-129,spin-290 --frames "$frames" --write-scenes "$work" >"$work/log" 2>&1; then
  echo "growth.sh: $drapery bench --write-scenes failed: $(tail -n1 "$work/log")" >&2
  exit 1
fi
self_collision=${SELF_COLLISION:-on}
case $self_collision in
on) ;;
off)
  for n in 129 290; do
    grep -q '^self_collision = true$' "$work/spin-$n.toml" || { echo "growth.sh: spin-$n.toml has no 'self_collision = true' line to turn off" >&2; exit 1; }
    sed -i 's/^self_collision = true$/self_collision = false/' "$work/spin-$n.toml"
  done
  ;;
*) echo "growth.sh: SELF_COLLISION must be on or off, not '$self_collision'" >&2; exit 2 ;;
esac
steps=$((4 * frames))
have_time=false
[ -x /usr/bin/time ] && have_time=true

# run N: prints "SECONDS PEAK_MB"
run() {
  local out=$work/out-$1
  rm -rf "$out"
  local t0 t1 peak=-
  t0=$(date +%s.%N)
  local cmd=("$drapery" run "$work/spin-$1.toml" --output "$out" --format ply --quiet --threads "$threads")
  if $have_time; then
    if ! /usr/bin/time -o "$work/time" -f '%M' "${cmd[@]}" >"$work/log" 2>&1; then
      echo "growth.sh: spin-$1 failed: $(tail -n1 "$work/log")" >&2
      return 1
    fi
    peak=$(awk '{ k = $1 } END { printf "%.0f", k / 1024 }' "$work/time")
  elif ! "${cmd[@]}" >"$work/log" 2>&1; then
    echo "growth.sh: spin-$1 failed: $(tail -n1 "$work/log")" >&2
    return 1
  fi
  t1=$(date +%s.%N)
  rm -rf "$out"
  awk -v a="$t0" -v b="$t1" -v p="$peak" 'BEGIN { printf "%.2f %s\n", b - a, p }'
}

# growth T129 T290: the time per vertex per step of spin-290 over spin-129's
growth() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.3f", (b / (290 * 290)) / (a / (129 * 129)) }'; }
median() { printf '%s\n' "$@" | sort -g | awk '{ v[NR] = $1 } END { if (NR % 2) print v[(NR + 1) / 2]; else print (v[NR / 2] + v[NR / 2 + 1]) / 2 }'; }

echo "spin-129 and spin-290, $frames frames ($steps steps) each, $pairs pairs, $threads threads, self-collision $self_collision"
ratios=()
times129=()
times290=()
for k in $(seq 1 "$pairs"); do
  # alternate which size goes first
  if [ $((k % 2)) -eq 1 ]; then order="129 290"; else order="290 129"; fi
  for n in $order; do
    res=$(run "$n") || exit 1
    read -r secs peak <<<"$res"
    if [ "$n" = 129 ]; then times129+=("$secs"); else times290+=("$secs"); fi
    awk -v k="$k" -v n="$n" -v s="$secs" -v st="$steps" -v p="$peak" \
      'BEGIN { printf "  pair %s  spin-%s  %8.2f s  %.4f s/step  peak %s MB\n", k, n, s, s / st, p }'
  done
  r=$(growth "${times129[-1]}" "${times290[-1]}")
  ratios+=("$r")
  echo "  pair $k  growth per vertex per step ${r}x"
done
median_ratio=$(awk -v m="$(median "${ratios[@]}")" 'BEGIN { printf "%.3f", m }')
of_medians=$(growth "$(median "${times129[@]}")" "$(median "${times290[@]}")")
echo "growth per vertex per step: ${ratios[*]}; median ${median_ratio}x (issue 18 asks at most 1.3x)"
echo "the same from the median run of each size: ${of_medians}x"
