#!/usr/bin/env bash
# Validates drapery's animation outputs with the reference tools, for CI.
#
#   scripts/validate-outputs.sh [FILE.glb|FILE.usda ...]
#
# - .glb / .gltf: the Khronos glTF validator (npm `gltf-validator`, a library, driven by
#   scripts/gltf-validate.mjs); any error fails (warnings are allowed).
# - .usda / .usd: Pixar's USD (PyPI `usd-core`) through scripts/usd_check.py: the stage opens,
#   time codes are set, `points` is read at every time code, and time-sampled xform ops (moving
#   colliders) cover every time code and evaluate.
#
# Without arguments it first writes target/sample-outputs/sample.{glb,usda} (a small animated
# grid, a line-element rope, a static ground, and colliders moving rigidly, fixed and deforming;
# deterministic fake motion) by running the test
# `io::gltf::tests::sample_outputs` with DRAPERY_SAMPLE_DIR set, then validates those.
#
# The tools are installed once into $DRAPERY_TOOLS_DIR (default target/validator-tools): npm
# package into ./npm, usd-core into the virtualenv ./venv. Re-runs reuse them. Needs node ≥ 18,
# npm and python3 (with venv). Quiet on success; prints the problems and exits 1 on failure.
set -euo pipefail

root=$(cd "$(dirname "$0")/.." && pwd)
tools=${DRAPERY_TOOLS_DIR:-$root/target/validator-tools}
validator_version=2.0.0-dev.3.10
mkdir -p "$tools"
log="$tools/last.log"

run_quiet() { # run a command, show its output only if it fails
  if ! "$@" >"$log" 2>&1; then
    cat "$log" >&2
    echo "validate-outputs: failed: $*" >&2
    exit 1
  fi
}

files=("$@")
if [ ${#files[@]} -eq 0 ]; then
  sample_dir="$root/target/sample-outputs"
  mkdir -p "$sample_dir"
  (cd "$root" && DRAPERY_SAMPLE_DIR="$sample_dir" run_quiet cargo test --release -p drapery --lib \
    io::gltf::tests::sample_outputs)
  files=("$sample_dir/sample.glb" "$sample_dir/sample.usda")
fi

glb=()
usd=()
for f in "${files[@]}"; do
  [ -f "$f" ] || { echo "validate-outputs: no such file: $f" >&2; exit 1; }
  case "$f" in
    *.glb | *.gltf) glb+=("$(cd "$(dirname "$f")" && pwd)/$(basename "$f")") ;;
    *.usda | *.usd | *.usdc) usd+=("$f") ;;
    *) echo "validate-outputs: unknown file type: $f" >&2; exit 1 ;;
  esac
done

if [ ${#glb[@]} -gt 0 ]; then
  module="$tools/npm/node_modules/gltf-validator"
  if ! grep -q "\"version\": \"$validator_version\"" "$module/package.json" 2>/dev/null; then
    run_quiet npm install --silent --no-audit --no-fund --prefix "$tools/npm" \
      "gltf-validator@$validator_version"
  fi
  GLTF_VALIDATOR_MODULE="$module/index.js" node "$root/scripts/gltf-validate.mjs" "${glb[@]}"
fi

if [ ${#usd[@]} -gt 0 ]; then
  py="$tools/venv/bin/python"
  if ! "$py" -c "import pxr.Usd" 2>/dev/null; then
    run_quiet python3 -m venv "$tools/venv"
    run_quiet "$py" -m pip install --quiet --disable-pip-version-check usd-core
  fi
  for f in "${usd[@]}"; do
    "$py" "$root/scripts/usd_check.py" "$f"
  done
fi
