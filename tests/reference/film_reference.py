#!/usr/bin/env python3
"""Independent reference for one rayreel *film frame with a lens* (no shutter).

Transcribes, from the docs alone (never from src/), the rules of docs/spec/tracer.md
("Conventions", "The arithmetic, exactly": Vectors, Loading, Camera, Eye ray, Sphere, Plane,
Nearest hit, Surface, Each light (point lights), Path, Pixel, Sample offsets' mix, Film frames
(Owen-scrambled Sobol' points), Rounds (adaptive sampling in rounds), Thin lens (concentric map
with the Taylor sin/cos)) and docs/spec/output.md (EXR float channels hold the f32 pixel
values). All arithmetic is IEEE-754 f64 on scalar Python floats, in the spec's operation
order; each pixel's mean is rounded to f32 as the Pixel and Rounds rules say.

The scene is film_40x24.yaml beside this script, hard-coded here (frame 0; no sampling set,
so film's default with a lens: 4 samples, then rounds up to 64 at threshold 0.035, then the
film filter).

rayreel's values: `rayreel render SCENE --exr-precision float -o frame.exr` (EXR float
channels hold the f32 pixel values); `--samples 4` / `--samples 16` give the uniform renders.
film_40x24.f32 is this script's default (rounds) output, equal bit for bit to rayreel's.
Caveat: the output is f32, so f64 operation-order details below the f32 rounding (the Taylor
sin/cos against libm's, the order of the lens origin's sums, how the first pass's mean is
summed) do not show in these values; the sampling, lens geometry and rounds decisions do.

Usage:
    python3 film_reference.py OUT.f32                # default sampling (rounds 4 -> 64)
    python3 film_reference.py OUT.f32 --samples N    # N uniform Sobol' samples, no rounds
OUT.f32 receives W*H*3 little-endian f32 values, RGB, row-major from the top-left pixel.
"""
import math
import struct
import sys
from fractions import Fraction

M64 = (1 << 64) - 1
M32 = (1 << 32) - 1

# ---------------------------------------------------------------- scene
W, H, MAX_DEPTH = 40, 24, 3
FRAME = 0
CAM_POS = (0.0, 0.1, 1.2)
CAM_LOOK = (-0.1, -0.1, -0.5)
CAM_UP = (0.0, 1.0, 0.0)
FOV = 70.0
APERTURE = 0.08
FOCUS = 1.0
BACKGROUND = (0.0, 0.0, 0.0)
MATERIALS = {
    'red': dict(ka=(0.1, 0.0, 0.0), kd=(0.7, 0.0, 0.0), ks=(1.0, 1.0, 1.0), shininess=100.0, refl=0.5),
    'green': dict(ka=(0.0, 0.1, 0.0), kd=(0.0, 0.6, 0.0), ks=(1.0, 1.0, 1.0), shininess=100.0, refl=0.5),
    'floor': dict(ka=(0.1, 0.1, 0.1), kd=(0.6, 0.6, 0.6), ks=(1.0, 1.0, 1.0), shininess=100.0, refl=0.5),
}
SPHERES_IN = [((-0.2, 0.0, -1.0), 0.7, 'red'), ((-0.3, 0.0, 0.0), 0.15, 'green')]
PLANES_IN = [((0.0, -0.7, 0.0), (0.0, 1.0, 0.0), 'floor')]
LIGHTS = [dict(pos=(5.0, 5.0, 5.0), ia=(1.0, 1.0, 1.0), id=(1.0, 1.0, 1.0), is_=(1.0, 1.0, 1.0))]
DEFAULT_SAMPLES, MAX_SAMPLES, THRESHOLD = 4, 64, 0.035


# ---------------------------------------------------------------- vectors
def dot(a, b):
    return (a[0] * b[0] + a[1] * b[1]) + a[2] * b[2]


def length(v):
    return math.sqrt(dot(v, v))


def normalize(v):
    r = 1.0 / length(v)
    return (v[0] * r, v[1] * r, v[2] * r)


