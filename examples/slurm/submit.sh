#!/usr/bin/env bash
# Submits a sharded linercav sweep to Slurm as four jobs chained by dependencies:
#   1. components.sbatch  an array of the engine's components (the liner, the crankcase or
#                    each of its rom.crankcase_components), each reduced into the shared
#                    component cache (`linercav rom --component auto`),
#   2. rom.sbatch    assembles the engine ROM from the cached components (seconds),
#   3. shard.sbatch  an array job, one task per shard (`linercav sweep` takes its shard from
#                    SLURM_ARRAY_TASK_ID/MIN/MAX), each writing part-I-of-N.json,
#   4. merge.sbatch  `linercav sweep-merge`: checks every run is there once, writes the outputs.
# Each job starts only when the one before succeeded (afterok); a failed shard leaves the merge
# pending with reason DependencyNeverSatisfied (cancel it, fix, resubmit the shard and merge).
#
# usage: bash examples/slurm/submit.sh SCENE OUT_DIR SWEEP_ARGS...
#   SWEEP_ARGS: the design, e.g. --sample lhs:2000 --range piston.clearance_um=40:120 --seed 7
#               (or --vary KEY=V1,V2 ...); arguments must not contain spaces.
# environment (all optional):
#   SHARDS=10          number of array tasks
#   COMPONENTS=2       component tasks: 2, or 1 + rom.crankcase_components when the scene
#                      (or SETS) substructures the crankcase
#   CPUS=2             CPUs per shard (the shard's runs go in parallel on them)
#   SETS="K=V K2=V2"   fixed scene overrides for the ROM and every run
#   WORK=OUT_DIR.work  shared directory (all nodes): ROM cache, parts, logs
#   LINERCAV=linercav  the binary (on a shared path or installed on every node)
#   SBATCH_ARGS=""     extra sbatch options for all three jobs (partition, account, time ...)
# prints the four job ids: components, ROM, array, merge.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
if [ $# -lt 3 ]; then
  sed -n '2,28p' "$0" >&2
  exit 2
fi
scene=$(realpath "$1")
out=$(realpath -m "$2")
shift 2
shards=${SHARDS:-10}
work=$(realpath -m "${WORK:-$out.work}")
mkdir -p "$work/logs"
sets=()
for s in ${SETS:-}; do sets+=(--set "$s"); done
export LINERCAV=${LINERCAV:-$(command -v linercav)}
export SCENE=$scene CACHE=$work/cache PARTS=$work/parts OUT=$out
export SETS_ARGS="${sets[*]:-}" SWEEP_ARGS="$*"
common=(--parsable --chdir "$work" ${SBATCH_ARGS:-})
components=$(sbatch "${common[@]}" --job-name linercav-components --cpus-per-task "${CPUS:-2}" \
  --array "1-${COMPONENTS:-2}" --output "$work/logs/component-%A_%a.out" "$here/components.sbatch")
rom=$(sbatch "${common[@]}" --job-name linercav-rom --cpus-per-task "${CPUS:-2}" \
  --dependency "afterok:$components" --output "$work/logs/rom-%j.out" "$here/rom.sbatch")
array=$(sbatch "${common[@]}" --job-name linercav-shard --cpus-per-task "${CPUS:-2}" \
  --dependency "afterok:$rom" --array "1-$shards" \
  --output "$work/logs/shard-%A_%a.out" "$here/shard.sbatch")
merge=$(sbatch "${common[@]}" --job-name linercav-merge --cpus-per-task 1 \
  --dependency "afterok:$array" --output "$work/logs/merge-%j.out" "$here/merge.sbatch")
echo "$components $rom $array $merge"
