#!/usr/bin/env bash
# Convergence study of the piston-slap transient (issue 22): the default engine at its default
# settings against the same tool at a fixed step 64 times finer (the converged reference), both
# with 20 averaged cycles. Prints per cylinder the mean peak negative acceleration of its worst
# point at both settings, their difference, the standard errors of both means (cycles
# correlated), the default run's own step-error estimate, and the wall-time ratio.
#   bash benches/convergence.sh [SCENE] [--out FILE]      (~12 min on 2 cores)
set -euo pipefail
cd "$(dirname "$0")/.."
scene=${1:-models/engine.toml}
cargo build --release --quiet
bin=$(mktemp -d)/linercav
cp target/release/linercav "$bin"
work=$(mktemp -d)
step=$(grep -E '^step_deg' "$scene" | head -1 | sed -E 's/[^=]*= *([0-9.eE+-]+).*/\1/')
fine=$(python3 -c "print($step / 64)")
common=(--set transient.cycles=21 --set transient.averaged_cycles=20)
"$bin" rom "$scene" > /dev/null
t0=$(date +%s.%N)
"$bin" simulate "$scene" --json "${common[@]}" > "$work/default.json"
t1=$(date +%s.%N)
# the reference: a fixed step, no tolerance control
"$bin" simulate "$scene" --json "${common[@]}" --set transient.step_deg="$fine" --set transient.tolerance=0.99 > "$work/fine.json"
t2=$(date +%s.%N)
python3 - "$work/default.json" "$work/fine.json" "$t0" "$t1" "$t2" "$step" "$fine" <<'PY'
import json, math, sys, platform, os
d, f = (json.load(open(p)) for p in sys.argv[1:3])
t0, t1, t2 = map(float, sys.argv[3:6])
step, fine = sys.argv[6], sys.argv[7]
def worst(c):
    return max(c['points'], key=lambda p: p['peak_negative_m_s2'])
print(f"machine: {platform.machine()}, {os.cpu_count()} cores; scene {d['scene']}")
print(f"default: step {step} deg (used {d['stats']['dt_s']*d['speed_rpm']*6:.4f}), {d['stats']['cycles_averaged']} cycles averaged, autocorrelation time {d['stats']['autocorrelation_cycles']:.2f}")
print(f"reference: step {fine} deg fixed, {f['stats']['cycles_averaged']} cycles averaged, autocorrelation time {f['stats']['autocorrelation_cycles']:.2f}")
print("cyl  worst point: default +- SE   reference +- SE   difference   combined SE   step-error estimate")
for c, r in zip(d['cylinders'], f['cylinders']):
    wd, wr = worst(c), worst(r)
    diff = (wd['peak_negative_m_s2'] - wr['peak_negative_m_s2']) / wr['peak_negative_m_s2']
    se = math.hypot(wd['peak_negative_se_m_s2'], wr['peak_negative_se_m_s2']) / wr['peak_negative_m_s2']
    est = wd['peak_negative_step_error_m_s2'] / wd['peak_negative_m_s2']
    print(f"{c['cylinder']:>3}  p{wd['point']} {wd['peak_negative_m_s2']:7.0f} +- {wd['peak_negative_se_m_s2']:3.0f}    p{wr['point']} {wr['peak_negative_m_s2']:7.0f} +- {wr['peak_negative_se_m_s2']:3.0f}   {100*diff:+6.1f} %   {100*se:5.1f} %   {100*est:5.1f} %")
md = [p['peak_negative_m_s2'] for c in d['cylinders'] for p in c['points']]
mf = [p['peak_negative_m_s2'] for c in f['cylinders'] for p in c['points']]
a, b = sum(md)/len(md), sum(mf)/len(mf)
print(f"mean of all {len(md)} points: default {a:.1f}, reference {b:.1f}, difference {100*(a-b)/b:+.2f} % (default's own step-error estimate {100*d['stats']['step_error_estimate']:.2f} %)")
cyc = d['stats']['cycles_run']
print(f"wall time: default {t1-t0:.1f} s ({(t1-t0)/cyc:.3f} s per cycle incl. the step-error windows, transient {d['transient_seconds']:.1f} s), reference {t2-t1:.1f} s; ratio {(t2-t1)/(t1-t0):.1f}")
PY
