#!/usr/bin/env python3
"""The film test set's figures (docs/quality.md#the-film-test-set).

For each frame: `rayreel measure` against a converged reference (kept in a cache directory,
rendered once) gives the quality of the film default and `final`, with and without the film
filter; then the old binary (the commit before film sampling, 33ff5e9) and the new one render
the frame with their default and with `--quality final`, in turn, RUNS times, through the
command line (process start and PNG writing included), so their times are measured side by
side in one run. Times are CPU seconds (user + system of the render process): the machine
is shared, and a busy moment stretches wall time far more than CPU time. The old binary's
images are compared with measure's reference.png like measure compares its rows.

    python3 sequences/film/measure_set.py --old PREFILM_BINARY [--new BINARY]
        [--frames tuning|held-out|all|SEQ:N,...] [--size 640x360] [--runs 3]
        [--cache DIR] [--reference-samples 1024] [--out DIR]

Needs numpy and Pillow. Prints a Markdown table (and writes it, with the raw figures as
JSON, to the --out directory).
"""
import argparse
import json
import os
import re
import resource
import subprocess
import sys

import numpy as np
from PIL import Image

HERE = os.path.dirname(os.path.abspath(__file__))
SPLIT = {
    'tuning': ['pan:12', 'pan:24', 'orbit:100', 'orbit:300', 'glass:10', 'glass:35', 'floor:12', 'floor:36'],
    'held-out': ['pan:40', 'orbit:500', 'glass:55', 'floor:60', 'mirrors:15', 'mirrors:36', 'mirrors:60',
                 'mesh:10', 'mesh:36', 'mesh:62'],
}
SPLIT['all'] = SPLIT['tuning'] + SPLIT['held-out']


def depth_of(seq):
    text = open(os.path.join(HERE, seq + '.yaml')).read()
    return int(re.search(r'^\s*max_depth:\s*(\d+)', text, re.M).group(1))


def measure(a, seq, n, out):
    """measure's rows for the frame, by label, from its JSON."""
    cmd = [a.new, 'measure', os.path.join(HERE, seq + '.yaml'), '--frame', str(n), '--size', a.size,
           '--reference-depth', str(depth_of(seq)), '--reference-samples', str(a.reference_samples),
           '--reference-cache', a.cache, '--only', 'default,preset,denoise', '--runs', '1', '--out', out]
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    report = json.load(open(os.path.join(out, 'measure.json')))
    return {r['settings']: r for r in report['rows']}, report['reference']


def render(binary, seq, n, size, extra, png):
    """CPU and wall seconds of one render through the command line."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    wall = os.times().elapsed
    subprocess.run([binary, 'render', os.path.join(HERE, seq + '.yaml'), '--frames', str(n), '--size', size,
                    '-q', '--force', '-o', png] + extra, check=True)
    wall = os.times().elapsed - wall
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime, wall


def distance(png, reference):
    """PSNR in dB and the share of pixels some channel of which is more than 8 levels off."""
    a = np.asarray(Image.open(png).convert('RGB')).astype(float)
    b = np.asarray(Image.open(reference).convert('RGB')).astype(float)
    mse = ((a - b) ** 2).mean()
    return 20 * np.log10(255 / np.sqrt(mse)), (np.abs(a - b).max(axis=2) > 8).mean()


def frame(a, seq, n):
    out = os.path.join(a.out, f'{seq}-{n}')
    rows, reference = measure(a, seq, n, out)
    tmp = os.path.join(out, 'render.png')
    kinds = {'old default': (a.old, []), 'new default': (a.new, []),
             'old final': (a.old, ['--quality', 'final']), 'new final': (a.new, ['--quality', 'final'])}
    times = {k: [] for k in kinds}
    old_quality = {}
    for _ in range(a.runs):
        for k, (binary, extra) in kinds.items():
            times[k].append(render(binary, seq, n, a.size, extra, tmp))
            if k.startswith('old'):
                old_quality[k] = distance(tmp, os.path.join(out, 'reference.png'))
    ratio = lambda new, old: float(np.median([t[0] / o[0] for t, o in zip(times[new], times[old])]))
    q = lambda label: (rows[label]['psnr_db'], rows[label]['share_off_8'])
    return {
        'frame': f'{seq}:{n}', 'reference': reference,
        'old default': old_quality['old default'], 'old final': old_quality['old final'],
        'default': q('default'), 'default (denoise off)': q('default (denoise off)'),
        'final': q('final'), 'final (denoise off)': q('final (denoise off)'),
        'default spp': rows['default']['samples_per_pixel'], 'final spp': rows['final']['samples_per_pixel'],
        'default time': ratio('new default', 'old default'), 'final time': ratio('new final', 'old final'),
        'cpu seconds': {k: [t[0] for t in v] for k, v in times.items()},
        'wall seconds': {k: [t[1] for t in v] for k, v in times.items()},
    }


def table(results):
    head = ('| frame | old default dB, > 8 | default dB, > 8 (filter off) | spp | CPU × old | '
            'old `final` dB | `final` dB, > 8 (filter off) | CPU × old `final` |\n'
            '| --- | --- | --- | --- | --- | --- | --- | --- |\n')
    lines = []
    for r in results:
        d, do, f, fo = r['default'], r['default (denoise off)'], r['final'], r['final (denoise off)']
        lines.append(
            f"| {r['frame']} | {r['old default'][0]:.2f}, {100 * r['old default'][1]:.2f}% "
            f"| **{d[0]:.2f}, {100 * d[1]:.2f}%** ({do[0]:.2f}, {100 * do[1]:.2f}%) | {r['default spp']:.1f} "
            f"| **{r['default time']:.2f}** | {r['old final'][0]:.2f} "
            f"| **{f[0]:.2f}, {100 * f[1]:.2f}%** ({fo[0]:.2f}, {100 * fo[1]:.2f}%) | **{r['final time']:.2f}** |")
    return head + '\n'.join(lines) + '\n'


def main():
    p = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    p.add_argument('--old', required=True, help='rayreel built from 33ff5e9 (before film sampling)')
    p.add_argument('--new', default='rayreel')
    p.add_argument('--frames', default='all')
    p.add_argument('--size', default='640x360')
    p.add_argument('--runs', type=int, default=3)
    p.add_argument('--cache', default=os.path.expanduser('~/.cache/rayreel-film-references'))
    p.add_argument('--reference-samples', type=int, default=1024)
    p.add_argument('--out', default='film-set')
    a = p.parse_args()
    frames = SPLIT.get(a.frames, a.frames.split(','))
    results = []
    for f in frames:
        seq, n = f.split(':')
        results.append(frame(a, seq, int(n)))
        print(table(results[-1:]).splitlines()[-1], file=sys.stderr, flush=True)
    os.makedirs(a.out, exist_ok=True)
    text = table(results)
    open(os.path.join(a.out, 'table.md'), 'w').write(text)
    json.dump(results, open(os.path.join(a.out, 'results.json'), 'w'), indent=1)
    print(text)


if __name__ == '__main__':
    main()