def cross(a, b):
    return (a[1] * b[2] - b[1] * a[2], a[2] * b[0] - b[2] * a[0], a[0] * b[1] - b[0] * a[1])


def add(a, b):
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def scale(s, v):
    return (s * v[0], s * v[1], s * v[2])


def had(a, b):
    return (a[0] * b[0], a[1] * b[1], a[2] * b[2])


def f32(x):
    return struct.unpack('<f', struct.pack('<f', x))[0]


# ---------------------------------------------------------------- loading
# objects: index, kind, data
OBJECTS = []
for (c, r, m) in SPHERES_IN:
    OBJECTS.append(('sphere', c, r * r, MATERIALS[m]))
for (p, n, m) in PLANES_IN:
    OBJECTS.append(('plane', p, normalize(n), MATERIALS[m]))
for mat in MATERIALS.values():
    e = mat['shininess'] / 4.0
    mat['e'] = e
    mat['floor'] = 0.0 if e == 0.0 else math.exp(-69.08 / e)

# ---------------------------------------------------------------- camera
_dl = sub(CAM_LOOK, CAM_POS)
_len = length(_dl)
FWD = (_dl[0] / _len, _dl[1] / _len, _dl[2] / _len)
_ud = dot(CAM_UP, FWD)
UPC = normalize((CAM_UP[0] - _ud * FWD[0], CAM_UP[1] - _ud * FWD[1], CAM_UP[2] - _ud * FWD[2]))
RIGHT = cross(FWD, UPC)
S = math.tan((FOV * (math.pi / 180.0)) * 0.5)
RHO = 0.5 * APERTURE

# Taylor coefficients, nearest f64 of (-1)^i/(2i+1)! and (-1)^i/(2i)!
PC = [float(Fraction((-1) ** i, math.factorial(2 * i + 1))) for i in range(9)]
QC = [float(Fraction((-1) ** i, math.factorial(2 * i))) for i in range(9)]
QUARTER_PI = math.pi / 4.0


def sin_cos(x):
    y = x * x
    p = PC[8]
    for i in range(7, -1, -1):
        p = p * y + PC[i]
    q = QC[8]
    for i in range(7, -1, -1):
        q = q * y + QC[i]
    return x * p, q


def eye_ray(i, j, u, v, a, b):
    x = -1.0 + (2.0 * (j + u)) / W
    y = ((1.0 - (2.0 * (i + v)) / H) * H) / W
    xs, ys = x * S, y * S
    w = tuple((FWD[c] + xs * RIGHT[c]) + ys * UPC[c] for c in range(3))
    if not (RHO > 0.0):
        return CAM_POS, normalize(w)
    a2 = 2.0 * a - 1.0
    b2 = 2.0 * b - 1.0
    if a2 == 0.0 and b2 == 0.0:
        dx, dy = 0.0, 0.0
    elif max(a2, 0.0 - a2) > max(b2, 0.0 - b2):
        r = a2
        sn, cs = sin_cos(QUARTER_PI * (b2 / a2))
        dx, dy = r * cs, r * sn
    else:
        r = b2
        sn, cs = sin_cos(QUARTER_PI * (a2 / b2))
        dx, dy = r * sn, r * cs
    rdx, rdy = RHO * dx, RHO * dy
    origin = tuple((CAM_POS[c] + RIGHT[c] * rdx) + UPC[c] * rdy for c in range(3))
    target = tuple(CAM_POS[c] + w[c] * FOCUS for c in range(3))
    return origin, normalize(sub(target, origin))


# ---------------------------------------------------------------- intersection
INF = float('inf')


def hit_sphere(o, d, c, r2, leaving_this):
    f = sub(o, c)
    b = dot(f, d)
    p = (f[0] - b * d[0], f[1] - b * d[1], f[2] - b * d[2])
    disc = r2 - dot(p, p)
    if not (disc >= 0.0):
        return None
    cc = dot(f, f) - r2
    if b > 0.0 and (cc >= 0.0 or leaving_this):
        return None
    q = -(b + math.copysign(math.sqrt(disc), b))
    if q == 0.0:
        return None
    t0, t1 = cc / q, q
    lo, hi = (t0, t1) if t0 <= t1 else (t1, t0)
    if leaving_this:
        if b < 0.0 and hi > 0.0:
            return hi
        return None
    if lo > 0.0:
        return lo
    if hi > 0.0:
        return hi
    return None


