#!/usr/bin/env bash
# ROM build time and peak memory against crankcase size, in one run (issue 37).
# Usage: bash benches/rom_scaling.sh [--max-gb 20]
# For each refinement of the default engine's crankcase it prints the tool's own up-front
# estimate and, where that fits within --max-gb, the measured build from an empty cache
# (/usr/bin/time: wall seconds, peak RSS), then the same engine with the crankcase taken from
# the component cache after a liner-only change (the liner's material). A refinement whose
# one-piece estimate exceeds the bound is built substructured (rom.crankcase_components, the
# fewest components from 2, 3, 6 whose estimate fits; column C); one that fits in no way is
# printed with its estimate only (the tool refuses it up front, exit 2, in seconds).
set -euo pipefail
cd "$(dirname "$0")/.."
max_gb=20
[ "${1:-}" = "--max-gb" ] && max_gb=$2
bash scripts/setup.sh >/dev/null
cargo build --release --quiet
bin=target/release/linercav
cache=$(mktemp -d)
trap 'rm -rf "$cache"' EXIT
printf '%-28s %3s %12s %10s %10s %10s %14s\n' "crankcase mesh" "C" "full DOFs" "est. GB" "wall s" "peak GB" "liner-only s"
for spec in "4 25 2" "8 25 2" "8 12.5 2" "8 12.5 4" "12 8 4" "20 5 4"; do
  set -- $spec
  sets=(--set crankcase.mesh.per_sector=$1 --set crankcase.mesh.axial_size_mm=$2 --set crankcase.mesh.wall_layers=$3)
  label="per_sector=$1 axial=$2 layers=$3"
  fits=""
  for c in 1 2 3 6; do
    est=$("$bin" rom models/engine.toml --no-cache "${sets[@]}" --set rom.crankcase_components=$c --set limits.max_memory_gb=0.001 2>&1 || true)
    gb=$(sed -n 's/.*needs about \([0-9.e+]*\) GB.*/\1/p' <<<"$est")
    if awk -v g="$gb" -v m="$max_gb" 'BEGIN { exit !(g <= m) }'; then fits=$c; break; fi
  done
  if [ -z "$fits" ]; then
    printf '%-28s %3s %12s %10s %10s %10s %14s\n' "$label" "-" "-" "$gb" "refused" "-" "-"
    continue
  fi
  sets+=(--set rom.crankcase_components=$fits)
  rm -rf "$cache"/*
  # a build that stops (the tool refusing it when the machine has less memory free than its
  # estimate, or any error) is printed with the tool's last message, and the next size runs
  if ! out=$( { /usr/bin/time -f 'TIME %e %M' "$bin" rom models/engine.toml --cache-dir "$cache" "${sets[@]}" --json; } 2>&1 ); then
    printf '%-28s %3s %12s %10s  stopped: %s\n' "$label" "$fits" "-" "$gb" \
      "$(grep -v -e '^TIME' -e '^Command exited' <<<"$out" | tail -1)"
    continue
  fi
  dofs=$(sed -n 's/.*"full_dofs": *\([0-9]*\).*/\1/p' <<<"$out" | head -1)
  read -r wall kb < <(sed -n 's/^TIME \([0-9.]*\) \([0-9]*\)/\1 \2/p' <<<"$out")
  t2=$( { /usr/bin/time -f 'TIME %e' "$bin" rom models/engine.toml --cache-dir "$cache" "${sets[@]}" --set liner.material=compacted_graphite_iron >/dev/null; } 2>&1 | sed -n 's/^TIME //p')
  printf '%-28s %3s %12s %10s %10s %10.2f %14s\n' "$label" "$fits" "$dofs" "$gb" "$wall" "$(awk -v k="$kb" 'BEGIN{print k/1048576}')" "$t2"
done
