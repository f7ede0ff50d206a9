#!/usr/bin/env python3
"""Self instruction counts per address from a callgrind profile taken with --dump-instr=yes.

python3 scripts/cg_addr.py callgrind.out PREFIX > addr.txt prints "0xADDR COUNT" for every
instruction of the functions whose name starts with PREFIX (e.g. "rayreel"). Comparing two
binaries: group the addresses by their count (a basic block runs as often as each of its
instructions), and the blocks that grew show with their execution count; objdump those
addresses to see what was added. This found the film frames' +1.8% (see performance.md,
"Things that move")."""
import collections
import re
import sys

path, prefix = sys.argv[1], sys.argv[2]
names = {}
cost = collections.Counter()
cur_fn = None; last = 0; skip_next = False
def num(tok, last):
    if tok == '*': return last
    if tok.startswith('+'): return last + int(tok[1:], 0)
    if tok.startswith('-'): return last - int(tok[1:], 0)
    return int(tok, 0)
for line in open(path):
    line = line.rstrip('\n')
    if not line: continue
    c = line[0]
    if line.startswith('fn='):
        m = re.match(r'fn=\((\d+)\)(?: (.*))?', line)
        if m.group(2): names[m.group(1)] = m.group(2)
        cur_fn = names.get(m.group(1), '')
        continue
    if line.startswith('calls='):
        skip_next = True; continue
    if c.isdigit() or c in '+-*':
        parts = line.split()
        a = num(parts[0], last); last = a
        if skip_next: skip_next = False; continue
        if cur_fn and cur_fn.startswith(prefix) and len(parts) >= 3:
            cost[a] += int(parts[2])
        continue
    if '=' in line:
        m = re.match(r'c?fn=\((\d+)\)(?: (.*))?', line)
        if m and m.group(2): names[m.group(1)] = m.group(2)
for a, v in sorted(cost.items()):
    print(hex(a), v)
