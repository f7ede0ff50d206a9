# An independent float64 implementation of textured frames, written from docs/spec/texture.md,
# docs/textures.md, docs/spec/tracer.md, docs/spec/mesh.md and docs/spec/output.md alone (not
# from rayreel's code). It reuses the tracer of mesh_reference.py (imported as a module and
# subclassed; mesh_reference.py itself is unchanged) and adds the footprint cone (eye spread,
# width at a hit, reflection and transmission updates), the footprint ellipse and its taps,
# snapping, the checker's box filter, PNG decoding (8 and 16 bits, grey, RGB, palette), the
# binary32 mip pyramid, texture coordinates of planes (default u axis and `u_axis`), spheres and
# OBJ meshes (`vt`), the trilinear lookup and the replacement of diffuse and ambient, and the
# sky (a gradient, or an equirectangular image by direction and footprint) seen by every miss.
# Same limits as mesh_reference.py (encoding linear, f64, no adaptive sampling, no alpha), except
# that n² stratified samples a pixel are traced (tracer.md "Sample offsets", frame 0).
#
# Usage: python3 texture_reference.py [SCENE ...]     (needs numpy and Pillow; OpenEXR, mpmath optional)
#   writes texture/SCENE.yaml (and the texture PNGs when missing) and texture/ref_SCENE.png; with
#   RAYREEL=path/to/rayreel it also renders each YAML with rayreel and compares the 8-bit PNG
#   bytes and (with the OpenEXR module, through a 32-bit EXR) every f32 channel bit for bit.
#
# libm: texture.md names the `libm` crate's log2, atan2, acos and pow. Python's math module is
# the C library's (glibc here); check_libm() compares every call made with the correctly rounded
# value (mpmath). Where glibc is correctly rounded and the Rust libm is not, the two could differ
# by an ulp; the check cannot see that, it only says whether glibc was exact.
import math, os, struct, subprocess, sys, zlib
import numpy as np
from PIL import Image

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import mesh_reference as mr  # noqa: E402
from mesh_reference import add, sub, vmul, had, neg, dot, length, normalize, cross, fdiv, INF  # noqa: E402

TEXDIR = os.path.join(HERE, 'texture')
mr.MESHDIR = TEXDIR  # mesh files of the texture scenes live beside them


# ---------------------------------------------------------------- helpers

def snapper(snaps):
    """snap(X): X with each held coordinate (i, c) in snaps set to c (texture.md)."""
    def snap(X):
        X = list(X)
        for i, c in snaps:
            X[i] = c
        return tuple(X)
    return snap

def ffloor(x):  # IEEE floor on floats (Python's math.floor gives ints and fails on inf/NaN)
    return float(math.floor(x)) if math.isfinite(x) else x

def fmax(a, b):  # Rust's f64::max: a NaN side gives the other
    if a != a: return b
    if b != b: return a
    return a if a > b else b

def sdiv(v, s): return (fdiv(v[0], s), fdiv(v[1], s), fdiv(v[2], s))

def normalize_or_zero(v):
    r = fdiv(1.0, math.sqrt(dot(v, v)))
    if math.isfinite(r) and r > 0:
        return (v[0] * r, v[1] * r, v[2] * r)
    return (0.0, 0.0, 0.0)

LIBM = {}  # (name, args) -> result, for check_libm
def libm(name, *x):
    y = getattr(math, name)(*x)
    LIBM[(name, x)] = y
    return y

def check_libm():
    try:
        import mpmath
    except ImportError:
        print('libm: mpmath not installed, glibc results not checked')
        return
    mpmath.mp.prec = 200
    f = {'pow': mpmath.power, 'atan2': mpmath.atan2, 'acos': mpmath.acos, 'log2': lambda x: mpmath.log(x, 2)}
    bad = [(k, y) for k, y in LIBM.items() if float(f[k[0]](*[mpmath.mpf(a) for a in k[1]])) != y]
    print(f'libm: {len(LIBM)} distinct log2/atan2/acos/pow calls, {len(bad)} not correctly rounded by glibc', bad[:3])


