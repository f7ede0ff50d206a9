#!/bin/sh
# The rayreel side of the mesh comparison: the same meshes, cameras, light and image size as
# run.sh gives the Embree harness, traced by `rayreel render` (1 sample per pixel, max_depth 1:
# eye rays and one shadow ray per lit hit) in f32 and f64, 24 frames of a still camera each,
# streamed raw to /dev/null. Prints per run the wall time and CPU time per frame (CPU time is
# what survives a shared machine: a quiet wall time is about CPU time / cores).
# Run run.sh first (it generates the meshes). Extra arguments go to every render.
set -eu
root=$(cd "$(dirname "$0")/../.." && pwd)
cd "$root"
[ -n "${RAYREEL:-}" ] || cargo build --quiet --release
. benches/embree/views.sh
for p in f32 f64; do
    scene blob $p
    scene terrain $p
done
for name in blob terrain; do
    for p in f32 f64; do
        out=$(/usr/bin/time -f "%e %U %S" ${RAYREEL:-target/release/rayreel} render "target/meshes/$name-$p.yaml" \
            --pipe raw --quiet --frames 0-23 "$@" 2>&1 >/dev/null | tail -1)
        echo "$name $p" "$out" | awk '{ printf "%s %s: %.1f ms wall, %.1f ms CPU a frame (24 frames, load and hierarchy included)\n", $1, $2, 1000*$3/24, 1000*($4+$5)/24 }'
    done
done
