# The f32-precision variant of film_reference.py (same scene with `render.precision: f32`),
# written from docs/spec/f32.md over docs/spec/tracer.md alone: every f64 value rounded to f32
# where the rules use it and the operations done in f32 in the same order. Unlike the f64
# frame, its values show the Thin lens rule's Taylor sine and cosine and its order of
# operations (libm's sin and cos would change 34 pixels of the 16-sample frame).
# film_40x24_precision_f32.f32 is its default (rounds) output, equal bit for bit to rayreel's;
# tests/film_camera.rs checks both frames.
# Usage: python3 film_f32_reference.py OUT.f32 [--samples N]   (imports film_reference.py)
import math, struct, sys
from fractions import Fraction
import film_reference as fr

def R(x): return struct.unpack('<f', struct.pack('<f', x))[0]
def fa(a, b): return R(a + b)
def fs(a, b): return R(a - b)
def fm(a, b): return R(a * b)
def fd(a, b): return R(a / b)
def fsq(a): return R(math.sqrt(a))
def dot(a, b): return fa(fa(fm(a[0], b[0]), fm(a[1], b[1])), fm(a[2], b[2]))
def length(v): return fsq(dot(v, v))
def normalize(v):
    r = fd(1.0, length(v)); return (fm(v[0], r), fm(v[1], r), fm(v[2], r))
def add(a, b): return tuple(fa(a[c], b[c]) for c in range(3))
def sub(a, b): return tuple(fs(a[c], b[c]) for c in range(3))
def had(a, b): return tuple(fm(a[c], b[c]) for c in range(3))
def Rv(v): return tuple(R(x) for x in v)

O = fr.CAM_POS  # camera-relative origin (f64)
W, H = fr.W, fr.H
OBJ = []
for kind, p, x, mat in fr.OBJECTS:
    if kind == 'sphere':
        OBJ.append(('sphere', Rv(fr.sub(p, O)), R(x), mat))   # x = r*r in f64
    else:
        n = x; k = fr.dot(fr.sub(p, O), n)
        OBJ.append(('plane', Rv((n[0]*k, n[1]*k, n[2]*k)), Rv(n), mat))
LIGHTS = [dict(pos=Rv(fr.sub(l['pos'], O)), ia=Rv(l['ia']), id=Rv(l['id']), is_=Rv(l['is_'])) for l in fr.LIGHTS]
MATS = {}
for m in fr.MATERIALS.values():
    MATS[id(m)] = dict(ka=Rv(m['ka']), kd=Rv(m['kd']), ks=Rv(m['ks']), refl=R(m['refl']), e=m['e'], floor=R(m['floor']))
FWD, UPC, RIGHT, S = Rv(fr.FWD), Rv(fr.UPC), Rv(fr.RIGHT), R(fr.S)
POS = (0.0, 0.0, 0.0)
RHO, FOCUS = R(fr.RHO), R(fr.FOCUS)
PC = [R(c) for c in fr.PC]; QC = [R(c) for c in fr.QC]; QP = R(math.pi / 4)
LOOP_VARIANT = {}

def sin_cos(x):
    y = fm(x, x); p = PC[8]
    for i in range(7, -1, -1): p = fa(fm(p, y), PC[i])
    q = QC[8]
    for i in range(7, -1, -1): q = fa(fm(q, y), QC[i])
    return fm(x, p), q

def eye_ray(i, j, u, v, a, b):
    u, v, a, b = R(u), R(v), R(a), R(b)
    x = fa(-1.0, fd(fm(2.0, fa(float(j), u)), float(W)))
    y = fd(fm(fs(1.0, fd(fm(2.0, fa(float(i), v)), float(H))), float(H)), float(W))
    xs, ys = fm(x, S), fm(y, S)
    w = tuple(fa(fa(FWD[c], fm(xs, RIGHT[c])), fm(ys, UPC[c])) for c in range(3))
    a2 = fs(fm(2.0, a), 1.0); b2 = fs(fm(2.0, b), 1.0)
    if a2 == 0.0 and b2 == 0.0: dx, dy = 0.0, 0.0
    elif max(a2, 0.0 - a2) > max(b2, 0.0 - b2):
        sn, cs = sin_cos(fm(QP, fd(b2, a2))); dx, dy = fm(a2, cs), fm(a2, sn)
    else:
        sn, cs = sin_cos(fm(QP, fd(a2, b2))); dx, dy = fm(b2, sn), fm(b2, cs)
    rdx, rdy = fm(RHO, dx), fm(RHO, dy)
    origin = tuple(fa(fa(POS[c], fm(RIGHT[c], rdx)), fm(UPC[c], rdy)) for c in range(3))
    target = tuple(fa(POS[c], fm(w[c], FOCUS)) for c in range(3))
    return origin, normalize(sub(target, origin))

def hit_sphere(o, d, c, r2, leaving_this):
    f = sub(o, c); b = dot(f, d)
    p = tuple(fs(f[k], fm(b, d[k])) for k in range(3))
    disc = fs(r2, dot(p, p))
    if not (disc >= 0.0): return None
    cc = fs(dot(f, f), r2)
    if b > 0.0 and (cc >= 0.0 or leaving_this): return None
    q = -fa(b, math.copysign(fsq(disc), b))
    if q == 0.0: return None
    t0, t1 = fd(cc, q), q
    lo, hi = (t0, t1) if t0 <= t1 else (t1, t0)
    if leaving_this: return hi if (b < 0.0 and hi > 0.0) else None
    if lo > 0.0: return lo
    if hi > 0.0: return hi
    return None