# ---------------------------------------------------------------- PNG (decoded by hand: Pillow
# turns 16-bit RGB into 8 bits); 8-bit files are cross-checked against Pillow
def read_png(path):
    data = open(path, 'rb').read()
    assert data[:8] == b'\x89PNG\r\n\x1a\n', path
    pos = 8; idat = b''; plte = None
    while pos < len(data):
        n, = struct.unpack('>I', data[pos:pos + 4]); typ = data[pos + 4:pos + 8]; body = data[pos + 8:pos + 8 + n]
        pos += 12 + n
        if typ == b'IHDR':
            w, h, bd, ct, _, _, inter = struct.unpack('>IIBBBBB', body)
        elif typ == b'PLTE':
            plte = body
        elif typ == b'IDAT':
            idat += body
        elif typ == b'IEND':
            break
    assert inter == 0 and bd in (8, 16), (path, bd, inter)
    ch = {0: 1, 2: 3, 3: 1, 4: 2, 6: 4}[ct]
    bpp = ch * bd // 8; stride = w * bpp
    raw = zlib.decompress(idat)
    out = bytearray(); prev = bytearray(stride)
    for y in range(h):
        f = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for x in range(stride):
            a = line[x - bpp] if x >= bpp else 0; b = prev[x]; c = prev[x - bpp] if x >= bpp else 0
            if f == 1: line[x] = (line[x] + a) & 255
            elif f == 2: line[x] = (line[x] + b) & 255
            elif f == 3: line[x] = (line[x] + ((a + b) >> 1)) & 255
            elif f == 4:
                p = a + b - c; pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[x] = (line[x] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        out += line; prev = line
    arr = np.frombuffer(bytes(out), dtype='>u2' if bd == 16 else np.uint8).reshape(h, w, ch).astype(np.int64)
    if ct == 3:
        arr = np.frombuffer(plte, np.uint8).reshape(-1, 3)[arr[:, :, 0]].astype(np.int64)
    elif ct in (0, 4):
        arr = np.repeat(arr[:, :, :1], 3, axis=2)
    elif ct == 6:
        arr = arr[:, :, :3]
    if bd == 8:
        pil = np.asarray(Image.open(path).convert('RGB')).astype(np.int64)
        assert (pil == arr).all(), 'PNG decoder disagrees with Pillow: ' + path
    return arr, bd

def write_png(path, arr, bd, ct):
    """arr: h × w × channels ints; filter 0 on every row."""
    h, w = arr.shape[:2]
    dt = '>u2' if bd == 16 else np.uint8
    raw = b''.join(b'\x00' + arr[y].astype(dt).tobytes() for y in range(h))
    chunk = lambda t, b: struct.pack('>I', len(b)) + t + b + struct.pack('>I', zlib.crc32(t + b))
    open(path, 'wb').write(b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', w, h, bd, ct, 0, 0, 0))
                           + chunk(b'IDAT', zlib.compress(raw, 9)) + chunk(b'IEND', b''))


# ---------------------------------------------------------------- image maps (texture.md "Image")
IMAGES = {}
def load_image(name, encoding):
    key = (name, encoding)
    if key in IMAGES:
        return IMAGES[key]
    if name.lower().endswith('.exr'):  # R, G, B of the first layer, binary32 (half widened exactly)
        import OpenEXR
        ch = OpenEXR.File(os.path.join(TEXDIR, name), separate_channels=True).channels()
        L0 = np.stack([ch[c].pixels.astype(np.float32) for c in 'RGB'], axis=2)
        assert np.isfinite(L0).all() and (L0 >= 0).all()
        IMAGES[key] = pyramid(L0)
        return IMAGES[key]
    codes, bd = read_png(os.path.join(TEXDIR, name))
    maxv = float(2 ** bd - 1)
    memo = {}
    def texel(v):
        if v not in memo:
            x = float(v) / maxv
            if encoding == 'srgb':
                x = x / 12.92 if x <= 0.04045 else libm('pow', (x + 0.055) / 1.055, 2.4)
            memo[v] = np.float32(x)
        return memo[v]
    h, w = codes.shape[:2]
    L0 = np.array([[[texel(int(codes[y, x, c])) for c in range(3)] for x in range(w)] for y in range(h)], dtype=np.float32)
    IMAGES[key] = pyramid(L0)
    return IMAGES[key]

def pyramid(L0):
    levels = [L0]
    while levels[-1].shape[0] > 1 or levels[-1].shape[1] > 1:
        L = levels[-1]; lh, lw = L.shape[:2]
        nw, nh = (lw + 1) // 2, (lh + 1) // 2
        x0 = (2 * np.arange(nw)) % lw; x1 = (2 * np.arange(nw) + 1) % lw
        y0 = (2 * np.arange(nh)) % lh; y1 = (2 * np.arange(nh) + 1) % lh
        a = L[y0][:, x0]; b = L[y0][:, x1]; c = L[y1][:, x0]; d = L[y1][:, x1]
        nxt = ((a + b) + (c + d)) * np.float32(0.25)  # all binary32
        assert nxt.dtype == np.float32
        levels.append(nxt)
    return levels

def bilinear(level, u, v):
    h, w = level.shape[:2]
    x = (u - ffloor(u)) * float(w) - 0.5
    y = (1.0 - (v - ffloor(v))) * float(h) - 0.5
    x0 = ffloor(x); y0 = ffloor(y); fx = x - x0; fy = y - y0
    i0 = int(x0) % w; j0 = int(y0) % h; i1 = (i0 + 1) % w; j1 = (j0 + 1) % h
    T = lambda i, j: [float(c) for c in level[j, i]]
    t00, t10, t01, t11 = T(i0, j0), T(i1, j0), T(i0, j1), T(i1, j1)
    return tuple((t00[c] * (1.0 - fx) + t10[c] * fx) * (1.0 - fy) + (t01[c] * (1.0 - fx) + t11[c] * fx) * fy
                 for c in range(3))

def image_lookup(levels, scale, u, v, F):
    u = u * scale[0]; v = v * scale[1]
    L = len(levels)
    if not (math.isfinite(u) and math.isfinite(v)):
        return tuple(float(c) for c in levels[L - 1][0, 0])
    lam = libm('log2', F) if F > 1 else 0.0
    if not (lam < L - 1):
        return bilinear(levels[L - 1], u, v)
    l = ffloor(lam); f = lam - l
    c = bilinear(levels[int(l)], u, v)
    if f == 0:
        return c
    c1 = bilinear(levels[int(l) + 1], u, v)
    return tuple(c[i] * (1.0 - f) + c1[i] * f for i in range(3))


# ---------------------------------------------------------------- the sky (texture.md "The sky")
TAU = 6.283185307179586

def sky_bilinear(level, u, v):
    """The sky's bilinear rule: repeating along u, rows clamped."""
    h, w = level.shape[:2]
    x = (u - ffloor(u)) * float(w) - 0.5
    y = (1.0 - v) * float(h) - 0.5
    x0 = ffloor(x); y0 = ffloor(y); fx = x - x0; fy = y - y0
    i0 = int(x0) % w; i1 = (i0 + 1) % w
    j0 = min(max(int(y0), 0), h - 1); j1 = min(max(int(y0 + 1.0), 0), h - 1)
    T = lambda i, j: [float(c) for c in level[j, i]]
    t00, t10, t01, t11 = T(i0, j0), T(i1, j0), T(i0, j1), T(i1, j1)
    return tuple((t00[c] * (1.0 - fx) + t10[c] * fx) * (1.0 - fy) + (t01[c] * (1.0 - fx) + t11[c] * fx) * fy
                 for c in range(3))

def sky_seen(sky, d, s):
    """What a ray of direction d (any length) and cone spread s sees of `sky`."""
    if sky[0] == 'gradient':
        _, Z, Hc, G = sky
        y = fdiv(d[1], math.sqrt((d[0] * d[0] + d[1] * d[1]) + d[2] * d[2]))
        if not math.isfinite(y):
            return Hc
        a, C = (y, Z) if y >= 0 else (-y, G)
        return tuple(Hc[c] * (1.0 - a) + C[c] * a for c in range(3))
    _, levels, R, K = sky
    phi = libm('atan2', d[0], -d[2])
    rho = math.sqrt(d[0] * d[0] + d[2] * d[2])
    theta = libm('atan2', d[1], rho)
    u = (phi / TAU + 0.5) + R / 360.0
    v = theta / math.pi + 0.5
    L = len(levels)
    if not (math.isfinite(u) and math.isfinite(v)):
        c = tuple(float(x) for x in levels[L - 1][0, 0])
    else:
        Th, Tw = levels[0].shape[:2]
        F = abs(s) * fmax(float(Tw) / TAU, float(Th) / math.pi)
        lam = libm('log2', F) if F > 1 else 0.0
        if not (lam < L - 1):
            c = sky_bilinear(levels[L - 1], u, v)
        else:
            l = ffloor(lam); f = lam - l
            c = sky_bilinear(levels[int(l)], u, v)
            if f != 0:
                c1 = sky_bilinear(levels[int(l) + 1], u, v)
                c = tuple(c[i] * (1.0 - f) + c1[i] * f for i in range(3))
    return tuple(x * K for x in c)


# ---------------------------------------------------------------- checker (texture.md "Checker")
def sgn(k):
    return 1.0 if k - 2.0 * ffloor(k / 2.0) == 0 else -1.0

def tri(u):
    f = u - 2.0 * ffloor(u / 2.0)
    return f if f < 1 else 2.0 - f

def box_avg(x, h):
    if h != h or h == INF:
        return 0.0
    if h < 1e-12:
        return sgn(ffloor(x))
    a = x - h; b = x + h; ka = ffloor(a); kb = ffloor(b)
    if ka == kb:
        return sgn(ka)
    if kb == ka + 1:
        return fdiv(sgn(ka) * (kb - a) + sgn(kb) * (b - kb), b - a)
    return fdiv(tri(b) - tri(a), b - a)


def one_cell(P, major, minor, z):
    """texture.md "One cell": S's sign over the footprint's box when it lies in one cell, else None."""
    A = 1.0
    for i in range(3):
        x = fdiv(P[i], z)
        h = fdiv(abs(major[i]) + abs(minor[i]), z)
        if h < 1e-12:
            k = ffloor(x)
        else:
            k = ffloor(x - h)
            if k != ffloor(x + h):
                return None
        A = A * sgn(k)
    return A


# ---------------------------------------------------------------- texture.md "The pixel"
def U2(u):
    n = ffloor(u * 0.5); f = u - 2.0 * n
    return n + ((0.5 * f) * f) if f < 1 else n + (((2.0 * f - (0.5 * f) * f) - 1.0))

def pix_line(x, a, b):
    a = abs(a); b = abs(b)
    if not a >= b:
        a, b = b, a
    if b <= a * 2.0 ** -20 or a * b < 2.0 ** -34:
        return box_avg(x, a)
    x = x - 2.0 * ffloor(x * 0.5)
    s = ((U2((x + a) + b) - U2((x + a) - b)) - U2((x - a) + b)) + U2((x - a) - b)
    return fdiv(s, (4.0 * a) * b)

def pix_edge(p, q):
    (x0, y0), (x1, y1) = p, q
    if y1 == y0:
        return 0.0
    m = fdiv(x1 - x0, y1 - y0)
    if not math.isfinite(m):
        return None
    up = y1 > y0; row = ffloor(y0); ya, xa, ua = y0, x0, U2(x0); s = 0.0
    for _ in range(35):
        bound = row + 1.0 if up else row
        last = bound >= y1 if up else bound <= y1
        yb, xb = (y1, x1) if last else (bound, x0 + (bound - y0) * m)
        ub = U2(xb)
        piece = tri(0.5 * (xa + xb)) * (yb - ya) if abs(m) < 2.0 ** -20 else fdiv(ub - ua, m)
        s = s + sgn(row) * piece
        if last:
            return s
        ya, xa, ua = yb, xb, ub
        row = row + 1.0 if up else row - 1.0
    return None

def pix_area(X, Y, hy):
    (cx, ax, bx), (cy, ay, by) = X, Y
    k = ax * by - ay * bx
    if not abs(k) >= ((abs(ax) + abs(ay)) * (abs(bx) + abs(by))) * 2.0 ** -10 or abs(k) < 2.0 ** -34:
        return None
    if ffloor(cy + hy) - ffloor(cy - hy) > 32:
        return None
    cx = cx - 2.0 * ffloor(cx * 0.5); cy = cy - 2.0 * ffloor(cy * 0.5)
    p = [((cx - ax) - bx, (cy - ay) - by), ((cx + ax) - bx, (cy + ay) - by),
         ((cx + ax) + bx, (cy + ay) + by), ((cx - ax) + bx, (cy - ay) + by)]
    s = 0.0
    for i in range(4):
        e = pix_edge(p[i], p[(i + 1) % 4])
        if e is None:
            return None
        s = s + e
    return fdiv(s, 4.0 * k)

def pixel_patch(o, p, n, pix):
    """The eye ray's pixel on the tangent plane at p: (Δ, a, b), or None."""
    c, rt, dn = pix
    q = dot(n, c)
    if not q < 0:
        return None
    t = fdiv(dot(sub(p, o), n), q)
    if not t > 0:
        return None
    h = 0.5 * t
    D = sub(add(o, vmul(c, t)), p)
    a = vmul(sub(rt, vmul(c, fdiv(dot(rt, n), q))), h)
    b = vmul(sub(dn, vmul(c, fdiv(dot(dn, n), q))), h)
    if not all(math.isfinite(v) for v in D + a + b):
        return None
    return D, a, b

def pixel_checker(C, a, b, z, colors):
    x = [fdiv(C[i], z) for i in range(3)]
    h = [fdiv(abs(a[i]) + abs(b[i]), z) for i in range(3)]
    held = 1.0; vary = []
    for i in range(3):
        if h[i] < 1e-12:
            held = held * sgn(ffloor(x[i])); continue
        k = ffloor(x[i] - h[i])
        if k == ffloor(x[i] + h[i]):
            held = held * sgn(k)
        else:
            vary.append(i)
    cells = lambda i: (x[i], fdiv(a[i], z), fdiv(b[i], z))
    if not vary:
        M = held
    elif len(vary) == 1:
        M = held * pix_line(*cells(vary[0]))
    elif len(vary) == 2:
        i, j = vary
        X, Y = (i, j) if h[i] >= h[j] else (j, i)
        r = pix_area(cells(X), cells(Y), h[Y])
        if r is None:
            return None
        M = held * r
    else:
        return None
    if not math.isfinite(M):
        return None
    M = min(max(M, -1.0), 1.0)
    c0, c1 = colors
    return tuple(c0[c] * (0.5 + 0.5 * M) + c1[c] * (0.5 - 0.5 * M) for c in range(3))


# ---------------------------------------------------------------- meshes keep their texture coordinates
class TexMeshFile(mr.MeshFile):
    def build(self, pos, nrm, tex, corners_faces):
        seen = {}; triples = []
        for face in corners_faces:  # the same numbering as MeshFile.build: order of first use
            for c in face:
                if c not in seen:
                    seen[c] = len(triples); triples.append(c)
        self.UV = [tuple(tex[tr[1]]) for tr in triples] if all(tr[1] is not None for tr in triples) else None
        super().build(pos, nrm, tex, corners_faces)
mr.MeshFile = TexMeshFile


class TexScene(mr.Scene):
    def __init__(self, d):
        if isinstance(d['render'].get('background'), dict):  # a sky: mesh_reference reads colours only
            super().__init__(dict(d, render=dict(d['render'], background=[0, 0, 0])))
        else:
            super().__init__(d)
        for s in self.spheres:
            s['R'] = float(d['objects'][s['idx']]['sphere']['radius'])
        for p in self.planes:
            N = p['n']
            ua = d['objects'][p['idx']]['plane'].get('u_axis')
            if ua is not None:
                a = normalize(tuple(map(float, ua)))
            elif abs(N[0]) > 0.5:
                a = (0.0, 0.0, -math.copysign(1.0, N[0]))
            else:
                a = (1.0, 0.0, 0.0)
            U = normalize(sub(a, vmul(N, dot(a, N))))
            p['U'] = U; p['V'] = cross(N, U)
            nz = [i for i in range(3) if N[i] != 0]
            p['snap'] = [(nz[0], p['p'][nz[0]])] if len(nz) == 1 else []
        self.textured_scene = any(o['m']['maps'] for o in self.spheres + self.planes + self.meshes)
        bg = d['render'].get('background')
        self.sky = None
        if isinstance(bg, dict) and 'image' in bg:
            levels = load_image(bg['image'], bg.get('encoding', 'srgb'))
            self.sky = ('image', levels, float(bg.get('rotate', 0)), float(bg.get('intensity', 1)))
        elif isinstance(bg, dict):
            g = bg['gradient']
            Hc = tuple(map(float, g['horizon']))
            self.sky = ('gradient', tuple(map(float, g['zenith'])), Hc, tuple(map(float, g.get('ground', Hc))))
        # texture.md "Eye rays": ((2 · tan_half_fov) / width) / sqrt(samples)
        self.samples = int(d['render'].get('samples', 1))
        self.eye_spread = ((2.0 * self.s) / float(self.W)) / math.sqrt(float(self.samples))

    def render(self):
        """tracer.md: one sample at the centre, or n² stratified samples (frame 0, `sampler`
        stratified), summed in sample order and divided by their count."""
        n = math.isqrt(self.samples)
        assert n * n == self.samples, 'the reference does n² samples only'
        M = (1 << 64) - 1
        def mix(z):
            z = (z + 0x9e3779b97f4a7c15) & M
            z = ((z ^ (z >> 30)) * 0xbf58476d1ce4e5b9) & M
            z = ((z ^ (z >> 27)) * 0x94d049bb133111eb) & M
            return z ^ (z >> 31)
        unit = lambda b: float(b >> 11) * 2.0 ** -53
        W, H = self.W, self.H
        img = np.zeros((H, W, 3))
        for i in range(H):
            for j in range(W):
                seed = mix(mix(0x9e3779b97f4a7c15 ^ 0) ^ (i * W + j))
                acc = (0.0, 0.0, 0.0)
                for k in range(self.samples):
                    if self.samples == 1:
                        u = v = 0.5
                    else:
                        h = mix(seed ^ k)
                        u = ((k % n) + unit(h)) / n; v = ((k // n) + unit(mix(h))) / n
                    x = -1.0 + (2.0 * (j + u)) / W
                    y = ((1.0 - (2.0 * (i + v)) / H) * H) / W
                    dd = normalize(add(add(self.fwd, mr.smul(x * self.s, self.right)), mr.smul(y * self.s, self.up_c)))
                    self.pix = self.pixel_rays(i, j)
                    acc = add(acc, self.trace_tree(self.pos, dd) if self.trees else self.trace(self.pos, dd))
                img[i, j] = acc if self.samples == 1 else sdiv(acc, float(self.samples))
        return img

    def pixel_rays(self, i, j):
        """texture.md "The pixel": the pixel centre's direction and its steps right and down."""
        if not any(mp[0] == 'checker' for o in self.spheres + self.planes + self.meshes
                   for mp in o['m']['maps'].values()):
            return None
        W, H = float(self.W), float(self.H)
        x = -1.0 + (2.0 * (j + 0.5)) / W
        y = ((1.0 - (2.0 * (i + 0.5)) / H) * H) / W
        c = add(add(self.fwd, mr.smul(x * self.s, self.right)), mr.smul(y * self.s, self.up_c))
        step = (2.0 / W) * self.s
        return c, vmul(self.right, step), vmul(self.up_c, -step)

    @staticmethod
    def material(m):
        m2 = dict(m); maps = {}
        for key in ('diffuse', 'ambient'):
            v = m.get(key)
            if isinstance(v, dict):
                if 'checker' in v:
                    ck = v['checker']
                    maps[key] = ('checker', float(ck.get('size', 1)), [tuple(map(float, c)) for c in ck['colors']])
                else:
                    sc = tuple(map(float, v.get('scale', (1, 1))))
                    maps[key] = ('image', load_image(v['image'], v.get('encoding', 'srgb')), sc)
                m2[key] = [0, 0, 0]
        r = mr.Scene.material(m2)
        r['maps'] = maps
        return r

    # ---- the lookup (texture.md "Where a lookup happens", "The footprint cone")
    def mesh_normal(self, ob, extra, d):
        """N of mesh.md's "Surface at a mesh hit" (turned when back), as mesh_surface computes it."""
        pl = ob['pl']; mf = pl.mf
        k, w0, w1, w2 = extra
        i0, i1, i2 = mf.tris[k]
        S_ = (w0 + w1) + w2
        u = w1 / S_; v = w2 / S_
        b0 = (1.0 - u) - v
        n0, n1, n2 = mf.VN[i0], mf.VN[i1], mf.VN[i2]
        S = pl.normal(add(add(vmul(n0, b0), vmul(n1, u)), vmul(n2, v)))
        Wn = pl.normal(mf.TN[k])
        G = neg(Wn) if dot(Wn, S) < 0 else Wn
        back = dot(G, d) > 0
        N = S if ob['shading'] in ('phong', 'gouraud') else G
        return neg(N) if back else N

    def textured(self, kind, ob, extra, P_hit, N, d, Wd, o=None, pix=None):
        mat = ob['m']
        if not mat['maps']:
            return mat
        if kind == 'mesh':
            pl = ob['pl']; mf = pl.mf
            k, w0, w1, w2 = extra
            tri_ = mf.tris[k]
            S_ = (w0 + w1) + w2
            b1 = w1 / S_; b2 = w2 / S_
            Q = [pl.point(mf.P[i]) for i in tri_]
            H = add(add(vmul(Q[0], (1.0 - b1) - b2), vmul(Q[1], b1)), vmul(Q[2], b2))
            snaps = [(i, Q[0][i]) for i in range(3) if Q[0][i] == Q[1][i] == Q[2][i]]
        else:
            H = P_hit  # f64 frame: O = (0, 0, 0); p + O per component is p
            H = add(H, (0.0, 0.0, 0.0))
            snaps = ob['snap'] if kind == 'plane' else []
        snap = snapper(snaps)
        P = snap(H)
        # footprint ellipse
        r = 0.5 * Wd
        m = cross(d, N)
        if m == (0.0, 0.0, 0.0):
            m = cross(N, (1.0, 0.0, 0.0))
            if m == (0.0, 0.0, 0.0):
                m = cross(N, (0.0, 1.0, 0.0))
        a = normalize(m)
        e = cross(a, d)
        minor = vmul(a, r)
        major = vmul(sub(e, vmul(d, fdiv(dot(e, N), dot(d, N)))), r)
        q = fdiv(length(major), length(minor))
        taps = (16 if q > 15 else int(math.ceil(q))) if q > 0 else 1
        def ellipses(taps):
            bax = sdiv(major, float(taps))
            def E(x):
                p1 = dot(minor, x); p2 = dot(bax, x)
                v = math.sqrt(p1 * p1 + p2 * p2) if (p1 * p1 + p2 * p2) >= 0 else math.nan
                return v if math.isfinite(v) else INF
            centres = [snap(add(P, vmul(major, fdiv(float(2 * kk + 1) - float(taps), float(taps))))) for kk in range(taps)]
            return bax, E, centres
        out = dict(mat)
        for key, mkey in (('diffuse', 'kd'), ('ambient', 'ka')):
            mp = mat['maps'].get(key)
            if mp is None:
                continue
            if mp[0] == 'checker' and pix is not None:  # texture.md "The pixel"
                pt = pixel_patch(o, P_hit, N, pix)
                if pt is not None:
                    D, a_, b_ = pt
                    held_axes = [i for i, _ in snaps]
                    keep = lambda v: tuple(0.0 if i in held_axes else v[i] for i in range(3))
                    val = pixel_checker(snap(add(P, D)), keep(a_), keep(b_), mp[1], mp[2])
                    if val is not None:
                        out[mkey] = val
                        continue
            if mp[0] == 'checker':
                cell = one_cell(P, major, minor, mp[1])
                if cell is not None:  # texture.md "One cell": the footprint's box in one cell
                    out[mkey] = mp[2][0] if cell > 0 else mp[2][1]
                    continue
            # texture.md "Checker": a footprint whose r is at least half a cell takes one tap
            n = 1 if mp[0] == 'checker' and r >= 0.5 * mp[1] else taps
            bax, E, centres = ellipses(n)
            acc = (0.0, 0.0, 0.0)
            for Pk in centres:
                if mp[0] == 'checker':
                    z, (c0, c1) = mp[1], mp[2]
                    A = 1.0
                    for i, ax in enumerate(((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))):
                        A = A * box_avg(fdiv(Pk[i], z), fdiv(E(ax), z))
                    val = tuple(c0[c] * (0.5 + 0.5 * A) + c1[c] * (0.5 - 0.5 * A) for c in range(3))
                else:
                    levels, sc = mp[1], mp[2]
                    val = image_lookup(levels, sc, *self.uvF(kind, ob, extra, P, Pk, E, minor, bax, levels, sc))
                acc = add(acc, val)
            out[mkey] = sdiv(acc, float(n))
        return out

    def uvF(self, kind, ob, extra, P, Pk, E, minor, bax, levels, sc):
        Hh, Ww = levels[0].shape[:2]
        Wf, Hf = float(Ww), float(Hh)
        sx, sy = abs(sc[0]), abs(sc[1])
        if kind == 'plane':
            U, V = ob['U'], ob['V']
            u = dot(Pk, U); v = dot(Pk, V)
            F = fmax(((2.0 * E(U)) * sx) * Wf, ((2.0 * E(V)) * sy) * Hf)
            return u, v, F
        if kind == 'sphere':
            C, R = ob['c'], ob['R']
            qv = normalize(sub(Pk, C))
            u = 0.5 - libm('atan2', qv[2], qv[0]) / (2.0 * math.pi)
            v = 1.0 - libm('acos', min(max(qv[1], -1.0), 1.0)) / math.pi
            rho = math.sqrt(qv[0] * qv[0] + qv[2] * qv[2])
            if rho > 0:
                Tu = (fdiv(-qv[2], rho), 0.0, fdiv(qv[0], rho))
                Fu = fdiv(((2.0 * E(Tu)) * sx) * Wf, ((2.0 * math.pi) * R) * rho)
            else:
                Fu = INF
            Tv = normalize_or_zero(cross(qv, (-qv[2], 0.0, qv[0])))
            Fv = fdiv(((2.0 * E(Tv)) * sy) * Hf, math.pi * R)
            return u, v, fmax(Fu, Fv)
        # mesh
        pl = ob['pl']; mf = pl.mf
        k, w0, w1, w2 = extra
        tri_ = mf.tris[k]
        S_ = (w0 + w1) + w2
        b1 = w1 / S_; b2 = w2 / S_
        Q = [pl.point(mf.P[i]) for i in tri_]
        t0, t1, t2 = (mf.UV[i] for i in tri_)
        e1 = sub(Q[1], Q[0]); e2 = sub(Q[2], Q[0])
        o = sub(Pk, P)
        g11 = dot(e1, e1); g12 = dot(e1, e2); g22 = dot(e2, e2)
        r1 = dot(o, e1); r2 = dot(o, e2)
        det = g11 * g22 - g12 * g12
        al = fdiv(g22 * r1 - g12 * r2, det); be = fdiv(g11 * r2 - g12 * r1, det)
        b0 = (1.0 - b1) - b2
        uv = [((t0[c] * b0 + t1[c] * b1) + t2[c] * b2) + (t1[c] - t0[c]) * al for c in range(2)]
        uv = [uv[c] + (t2[c] - t0[c]) * be for c in range(2)]
        A_world = length(cross(e1, e2))
        d1 = (t1[0] - t0[0], t1[1] - t0[1]); d2 = (t2[0] - t0[0], t2[1] - t0[1])
        A_uv = abs(d1[0] * d2[1] - d1[1] * d2[0])
        density = math.sqrt(fdiv((((Wf * Hf) * sx) * sy) * A_uv, A_world))
        F = density * (2.0 * fmax(length(minor), length(bax)))
        return uv[0], uv[1], F

    def seen(self, d, cs):
        """A miss: the background colour, or the sky along d with the ray's cone spread."""
        return self.bg if self.sky is None else sky_seen(self.sky, d, cs)

    # ---- a path with its cone (tracer.md "Path" + texture.md)
    def trace(self, o, d):
        colour = (0.0, 0.0, 0.0); w = 1.0; leaving = None
        cw, cs = 0.0, self.eye_spread
        self.view_o = o
        for depth in range(self.max_depth):
            h = self.nearest(o, d, leaving)
            if h is None:
                colour = add(colour, mr.smul(w, self.seen(d, cs)))
                break
            t, kind, ob, extra = h
            P = add(o, mr.smul(t, d))
            Wd = abs(cw + cs * t)
            if kind in ('sphere', 'plane'):
                N0 = normalize(sub(P, ob['c'])) if kind == 'sphere' else ob['n']
                entering = not (dot(N0, d) > 0)
                N = neg(N0) if dot(N0, d) > 0 else N0
                mat = self.textured(kind, ob, None, P, N, d, Wd, o, self.pix if depth == 0 else None)
                local = self.light_sum(P, N, d, mat, lambda r: P, ob)
                next_origin = lambda r: P
                next_leaving = ob
            else:
                mat = self.textured(kind, ob, extra, P, self.mesh_normal(ob, extra, d), d, Wd, o,
                                    self.pix if depth == 0 else None)
                local, N, G, delta = self.mesh_surface(dict(ob, m=mat), extra, P, t, d, o)
                entering = True
                next_origin = self.lifted(P, G, delta)
                next_leaving = None
            colour = add(colour, mr.smul(w, local))
            w = w * mat['refl']
            if w < 1e-30 or depth == self.max_depth - 1:
                break
            r = normalize(sub(d, mr.smul(2.0 * dot(d, N), N)))
            o = next_origin(r); d = r; leaving = next_leaving
            c = fdiv(1.0, ob['R']) if kind == 'sphere' else 0.0
            cs = cs + (2.0 * Wd) * c if entering else cs - (2.0 * Wd) * c
            cw = Wd
            self.view_o = P if mr.UNLIFTED_O else o
        return colour

    # ---- glass trees with their cones
    def trace_tree(self, o, d):
        B = max(1024, self.max_depth)
        colour = (0.0, 0.0, 0.0); spent = 0
        level = [(o, d, None, (1.0, 1.0, 1.0), o, 0.0, self.eye_spread)]
        for lv in range(self.max_depth):
            nxt = []
            for (o, d, leaving, w, unlifted, cw, cs) in level:
                self.view_o = unlifted if mr.UNLIFTED_O else o
                if spent >= B:
                    continue
                spent += 1
                h = self.nearest(o, d, leaving)
                if h is None:
                    colour = add(colour, had(self.seen(d, cs), w)); continue
                t, kind, ob, extra = h
                P = add(o, mr.smul(t, d))
                Wd = abs(cw + cs * t)
                if kind in ('sphere', 'plane'):
                    N0 = normalize(sub(P, ob['c'])) if kind == 'sphere' else ob['n']
                    entering = not (dot(N0, d) > 0)
                    N = neg(N0) if dot(N0, d) > 0 else N0
                    mat = self.textured(kind, ob, None, P, N, d, Wd, o, self.pix if lv == 0 else None)
                    local = self.light_sum(P, N, d, mat, lambda r: P, ob)
                    origin = (lambda P: (lambda r: P))(P); lv_obj = ob
                else:
                    mat = self.textured(kind, ob, extra, P, self.mesh_normal(ob, extra, d), d, Wd, o,
                                        self.pix if lv == 0 else None)
                    local, N, G, delta, back = self.mesh_surface(dict(ob, m=mat), extra, P, t, d, o, want_back=True)
                    entering = not back
                    origin = self.lifted(P, G, delta); lv_obj = None
                colour = add(colour, had(local, w))
                if lv == self.max_depth - 1:
                    continue
                cos_i = -dot(N, d)
                ior = mat['ior']
                eta = 1.0 / ior if entering else ior
                k = 1.0 - (eta * eta) * (1.0 - cos_i * cos_i)
                tir = k < 0
                root = 0.0 if tir else math.sqrt(k)
                if eta == 1.0:
                    T = d
                else:
                    T = normalize(add(vmul(d, eta), vmul(N, eta * cos_i - root)))
                if mat['fresnel']:
                    n1, n2 = (1.0, ior) if entering else (ior, 1.0)
                    q = (n1 - n2) / (n1 + n2); R0 = q * q
                    c = cos_i if entering else root
                    x = 1.0 - c
                    F = 1.0 if tir else R0 + (1.0 - R0) * (x * ((x * x) * (x * x)))
                    R = (F, F, F); Tw = vmul(mat['trans'], 1.0 - F)
                else:
                    r_ = mat['refl']; R = (r_, r_, r_); Tw = mat['trans']
                if tir:
                    R = add(R, Tw); Tw = (0.0, 0.0, 0.0)
                cc = fdiv(1.0, ob['R']) if kind == 'sphere' else 0.0
                cs_r = cs + (2.0 * Wd) * cc if entering else cs - (2.0 * Wd) * cc
                wr = had(w, R)
                if max(max(wr[0], wr[1]), wr[2]) >= 1e-30:
                    r = normalize(sub(d, mr.smul(2.0 * dot(d, N), N)))
                    nxt.append((origin(r), r, lv_obj, wr, P, Wd, cs_r))
                wt = had(w, Tw)
                if max(max(wt[0], wt[1]), wt[2]) >= 1e-30:
                    nxt.append((origin(T), T, lv_obj, wt, P, Wd, cs))
            level = nxt
            if not level:
                break
        return colour


# ---------------------------------------------------------------- textures and scenes
def make_textures():
    os.makedirs(TEXDIR, exist_ok=True)
    rng = np.random.RandomState(20261126)
    p = os.path.join(TEXDIR, 'rgb8.png')  # 8 × 4, distinct colours, 8-bit RGB (Pillow's filters)
    if not os.path.exists(p):
        Image.fromarray(rng.randint(0, 256, (4, 8, 3)).astype(np.uint8)).save(p)
    p = os.path.join(TEXDIR, 'grey16.png')  # 7 × 5 (odd: the pyramid wraps), 16-bit grey
    if not os.path.exists(p):
        write_png(p, rng.randint(0, 65536, (5, 7, 1)), 16, 0)
    p = os.path.join(TEXDIR, 'rgb16.png')  # 5 × 3, 16-bit RGB
    if not os.path.exists(p):
        write_png(p, rng.randint(0, 65536, (3, 5, 3)), 16, 2)
    p = os.path.join(TEXDIR, 'pal.png')  # 6 × 6 palette
    if not os.path.exists(p):
        im = Image.fromarray(rng.randint(0, 5, (6, 6)).astype(np.uint8), mode='P')
        im.putpalette([250, 20, 20, 20, 200, 40, 30, 40, 230, 240, 230, 30, 10, 10, 10] + [0] * 3 * 251)
        im.save(p)
    p = os.path.join(TEXDIR, 'rgba8.png')  # 37 × 23 8-bit RGBA (alpha ignored): six odd-sized mip levels
    if not os.path.exists(p):
        Image.fromarray(rng.randint(0, 256, (23, 37, 4)).astype(np.uint8), mode='RGBA').save(p)
    p = os.path.join(TEXDIR, 'sky.png')  # 24 × 11 8-bit RGB (odd rows): an equirectangular sky
    if not os.path.exists(p):
        Image.fromarray(rng.randint(0, 256, (11, 24, 3)).astype(np.uint8)).save(p)
    p = os.path.join(TEXDIR, 'quad_vn.obj')  # vertex normals leaning to +x: a phong S that can face away from the ray
    if not os.path.exists(p):
        open(p, 'w').write('# a quad in y = 0 with texture coordinates and normals leaning to +x\n'
                           'v -1 0 1\nv 1 0 1\nv 1 0 -1\nv -1 0 -1\n'
                           'vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 1 0.25 0\nvn 1 0.3 0.1\n'
                           'f 1/1/1 2/2/2 3/3/1 4/4/2\n')
    try:
        import OpenEXR
    except ImportError:
        OpenEXR = None
    p = os.path.join(TEXDIR, 'half.exr')  # 9 × 6 half RGB: values above 1, zeros, subnormal halves
    if OpenEXR and not os.path.exists(p):
        v = rng.gamma(1.0, 0.6, (6, 9, 3)).astype(np.float16)
        v[0, 0] = 0; v[1, 2, 1] = np.float16(3e-7); v[2, 3] = np.float16(6.0)
        OpenEXR.File({'compression': OpenEXR.ZIP_COMPRESSION, 'type': OpenEXR.scanlineimage}, {'RGB': v}).write(p)
    p = os.path.join(TEXDIR, 'float.exr')  # 5 × 4 float RGBA (alpha ignored)
    if OpenEXR and not os.path.exists(p):
        v = rng.uniform(0, 1.5, (4, 5, 4)).astype(np.float32)
        OpenEXR.File({'compression': OpenEXR.NO_COMPRESSION, 'type': OpenEXR.scanlineimage}, {'RGBA': v}).write(p)
    p = os.path.join(TEXDIR, 'quad_uv.obj')
    if not os.path.exists(p):
        open(p, 'w').write('# a quad in y = 0 with texture coordinates (two repeats along u), CCW from +y\n'
                           'v -1 0 1\nv 1 0 1\nv 1 0 -1\nv -1 0 -1\n'
                           'vt 0 0\nvt 2 0\nvt 2 1\nvt 0 1\n'
                           'f 1/1 2/2 3/3 4/4\n')

LIGHTS = [{'point': {'position': [3, 6, 4], 'ambient': [0.25, 0.25, 0.25], 'diffuse': [0.9, 0.9, 0.9], 'specular': [1, 1, 1]}},
          {'directional': {'direction': [-1, -2, -0.5], 'diffuse': [0.3, 0.3, 0.3], 'specular': [0.3, 0.3, 0.3]}},
          {'ambient': {'color': [0.1, 0.1, 0.12]}}]
CHK = {'checker': {'size': 1, 'colors': [[0.9, 0.85, 0.8], [0.1, 0.15, 0.3]]}}
MATERIALS = {
    'tiles': {'diffuse': CHK, 'ambient': [0.1, 0.1, 0.1], 'specular': [0.3, 0.3, 0.3], 'shininess': 40},
    'tiles_amb': {'diffuse': {'checker': {'size': 0.7, 'colors': [[0.2, 0.8, 0.3], [0.9, 0.2, 0.1]]}},
                  'ambient': {'checker': {'size': 0.35, 'colors': [[0.3, 0.3, 0.3], [0.0, 0.0, 0.1]]}},
                  'specular': [0.5, 0.5, 0.5], 'shininess': 100},
    'rgb8': {'diffuse': {'image': 'rgb8.png'}, 'ambient': {'image': 'rgb8.png'}, 'specular': [0.4, 0.4, 0.4], 'shininess': 60},
    'rgb8s': {'diffuse': {'image': 'rgb8.png', 'scale': [0.5, -1.5]}, 'ambient': [0.05, 0.05, 0.05], 'specular': [0.2, 0.2, 0.2], 'shininess': 20},
    'grey16': {'diffuse': {'image': 'grey16.png', 'encoding': 'linear', 'scale': [2, 1]}, 'ambient': {'image': 'grey16.png', 'encoding': 'linear'},
               'specular': [0.3, 0.3, 0.3], 'shininess': 30},
    'rgb16': {'diffuse': {'image': 'rgb16.png', 'scale': [1.5, 1]}, 'ambient': [0.05, 0.05, 0.05], 'specular': [0.2, 0.2, 0.2], 'shininess': 20},
    'pal': {'diffuse': {'image': 'pal.png', 'scale': [1, 2]}, 'ambient': {'checker': {'size': 0.25, 'colors': [[0.2, 0.2, 0.2], [0, 0, 0]]}},
            'specular': [0.3, 0.3, 0.3], 'shininess': 50},
    'rgba8': {'diffuse': {'image': 'rgba8.png', 'scale': [3, 2]}, 'ambient': {'image': 'rgba8.png', 'scale': [3, 2]},
              'specular': [0.4, 0.4, 0.4], 'shininess': 80},
    'rgba8_fine': {'diffuse': {'image': 'rgba8.png', 'scale': [12, -7]}, 'ambient': [0.1, 0.1, 0.1], 'specular': [0.2, 0.2, 0.2], 'shininess': 20},
    'mirror': {'ambient': [0.02, 0.02, 0.02], 'diffuse': [0.1, 0.1, 0.1], 'specular': [1, 1, 1], 'shininess': 400, 'reflection': 0.8},
    'glass': {'ambient': [0, 0, 0], 'diffuse': [0.03, 0.03, 0.03], 'specular': [1, 1, 1], 'shininess': 300, 'reflection': 0.1,
              'transmission': 0.85, 'ior': 1.5},
    'clay': {'ambient': [0.1, 0.08, 0.06], 'diffuse': [0.8, 0.6, 0.5], 'specular': [0.5, 0.5, 0.5], 'shininess': 40},
}

def scene(objects, camera, w=64, h=36, max_depth=3, lights=LIGHTS, samples=1):
    return {'render': {'width': w, 'height': h, 'samples': samples, 'encoding': 'linear', 'max_depth': max_depth,
                       'background': [0.4, 0.55, 0.8]},
            'camera': camera, 'materials': MATERIALS, 'objects': objects, 'lights': lights}

FLOOR = {'plane': {'point': [0, 0, 0], 'normal': [0, 1, 0], 'material': 'tiles'}}
SCENES = {
    # a checker floor to the horizon, camera low: footprints from a fraction of a cell to many
    'checker_floor': scene([FLOOR], {'position': [0.3, 0.25, 4], 'look_at': [0, 0.1, -10], 'fov': 70}),
    # checkers on spheres (a boundary crossing a curved surface), a tilted plane, an off-boundary
    # wall (snap to z = -6), and a second checker in the ambient
    'checker_shapes': scene([
        {'plane': {'point': [0, -1, 0], 'normal': [0, 1, 0], 'material': 'tiles_amb'}},
        {'plane': {'point': [0, 0, -6], 'normal': [0, 0, 1], 'material': 'tiles'}},
        {'plane': {'point': [4, 0, 0], 'normal': [-1, 0.3, 0.2], 'material': 'tiles_amb'}},
        {'sphere': {'center': [-1.2, 0, -2], 'radius': 1, 'material': 'tiles'}},
        {'sphere': {'center': [1.3, -0.4, -1.2], 'radius': 0.6, 'material': 'tiles_amb'}},
    ], {'position': [0, 1, 4], 'look_at': [0, -0.3, -2], 'fov': 65}),
    # image-mapped planes: floor with a scale (one negative), a wall with default axes, a tilted
    # wall with u_axis, 16-bit RGB
    'image_planes': scene([
        {'plane': {'point': [0, -1, 0], 'normal': [0, 1, 0], 'material': 'rgb8s'}},
        {'plane': {'point': [0, 0, -7], 'normal': [0, 0, 1], 'material': 'rgb16'}},
        {'plane': {'point': [-3, 0, 0], 'normal': [1, 0, 0.3], 'u_axis': [0.2, 1, 0.5], 'material': 'rgb8'}},
        {'plane': {'point': [3.5, 0, 0], 'normal': [-1, 0, 0], 'material': 'grey16'}},
    ], {'position': [0.2, 0.6, 4], 'look_at': [0, -0.2, -3], 'fov': 75}),
    # image-mapped spheres: 8-bit sRGB (diffuse and ambient), 16-bit grey linear, a palette image
    'image_spheres': scene([
        {'plane': {'point': [0, -1.2, 0], 'normal': [0, 1, 0], 'material': 'clay'}},
        {'sphere': {'center': [-1.3, 0, -1], 'radius': 1, 'material': 'rgb8'}},
        {'sphere': {'center': [1.2, -0.2, -1.5], 'radius': 0.9, 'material': 'grey16'}},
        {'sphere': {'center': [0.1, 1.1, -3.5], 'radius': 1.2, 'material': 'pal'}},
        {'sphere': {'center': [2.6, 1.2, -4], 'radius': 0.9, 'material': 'rgba8_fine'}},
        {'sphere': {'center': [-2.8, 1.3, -5], 'radius': 1.0, 'material': 'rgba8'}},
    ], {'position': [0, 0.8, 3.5], 'look_at': [0, 0, -1.5], 'fov': 60}),
    # OBJ quads with vt: an image (phong, flat, gouraud) and a checker on a mesh
    'mesh_quads': scene([
        {'plane': {'point': [0, -1, 0], 'normal': [0, 1, 0], 'material': 'tiles'}},
        {'mesh': {'file': 'quad_uv.obj', 'material': 'rgb8', 'shading': 'flat', 'translate': [-1.3, -0.5, -1], 'rotate': [60, 20, 0]}},
        {'mesh': {'file': 'quad_uv.obj', 'material': 'grey16', 'shading': 'phong', 'translate': [1.3, -0.9, -1.5], 'scale': [1.2, 1, 0.8], 'rotate': [0, -30, 0]}},
        {'mesh': {'file': 'quad_uv.obj', 'material': 'pal', 'shading': 'gouraud', 'translate': [0, 0.6, -3], 'rotate': [80, 0, 10]}},
        {'mesh': {'file': 'quad_uv.obj', 'material': 'tiles_amb', 'shading': 'flat', 'translate': [2.3, 0.8, -2.5], 'scale': 0.7, 'rotate': [90, -40, 0]}},
        {'mesh': {'file': 'quad_uv.obj', 'material': 'rgba8_fine', 'shading': 'constant', 'translate': [-2.6, 0.9, -3.5], 'scale': [0.8, 1, 1.3], 'rotate': [75, 35, 0]}},
        {'mesh': {'file': 'quad_vn.obj', 'material': 'rgba8', 'shading': 'phong', 'translate': [-0.2, -0.7, 0.6], 'scale': 0.8, 'rotate': [0, 0, -25]}},
    ], {'position': [0, 1.2, 3.5], 'look_at': [0, -0.3, -1.5], 'fov': 70}),
    # a mirror sphere reflecting a checker floor: the cone's curvature term s + 2·W/R; a mirror
    # mesh quad and a mirror plane (c = 0: the spread goes on, the width restarts at W)
    'mirror_checker': scene([
        FLOOR,
        {'sphere': {'center': [0, 1, -1], 'radius': 1, 'material': 'mirror'}},
        {'sphere': {'center': [2, 0.5, -2], 'radius': 0.5, 'material': 'rgb8'}},
        {'mesh': {'file': 'quad_uv.obj', 'material': 'mirror', 'shading': 'flat', 'translate': [-2.2, 0.9, -1.5], 'scale': 0.9, 'rotate': [90, 35, 0]}},
        {'plane': {'point': [0, 0, -6], 'normal': [0.2, 0, 1], 'material': 'mirror'}},
    ], {'position': [0, 1.4, 3], 'look_at': [0, 0.8, -1], 'fov': 55}, max_depth=4),
    # a glass sphere before a checker wall and floor: trees, transmission keeps the spread
    'glass_checker': scene([
        FLOOR,
        {'plane': {'point': [0, 0, -3], 'normal': [0, 0, 1], 'material': 'tiles_amb'}},
        {'sphere': {'center': [0, 0.8, 0], 'radius': 0.8, 'material': 'glass'}},
        {'sphere': {'center': [-1.6, 0.5, -1], 'radius': 0.5, 'material': 'mirror'}},
    ], {'position': [0, 1.2, 3.2], 'look_at': [0, 0.7, 0], 'fov': 55}, max_depth=4),
}

# straight down onto a sphere's north pole: the centre pixel (odd size) hits q = (0, 1, 0) exactly,
# so ρ = 0 (Fu = +∞, the last level), and d × n = 0 (the footprint's fallback axis)
SCENES['pole'] = scene([
    {'plane': {'point': [0, -1, 0], 'normal': [0, 1, 0], 'material': 'tiles'}},
    {'sphere': {'center': [0, 0, 0], 'radius': 1, 'material': 'rgba8'}},
    {'sphere': {'center': [2, 0, 0], 'radius': 0.8, 'material': 'tiles_amb'}},
], {'position': [0, 4, 0], 'look_at': [0, 0, 0], 'up': [0, 0, -1], 'fov': 60}, w=33, h=19)

# EXR textures (needs the OpenEXR module; skipped without it)
EXR_MATERIALS = dict(MATERIALS,
                     half={'diffuse': {'image': 'half.exr', 'scale': [2, 3]}, 'ambient': {'image': 'half.exr'}, 'specular': [0.3, 0.3, 0.3], 'shininess': 40},
                     float32={'diffuse': {'image': 'float.exr'}, 'ambient': [0.05, 0.05, 0.05], 'specular': [0.5, 0.5, 0.5], 'shininess': 90})
SCENES['exr'] = dict(scene([
    {'plane': {'point': [0, -1, 0], 'normal': [0, 1, 0], 'material': 'half'}},
    {'sphere': {'center': [0, 0, -2], 'radius': 1, 'material': 'float32'}},
    {'mesh': {'file': 'quad_uv.obj', 'material': 'half', 'shading': 'flat', 'translate': [2, 0, -3], 'rotate': [90, -30, 0]}},
], {'position': [0, 0.8, 3], 'look_at': [0, -0.3, -2], 'fov': 70}), materials=EXR_MATERIALS)

# skies (texture.md "The sky"): an image sky turned and brightened, seen directly, in a mirror
# sphere (the cone's spread grows: coarser levels), a mirror plane and through glass; a gradient
def sky_scene(background, **kw):
    d = scene([
        {'plane': {'point': [0, -1, 0], 'normal': [0, 1, 0], 'material': 'clay'}},
        {'sphere': {'center': [-1, 0, -1.5], 'radius': 0.9, 'material': 'mirror'}},
        {'sphere': {'center': [1.1, -0.2, -1], 'radius': 0.7, 'material': 'glass'}},
        {'plane': {'point': [0, 0, -9], 'normal': [0.3, 0.1, 1], 'material': 'mirror'}},
    ], {'position': [0, 0.3, 3], 'look_at': [0, 0.6, -2], 'fov': 80}, max_depth=4, **kw)
    d['render']['background'] = background
    return d
SCENES['sky_image'] = sky_scene({'image': 'sky.png', 'rotate': 30, 'intensity': 1.5})
SCENES['sky_image_s4'] = sky_scene({'image': 'sky.png', 'rotate': -75.5}, w=40, h=24, samples=4)
SCENES['sky_gradient'] = sky_scene({'gradient': {'zenith': [0.1, 0.2, 0.7], 'horizon': [0.9, 0.85, 0.8], 'ground': [0.2, 0.3, 0.1]}})

# more samples: the eye cone narrows by sqrt(samples) (4: stratified 2 × 2, 9: 3 × 3)
SCENES['checker_floor_s4'] = scene(SCENES['checker_floor']['objects'], SCENES['checker_floor']['camera'], w=48, h=27, samples=4)
SCENES['image_spheres_s9'] = scene(SCENES['image_spheres']['objects'], SCENES['image_spheres']['camera'], w=32, h=18, samples=9)


def main():
    make_textures()
    names = sys.argv[1:] or list(SCENES)
    rr_bin = os.environ.get('RAYREEL')
    total = [0, 0]
    for name in names:
        d = SCENES[name]
        if name == 'exr':
            try:
                import OpenEXR  # noqa: F401
            except ImportError:
                print('exr: skipped (no OpenEXR module)')
                continue
        ypath = os.path.join(TEXDIR, name + '.yaml')
        open(ypath, 'w').write(mr.to_yaml(d))
        sc = TexScene(d)
        img = sc.render()
        out = mr.encode_linear(img)
        Image.fromarray(out).save(os.path.join(TEXDIR, 'ref_' + name + '.png'))
        if not rr_bin:
            print(f'{name}: rendered (no RAYREEL to compare with)')
            continue
        try:
            import OpenEXR
            epath = os.path.join('/tmp', 'rayreel_tex_' + name + '.exr')
            subprocess.run([rr_bin, 'render', ypath, '-o', epath, '--exr-precision', 'float', '--force', '--quiet'], check=True)
            ex = OpenEXR.File(epath).channels()['RGB'].pixels
            mine = img.astype(np.float32)
            bad = np.argwhere((ex != mine).any(axis=2))
            print(f'{name}: f32 values: {int((ex == mine).sum())}/{ex.size} channels equal bit for bit')
            for (a, b) in bad[:10]:
                print('   f32', a, b, 'rayreel', ex[a, b], 'ref', mine[a, b])
        except ImportError:
            pass
        rpath = os.path.join(TEXDIR, 'rayreel_' + name + '.png')
        subprocess.run([rr_bin, 'render', ypath, '-o', rpath, '--force', '--quiet'], check=True)
        rr = np.asarray(Image.open(rpath).convert('RGB')).astype(int)
        diff = np.abs(rr - out.astype(int))
        nch = diff.size; neq = int((diff == 0).sum())
        total[0] += neq; total[1] += nch
        px = np.argwhere(diff.max(axis=2) > 0)
        print(f'{name}: {neq}/{nch} channel bytes equal, {len(px)} of {sc.W * sc.H} pixels differ, max abs {diff.max()}')
        for (a, b) in px[:20]:
            print('  ', a, b, 'rayreel', rr[a, b], 'ref', out[a, b], 'ref·255', np.round(255 * img[a, b], 4))
    if rr_bin:
        print(f'total: {total[0]}/{total[1]} channel bytes equal')
    check_libm()

if __name__ == '__main__':
    main()
