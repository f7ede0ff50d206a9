# An independent float64 implementation of mesh pixels, written from docs/spec/tracer.md,
# docs/spec/mesh.md (as of d569cf4: gouraud and constant see the viewer from each station),
# docs/spec/output.md and docs/meshes.md alone (not from rayreel's code). It covers what the
# test scenes use: one sample a pixel (the centre), encoding linear, f64, point / directional /
# spot / ambient lights, spheres, planes, OBJ and PLY meshes (phong, flat, gouraud, constant),
# reflection paths and glass trees (no adaptive sampling, no alpha, no f32 frames).
#
# Usage: python3 mesh_reference.py [SCENE ...]    (needs numpy and Pillow; OpenEXR and mpmath optional)
#   writes mesh/SCENE.yaml and mesh/ref_SCENE.png; with RAYREEL=path/to/rayreel it also renders
#   the YAML with rayreel, compares the 8-bit PNG bytes and (with the OpenEXR module, through a
#   32-bit EXR) every f32 channel bit for bit, listing differing pixels.
#   SIZE=3 renders every scene 3x wider and higher.
#   PLY_F32_ROUNDED=1 rounds ASCII PLY `float` values to f32 before widening them (an earlier
#   reading of the spec); by default they are parsed straight to f64, as docs/spec/mesh.md says.
#   UNLIFTED_O=1 takes the unlifted hit point as "o the hit ray's origin" of gouraud/constant
#   view directions (rayreel uses the lifted origin: scene far_inside at SIZE=3 differs otherwise).
#
# Every operation follows the operation order the docs give; Python floats are IEEE f64
# without fused multiply-add, numpy elementwise ops likewise. math.sin/cos/tan/exp/pow (the C
# library) stand in for Rust's libm; check_libm() compares them with correctly rounded values.
import math, os, subprocess, sys
import numpy as np
from PIL import Image

HERE = os.path.dirname(os.path.abspath(__file__))
MESHDIR = os.path.join(HERE, 'mesh')
INF = math.inf
U64 = 2.0 ** -53
# "o the hit ray's origin" for gouraud and constant: the ray's actual (lifted) origin, or, with
# UNLIFTED_O=1, the unlifted hit point it was lifted from (an alternative reading, for the report)
UNLIFTED_O = os.environ.get('UNLIFTED_O') == '1'


# ---------------------------------------------------------------- vectors (tracer.md)
np.seterr(all='ignore')
def fdiv(a, b):  # IEEE division (Python raises on /0)
    return float(np.float64(a) / np.float64(b))
def add(a, b): return (a[0] + b[0], a[1] + b[1], a[2] + b[2])
def sub(a, b): return (a[0] - b[0], a[1] - b[1], a[2] - b[2])
def smul(s, v): return (s * v[0], s * v[1], s * v[2])
def vmul(v, s): return (v[0] * s, v[1] * s, v[2] * s)
def had(a, b): return (a[0] * b[0], a[1] * b[1], a[2] * b[2])
def vdiv(a, b): return (a[0] / b[0], a[1] / b[1], a[2] / b[2])
def neg(a): return (-a[0], -a[1], -a[2])
def dot(a, b): return (a[0] * b[0] + a[1] * b[1]) + a[2] * b[2]

def spot_scale(li, L):
    """A spot's smoothstep between its outer and inner cones along -L (spec: lights)."""
    x = -dot(L, li['axis'])
    if x >= li['ci']:
        return 1.0
    if x <= li['co']:
        return 0.0
    tt = (x - li['co']) / (li['ci'] - li['co'])
    return (tt * tt) * (3.0 - 2.0 * tt)

def length(v): return math.sqrt(dot(v, v))
def normalize(v):
    r = fdiv(1.0, math.sqrt(dot(v, v)))
    return (v[0] * r, v[1] * r, v[2] * r)
def cross(a, b):  # glam
    return (a[1] * b[2] - b[1] * a[2], a[2] * b[0] - b[2] * a[0], a[0] * b[1] - b[0] * a[1])


# ---------------------------------------------------------------- libm stand-ins
# Python's math uses the C library; the docs name the Rust `libm` crate. For the arguments
# used here both are checked against mpmath's correctly rounded value (check_libm below).
LIBM_CALLS = []
def libm(name, *x):
    y = getattr(math, name)(*x)
    LIBM_CALLS.append((name, x, y))
    return y

def check_libm():
    try:
        import mpmath
    except ImportError:
        return
    mpmath.mp.prec = 200
    bad = []
    for name, x, y in LIBM_CALLS:
        exact = float(getattr(mpmath, 'power' if name == 'pow' else name)(*[mpmath.mpf(a) for a in x]))
        if exact != y:
            bad.append((name, x, y, exact))
    if bad:
        print('libm results not correctly rounded (may differ from Rust libm):', bad[:5])


# ---------------------------------------------------------------- OBJ (mesh.md "Loading")
PLY_TYPES = {'char': 'b', 'int8': 'b', 'uchar': 'B', 'uint8': 'B', 'short': 'h', 'int16': 'h', 'ushort': 'H',
             'uint16': 'H', 'int': 'i', 'int32': 'i', 'uint': 'I', 'uint32': 'I', 'float': 'f', 'float32': 'f',
             'double': 'd', 'float64': 'd'}
# ASCII PLY: is a `float` property's decimal text rounded to f32 first, then widened (as "values of
# any PLY scalar type are widened exactly to f64" suggests), or parsed straight to f64?
PLY_ASCII_AS_F64 = os.environ.get('PLY_F32_ROUNDED') != '1'