def hit_plane(o, d, p, n):
    t = dot(sub(p, o), n) / dot(n, d)
    if 0.0 < t < INF:
        return t
    return None


def nearest(o, d, leaving):
    best_t, best_k = None, None
    for k, obj in enumerate(OBJECTS):
        if obj[0] == 'sphere':
            t = hit_sphere(o, d, obj[1], obj[2], leaving == k)
        else:
            if leaving == k:
                continue
            t = hit_plane(o, d, obj[1], obj[2])
        if t is not None and (best_t is None or t < best_t):
            best_t, best_k = t, k
    return best_t, best_k


def blocked(P, L, dist, leaving):
    dirn = normalize(L)
    for k, obj in enumerate(OBJECTS):
        if obj[0] == 'sphere':
            t = hit_sphere(P, dirn, obj[1], obj[2], leaving == k)
        else:
            if leaving == k:
                continue
            t = hit_plane(P, dirn, obj[1], obj[2])
        if t is not None and t < dist:
            return True
    return False


def spec_pow(x, e, flo):
    if e == 0.0:
        return 1.0
    if x <= flo:
        return 0.0
    if e == math.floor(e) and e <= 4096:
        n = int(e)
        result, base = 1.0, x
        while n:
            if n & 1:
                result = result * base
            n >>= 1
            if n:
                base = base * base
        return result
    return math.pow(x, e)


def shade(P, N, d, k):
    mat = OBJECTS[k][3]
    local = (0.0, 0.0, 0.0)
    for li in LIGHTS:
        v = sub(li['pos'], P)
        dist = length(v)
        if dist > 0.0:
            L = (v[0] / dist, v[1] / dist, v[2] / dist)
        else:
            L, dist = (0.0, 0.0, 0.0), 0.0
        local = add(local, had(mat['ka'], li['ia']))
        n_l = dot(N, L)
        if n_l <= 0.0:
            continue
        if blocked(P, L, dist, k):
            continue
        Hv = normalize((L[0] + (-d[0]), L[1] + (-d[1]), L[2] + (-d[2])))
        x = dot(N, Hv)
        if x < 0.0:
            x = 0.0
        if x > 1.0:
            x = 1.0
        sp = spec_pow(x, mat['e'], mat['floor'])
        kdid = had(mat['kd'], li['id'])
        ksis = had(mat['ks'], li['is_'])
        term = tuple(kdid[c] * n_l + ksis[c] * sp for c in range(3))
        local = add(local, term)
    return local


def trace(o, d):
    colour = (0.0, 0.0, 0.0)
    w = 1.0
    leaving = None
    for depth in range(MAX_DEPTH):
        t, k = nearest(o, d, leaving)
        if t is None:
            colour = add(colour, scale(w, BACKGROUND))
            break
        P = (o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2])
        obj = OBJECTS[k]
        N = normalize(sub(P, obj[1])) if obj[0] == 'sphere' else obj[2]
        if dot(N, d) > 0.0:
            N = (-N[0], -N[1], -N[2])
        local = shade(P, N, d, k)
        colour = add(colour, scale(w, local))
        w = w * obj[3]['refl']
        if w < 1e-30 or depth == MAX_DEPTH - 1:
            break
        dn2 = 2.0 * dot(d, N)
        d = normalize((d[0] - dn2 * N[0], d[1] - dn2 * N[1], d[2] - dn2 * N[2]))
        o = P
        leaving = k
    return colour


# ---------------------------------------------------------------- samples
def mix(z):
    z = (z + 0x9e3779b97f4a7c15) & M64
    z = ((z ^ (z >> 30)) * 0xbf58476d1ce4e5b9) & M64
    z = ((z ^ (z >> 27)) * 0x94d049bb133111eb) & M64
    return z ^ (z >> 31)


