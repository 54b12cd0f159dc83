#!/usr/bin/env bash
# Speed against error of the slap transient on the default engine: system-mode cut-off and
# crank-angle step, each run against the finest setting (all ROM modes, 0.0625 deg).
# Prints the machine-independent figure first (largest relative error of the per-cylinder,
# per-point peak negative acceleration), then the transient wall time of one cycle.
# Usage: bash benches/transient_tradeoff.sh   (needs the default ROM, built on first use)
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -q
bin=target/release/linercav
out=$(mktemp -d)
run() { # name, extra --set args...
  local name=$1; shift
  $bin simulate models/engine.toml --set transient.cycles=1 "$@" --json > "$out/$name.json"
}
run ref --set transient.step_deg=0.0625
for f in 3000 4500 6000; do run "modes_$f" --set transient.mode_cutoff_hz=$f; done
run modes_all
for s in 1.0 0.5 0.25 0.125; do run "step_$s" --set transient.step_deg=$s; done
python3 - "$out" <<'PY'
import json, sys, os
d = sys.argv[1]
ref = json.load(open(os.path.join(d, "ref.json")))
def err(r):
    return max(abs(p["peak_negative_m_s2"] - q["peak_negative_m_s2"]) / q["peak_negative_m_s2"]
               for c, rc in zip(r["cylinders"], ref["cylinders"]) for p, q in zip(c["points"], rc["points"]))
print(f"{'setting':>16} {'modes':>6} {'step deg':>9} {'peak error':>11} {'transient s':>12}")
for name in ["modes_3000", "modes_4500", "modes_6000", "modes_all", "step_1.0", "step_0.5", "step_0.25", "step_0.125"]:
    r = json.load(open(os.path.join(d, name + ".json")))
    st = r["stats"]
    print(f"{name:>16} {st['modes']:>6} {st['dt_s'] * 6 * r['speed_rpm']:>9.4f} {err(r):>11.2e} {r['transient_seconds']:>12.3f}")
print(f"reference: {ref['stats']['modes']} modes, step 0.0625 deg, {ref['transient_seconds']:.2f} s")
PY