def read_ply(path):
    import struct
    data = open(path, 'rb').read()
    end = data.index(b'end_header') + len(b'end_header')
    end = data.index(b'\n', end) + 1
    header = data[:end].decode().split('\n')
    fmt = None; elements = []
    for line in header:
        f = line.split()
        if not f: continue
        if f[0] == 'format': fmt = f[1]
        elif f[0] == 'element': elements.append((f[1], int(f[2]), []))
        elif f[0] == 'property':
            if f[1] == 'list': elements[-1][2].append((f[4], 'list', f[2], f[3]))
            else: elements[-1][2].append((f[2], f[1]))
    body = data[end:]
    values = {}
    if fmt == 'ascii':
        toks = body.split(); pos = 0
        for name, count, props in elements:
            rows = []
            for _ in range(count):
                row = {}
                for p in props:
                    if p[1] == 'list':
                        n = int(toks[pos]); pos += 1
                        row[p[0]] = [int(x) for x in toks[pos:pos + n]]; pos += n
                    else:
                        t = toks[pos].decode(); pos += 1
                        if PLY_TYPES[p[1]] in 'fd':
                            x = float(t)
                            if PLY_TYPES[p[1]] == 'f' and not PLY_ASCII_AS_F64:
                                x = float(np.float32(t))
                            row[p[0]] = x
                        else:
                            row[p[0]] = int(t)
                rows.append(row)
            values[name] = rows
    else:
        e = '<' if fmt == 'binary_little_endian' else '>'
        pos = 0
        for name, count, props in elements:
            rows = []
            for _ in range(count):
                row = {}
                for p in props:
                    if p[1] == 'list':
                        c = PLY_TYPES[p[2]]; n, = struct.unpack_from(e + c, body, pos); pos += struct.calcsize(c)
                        c = PLY_TYPES[p[3]]; row[p[0]] = list(struct.unpack_from(e + str(n) + c, body, pos)); pos += n * struct.calcsize(c)
                    else:
                        c = PLY_TYPES[p[1]]; row[p[0]], = struct.unpack_from(e + c, body, pos); pos += struct.calcsize(c)
                        row[p[0]] = float(row[p[0]]) if c in 'fd' else row[p[0]]
                rows.append(row)
            values[name] = rows
    return values


class MeshFile:
    def __init__(self, path):
        if path.lower().endswith('.ply'):
            v = read_ply(path)
            verts = v['vertex']
            pos = [(float(r['x']), float(r['y']), float(r['z'])) for r in verts]
            has_n = all(k in verts[0] for k in ('nx', 'ny', 'nz'))
            nrm = [(float(r['nx']), float(r['ny']), float(r['nz'])) for r in verts] if has_n else []
            tex = []
            corners_faces = [[(k, None, k if has_n else None) for k in (r.get('vertex_indices') or r.get('vertex_index'))]
                             for r in v['face']]
            self.build(pos, nrm, tex, corners_faces)
            return
        pos, nrm, tex = [], [], []
        corners_faces = []  # list of lists of (v, vt, vn) absolute 0-based, vt/vn may be None
        for line in open(path):
            f = line.split()
            if not f or f[0].startswith('#'):
                continue
            if f[0] == 'v':
                pos.append(tuple(float(x) for x in f[1:4]))
            elif f[0] == 'vn':
                nrm.append(tuple(float(x) for x in f[1:4]))
            elif f[0] == 'vt':
                tex.append(tuple(float(x) for x in f[1:3]))
            elif f[0] == 'f':
                face = []
                for c in f[1:]:
                    parts = c.split('/')
                    def idx(s, n):
                        if s is None or s == '':
                            return None
                        k = int(s)
                        return k - 1 if k > 0 else n + k
                    v = idx(parts[0], len(pos))
                    vt = idx(parts[1], len(tex)) if len(parts) > 1 else None
                    vn = idx(parts[2], len(nrm)) if len(parts) > 2 else None
                    face.append((v, vt, vn))
                corners_faces.append(face)
        self.build(pos, nrm, tex, corners_faces)

    def build(self, pos, nrm, tex, corners_faces):
        # mesh vertices: distinct triples in order of first use
        vid = {}
        triples = []
        def vertex(tr):
            if tr not in vid:
                vid[tr] = len(triples)
                triples.append(tr)
            return vid[tr]
        tris = []
        self.degenerate = 0
        for face in corners_faces:
            ids = [vertex(c) for c in face]
            for i in range(1, len(ids) - 1):
                t = (ids[0], ids[i], ids[i + 1])
                a, b, c = (pos[triples[k][0]] for k in t)
                if (len(set(t)) < 3 or not all(math.isfinite(x) for p in (a, b, c) for x in p)
                        or cross(sub(b, a), sub(c, a)) == (0.0, 0.0, 0.0)):
                    self.degenerate += 1
                    continue
                tris.append(t)
        self.P = [pos[tr[0]] for tr in triples]
        self.tris = tris
        # triangle normals (file coordinates, not normalised)
        self.TN = [cross(sub(self.P[b], self.P[a]), sub(self.P[c], self.P[a])) for a, b, c in tris]
        # vertex normals
        acc = [(0.0, 0.0, 0.0)] * len(triples)
        for (a, b, c), n in zip(tris, self.TN):
            for k in (a, b, c):
                acc[k] = add(acc[k], n)
        self.VN = []
        self.normal_source = set()
        for k, tr in enumerate(triples):
            n = None
            if tr[2] is not None:
                fn = nrm[tr[2]]
                try:
                    m = normalize(fn)
                except (ZeroDivisionError, ValueError):
                    m = None
                if m is not None and all(math.isfinite(x) for x in m) and m != (0.0, 0.0, 0.0):
                    n = m
                    self.normal_source.add('file')
            if n is None:
                s = acc[k]
                ok = s != (0.0, 0.0, 0.0) and all(math.isfinite(x) for x in s)
                if ok:
                    m = normalize(s)
                    ok = all(math.isfinite(x) for x in m)
                n = m if ok else (0.0, 1.0, 0.0)
                self.normal_source.add('area')
            self.VN.append(n)
        # numpy arrays of the triangles for the vectorised test
        v0 = np.array([self.P[t[0]] for t in tris]); v1 = np.array([self.P[t[1]] for t in tris])
        v2 = np.array([self.P[t[2]] for t in tris]); tn = np.array(self.TN)
        self.np = (v0, v1, v2, tn)


