#!/usr/bin/env bash
# Two binaries timed on the same render, alternated ROUNDS times (so the machine's drift hits
# both alike): wall and CPU seconds (user + system) of each run, raw frames to nowhere.
#   scripts/alternate.sh ROUNDS OLD NEW FILE [RENDER ARGS...]
set -euo pipefail
[ $# -ge 4 ] || { sed -n 2,4p "$0"; exit 2; }
rounds=$1 old=$2 new=$3
shift 3
for r in $(seq "$rounds"); do
  for name in old new; do
    bin=$old
    [ "$name" = new ] && bin=$new
    t=$(/usr/bin/time -f "%e %U %S" "$bin" render "$@" --pipe raw --quiet 2>&1 >/dev/null | tail -n 1)
    echo "$name $t"
  done
done | awk '{ w[$1] = w[$1] " " $2; c[$1] = c[$1] " " ($3 + $4) }
  END { for (k in w) print k ": wall" w[k] "  cpu" c[k] }' | sort
