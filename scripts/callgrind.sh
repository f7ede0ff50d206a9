#!/usr/bin/env bash
# Whole-process instruction count of one render, the figure kernel commits quote: callgrind
# (valgrind, which runs the AVX2 kernels: it has no AVX-512), 1 thread, raw frames to nowhere.
# Instructions do not move with the machine's load; compare two binaries on the same files.
#   scripts/callgrind.sh BIN FILE [RENDER ARGS...]
#   e.g. scripts/callgrind.sh target/release/rayreel sequences/bench/talk_orbit.yaml \
#          --frames 0 --size 960x540 --samples 1 --precision f32
set -euo pipefail
[ $# -ge 2 ] || { sed -n 2,6p "$0"; exit 2; }
bin=$1
shift
out=$(mktemp)
trap 'rm -f "$out"' EXIT
valgrind --tool=callgrind --callgrind-out-file="$out" "$bin" render "$@" \
  --pipe raw --quiet --threads 1 >/dev/null 2>/dev/null
awk '/^(summary|totals):/ { print $2; exit }' "$out"
