#!/usr/bin/env bash
# The talk orbit's 1080p raw stream (1 sample, 24 frames) against its peers, alternated:
# rayreel in f32 and f64 (wall time of the whole process / 24), the packet prototype
# (../shared/reference/packet-prototype, built with `cargo build --release`) and Mitsuba 3's
# warm frame (../shared/reference/peers/mitsuba_whitted.py, `pip install mitsuba`).
#   scripts/stream_compare.sh [ROUNDS]   (RAYREEL, PROTO and PEERS override the paths)
set -euo pipefail
cd "$(dirname "$0")/.."
rounds=${1:-3}
rayreel=${RAYREEL:-target/release/rayreel}
proto=${PROTO:-../shared/reference/packet-prototype/target/release/proto}
peers=${PEERS:-../shared/reference/peers}
for r in $(seq "$rounds"); do
  for p in f32 f64; do
    s=$(date +%s.%N)
    "$rayreel" render sequences/bench/talk_orbit.yaml --size 1920x1080 --samples 1 \
      --precision "$p" --pipe raw -q > /dev/null
    e=$(date +%s.%N)
    echo "round $r rayreel $p: $(echo "($e - $s) * 1000 / 24" | bc -l | cut -c1-6) ms a frame"
  done
  echo "round $r prototype: $("$proto" bench 1 24 1920 1080 f64x8 f32x16 2>&1 | awk '{print $1, $2, $3}' | tr '\n' ' ')"
  warm=$(python3 "$peers/mitsuba_whitted.py" orbit --size 1920x1080 --raw 2>&1 >/dev/null | tail -n 1 |
    python3 -c "import json, sys; print(round(json.load(sys.stdin)['warm_median_s'] * 1000, 2))")
  echo "round $r mitsuba: $warm ms a warm frame"
done
