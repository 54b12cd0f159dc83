#!/usr/bin/env bash
# Cost of the liner maps (issue 38 item 5): `simulate` of a scene with and without `--maps`,
# side by side on the cached ROM, RUNS pairs (A B A B ...), /usr/bin/time's whole-process
# wall and CPU seconds and peak RSS; prints each pair's ratios and their medians. The maps run
# on a worker thread beside the transient (which keeps one core busy), so their wall cost is
# below their CPU cost on a 2-core machine.
#   bash benches/liner_maps.sh [SCENE] [RUNS]   (defaults models/engine.toml, 3: ~1 min after the ROM)
set -euo pipefail
cd "$(dirname "$0")/.."
scene=${1:-models/engine.toml}
runs=${2:-3}
cargo build --release --quiet
bin=target/release/linercav
"$bin" rom "$scene" > /dev/null
work=$(mktemp -d)
measure() { # label args...
    local label=$1
    shift
    /usr/bin/time -f "%e %U %S %M" -o "$work/$label.time" "$bin" simulate "$scene" "$@" > "$work/$label.out" 2>&1
    read -r wall user sys rss < "$work/$label.time"
    echo "$wall $(python3 -c "print($user + $sys)") $rss"
}
printf "%-5s %10s %10s %10s %10s %10s %10s\n" pair "wall maps" "wall plain" "wall A/B" "cpu A/B" "MB maps" "MB plain"
ratios=()
for k in $(seq 1 "$runs"); do
    read -r wa ca ra < <(measure maps --maps)
    read -r wb cb rb < <(measure plain)
    r=$(python3 -c "print(f'{$wa / $wb:.3f} {$ca / $cb:.3f}')")
    ratios+=("$r")
    printf "%-5s %10s %10s %10s %10s %10.0f %10.0f\n" "$k" "$wa" "$wb" ${r% *} ${r#* } "$(python3 -c "print($ra / 1024)")" "$(python3 -c "print($rb / 1024)")"
done
printf '%s\n' "${ratios[@]}" | python3 -c "
import sys, statistics
rows = [tuple(map(float, l.split())) for l in sys.stdin if l.strip()]
print(f'median wall ratio {statistics.median(r[0] for r in rows):.3f}, median CPU ratio {statistics.median(r[1] for r in rows):.3f} (maps / plain)')
"
grep -A8 "^liner maps" "$work/maps.out" || true
