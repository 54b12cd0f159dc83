#!/usr/bin/env bash
# Times `linercav modes` against SciPy's eigsh on the same exported matrices, in one run.
# Usage: bash benches/vs_scipy.sh [--size-mm 5] [--count 24]  (or --scene models/engine.toml --part liner)
# (size 5 mm gives ~100k DOF, 4 mm ~190k DOF: the 70k-250k range of the floor.)
set -euo pipefail
cd "$(dirname "$0")/.."
. benches/python_env.sh
export OPENBLAS_NUM_THREADS=1
"$venv/bin/python" benches/vs_scipy.py "$@"
