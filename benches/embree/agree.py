# Hits and depths of rayreel against Embree on the comparison meshes: rayreel's EXR Z (planar
# depth, 1e10 for a miss) against the harness's PFM (--depth-kind planar, +inf for a miss).
# Usage: python3 benches/embree/agree.py RAYREEL.exr EMBREE.pfm   (needs numpy and OpenEXR)
import sys
import numpy as np
import OpenEXR


def pfm(path):
    with open(path, 'rb') as f:
        f.readline()
        w, h = map(int, f.readline().split())
        scale = float(f.readline())
        d = np.frombuffer(f.read(), dtype='<f4' if scale < 0 else '>f4').reshape(h, w)
    return d[::-1]  # PFM rows run bottom to top


def main(exr, pfm_path):
    z = np.asarray(OpenEXR.File(exr).channels()['Z'].pixels, dtype=np.float64)
    e = pfm(pfm_path)
    hit_r, hit_e = z < 1e9, np.isfinite(e)
    both = hit_r & hit_e
    rel = np.abs(z[both] - e[both]) / np.maximum(e[both], 1e-30)
    agree = hit_r == hit_e
    agree[both] &= rel < 1e-3
    print(f'{exr}: hit and depth (within 0.1%) agree with Embree on {100 * agree.mean():.4f}% '
          f'of {z.size} pixels; hit/miss alone {100 * (hit_r == hit_e).mean():.4f}%')


if __name__ == '__main__':
    main(*sys.argv[1:3])