# ---------------------------------------------------------------- placement (mesh.md)
def sincos_deg(alpha):
    d = math.fmod(alpha, 360.0)
    if math.fmod(d, 90.0) == 0.0:
        k = int(d / 90.0) % 4
        return [(0.0, 1.0), (1.0, 0.0), (0.0, -1.0), (-1.0, 0.0)][k]
    r = d * (math.pi / 180.0)
    return libm('sin', r), libm('cos', r)

def matmul(A, B):  # rows; column j of A·B is A·(column j of B)
    C = [[0.0] * 3 for _ in range(3)]
    for j in range(3):
        col = (B[0][j], B[1][j], B[2][j])
        r = matvec(A, col)
        for i in range(3):
            C[i][j] = r[i]
    return C

def matvec(A, v):  # ((A0·vx + A1·vy) + A2·vz), A_k the columns
    return tuple((A[i][0] * v[0] + A[i][1] * v[1]) + A[i][2] * v[2] for i in range(3))

class Placement:
    def __init__(self, mf, scale, rotate, translate):
        self.mf = mf
        self.s = tuple(float(x) for x in (scale if isinstance(scale, (list, tuple)) else (scale,) * 3))
        sx, cx = sincos_deg(float(rotate[0])); sy, cy = sincos_deg(float(rotate[1])); sz, cz = sincos_deg(float(rotate[2]))
        Rx = [[1.0, 0.0, 0.0], [0.0, cx, -sx], [0.0, sx, cx]]
        Ry = [[cy, 0.0, sy], [0.0, 1.0, 0.0], [-sy, 0.0, cy]]
        Rz = [[cz, -sz, 0.0], [sz, cz, 0.0], [0.0, 0.0, 1.0]]
        self.R = matmul(Rz, matmul(Ry, Rx))
        self.T = tuple(float(x) for x in translate)
        # A[i][k] = R[k][i] / s_i
        self.A = [[self.R[k][i] / self.s[i] for k in range(3)] for i in range(3)]
    def point(self, p):
        return add(self.T, matvec(self.R, had(self.s, p)))
    def normal(self, n):
        return normalize(matvec(self.R, vdiv(n, self.s)))
    def to_mesh(self, o, d):
        return matvec(self.A, sub(o, self.T)), matvec(self.A, d)


def tri_test(pl, o, d):
    """All triangles of the placement against the world ray (o, d): (hit mask, t, w0, w1, w2)."""
    op, dp = pl.to_mesh(o, d)
    v0, v1, v2, n = pl.mf.np
    ax = v0[:, 0] - op[0]; ay = v0[:, 1] - op[1]; az = v0[:, 2] - op[2]
    bx = v1[:, 0] - op[0]; by = v1[:, 1] - op[1]; bz = v1[:, 2] - op[2]
    cx = v2[:, 0] - op[0]; cy = v2[:, 1] - op[1]; cz = v2[:, 2] - op[2]
    def cr_dot(px, py, pz, qx, qy, qz):
        x = py * qz - qy * pz; y = pz * qx - qz * px; z = px * qy - qx * py
        return (x * dp[0] + y * dp[1]) + z * dp[2]
    w0 = cr_dot(bx, by, bz, cx, cy, cz)
    w1 = cr_dot(cx, cy, cz, ax, ay, az)
    w2 = cr_dot(ax, ay, az, bx, by, bz)
    outside = ((w0 < 0) | (w1 < 0) | (w2 < 0)) & ((w0 > 0) | (w1 > 0) | (w2 > 0))
    num = (ax * n[:, 0] + ay * n[:, 1]) + az * n[:, 2]
    den = (dp[0] * n[:, 0] + dp[1] * n[:, 1]) + dp[2] * n[:, 2]
    t = num / den
    hit = ~outside & (t > 0) & (t < INF)
    return hit, t, w0, w1, w2


