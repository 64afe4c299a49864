#!/usr/bin/env bash
# Peers in the same sitting: Blender's cloth (bpy, from PyPI) next to `drapery bench` on the
# hang and drape scenes at 64² and 128², alternated run by run; prints one table.
#
#   bash scripts/bench-peers.sh [bench_blender.py options, e.g. --runs 5 --scenes hang-64]
#
# Installs bpy into target/bpy-venv if it is missing (PYTHON, default python3.11: the bpy
# wheels are built for one Python version each; 5.0.x is for 3.11), builds the drapery CLI in
# release mode, then runs scripts/bench_blender.py. See BENCHMARKS.md, "Peers in the same sitting".
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
venv=$root/target/bpy-venv
python=${PYTHON:-python3.11}
bpy_version=${BPY_VERSION:-5.0.1}
if ! "$venv/bin/python" -c 'import bpy' 2>/dev/null; then
  "$python" -m venv "$venv"
  "$venv/bin/pip" install --quiet "bpy==$bpy_version"
fi
(cd "$root" && cargo build --release -p drapery-cli --quiet)
exec "$venv/bin/python" "$root/scripts/bench_blender.py" "$@"