def direction_numbers():
    dims = [[(1 << (31 - j)) for j in range(32)]]
    for (s, a, m0) in [(1, 0, [1]), (2, 1, [1, 3]), (3, 1, [1, 3, 1]), (3, 2, [1, 1, 1])]:
        m = list(m0)
        for k in range(s, 32):
            x = m[k - s] ^ (m[k - s] << s)
            for i in range(1, s):
                if (a >> (s - 1 - i)) & 1:
                    x ^= m[k - i] << i
            m.append(x)
        dims.append([(m[j] << (31 - j)) & M32 for j in range(32)])
    return dims


DIRS = direction_numbers()


def rev32(x):
    return int('{:032b}'.format(x)[::-1], 2)


def lk(x, s):
    x = (x + s) & M32
    x ^= (x * 0x6c50b47c) & M32
    x ^= (x * 0xb82f1e52) & M32
    x ^= (x * 0xc7afe638) & M32
    x ^= (x * 0x8d22f6e6) & M32
    return x


def scramble(x, s):
    return rev32(lk(rev32(x), s))


def pixel_seeds(pixel):
    z = mix(mix(0x9e3779b97f4a7c15 ^ FRAME) ^ pixel)
    w0 = mix(z ^ 0x3c6ef372fe94f82b)
    w1 = mix(w0)
    w2 = mix(w1)
    return (w0 >> 32, w0 & M32, w1 >> 32, w1 & M32, w2 >> 32)


def sobol_point(k, seeds):
    out = []
    for dd in range(5):
        p = 0
        j = 0
        kk = k
        while kk:
            if kk & 1:
                p ^= DIRS[dd][j]
            kk >>= 1
            j += 1
        out.append(scramble(p, seeds[dd]) * 2.0 ** -32)
    return out


def sample_colour(i, j, k, seeds):
    x = sobol_point(k, seeds)
    o, d = eye_ray(i, j, x[0], x[1], x[2], x[3])
    return trace(o, d)


def sum_samples(i, j, k0, k1, seeds):
    s = (0.0, 0.0, 0.0)
    for k in range(k0, k1):
        s = add(s, sample_colour(i, j, k, seeds))
    return s


# ---------------------------------------------------------------- render
def render_uniform(n):
    img = []
    for i in range(H):
        for j in range(W):
            seeds = pixel_seeds(i * W + j)
            s = sum_samples(i, j, 0, n, seeds)
            img.append(tuple(f32(c) if n == 1 else f32(c / n) for c in s))
    return img


def estimate(a, b):
    g = []
    for c in range(3):
        ca = math.sqrt(min_(max_(a[c], 0.0), 1.0))
        cb = math.sqrt(min_(max_(b[c], 0.0), 1.0))
        dd = ca - cb
        g.append(max_(dd, 0.0 - dd))
    return f32(max_(max_(g[0], g[1]), g[2]) * 0.5)


def max_(x, y):
    return x if x > y else y


def min_(x, y):
    return x if x < y else y