# ---------------------------------------------------------------- scene
class Scene:
    def __init__(self, d):
        self.d = d
        r = d['render']
        self.W, self.H = r['width'], r['height']
        self.max_depth = r.get('max_depth', 3)
        self.bg = tuple(float(x) for x in r.get('background', (0, 0, 0)))
        mats = {k: self.material(v) for k, v in d['materials'].items()}
        self.spheres, self.planes, self.meshes = [], [], []
        files = {}
        for idx, ob in enumerate(d['objects']):
            (kind, o), = ob.items()
            m = mats[o['material']] if isinstance(o['material'], str) else self.material(o['material'])
            if kind == 'sphere':
                r_ = float(o['radius'])
                self.spheres.append(dict(idx=idx, c=tuple(map(float, o['center'])), r2=r_ * r_, m=m))
            elif kind == 'plane':
                self.planes.append(dict(idx=idx, p=tuple(map(float, o['point'])), n=normalize(tuple(map(float, o['normal']))), m=m))
            else:
                f = o['file']
                if f not in files:
                    files[f] = MeshFile(os.path.join(MESHDIR, f))
                pl = Placement(files[f], o.get('scale', 1), o.get('rotate', (0, 0, 0)), o.get('translate', (0, 0, 0)))
                self.meshes.append(dict(idx=idx, pl=pl, m=m, shading=o.get('shading', 'phong')))
        self.lights = []
        for l in d['lights']:
            (kind, o), = l.items()
            col = lambda k: tuple(map(float, o.get(k, (0, 0, 0))))
            if kind == 'point':
                self.lights.append(dict(kind='point', q=tuple(map(float, o['position'])), ia=col('ambient'), id=col('diffuse'), is_=col('specular')))
            elif kind == 'directional':
                self.lights.append(dict(kind='dir', L=neg(normalize(tuple(map(float, o['direction'])))), ia=col('ambient'), id=col('diffuse'), is_=col('specular')))
            elif kind == 'ambient':
                self.lights.append(dict(kind='ambient', a=tuple(map(float, o['color']))))
            elif kind == 'spot':
                self.lights.append(dict(kind='spot', q=tuple(map(float, o['position'])), axis=normalize(tuple(map(float, o['direction']))),
                                        ci=libm('cos', float(o['inner_angle']) * (math.pi / 180.0)),
                                        co=libm('cos', float(o['outer_angle']) * (math.pi / 180.0)),
                                        ia=col('ambient'), id=col('diffuse'), is_=col('specular')))
            else:
                raise NotImplementedError(kind)
        objs = self.spheres + self.planes + self.meshes
        self.transparent = any(o['m']['trans'] != (0.0, 0.0, 0.0) for o in objs)
        self.trees = self.transparent or any(o['m']['fresnel'] for o in objs)
        c = d['camera']
        pos = tuple(map(float, c['position'])); la = tuple(map(float, c['look_at']))
        up = tuple(map(float, c.get('up', (0, 1, 0)))); fov = float(c.get('fov', 90))
        v = sub(la, pos); l = length(v)
        fwd = (v[0] / l, v[1] / l, v[2] / l)
        upp = sub(up, smul(dot(up, fwd), fwd))
        self.up_c = normalize(upp)
        self.right = cross(fwd, self.up_c)
        self.fwd = fwd; self.pos = pos
        self.s = libm('tan', (fov * (math.pi / 180.0)) * 0.5)

    @staticmethod
    def material(m):
        g = lambda k, dflt: tuple(map(float, m.get(k, dflt)))
        e = float(m.get('shininess', 100)) / 4.0
        return dict(ka=g('ambient', (0, 0, 0)), kd=g('diffuse', None), ks=g('specular', (0, 0, 0)),
                    e=e, floor=(libm('exp', -69.08 / e) if e != 0 else 0.0), refl=float(m.get('reflection', 0)),
                    trans=(tuple(map(float, m['transmission'])) if isinstance(m.get('transmission'), list)
                           else (float(m.get('transmission', 0)),) * 3),
                    ior=float(m.get('ior', 1.5)), fresnel=bool(m.get('fresnel', False)))

    # ---- intersection
    @staticmethod
    def sphere_t(s, o, d, leaving):
        f = sub(o, s['c']); b = dot(f, d); p = sub(f, smul(b, d))
        disc = s['r2'] - dot(p, p)
        if not (disc >= 0):
            return None
        cc = dot(f, f) - s['r2']
        if b > 0 and (cc >= 0 or leaving):
            return None
        q = -(b + math.copysign(math.sqrt(disc), b))
        if q == 0:
            return None
        t0 = cc / q; t1 = q
        lo, hi = (t0, t1) if t0 <= t1 else (t1, t0)
        if leaving:
            return hi if (b < 0 and hi > 0) else None
        if lo > 0:
            return lo
        if hi > 0:
            return hi
        return None

    @staticmethod
    def plane_t(p, o, d, leaving):
        if leaving:
            return None
        t = fdiv(dot(sub(p['p'], o), p['n']), dot(p['n'], d))
        return t if (0 < t < INF) else None

    def nearest(self, o, d, leaving):
        best = None  # (t, kind, obj, extra)
        for s in self.spheres:
            t = self.sphere_t(s, o, d, leaving is s)
            if t is not None and (best is None or t < best[0]):
                best = (t, 'sphere', s, None)
        for p in self.planes:
            t = self.plane_t(p, o, d, leaving is p)
            if t is not None and (best is None or t < best[0]):
                best = (t, 'plane', p, None)
        for m in self.meshes:
            hit, t, w0, w1, w2 = tri_test(m['pl'], o, d)
            if not hit.any():
                continue
            tt = np.where(hit, t, INF)
            k = int(np.argmin(tt))  # first (lowest triangle index) among the smallest t
            tk = float(tt[k])
            if best is None or tk < best[0]:
                best = (tk, 'mesh', m, (k, float(w0[k]), float(w1[k]), float(w2[k])))
        return best

    def shadow_filter(self, o, d, dist, leaving):
        """None when an opaque object blocks, else the product (file order) of the transmissions
        of the transparent objects hit at t < dist."""
        hits = []
        for s in self.spheres:
            t = self.sphere_t(s, o, d, leaving is s)
            if t is not None and t < dist: hits.append(s)
        for p in self.planes:
            t = self.plane_t(p, o, d, leaving is p)
            if t is not None and t < dist: hits.append(p)
        for m in self.meshes:
            hit, t, *_ = tri_test(m['pl'], o, d)
            if (hit & (t < dist)).any(): hits.append(m)
        f = (1.0, 1.0, 1.0)
        for ob in sorted(hits, key=lambda ob: ob['idx']):
            if ob['m']['trans'] == (0.0, 0.0, 0.0):
                return None
            f = had(f, ob['m']['trans'])
        return f

    def blocked(self, o, d, dist, leaving):
        for s in self.spheres:
            t = self.sphere_t(s, o, d, leaving is s)
            if t is not None and t < dist:
                return True
        for p in self.planes:
            t = self.plane_t(p, o, d, leaving is p)
            if t is not None and t < dist:
                return True
        for m in self.meshes:
            hit, t, *_ = tri_test(m['pl'], o, d)
            if (hit & (t < dist)).any():
                return True
        return False

    # ---- lighting (tracer.md "Each light, in file order"); origin(r) gives the shadow ray origin
    def light_sum(self, P, N, d, mat, origin, leaving):
        local = (0.0, 0.0, 0.0)
        for li in self.lights:
            if li['kind'] == 'ambient':
                local = add(local, had(mat['ka'], li['a']))
                continue
            if li['kind'] in ('point', 'spot'):
                v = sub(li['q'], P); dist = length(v)
                if dist > 0:
                    L = (v[0] / dist, v[1] / dist, v[2] / dist)
                else:
                    L = (0.0, 0.0, 0.0); dist = 0.0
            else:
                L = li['L']; dist = INF
            scale = None
            if li['kind'] == 'spot':
                scale = spot_scale(li, L)
                if scale == 0:
                    continue
                local = add(local, had(smul(scale, mat['ka']), li['ia']))
            else:
                local = add(local, had(mat['ka'], li['ia']))
            n_l = dot(N, L)
            if n_l <= 0:
                continue
            r = normalize(L)
            filt = None
            if self.transparent:
                filt = self.shadow_filter(origin(r), r, dist, leaving)
                if filt is None:
                    continue
            elif self.blocked(origin(r), r, dist, leaving):
                continue
            H = normalize(add(L, neg(d)))
            x = dot(N, H)
            if x < 0: x = 0.0
            if x > 1: x = 1.0
            e = mat['e']
            if e == 0:
                spec = 1.0
            elif x <= mat['floor']:
                spec = 0.0
            elif e == math.floor(e) and e <= 4096:
                res, base, bits = 1.0, x, int(e)
                while True:
                    if bits & 1:
                        res = res * base
                    bits >>= 1
                    if bits == 0:
                        break
                    base = base * base
                spec = res
            else:
                spec = libm('pow', x, e)
            term = add(vmul(had(mat['kd'], li['id']), n_l), vmul(had(mat['ks'], li['is_']), spec))
            if filt is not None:
                term = had(term, filt)
            if scale is not None:
                term = smul(scale, term)
            local = add(local, term)
        return local

    @staticmethod
    def lifted(P, G, delta):
        # P' = P + G·copysign(δ, G·r)
        return lambda r: add(P, vmul(G, math.copysign(delta, dot(G, r))))

    # ---- a path (tracer.md "Path")
    def trace(self, o, d):
        colour = (0.0, 0.0, 0.0); w = 1.0; leaving = None
        self.view_o = o
        for depth in range(self.max_depth):
            h = self.nearest(o, d, leaving)
            if h is None:
                colour = add(colour, smul(w, self.bg))
                break
            t, kind, ob, extra = h
            P = add(o, smul(t, d))
            mat = ob['m']
            if kind in ('sphere', 'plane'):
                N = normalize(sub(P, ob['c'])) if kind == 'sphere' else ob['n']
                if dot(N, d) > 0:
                    N = neg(N)
                local = self.light_sum(P, N, d, mat, lambda r: P, ob)
                next_origin = lambda r: P
                next_leaving = ob
            else:
                local, N, G, delta = self.mesh_surface(ob, extra, P, t, d, o)
                next_origin = self.lifted(P, G, delta)
                next_leaving = None
            colour = add(colour, smul(w, local))
            w = w * mat['refl']
            if w < 1e-30 or depth == self.max_depth - 1:
                break
            r = normalize(sub(d, smul(2.0 * dot(d, N), N)))
            o = next_origin(r); d = r; leaving = next_leaving
            self.view_o = P if UNLIFTED_O else o
        return colour

    def surface(self, o, d, h):
        """(P, local, N, entering, origin(r), leaving) of a hit."""
        t, kind, ob, extra = h
        P = add(o, smul(t, d))
        if kind in ('sphere', 'plane'):
            N0 = normalize(sub(P, ob['c'])) if kind == 'sphere' else ob['n']
            entering = not (dot(N0, d) > 0)
            N = neg(N0) if dot(N0, d) > 0 else N0
            local = self.light_sum(P, N, d, ob['m'], lambda r: P, ob)
            return local, N, entering, (lambda r: P), ob
        local, N, G, delta, back = self.mesh_surface(ob, extra, P, t, d, o, want_back=True)
        return local, N, not back, self.lifted(P, G, delta), None

    def trace_tree(self, o, d):
        B = max(1024, self.max_depth)
        colour = (0.0, 0.0, 0.0); spent = 0
        level = [(o, d, None, (1.0, 1.0, 1.0), o)]
        for lv in range(self.max_depth):
            nxt = []
            for (o, d, leaving, w, unlifted) in level:
                self.view_o = unlifted if UNLIFTED_O else o
                if spent >= B:
                    continue
                spent += 1
                h = self.nearest(o, d, leaving)
                if h is None:
                    colour = add(colour, had(self.bg, w)); continue
                mat = h[2]['m']
                local, N, entering, origin, lv_obj = self.surface(o, d, h)
                P_hit = add(o, smul(h[0], d))
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
                wr = had(w, R)
                if max(max(wr[0], wr[1]), wr[2]) >= 1e-30:
                    r = normalize(sub(d, smul(2.0 * dot(d, N), N)))
                    nxt.append((origin(r), r, lv_obj, wr, P_hit))
                wt = had(w, Tw)
                if max(max(wt[0], wt[1]), wt[2]) >= 1e-30:
                    nxt.append((origin(T), T, lv_obj, wt, P_hit))
            level = nxt
            if not level:
                break
        return colour

    def mesh_surface(self, ob, extra, P, t, d, o, want_back=False):
        pl = ob['pl']; mf = pl.mf; mat = ob['m']
        k, w0, w1, w2 = extra
        i0, i1, i2 = mf.tris[k]
        S_ = (w0 + w1) + w2
        u = w1 / S_; v = w2 / S_
        b0 = (1.0 - u) - v
        n0, n1, n2 = mf.VN[i0], mf.VN[i1], mf.VN[i2]
        mix = add(add(vmul(n0, b0), vmul(n1, u)), vmul(n2, v))
        S = pl.normal(mix)
        W = pl.normal(mf.TN[k])
        if not abs(dot(S, S) - 1.0) < 0.5:  # mesh.md: cancelled vertex normals, S = W
            S = W
        G = neg(W) if dot(W, S) < 0 else W
        back = dot(G, d) > 0
        sh = ob['shading']
        N = S if sh in ('phong', 'gouraud') else G
        if back:
            N = neg(N); G = neg(G)
        delta = 64 * U64 * (max(abs(P[0]), abs(P[1]), abs(P[2])) + t)
        if sh in ('phong', 'flat'):
            local = self.light_sum(P, N, d, mat, self.lifted(P, G, delta), None)
        elif sh == 'gouraud':
            cs = []
            for idx in (i0, i1, i2):
                Q = pl.point(mf.P[idx]); Ni = pl.normal(mf.VN[idx])
                if back:
                    Ni = neg(Ni)
                dq = 64 * U64 * (max(abs(Q[0]), abs(Q[1]), abs(Q[2])) + 0.0)
                # mesh.md (d569cf4): d_i = normalize(Q_i − o), o the hit ray's origin, in the place of d
                cs.append(self.light_sum(Q, Ni, normalize(sub(Q, self.view_o)), mat, self.lifted(Q, G, dq), None))
            local = add(add(smul(b0, cs[0]), smul(u, cs[1])), smul(v, cs[2]))
        else:  # constant
            Q = [pl.point(mf.P[idx]) for idx in (i0, i1, i2)]
            C = vmul(add(add(Q[0], Q[1]), Q[2]), 1.0 / 3.0)
            dc = 64 * U64 * (max(abs(C[0]), abs(C[1]), abs(C[2])) + 0.0)
            local = self.light_sum(C, G, normalize(sub(C, self.view_o)), mat, self.lifted(C, G, dc), None)
        if want_back:
            return local, N, G, delta, back
        return local, N, G, delta

    def render(self):
        W, H = self.W, self.H
        img = np.zeros((H, W, 3))
        for i in range(H):
            for j in range(W):
                u = v = 0.5
                x = -1.0 + (2.0 * (j + u)) / W
                y = ((1.0 - (2.0 * (i + v)) / H) * H) / W
                dd = normalize(add(add(self.fwd, smul(x * self.s, self.right)), smul(y * self.s, self.up_c)))
                img[i, j] = self.trace_tree(self.pos, dd) if self.trees else self.trace(self.pos, dd)
        return img


