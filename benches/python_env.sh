# Sourced by the benches that run Python (casting.sh, vs_scipy.sh): sets up the machine, builds
# the release binary and makes the private venv with scipy, numpy and gmsh in bench-out/venv;
# leaves its python in $venv/bin/python.
bash scripts/setup.sh
cargo build --release --quiet
venv=bench-out/venv
if [ ! -x "$venv/bin/python" ]; then
  python3 -m venv "$venv"
  "$venv/bin/pip" install --quiet scipy numpy gmsh
fi
