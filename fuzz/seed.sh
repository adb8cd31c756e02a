#!/usr/bin/env bash
# Seed the libFuzzer corpora: the bundled scenes for `scene`, a few real checkpoints for `checkpoint`.
set -euo pipefail
cd "$(dirname "$0")/.."
mkdir -p fuzz/corpus/scene fuzz/corpus/checkpoint
cp scenes/*.toml scenes/fracture/*.toml fuzz/corpus/scene/
tmp=$(mktemp -d)
printf '[scene]\nkind = "coupled_demo"\n[demo]\nnx = 32\nny = 32\ntau = 0.8\ndiscs = 2\nradius = 4.0\nspeed = 0.01\nsteps = 40\nrecord_interval = 10\n' > "$tmp/demo.toml"
cargo run -q --release -p lbdem -- run "$tmp/demo.toml" --out "$tmp/out" --quiet
cp "$tmp/out/checkpoint.bin" fuzz/corpus/checkpoint/demo.bin
