#!/bin/sh
# Builds the Embree comparison harness into target/embree/harness.
# Needs Debian's libembree-dev (Embree 3.13): apt-get install -y libembree-dev
set -eu
root=$(cd "$(dirname "$0")/../.." && pwd)
out="$root/target/embree"
mkdir -p "$out"
if [ ! -f /usr/include/embree3/rtcore.h ]; then
    echo "build.sh: Embree 3 headers not found; install them with: apt-get install -y libembree-dev" >&2
    exit 1
fi
${CC:-gcc} -std=c11 -O3 -march=native -ffp-contract=off -fno-math-errno -fno-trapping-math -fopenmp-simd -Wall -Wextra -o "$out/harness" \
    "$root/benches/embree/harness.c" -lembree3 -lm -lpthread
echo "$out/harness"