def encode_linear(img):
    c = img.astype(np.float32)  # round to nearest f32
    c = np.where(np.isnan(c), np.float32(0), c)
    y = np.minimum(np.maximum(c, np.float32(0)), np.float32(1)) * np.float32(255)
    w = np.trunc(y)
    return (w + (y - w >= np.float32(0.5))).astype(np.uint8)


# ---------------------------------------------------------------- the test scenes
LIGHTS = [{'point': {'position': [4, 6, 5], 'ambient': [0.2, 0.2, 0.2], 'diffuse': [1, 1, 1], 'specular': [1, 1, 1]}},
          {'directional': {'direction': [1, -1.5, -0.7], 'diffuse': [0.3, 0.25, 0.2], 'specular': [0.4, 0.4, 0.4]}},
          {'ambient': {'color': [0.05, 0.05, 0.07]}}]
MATERIALS = {
    'clay': {'ambient': [0.1, 0.08, 0.06], 'diffuse': [0.8, 0.6, 0.5], 'specular': [0.5, 0.5, 0.5], 'shininess': 40},
    'blue': {'ambient': [0.05, 0.05, 0.15], 'diffuse': [0.2, 0.3, 0.8], 'specular': [0.9, 0.9, 0.9], 'shininess': 200},
    'green': {'ambient': [0.05, 0.1, 0.05], 'diffuse': [0.3, 0.7, 0.2], 'specular': [0.6, 0.6, 0.6], 'shininess': 100},
    'gold': {'ambient': [0.1, 0.08, 0.02], 'diffuse': [0.6, 0.5, 0.2], 'specular': [1, 0.9, 0.6], 'shininess': 60},
    'floor': {'ambient': [0.1, 0.1, 0.1], 'diffuse': [0.6, 0.6, 0.6], 'specular': [0.3, 0.3, 0.3], 'shininess': 20, 'reflection': 0.35},
    'mirror': {'ambient': [0.02, 0.02, 0.02], 'diffuse': [0.2, 0.2, 0.25], 'specular': [1, 1, 1], 'shininess': 400, 'reflection': 0.6},
}
SIZE = int(os.environ.get('SIZE', '1'))  # multiplies width and height (odd keeps odd)
def scene(objects, camera, w=64, h=48, max_depth=3, lights=LIGHTS):
    w *= SIZE; h *= SIZE
    return {'render': {'width': w, 'height': h, 'samples': 1, 'encoding': 'linear', 'max_depth': max_depth,
                       'background': [0.05, 0.07, 0.1]},
            'camera': camera, 'materials': MATERIALS, 'objects': objects, 'lights': lights}
