#!/usr/bin/env python3
"""Where a render's instructions go, by inlined source line: the kernels are one function
each with everything inlined, so callgrind's per-function view puts them all in one place.
This reads a callgrind file written with `--dump-instr=yes --dump-line=no`, looks up every
executed address's chain of inlined frames (`addr2line -i`, on a build with line tables) and
prints the instructions whose chain holds each of the given names, then, for each name, the
innermost `depth` source lines of this crate under it.

  CARGO_PROFILE_RELEASE_DEBUG=line-tables-only CARGO_TARGET_DIR=/tmp/lt cargo build --release
  valgrind --tool=callgrind --dump-instr=yes --dump-line=no --callgrind-out-file=/tmp/cg \\
      /tmp/lt/release/rayreel render FILE --frames 0 --pipe raw --quiet --threads 1 >/dev/null
  scripts/callgrind_parts.py /tmp/cg /tmp/lt/release/rayreel NearestVisit,AnyVisit [depth]
"""
import collections
import os
import re
import subprocess
import sys


def self_costs(path, binary):
    """Instructions executed at each address of `binary` (calls' inclusive lines skipped)."""
    cost = collections.Counter()
    names, in_binary, addr, skip = {}, False, 0, False
    for line in open(path):
        line = line.rstrip("\n")
        m = re.match(r"(c?)ob=\((\d+)\)(?: (.*))?", line)
        if m:
            if m.group(3):
                names[m.group(2)] = m.group(3)
            if not m.group(1):
                in_binary = binary in names.get(m.group(2), "")
            continue
        if line.startswith("calls="):
            skip = True
            continue
        if not line or line[0] not in "0123456789+-*":
            continue
        parts = line.split()
        p = parts[0]
        if p.startswith("0x"):
            addr = int(p, 16)
        elif p[0] in "+-":
            step = int(p[1:], 0)
            addr += step if p[0] == "+" else -step
        if skip:
            skip = False
            continue
        if in_binary and len(parts) > 1:
            cost[addr] += int(parts[1])
    return cost


def chains(binary, addrs):
    """Each address's inlined frames, innermost first: (function, file:line) pairs."""
    out = subprocess.run(
        ["addr2line", "-i", "-f", "-C", "-a", "-e", binary],
        input="".join(f"{a:#x}\n" for a in addrs),
        capture_output=True,
        text=True,
        check=True,
    ).stdout.splitlines()
    found, cur = {}, None
    for line in out:
        if line.startswith("0x"):
            cur = int(line, 16)
            found[cur] = []
        else:
            found[cur].append(line)
    return {a: list(zip(f[0::2], f[1::2])) for a, f in found.items()}


def main():
    path, binary, wanted = sys.argv[1], sys.argv[2], sys.argv[3].split(",")
    depth = int(sys.argv[4]) if len(sys.argv) > 4 else 2
    # This crate's sources, as the line tables name them (a build of this checkout).
    src = os.path.dirname(os.path.dirname(os.path.abspath(__file__))) + "/src/"
    cost = self_costs(path, binary)
    frames = chains(binary, sorted(cost))
    total = sum(cost.values())
    print(f"{total} instructions in {binary}")
    for name in wanted:
        under = collections.Counter()
        for a, c in cost.items():
            chain = frames.get(a, [])
            if not any(name in fn or name in fl for fn, fl in chain):
                continue
            ours = [fl[len(src) :].split(" ")[0] for _, fl in chain if fl.startswith(src)]
            under[" < ".join(ours[:depth])] += c
        print(f"{100 * sum(under.values()) / total:6.2f}% {name}")
        for where, c in under.most_common(15):
            print(f"    {100 * c / total:6.2f}% {where}")


if __name__ == "__main__":
    main()
