#!/usr/bin/env bash
# Are the reported standard errors honest? Runs R realisations of the default engine that
# differ only by a perturbation of the modal damping ratio at the 1e-6 level (the slap's
# history then decorrelates, as from one set of cycles to another) and compares the spread of
# the 24 points' mean peaks over the realisations with the standard errors the runs report
# (autocorrelation-corrected). Prints the pooled ratio sqrt(sum spread^2 / sum SE^2).
#   bash benches/realisations.sh [SCENE] [R]      (R = 6: ~40 s)
set -euo pipefail
cd "$(dirname "$0")/.."
scene=${1:-models/engine.toml}
runs=${2:-6}
cargo build --release --quiet
bin=target/release/linercav
"$bin" rom "$scene" > /dev/null
python3 - "$bin" "$scene" "$runs" <<'PY'
import json, math, subprocess, sys
bin, scene, R = sys.argv[1], sys.argv[2], int(sys.argv[3])
zeta = None
runs = []
for k in range(R):
    # the scene's damping ratio, perturbed by (k + 1) 1e-6 relative
    if zeta is None:
        zeta = float(subprocess.run(["grep", "-m1", "^damping_ratio", scene], capture_output=True, text=True).stdout.split("=")[1].split("#")[0])
    z = zeta * (1 + 1e-6 * (k + 1))
    out = subprocess.run([bin, "simulate", scene, "--json", "--set", f"transient.damping_ratio={z}"], capture_output=True, text=True, check=True).stdout
    runs.append(json.loads(out))
num = den = 0.0
for c in range(len(runs[0]["cylinders"])):
    for p in range(len(runs[0]["cylinders"][c]["points"])):
        means = [r["cylinders"][c]["points"][p]["peak_negative_m_s2"] for r in runs]
        ses = [r["cylinders"][c]["points"][p]["peak_negative_se_m_s2"] for r in runs]
        m = sum(means) / R
        num += sum((x - m) ** 2 for x in means) / (R - 1)
        den += sum(x * x for x in ses) / R
s = runs[0]["stats"]
print(f"{R} realisations of {scene} (damping ratio {zeta} perturbed by 1e-6 .. {R}e-6 relative), "
      f"{s['cycles_averaged']} cycles averaged each, autocorrelation time {s['autocorrelation_cycles']:.2f}")
print(f"spread of the means over the realisations / reported standard error (pooled over the points): {math.sqrt(num / den):.2f}")
PY