def shifted(sc, off):
    import copy
    sc = copy.deepcopy(sc)
    mv = lambda p: [p[0] + off[0], p[1] + off[1], p[2] + off[2]]
    for o in sc['objects']:
        (k, v), = o.items()
        key = {'sphere': 'center', 'plane': 'point', 'mesh': 'translate'}[k]
        v[key] = mv(v.get(key, [0, 0, 0]))
    for l in sc['lights']:
        (k, v), = l.items()
        if 'position' in v: v['position'] = mv(v['position'])
    sc['camera']['position'] = mv(sc['camera']['position']); sc['camera']['look_at'] = mv(sc['camera']['look_at'])
    return sc
FLOOR = {'plane': {'point': [0, -1, 0], 'normal': [0, 1, 0], 'material': 'floor'}}
SCENES = {
    # the four shading models side by side on the low-poly sphere; reflective floor
    'shading4': scene([
        FLOOR,
        {'mesh': {'file': 'sphere_lowpoly.obj', 'material': 'clay', 'shading': 'phong', 'translate': [-2.4, 0, 0], 'scale': 0.9}},
        {'mesh': {'file': 'sphere_lowpoly.obj', 'material': 'blue', 'shading': 'flat', 'translate': [-0.8, 0, -0.5], 'scale': 0.9, 'rotate': [0, 20, 0]}},
        {'mesh': {'file': 'sphere_lowpoly.obj', 'material': 'green', 'shading': 'gouraud', 'translate': [0.8, 0, -0.5], 'scale': 0.9, 'rotate': [10, 0, 90]}},
        {'mesh': {'file': 'sphere_lowpoly.obj', 'material': 'gold', 'shading': 'constant', 'translate': [2.4, 0, 0], 'scale': 0.9, 'rotate': [0, 0, 180]}},
    ], {'position': [0, 1.5, 6], 'look_at': [0, -0.2, 0], 'fov': 60}),
    # non-uniform and mirroring scales, odd angles, the clockwise octahedron and the quad cube,
    # a mirror mesh and a sphere casting shadows on meshes
    'placements': scene([
        FLOOR,
        {'mesh': {'file': 'octahedron_cw.obj', 'material': 'blue', 'shading': 'phong', 'translate': [-1.8, 0.2, 0], 'scale': [0.8, 1.1, 0.7], 'rotate': [15, 37.5, -12]}},
        {'mesh': {'file': 'octahedron_cw.obj', 'material': 'gold', 'shading': 'flat', 'translate': [0, 0.3, -1.5], 'scale': [1, -1, 1], 'rotate': [0, 45, 0]}},
        {'mesh': {'file': 'cube_quads.obj', 'material': 'mirror', 'shading': 'phong', 'translate': [1.7, -0.4, -0.2], 'scale': [0.6, 0.6, 0.6], 'rotate': [0, -30, 0]}},
        {'mesh': {'file': 'sphere_lowpoly.obj', 'material': 'clay', 'shading': 'gouraud', 'translate': [0.2, -0.45, 1.1], 'scale': [0.7, 0.55, 0.7], 'rotate': [-20, 0, 33]}},
        {'mesh': {'file': 'cube_quads.obj', 'material': 'green', 'shading': 'constant', 'translate': [-0.6, -0.75, 2], 'scale': [0.25, 0.25, -0.25], 'rotate': [0, 10, 0]}},
        {'sphere': {'center': [0.9, 1.6, 0.3], 'radius': 0.35, 'material': 'clay'}},
    ], {'position': [1, 2.2, 5.5], 'look_at': [0, -0.3, 0], 'fov': 65}, max_depth=4),
    # odd size: the centre pixel's ray runs down the z axis onto the octahedron's vertex; a quad
    # coplanar with the floor (ties of a plane and a mesh); two identical cube placements
    # (ties between object indices); angles like -90, 450, -0.0; a spot light
    'edges': scene([
        FLOOR,
        {'mesh': {'file': 'octahedron_cw.obj', 'material': 'gold', 'shading': 'flat'}},
        {'mesh': {'file': 'quad.obj', 'material': 'green', 'shading': 'flat', 'translate': [1.5, -1, 0.5], 'scale': [1.2, 1, 0.8], 'rotate': [0, 30, 0]}},
        {'mesh': {'file': 'cube_quads.obj', 'material': 'blue', 'shading': 'phong', 'translate': [-1.8, -0.5, -0.5], 'scale': 0.5, 'rotate': [-90, 450, -0.0]}},
        {'mesh': {'file': 'cube_quads.obj', 'material': 'clay', 'shading': 'phong', 'translate': [-1.8, -0.5, -0.5], 'scale': 0.5, 'rotate': [-90, 450, -0.0]}},
        {'mesh': {'file': 'quad.obj', 'material': 'mirror', 'shading': 'phong', 'translate': [0, -0.2, -2.5], 'scale': 2, 'rotate': [80, 0, 0]}},
        {'mesh': {'file': 'quad.obj', 'material': 'clay', 'shading': 'flat', 'translate': [2.2, 0, 0], 'scale': 0.6}},
    ], {'position': [0, 0, 5], 'look_at': [0, 0, 0], 'fov': 70}, w=63, h=47, max_depth=3,
       lights=LIGHTS + [{'spot': {'position': [-1, 3, 2], 'direction': [0.3, -1, -0.6], 'inner_angle': 15, 'outer_angle': 30,
                                  'ambient': [0.1, 0.1, 0.1], 'diffuse': [0.8, 0.8, 0.6], 'specular': [1, 1, 1]}}]),
    # inside a big low-poly sphere (every hit is on a back side), light inside too
    'inside': scene([
        {'mesh': {'file': 'sphere_lowpoly.obj', 'material': 'mirror', 'shading': 'phong', 'scale': 6, 'rotate': [5, 10, 0]}},
        {'mesh': {'file': 'octahedron_cw.obj', 'material': 'clay', 'shading': 'gouraud', 'translate': [0.5, -0.5, -2], 'rotate': [20, 30, 0]}},
        {'mesh': {'file': 'sphere_lowpoly.obj', 'material': 'blue', 'shading': 'constant', 'translate': [-1.5, 0.5, -1.5], 'scale': 0.7}},
    ], {'position': [0, 0.5, 3], 'look_at': [0, 0, 0], 'fov': 80}, max_depth=3,
       lights=[{'point': {'position': [1, 3, 1], 'ambient': [0.2, 0.2, 0.2], 'diffuse': [1, 1, 1], 'specular': [1, 1, 1]}}]),
    # the other files: OBJ corner forms, a zero vn, a degenerate first fan triangle; ASCII and
    # binary big-endian PLY
    'files': scene([
        FLOOR,
        {'mesh': {'file': 'pyramid_odd.obj', 'material': 'clay', 'shading': 'phong', 'translate': [-1.6, -0.6, 0], 'rotate': [0, 25, 0]}},
        {'mesh': {'file': 'pyramid_odd.obj', 'material': 'green', 'shading': 'gouraud', 'translate': [-0.4, 0.2, -1.8], 'rotate': [160, 25, 0]}},
        {'mesh': {'file': 'lumpy_ascii.ply', 'material': 'blue', 'shading': 'phong', 'translate': [1.2, -0.1, 0], 'scale': 0.8, 'rotate': [0, 0, 12]}},
        {'mesh': {'file': 'lumpy_be.ply', 'material': 'gold', 'shading': 'gouraud', 'translate': [2.4, 0.8, -2], 'scale': 0.8}},
    ], {'position': [0, 1.8, 5], 'look_at': [0, -0.2, 0], 'fov': 60}),
    # glass: trees, lifted transmission rays, shadows filtered by transparent meshes
    'glass': scene([
        FLOOR,
        {'mesh': {'file': 'sphere_lowpoly.obj', 'material': 'glass', 'shading': 'phong', 'translate': [-1.2, 0, 0.5], 'scale': 0.9}},
        {'mesh': {'file': 'octahedron_cw.obj', 'material': 'fglass', 'shading': 'flat', 'translate': [1.1, 0.1, 0.6], 'rotate': [0, 30, 10]}},
        {'mesh': {'file': 'cube_quads.obj', 'material': 'clay', 'shading': 'phong', 'translate': [0, -0.4, -2.5], 'scale': 0.6, 'rotate': [0, 40, 0]}},
        {'mesh': {'file': 'lumpy_be.ply', 'material': 'green', 'shading': 'gouraud', 'translate': [-2.2, 0, -2.2], 'scale': 0.8}},
        {'sphere': {'center': [0.2, -0.55, 1.8], 'radius': 0.45, 'material': 'glass'}},
        {'mesh': {'file': 'quad.obj', 'material': 'tinted', 'shading': 'flat', 'translate': [2.3, 0, -1.5], 'scale': 0.8, 'rotate': [90, -20, 0]}},
    ], {'position': [0, 1.2, 5.5], 'look_at': [0, -0.2, 0], 'fov': 62}, max_depth=6),
}
MATERIALS.update({
    'glass': {'ambient': [0, 0, 0], 'diffuse': [0.05, 0.05, 0.05], 'specular': [1, 1, 1], 'shininess': 300, 'reflection': 0.1, 'transmission': 0.85, 'ior': 1.5},
    'fglass': {'ambient': [0.01, 0.01, 0.01], 'diffuse': [0.02, 0.05, 0.05], 'specular': [1, 1, 1], 'shininess': 200, 'transmission': [0.8, 0.95, 0.9], 'ior': 1.7, 'fresnel': True},
    'tinted': {'ambient': [0.05, 0, 0], 'diffuse': [0.3, 0.05, 0.05], 'specular': [0.2, 0.2, 0.2], 'shininess': 50, 'transmission': [0.7, 0.2, 0.2], 'ior': 1.0},
})
SCENES['far'] = shifted(SCENES['shading4'], [3e6, -1e5, 2.5e6])
SCENES['far_placements'] = shifted(SCENES['placements'], [-7e4, 1e3, 5e5])
SCENES['far_inside'] = shifted(SCENES['inside'], [2e7, -3e6, 1e7])