def render_rounds(n, max_samples, threshold, first_mean='sequential', stats=None, lens=None):
    """`lens`: whether the frame's lens is open (the film filter's reach); by default RHO > 0."""
    thr = f32(threshold)
    h = n // 2
    mean = [None] * (W * H)
    est = [None] * (W * H)
    for i in range(H):
        for j in range(W):
            px = i * W + j
            seeds = pixel_seeds(px)
            A = (0.0, 0.0, 0.0)
            B = (0.0, 0.0, 0.0)
            tot = (0.0, 0.0, 0.0)
            for k in range(n):
                c = sample_colour(i, j, k, seeds)
                tot = add(tot, c)
                if k < h:
                    A = add(A, c)
                else:
                    B = add(B, c)
            if first_mean == 'halves':
                tot = add(A, B)
            mean[px] = tuple(f32(c / n) for c in tot)
            a = tuple(c / h for c in A)
            b = tuple(c / (n - h) for c in B)
            est[px] = estimate(a, b)
    have = n
    last = list(range(W * H))
    rounds = []
    while have < max_samples:
        go = []
        for px in last:
            i, j = divmod(px, W)
            on = False
            for di in (-1, 0, 1):
                for dj in (-1, 0, 1):
                    ii, jj = i + di, j + dj
                    if 0 <= ii < H and 0 <= jj < W and est[ii * W + jj] > thr:
                        on = True
            if on:
                go.append(px)
        if not go:
            break
        total = min(2 * have, max_samples)
        rounds.append((have, total, len(go)))
        for px in go:
            i, j = divmod(px, W)
            seeds = pixel_seeds(px)
            B = sum_samples(i, j, have, total, seeds)
            m = mean[px]
            b = tuple(c / (total - have) for c in B)
            mean[px] = tuple(f32((m[c] * have + B[c]) / total) for c in range(3))
            est[px] = estimate(m, b)
        have = total
        last = go
    if stats is not None:
        stats['rounds'] = rounds
    return film_filter(mean, est, RHO > 0.0 if lens is None else lens)


# ---------------------------------------------------------------- film filter (f32)
def film_filter(mean, est, lens=True):
    """docs/spec/tracer.md, Film filter: every operation in f32 (no alpha here: all whole).
    `lens`: the frame's lens is open (three passes at steps 1, 2, 4 with K = 16), else one pass
    at step 1 with K = 9."""
    F = f32(1.6e-5)
    steps, K = ((1, 2, 4), 16.0) if lens else ((1,), 9.0)

    def block(p, s):
        i, j = divmod(p, W)
        return [ii * W + jj for ii in (i - s, i, i + s) if 0 <= ii < H
                for jj in (j - s, j, j + s) if 0 <= jj < W]

    var = []
    for p in range(W * H):
        acc, n = 0.0, 0.0
        for q in block(p, 1):
            acc = f32(acc + f32(est[q] * est[q]))
            n = f32(n + 1.0)
        var.append(f32(acc / n))
    tap = (0.5, 0.25)
    for s in steps:
        guide = [tuple(f32(math.sqrt(max_(c, 0.0))) for c in m) for m in mean]
        out, out_var = [], []
        for p in range(W * H):
            vp = var[p]
            if not (vp > F):
                out.append(mean[p])
                out_var.append(vp)
                continue
            acc, total, V = [0.0, 0.0, 0.0], 0.0, 0.0
            for q in block(p, s):
                d2 = 0.0
                for c in range(3):
                    d = f32(guide[p][c] - guide[q][c])
                    dd = f32(d * d)
                    d2 = dd if dd > d2 else d2
                a = f32(K * f32(vp + var[q]))
                r = f32(a / f32(a + d2))
                t = f32(tap[abs(q // W - p // W) // s] * tap[abs(q % W - p % W) // s])
                weight = f32(t * f32(r * r))
                for c in range(3):
                    acc[c] = f32(acc[c] + f32(weight * mean[q][c]))
                total = f32(total + weight)
                V = f32(V + f32(f32(weight * weight) * var[q]))
            out.append(tuple(f32(acc[c] / total) for c in range(3)))
            out_var.append(f32(V / f32(total * total)))
        mean, var = out, out_var
    return mean


def main():
    args = sys.argv[1:]
    out = args[0]
    variant = 'sequential'
    if '--halves' in args:
        variant = 'halves'
    if '--samples' in args:
        n = int(args[args.index('--samples') + 1])
        img = render_uniform(n)
    else:
        st = {}
        img = render_rounds(DEFAULT_SAMPLES, MAX_SAMPLES, THRESHOLD, variant, st)
        print('rounds (have, total, pixels):', st['rounds'], file=sys.stderr)
    with open(out, 'wb') as fh:
        for px in img:
            fh.write(struct.pack('<3f', *px))


if __name__ == '__main__':
    main()
