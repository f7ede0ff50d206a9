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
dir=target/meshes
scene() { # name file eye look fov light precision
    cat > "$dir/$1-$7.yaml" <<YAML
render: { width: 1920, height: 1080, samples: 1, max_depth: 1, precision: $7 }
materials:
  clay: { ambient: [0.1, 0.08, 0.06], diffuse: [0.7, 0.55, 0.45], specular: [0.4, 0.4, 0.4], shininess: 60 }
objects:
  - mesh: { file: $2, material: clay }
lights:
  - point: { position: [$6], ambient: [1, 1, 1], diffuse: [1, 1, 1], specular: [1, 1, 1] }
timeline:
  fps: 24
  keyframes:
    - { time: 0, position: [$3], look_at: [$4], fov: $5 }
    - { time: 1, position: [$3], look_at: [$4], fov: $5 }
YAML
}
for p in f32 f64; do
    scene blob blob71.ply "0.5, 0.9, 4.2" "0, 0, 0" 50 "3, 4, 5" $p
    scene terrain terrain1001.ply "0, 0.6, 0.95" "0, -0.02, 0.16" 60 "-2.5, 1.2, -1.5" $p
done
for name in blob terrain; do
    for p in f32 f64; do
        out=$(/usr/bin/time -f "%e %U %S" ${RAYREEL:-target/release/rayreel} render "$dir/$name-$p.yaml" \
            --pipe raw --quiet --frames 0-23 "$@" 2>&1 >/dev/null | tail -1)
        echo "$name $p" "$out" | awk '{ printf "%s %s: %.1f ms wall, %.1f ms CPU a frame (24 frames, load and hierarchy included)\n", $1, $2, 1000*$3/24, 1000*($4+$5)/24 }'
    done
done
