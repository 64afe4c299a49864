#!/usr/bin/env bash
# Refactors keep results: runs every shipped example with `--format ply` through two drapery
# binaries and compares the frames byte for byte.
#
#   scripts/same-frames.sh BASE_BINARY [HEAD_BINARY] [EXAMPLE.toml ...]
#
# HEAD_BINARY defaults to target/release/drapery; the examples default to every
# examples/*.toml. BASE_BINARY may also be a folder written by an earlier call (it keeps the
# base frames in $OUT/base/<example>/), so the base binary need not be kept around:
#
#   git stash; cargo build --release; cp target/release/drapery /tmp/base-drapery; git stash pop
#   cargo build --release && scripts/same-frames.sh /tmp/base-drapery
#
# Prints one line per example (`same`, or the first frame that differs) and exits 1 when any
# frame differs or a run fails on one side only. Frames are kept in $OUT (default
# target/same-frames) for inspection.
set -uo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
base=${1:?usage: scripts/same-frames.sh BASE_BINARY [HEAD_BINARY] [EXAMPLE.toml ...]}
head=${2:-$root/target/release/drapery}
shift $(( $# >= 2 ? 2 : 1 ))
examples=("$@")
if [ ${#examples[@]} -eq 0 ]; then
  examples=("$root"/examples/*.toml)
fi
out=${OUT:-$root/target/same-frames}
status=0
for ex in "${examples[@]}"; do
  name=$(basename "$ex" .toml)
  for side in base head; do
    bin=$base
    [ "$side" = head ] && bin=$head
    dir=$out/$side/$name
    if [ -d "$bin" ]; then
      continue # frames kept from an earlier call
    fi
    rm -rf "$dir"
    mkdir -p "$dir"
    if ! "$bin" run "$ex" --output "$dir" --format ply --quiet --overwrite >"$dir.log" 2>&1; then
      echo "FAILED  $name ($side run failed: $(tail -n1 "$dir.log"))"
      touch "$dir.failed"
    else
      rm -f "$dir.failed"
    fi
  done
  bdir=$out/base/$name
  [ -d "$base" ] && bdir=$base/$name
  hdir=$out/head/$name
  if [ -e "$bdir.failed" ] || [ -e "$hdir.failed" ]; then
    if [ -e "$bdir.failed" ] && [ -e "$hdir.failed" ]; then
      echo "both-failed  $name"
    else
      status=1
    fi
  fi
  nb=$(ls "$bdir" | grep -c '\.ply$')
  nh=$(ls "$hdir" | grep -c '\.ply$')
  if [ "$nb" != "$nh" ]; then
    echo "DIFFER  $name: $nb base frames, $nh head frames"
    status=1
    continue
  fi
  first=""
  for f in "$bdir"/*.ply; do
    if ! cmp -s "$f" "$hdir/$(basename "$f")"; then
      first=$(basename "$f")
      break
    fi
  done
  if [ -n "$first" ]; then
    echo "DIFFER  $name: first at $first"
    status=1
  else
    echo "same    $name ($nb frames)"
  fi
done
exit $status
