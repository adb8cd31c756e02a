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
# `checkpoint_body` takes the payload only (the target seals it): the demo checkpoint without its envelope
# (magic 8, version 4, precision 1, kind length 4, "coupled_demo" 12, scene hash 32, step 8, length 8,
# checksum 32 = 109 bytes).
mkdir -p fuzz/corpus/checkpoint_body
tail -c +110 fuzz/corpus/checkpoint/demo.bin > fuzz/corpus/checkpoint_body/demo.body
