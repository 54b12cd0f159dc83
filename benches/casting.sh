#!/usr/bin/env bash
# The eigen-solve of a casting-like tet4 mesh (about 754k DOF), free-free, 20 modes, at the
# default shift and at a shift far from the modes, in one run (issue 37's casting floors).
# Usage: bash benches/casting.sh [--size-mm 2.7] [--count 20] [--scipy]
# (about 5 min at the default size; --scipy adds SciPy's eigsh under a 20 GB cap, up to 15 min)
set -euo pipefail
cd "$(dirname "$0")/.."
. benches/python_env.sh
"$venv/bin/python" benches/casting.py "$@"
