#!/usr/bin/env bash
# The default engine out as mm decks without linercav's set names, and back in:
#   bash examples/decks/run.sh [DIR]     (default DIR: decks)
# writes DIR/liner.inp (Abaqus part/instance, mm-t-s, *MATERIAL), DIR/crankcase.bdf (Nastran,
# mm-t-s, MAT1/PSOLID), DIR/engine.toml (the scene: no material keys, the fixed set as a box),
# then builds the ROM (printing the interfaces it found) and writes the report to DIR/report.
set -euo pipefail
cd "$(dirname "$0")/../.."
out=${1:-decks}
mkdir -p "$out"
bin=(cargo run --release --quiet --)
"${bin[@]}" export-mesh models/engine.toml --part liner --unit mm --no-sets --out "$out/liner.inp"
"${bin[@]}" export-mesh models/engine.toml --part crankcase --unit mm --no-sets --out "$out/crankcase.bdf"
cp examples/decks/engine.toml "$out/engine.toml"
"${bin[@]}" rom "$out/engine.toml"
"${bin[@]}" report "$out/engine.toml" --out "$out/report"
