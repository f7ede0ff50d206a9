# The two views of the side by side, sourced by run.sh (Embree), rayreel.sh and split.sh:
# the mesh file under target/meshes, the eye, the point looked at, the horizontal field of view
# in degrees and the point light, as `view NAME` sets them.
view() {
    case $1 in
        blob) file=blob71.ply eye=0.5,0.9,4.2 look=0,0,0 fov=50 light=3,4,5 ;;
        terrain) file=terrain1001.ply eye=0,0.6,0.95 look=0,-0.02,0.16 fov=60 light=-2.5,1.2,-1.5 ;;
        *) echo "views.sh: no view $1" >&2; return 1 ;;
    esac
}

# The harness on view NAME at 1920x1080 on 2 threads; further arguments go to the harness.
embree() {
    view "$1"; shift
    target/embree/harness "target/meshes/$file" --width 1920 --height 1080 --eye "$eye" \
        --look-at "$look" --up 0,1,0 --fov "$fov" --light "$light" --threads 2 "$@"
}

# Writes target/meshes/NAME-PRECISION.yaml, view NAME as rayreel renders it (1 sample a pixel,
# max_depth 1: eye rays and one shadow ray per lit hit), 24 frames of a still camera; with a
# third argument `unlit`, NAME-PRECISION-unlit.yaml, the same without its light (eye rays and
# their shading alone: nothing is lit, so no shadow ray is cast).
scene() {
    view "$1"
    lights="
  - point: { position: [$light], ambient: [1, 1, 1], diffuse: [1, 1, 1], specular: [1, 1, 1] }"
    out="target/meshes/$1-$2.yaml"
    if [ "${3:-}" = unlit ]; then lights=" []" out="target/meshes/$1-$2-unlit.yaml"; fi
    cat > "$out" <<YAML
render: { width: 1920, height: 1080, samples: 1, max_depth: 1, precision: $2 }
materials:
  clay: { ambient: [0.1, 0.08, 0.06], diffuse: [0.7, 0.55, 0.45], specular: [0.4, 0.4, 0.4], shininess: 60 }
objects:
  - mesh: { file: $file, material: clay }
lights:$lights
timeline:
  fps: 24
  keyframes:
    - { time: 0, position: [$eye], look_at: [$look], fov: $fov }
    - { time: 1, position: [$eye], look_at: [$look], fov: $fov }
YAML
}
