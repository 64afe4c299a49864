#!/usr/bin/env bash
# Builds and installs the Python package (crates/drapery-py) into a virtual environment and runs
# its pytest suite, for CI and developers.
#
#   scripts/python-tests.sh [PYTEST ARGS...]
#
# - The virtual environment is $DRAPERY_PY_VENV (default target/py-venv), created on first use
#   with python3 (or $PYTHON); maturin, numpy, pytest, mypy (its stubtest checks the type
#   stubs against the module), ray (the sweeps' Ray backend; about 20 s to install, 500 MB with
#   its dependencies) and tomli (Python < 3.11) come from PyPI. DRAPERY_REQUIRE_RAY=1: the Ray
#   tests fail instead of skipping when ray cannot be imported.
# - The package is installed the way a user installs it, `pip install ./crates/drapery-py`
#   (maturin builds the extension in release mode into the workspace's target/).
# - The tests compare with the drapery command's output, so target/release/drapery is built
#   first (`cargo build --release --workspace`, as .ci/run does just before: then nothing to
#   do). They find it through $DRAPERY_BIN ($CARGO_TARGET_DIR/release/drapery when set).
# - Fails when pytest fails or collects no test (its exit code 5).
set -euo pipefail

root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
target=${CARGO_TARGET_DIR:-$root/target}
venv=${DRAPERY_PY_VENV:-$root/target/py-venv}
python=${PYTHON:-python3}

start=$(date +%s)
if [ ! -x "$venv/bin/python" ]; then
  echo "python-tests: creating $venv" >&2
  "$python" -m venv "$venv"
fi
# maturin (the build backend, used without build isolation) from the venv
export PATH="$venv/bin:$PATH"
pip=("$venv/bin/python" -m pip --disable-pip-version-check --quiet)
"${pip[@]}" install --upgrade "pip>=23" "maturin>=1.9.4,<2" numpy pytest mypy "ray>=2" \
  "tomli>=1.1; python_version<'3.11'"
export DRAPERY_REQUIRE_RAY=1

cargo build --release --workspace --quiet
echo "python-tests: building and installing crates/drapery-py" >&2
"${pip[@]}" install --force-reinstall --no-deps --no-build-isolation ./crates/drapery-py

export DRAPERY_BIN="$target/release/drapery"
status=0
# From the tests' folder, so that `import drapery` is the installed package.
(cd crates/drapery-py/tests && "$venv/bin/python" -m pytest -q -p no:cacheprovider "$@") || status=$?
if [ "$status" -eq 5 ]; then
  echo "python-tests: pytest collected no test: failing" >&2
  exit 1
fi
if [ "$status" -ne 0 ]; then
  echo "python-tests: pytest failed (exit code $status)" >&2
  exit "$status"
fi
echo "python-tests: passed in $(($(date +%s) - start)) s" >&2
