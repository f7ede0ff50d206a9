#!/bin/sh
# The Embree side of the side-by-side mesh comparison, in one run:
# builds the harness, generates the two benchmark meshes (once) and prints one JSON line for
# each: the ~100k-triangle blob and the 2M-triangle terrain at 1920x1080, 2 threads.
# Extra arguments go to every harness run (e.g. --shadow facing, --robust, --repeat 5).
# Needs libembree-dev (apt-get install -y libembree-dev); skips with exit 0 without it.
set -eu
root=$(cd "$(dirname "$0")/../.." && pwd)
cd "$root"
if [ ! -f /usr/include/embree3/rtcore.h ]; then
    echo "run.sh: Embree 3 is not installed (apt-get install -y libembree-dev); skipped" >&2
    exit 0
fi
sh benches/embree/build.sh >/dev/null
mkdir -p target/meshes
[ -f target/meshes/blob71.ply ] ||
    cargo run --quiet --release --example gen_mesh -- blob 71 target/meshes/blob71.ply
[ -f target/meshes/terrain1001.ply ] ||
    cargo run --quiet --release --example gen_mesh -- terrain 1001 target/meshes/terrain1001.ply
. benches/embree/views.sh
embree blob --repeat 20 --build-repeat 5 "$@"
embree terrain --repeat 20 --build-repeat 5 "$@"