def to_yaml(d):
    import json
    def flow(x): return json.dumps(x)
    out = ['render: ' + flow(d['render']), 'output: out.png', 'camera: ' + flow(d['camera']), 'materials:']
    out += ['  %s: %s' % (k, flow(v)) for k, v in d['materials'].items()]
    out += ['objects:'] + ['  - ' + flow(o) for o in d['objects']]
    out += ['lights:'] + ['  - ' + flow(l) for l in d['lights']]
    return '\n'.join(out) + '\n'


def main():
    names = sys.argv[1:] or list(SCENES)
    rr_bin = os.environ.get('RAYREEL')
    total = [0, 0]
    for name in names:
        d = SCENES[name]
        tag = name + ('' if SIZE == 1 else '_x%d' % SIZE)
        ypath = os.path.join(MESHDIR, tag + '.yaml')
        open(ypath, 'w').write(to_yaml(d))
        sc = Scene(d)
        img = sc.render()
        out = encode_linear(img)
        Image.fromarray(out).save(os.path.join(MESHDIR, 'ref_' + tag + '.png'))
        np.save(os.path.join(MESHDIR, 'ref_' + tag + '.npy'), img)
        if not rr_bin:
            continue
        # exact f32 values through a 32-bit EXR (needs the OpenEXR module)
        try:
            import OpenEXR
            epath = os.path.join('/tmp', 'rayreel_' + tag + '.exr')
            subprocess.run([rr_bin, 'render', ypath, '-o', epath, '--exr-precision', 'float', '--force', '--quiet'], check=True)
            ex = OpenEXR.File(epath).channels()['RGB'].pixels
            mine = img.astype(np.float32)
            bad = np.argwhere((ex != mine).any(axis=2))
            print(f'{tag}: f32 values: {int((ex == mine).sum())}/{ex.size} channels equal bit for bit')
            for (a, b) in bad[:10]:
                print('   f32', a, b, 'rayreel', ex[a, b], 'ref', mine[a, b])
        except ImportError:
            pass
        rpath = os.path.join(MESHDIR, 'rayreel_' + tag + '.png')
        subprocess.run([rr_bin, 'render', ypath, '-o', rpath, '--force', '--quiet'], check=True)
        rr = np.asarray(Image.open(rpath).convert('RGB')).astype(int)
        diff = np.abs(rr - out.astype(int))
        nch = diff.size; neq = int((diff == 0).sum())
        total[0] += neq; total[1] += nch
        px = np.argwhere(diff.max(axis=2) > 0)
        print(f'{tag}: {neq}/{nch} channel bytes equal, {len(px)} of {sc.W * sc.H} pixels differ, max abs {diff.max()}')
        for (a, b) in px[:30]:
            print('  ', a, b, 'rayreel', rr[a, b], 'ref', out[a, b], 'ref·255', np.round(255 * img[a, b], 4))
    if rr_bin:
        print(f'total: {total[0]}/{total[1]} channel bytes equal')
    check_libm()

if __name__ == '__main__':
    main()