def hit_plane(o, d, p, n):
    t = fd(dot(sub(p, o), n), dot(n, d))
    return t if 0.0 < t < math.inf else None

def hit(o, d, obj, leaving_this):
    if obj[0] == 'sphere': return hit_sphere(o, d, obj[1], obj[2], leaving_this)
    if leaving_this: return None
    return hit_plane(o, d, obj[1], obj[2])

def nearest(o, d, leaving):
    bt, bk = None, None
    for k, obj in enumerate(OBJ):
        t = hit(o, d, obj, leaving == k)
        if t is not None and (bt is None or t < bt): bt, bk = t, k
    return bt, bk

def spec_pow(x, e, flo):
    if x <= flo: return 0.0
    n = int(e); result, base = 1.0, x
    while n:
        if n & 1: result = fm(result, base)
        n >>= 1
        if n: base = fm(base, base)
    return result

def shade(P, N, d, k):
    mat = MATS[id(OBJ[k][3])]; local = (0.0, 0.0, 0.0)
    for li in LIGHTS:
        v = sub(li['pos'], P); dist = length(v)
        L = tuple(fd(v[c], dist) for c in range(3))
        local = add(local, had(mat['ka'], li['ia']))
        n_l = dot(N, L)
        if n_l <= 0.0: continue
        dn = normalize(L)
        if any((t := hit(P, dn, obj, kk == k)) is not None and t < dist for kk, obj in enumerate(OBJ)): continue
        Hv = normalize(tuple(fa(L[c], -d[c]) for c in range(3)))
        x = dot(N, Hv); x = 0.0 if x < 0.0 else (1.0 if x > 1.0 else x)
        sp = spec_pow(x, mat['e'], mat['floor'])
        kdid, ksis = had(mat['kd'], li['id']), had(mat['ks'], li['is_'])
        local = add(local, tuple(fa(fm(kdid[c], n_l), fm(ksis[c], sp)) for c in range(3)))
    return local

TINY = R(1e-30)
def trace(o, d):
    colour = (0.0, 0.0, 0.0); w = 1.0; leaving = None
    for depth in range(fr.MAX_DEPTH):
        t, k = nearest(o, d, leaving)
        if t is None: break
        P = tuple(fa(o[c], fm(t, d[c])) for c in range(3))
        obj = OBJ[k]
        N = normalize(sub(P, obj[1])) if obj[0] == 'sphere' else obj[2]
        if dot(N, d) > 0.0: N = (-N[0], -N[1], -N[2])
        local = shade(P, N, d, k)
        colour = add(colour, tuple(fm(w, x) for x in local))
        w = fm(w, MATS[id(obj[3])]['refl'])
        if w < TINY or depth == fr.MAX_DEPTH - 1: break
        dn2 = fm(2.0, dot(d, N))
        d = normalize(tuple(fs(d[c], fm(dn2, N[c])) for c in range(3)))
        o = P; leaving = k
    return colour

def sample_colour(i, j, k, seeds):
    x = fr.sobol_point(k, seeds)
    return trace(*eye_ray(i, j, x[0], x[1], x[2], x[3]))

def estimate(a, b, e32):
    g = []
    for c in range(3):
        if e32:
            ca = fsq(min(max(a[c], 0.0), 1.0)); cb = fsq(min(max(b[c], 0.0), 1.0)); dd = fs(ca, cb)
        else:
            ca = math.sqrt(min(max(a[c], 0.0), 1.0)); cb = math.sqrt(min(max(b[c], 0.0), 1.0)); dd = ca - cb
        g.append(max(dd, 0.0 - dd))
    return R(max(max(g[0], g[1]), g[2]) * 0.5)

def render(n, rounds, e32=True):
    thr = R(fr.THRESHOLD); h = n // 2; mean = [None]*(W*H); est = [None]*(W*H)
    for i in range(H):
        for j in range(W):
            px = i*W+j; seeds = fr.pixel_seeds(px)
            A = B = T = (0.0, 0.0, 0.0)
            for k in range(n):
                c = sample_colour(i, j, k, seeds); T = add(T, c)
                if k < h: A = add(A, c)
                else: B = add(B, c)
            mean[px] = T if n == 1 else tuple(fd(x, float(n)) for x in T)
            if rounds:
                est[px] = estimate(tuple(fd(x, float(h)) for x in A), tuple(fd(x, float(n-h)) for x in B), e32)
    if not rounds: return mean
    have, last, log = n, list(range(W*H)), []
    while have < 64:
        go = [px for px in last if any(0 <= px//W+di < H and 0 <= px%W+dj < W and est[(px//W+di)*W+px%W+dj] > thr
                                       for di in (-1,0,1) for dj in (-1,0,1))]
        if not go: break
        total = min(2*have, 64); log.append((have, total, len(go)))
        for px in go:
            i, j = divmod(px, W); seeds = fr.pixel_seeds(px); B = (0.0,0.0,0.0)
            for k in range(have, total): B = add(B, sample_colour(i, j, k, seeds))
            m = mean[px]
            mean[px] = tuple(fd(fa(fm(m[c], float(have)), B[c]), float(total)) for c in range(3))
            est[px] = estimate(m, tuple(fd(x, float(total-have)) for x in B), e32)
        have, last = total, go
    print('rounds', log, file=sys.stderr)
    return fr.film_filter(mean, est, fr.RHO > 0.0)

if __name__ == '__main__':
    out = sys.argv[1]; a = sys.argv[2:]
    img = render(int(a[1]), False) if a[:1] == ['--samples'] else render(4, True, '--e64' not in a)
    with open(out, 'wb') as fh:
        for px in img: fh.write(struct.pack('<3f', *px))
