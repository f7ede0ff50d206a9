#!/bin/sh
# Where the side by side's time goes: each side with eye rays alone and with shadow rays too.
# Embree: the harness with --shadow none and --shadow facing. rayreel: rayreel.sh's scenes
# without their light (eye rays and their shading; nothing is lit, so no shadow ray) and with
# it, each rendered for 24 frames and for 1, so that a frame is (24 − 1 frames) / 23 and the
# load and build drop out, as Embree's build does from its frame. ROUNDS rounds (default 3)
# alternate all of it; the medians are printed per view and precision, in ms a frame (wall).
#   sh benches/embree/split.sh [ROUNDS]    (RAYREEL overrides the binary)
set -eu
root=$(cd "$(dirname "$0")/../.." && pwd)
cd "$root"
rounds=${1:-3}
[ -n "${RAYREEL:-}" ] || cargo build --quiet --release
rayreel=${RAYREEL:-target/release/rayreel}
sh benches/embree/run.sh --repeat 1 --build-repeat 1 >/dev/null # the harness and meshes
. benches/embree/views.sh
seconds() { # FILE FRAMES: wall seconds of rendering FRAMES of FILE
    /usr/bin/time -f %e "$rayreel" render "$1" --frames "$2" --pipe raw --quiet 2>&1 >/dev/null | tail -1
}
frame() { # FILE: ms a frame, load and build left out
    echo "($(seconds "$1" 0-23) - $(seconds "$1" 0)) * 1000 / 23" | bc -l
}
log=$(mktemp)
trap 'rm -f "$log"' EXIT
for r in $(seq "$rounds"); do
    for name in blob terrain; do
        for p in f32 f64; do
            scene $name $p
            scene $name $p unlit
            for s in none facing; do
                ms=$(embree $name --repeat 10 --build-repeat 1 --rays $p --shadow $s |
                    sed 's/.*"frame_ms_median":\([0-9.]*\).*/\1/')
                echo "$name $p embree_$s $ms" >> "$log"
            done
            echo "$name $p rayreel_unlit $(frame target/meshes/$name-$p-unlit.yaml)" >> "$log"
            echo "$name $p rayreel_lit $(frame target/meshes/$name-$p.yaml)" >> "$log"
        done
    done
done
python3 - "$log" <<'PY'
import collections, statistics, sys
runs = collections.defaultdict(list)
for line in open(sys.argv[1]):
    name, p, what, ms = line.split()
    runs[name, p, what].append(float(ms))
for name in ("blob", "terrain"):
    for p in ("f32", "f64"):
        m = {w: statistics.median(runs[name, p, w]) for w in
             ("embree_none", "embree_facing", "rayreel_unlit", "rayreel_lit")}
        print(f"{name} {p}: Embree eye rays {m['embree_none']:.1f} ms, with shadow rays "
              f"{m['embree_facing']:.1f} (+{m['embree_facing'] - m['embree_none']:.1f}); "
              f"rayreel unlit {m['rayreel_unlit']:.1f} ms, lit {m['rayreel_lit']:.1f} "
              f"(+{m['rayreel_lit'] - m['rayreel_unlit']:.1f}); frames/s against Embree: "
              f"eye {m['embree_none'] / m['rayreel_unlit']:.2f}x, "
              f"whole {m['embree_facing'] / m['rayreel_lit']:.2f}x "
              f"({len(runs[name, p, 'rayreel_lit'])} rounds)")
PY
