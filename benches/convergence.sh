#!/usr/bin/env bash
# Convergence study of the piston-slap transient (issue 22): the default engine at its default
# settings against the same tool at a fixed step 64 times finer (the converged reference).
# One realisation of 20 cycles cannot resolve a few percent per cylinder (standard errors of
# 1-2.5 % each), so both sides pool independent realisations: runs that differ only by a
# perturbation of the modal damping ratio at the 1e-6 level (the slap history decorrelates,
# as from one set of cycles to another; benches/realisations.sh). Each run: 31 cycles, the last
# 30 averaged. Pooled means are the means of the realisations' means, their standard errors
# sqrt(sum SE_k^2) / R. Prints per cylinder the worst point's pooled means, their difference,
# the combined standard error, the default runs' own step-error estimate, and the ratio of the
# work per cycle.
# The default runs go one at a time (their step-error windows use both cores, so their wall
# time is the user's); the reference runs, single-threaded almost throughout, go JOBS at a time
# (default 2, one per core; their wall time per cycle is then measured under that load).
#   bash benches/convergence.sh [SCENE] [R_DEFAULT] [R_REFERENCE]   (defaults R = 4 and 4: ~30 min on 2 cores: four reference runs of ~11 min two at a time, four default runs)
set -euo pipefail
cd "$(dirname "$0")/.."
scene=${1:-models/engine.toml}
rd=${2:-4}
rr=${3:-4}
cargo build --release --quiet
bin=$(mktemp -d)/linercav
cp target/release/linercav "$bin"
work=$(mktemp -d)
step=$(grep -E '^step_deg' "$scene" | head -1 | sed -E 's/[^=]*= *([0-9.eE+-]+).*/\1/')
zeta=$(grep -E '^damping_ratio' "$scene" | head -1 | sed -E 's/[^=]*= *([0-9.eE+-]+).*/\1/')
fine=$(python3 -c "print($step / 64)")
common=(--set transient.cycles=31 --set transient.averaged_cycles=30)
"$bin" rom "$scene" > /dev/null
run() { # kind k extra...
    local kind=$1 k=$2
    shift 2
    local z
    z=$(python3 -c "print($zeta * (1 + 1e-6 * $k))")
    local t0 t1
    t0=$(date +%s.%N)
    "$bin" simulate "$scene" --json "${common[@]}" --set transient.damping_ratio="$z" "$@" > "$work/$kind-$k.json"
    t1=$(date +%s.%N)
    python3 -c "print($t1 - $t0)" > "$work/$kind-$k.seconds"
}
for k in $(seq 1 "$rd"); do run default "$k"; done
# the reference: a fixed step (no slap sub-steps), no tolerance control
jobs=${JOBS:-2}
for k in $(seq 1 "$rr"); do
    run reference "$k" --set transient.step_deg="$fine" --set transient.tolerance=0.99 --set transient.slap_substeps=1 &
    if (( k % jobs == 0 )); then wait; fi
done
wait
python3 - "$work" "$rd" "$rr" "$step" "$fine" "$scene" <<'PY'
import json, math, sys, platform, os
work, rd, rr, step, fine, scene = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), sys.argv[4], sys.argv[5], sys.argv[6]
load = lambda kind, n: [json.load(open(f"{work}/{kind}-{k}.json")) for k in range(1, n + 1)]
secs = lambda kind, n: [float(open(f"{work}/{kind}-{k}.seconds").read()) for k in range(1, n + 1)]
d, f = load("default", rd), load("reference", rr)
def pooled(runs, c, p):
    m = sum(r["cylinders"][c]["points"][p]["peak_negative_m_s2"] for r in runs) / len(runs)
    se = math.sqrt(sum(r["cylinders"][c]["points"][p]["peak_negative_se_m_s2"] ** 2 for r in runs)) / len(runs)
    return m, se
print(f"machine: {platform.machine()}, {os.cpu_count()} cores; scene {scene}")
print(f"default: step {step} deg, {rd} realisations x {d[0]['stats']['cycles_averaged']} cycles averaged")
print(f"reference: step {fine} deg fixed, {rr} realisations x {f[0]['stats']['cycles_averaged']} cycles averaged")
print("cyl  worst point  default +- SE   reference +- SE   difference   combined SE   step-error estimate")
nc = len(d[0]["cylinders"])
for c in range(nc):
    npts = len(d[0]["cylinders"][c]["points"])
    # the worst point of the reference (the converged answer decides which point is worst)
    p = max(range(npts), key=lambda q: pooled(f, c, q)[0])
    (md, sd), (mf, sf) = pooled(d, c, p), pooled(f, c, p)
    est = sum(r["cylinders"][c]["points"][p]["peak_negative_step_error_m_s2"] for r in d) / len(d) / md
    print(f"{d[0]['cylinders'][c]['cylinder']:>3}  p{p + 1}          {md:7.0f} +- {sd:3.0f}    {mf:7.0f} +- {sf:3.0f}      {100 * (md - mf) / mf:+6.1f} %     {100 * math.hypot(sd, sf) / mf:5.1f} %     {100 * est:5.1f} %")
allp = lambda runs: sum(pooled(runs, c, p)[0] for c in range(nc) for p in range(len(runs[0]["cylinders"][c]["points"])))
a, b = allp(d), allp(f)
est = sum(r["stats"]["step_error_estimate"] for r in d) / len(d)
print(f"mean of all points: difference {100 * (a - b) / b:+.2f} % (the default runs' own step-error estimate {100 * est:.2f} %)")
cd, cf = d[0]["stats"]["cycles_run"], f[0]["stats"]["cycles_run"]
wd, wf = sum(secs("default", rd)) / (rd * cd), sum(secs("reference", rr)) / (rr * cf)
print(f"work per cycle: default {wd:.3f} s (incl. the step-error windows), reference {wf:.2f} s; ratio {wf / wd:.0f}")
PY
