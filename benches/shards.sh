#!/usr/bin/env bash
# Per-shard wall time against runs per shard: one sampled study (Latin hypercube, 48 runs of the
# small test engine) split into 1, 2, 4 and 8 shards, each shard run alone on one thread; prints
# per shard count the runs per shard, the mean shard wall time and the seconds per run (constant
# when the wall time scales with the runs), and checks that every split merges into the same
# sweep.csv.
#   bash benches/shards.sh [RUNS]      (~2 min on 2 cores)
set -euo pipefail
cd "$(dirname "$0")/.."
runs=${1:-48}
cargo build --release --quiet
bin=target/release/linercav
work=$(mktemp -d)
scene=tests/fixtures/engine_small.toml
design=(--sample "lhs:$runs" --seed 11 --range piston.clearance_um=40:120 --range piston.pin_offset_mm=-1:1 --range operating.load=0.5:1)
"$bin" rom "$scene" > /dev/null
export RAYON_NUM_THREADS=1
echo "machine: $(uname -m), $(nproc) cores; $runs-run Latin hypercube of $scene, one thread per shard"
echo "shards  runs/shard  mean shard wall [s]  s per run  merged CSV"
ref=""
for n in 1 2 4 8; do
  total=0
  for i in $(seq 1 "$n"); do
    t0=$(date +%s.%N)
    "$bin" sweep "$scene" "${design[@]}" --shard "$i/$n" --out "$work/parts$n" > /dev/null
    t1=$(date +%s.%N)
    total=$(python3 -c "print($total + $t1 - $t0)")
  done
  "$bin" sweep-merge "$work/parts$n" --out "$work/merged$n" > /dev/null
  sum=$(md5sum < "$work/merged$n/sweep.csv" | cut -c1-8)
  [ -z "$ref" ] && ref=$sum
  same=$([ "$sum" = "$ref" ] && echo "same" || echo "DIFFERENT")
  python3 -c "n=$n; r=$runs; t=$total; print(f'{n:>6}  {r/n:>10.1f}  {t/n:>19.2f}  {t/r:>9.3f}  {\"$same\"}')"
done
rm -rf "$work"
