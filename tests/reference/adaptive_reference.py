# An independent float64 implementation of adaptive sampling on frames that are not film frames,
# written from docs/spec/tracer.md ("Sample offsets", "Adaptive passes" with its sub-item "Smooth
# pixels" of 2026-12-04, "Pixel", "Path", "Each light"), docs/spec/texture.md ("The pixel"),
# docs/spec/output.md (the 8- and 16-bit linear values) and docs/sequence-file.md
# (`render.adaptive`: `threshold`, `max_samples`) alone, not from rayreel's code. It imports
# texture_reference.py (which builds on mesh_reference.py; both unchanged) for the tracer, the
# footprint cone and the checker's pixel mean, motion_reference.py (with camera_reference.py and
# film_reference.py) for sphere and rect lights (tracer.md "Area lights": the lanes that go on,
# the points of sample k, their shadow rays), and adds:
#   - the first pass: one sample at the centre, n² stratified samples, or R2 for other counts
#     (frame 0, `sampler: stratified`), summed in sample order, mean rounded to f32;
#   - the spread (per channel max − min, then the largest, rounded to f32; 0 for one sample);
#   - the marks: spread > threshold, or a row or column second difference |(2·c_i − c_a) − c_b|
#     > 2·threshold in f32 on the first pass's means;
#   - smooth pixels: in a scene with a checker and no tree-spawning material, a row or column
#     triple whose three pixels are all smooth on one object X is not tested. A first-pass sample
#     is smooth on X when (1) its eye ray's first hit is on X, a sphere or a plane whose material
#     has a checker and no image; (2) every checker of that material took the pixel's mean (The
#     pixel gave a value); (3) every non-ambient light reached the hit whole (N·L > 0 or NaN, the
#     shadow ray unblocked; a spot of scale 0 does not count; an area light's lane goes on and each
#     of the sample's m points has N·L > 0 and an unblocked shadow ray, every one traced here: a
#     ray rayreel skips by its cone test counts as unblocked); (4) the path ends there (w·r0 <
#     1e-30 or max_depth 1) or its reflection ray hits no object in a scene without a sky
#     (a material that spawns trees turns the exemption off even when no object uses it);
#   - the extension of marked pixels with R2 samples `samples` … `max_samples` − 1 and the mean
#     (m·samples + sum)/max_samples, m the f32 first-pass mean, rounded to f32.
# Alpha, f32 frames and film frames are left out.
#
# Usage: python3 adaptive_reference.py [SCENE ...]     (needs numpy and Pillow)
#   writes adaptive/SCENE.yaml (and the texture and mesh files when missing) and
#   adaptive/ref_SCENE.png; with RAYREEL=path/to/rayreel it also renders each YAML with rayreel as
#   8-bit and 16-bit linear PNGs and compares every channel value (the total counts both).
#   Per scene it prints how many pixels were marked, how many would have been without the
#   exemption, how many second-difference tests (row or column triples) were skipped as smooth,
#   and for how many first-pass samples each clause was the first to fail ('3 area lane', '3 area
#   N·L' and '3 area blocked' for an area light's part of clause 3).
#   SMOOTH=0 renders without the exemption (the rule before 2026-12-04), to check an older binary.
import math, os, subprocess, sys, time
import numpy as np
from PIL import Image

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import texture_reference as tr  # noqa: E402
import mesh_reference as mr  # noqa: E402
import motion_reference as mo  # noqa: E402  (its sphere and rect lights; it sets the file folders, reset below)
from mesh_reference import add, sub, vmul, smul, neg, dot, length, normalize  # noqa: E402

ADIR = os.path.join(HERE, 'adaptive')
tr.TEXDIR = ADIR  # image files of these scenes live beside them (motion_reference set its own)
mr.MESHDIR = ADIR  # and so do their mesh files
SMOOTH = os.environ.get('SMOOTH', '1') != '0'
f32 = np.float32

M64 = (1 << 64) - 1
def mix(z):  # splitmix64's finaliser (tracer.md "Sample offsets")
    z = (z + 0x9e3779b97f4a7c15) & M64
    z = ((z ^ (z >> 30)) * 0xbf58476d1ce4e5b9) & M64
    z = ((z ^ (z >> 27)) * 0x94d049bb133111eb) & M64
    return z ^ (z >> 31)
def unit(b): return float(b >> 11) * 2.0 ** -53
def random2(seed, k):
    h = mix(seed ^ k)
    return unit(h), unit(mix(h))
def fract(x): return x - math.trunc(x)
A1, A2 = 0.7548776662466927, 0.5698402909980532


def towards(q, P):  # tracer.md "Each light": L and dist of a point light at q seen from P
    v = sub(q, P); dist = length(v)
    if dist > 0:
        return (v[0] / dist, v[1] / dist, v[2] / dist), dist
    return (0.0, 0.0, 0.0), 0.0


class AdaptiveScene(mo.AreaTexScene):  # texture_reference's tracer; area lights by motion_reference's loop
    def __init__(self, d):
        super().__init__(d)
        ad = d['render']['adaptive']
        self.threshold = float(ad['threshold'])
        self.max_samples = int(ad['max_samples'])
        assert self.max_samples > self.samples
        objs = self.spheres + self.planes + self.meshes
        has_checker = any(mp[0] == 'checker' for o in objs for mp in o['m']['maps'].values())
        # tracer.md "Smooth pixels": a scene with a checker, filtered textures (rayreel's render),
        # and "no material that spawns trees": read literally, every material of the file counts,
        # those in `materials:` that no object uses included ("Trees": "some material of the
        # scene"); mesh_reference.py's tree flag looks at the objects' materials only, which gives
        # the same bits for opaque objects
        mats = list(d['materials'].values()) + [o[k]['material'] for o in d['objects'] for k in o
                                                if isinstance(o[k]['material'], dict)]
        def spawns(m):
            t = m.get('transmission', 0)
            return bool(m.get('fresnel', False)) or any(float(x) != 0 for x in (t if isinstance(t, list) else [t]))
        self.smooth_rule = SMOOTH and has_checker and not self.trees and not any(spawns(m) for m in mats)
        self.frame = 0

    # ---- sample offsets (tracer.md "Sample offsets"; frame 0, sampler stratified)
    def offset(self, seed, k):
        n = self.samples
        if k < n:  # the first pass
            if n == 1:
                return 0.5, 0.5
            r = math.isqrt(n)
            if r * r == n:
                jx, jy = random2(seed, k)
                return ((k % r) + jx) / r, ((k // r) + jy) / r
        sx, sy = random2(seed, 2 ** 32 - 1)  # R2: other counts, and the samples adaptive sampling adds
        return fract(sx + (k + 1) * A1), fract(sy + (k + 1) * A2)

    def eye(self, i, j, u, v):
        W, H = self.W, self.H
        x = -1.0 + (2.0 * (j + u)) / W
        y = ((1.0 - (2.0 * (i + v)) / H) * H) / W
        return normalize(add(add(self.fwd, smul(x * self.s, self.right)), smul(y * self.s, self.up_c)))

    def sample(self, i, j, k):
        self.ctx = (self.frame, i * self.W + j, k)  # the area lights' points of sample k
        d = self.eye(i, j, *self.offset(self.seed(i, j), k))
        return d, self.trace_tree(self.pos, d) if self.trees else self.trace(self.pos, d)

    def seed(self, i, j):
        return mix(mix(0x9e3779b97f4a7c15 ^ self.frame) ^ (i * self.W + j))

    # ---- tracer.md "Smooth pixels": the object a first-pass sample is smooth on, or the clause
    # that fails first ('miss' when the eye ray hits nothing, 1 to 4 otherwise)
    def smooth_on(self, o, d):
        h = self.nearest(o, d, None)
        if h is None:
            return None, 'miss'
        t, kind, ob, extra = h
        mat = ob['m']
        maps = mat['maps'].values()
        # 1. a sphere or a plane whose material has a checker and no image texture
        if kind not in ('sphere', 'plane') or not any(mp[0] == 'checker' for mp in maps) \
                or any(mp[0] == 'image' for mp in maps):
            return None, 1
        P = add(o, smul(t, d))  # tracer.md "Surface"
        N0 = normalize(sub(P, ob['c'])) if kind == 'sphere' else ob['n']
        N = neg(N0) if dot(N0, d) > 0 else N0
        # 2. every checker took the pixel's mean (texture.md "The pixel" gave a value)
        snaps = ob['snap'] if kind == 'plane' else []
        snap = tr.snapper(snaps)
        held = [i for i, _ in snaps]
        keep = lambda v: tuple(0.0 if i in held else v[i] for i in range(3))
        Pl = snap(add(P, (0.0, 0.0, 0.0)))  # the lookup point (f64 frame: O = 0)
        for mp in maps:
            if mp[0] != 'checker':
                continue
            pt = tr.pixel_patch(o, P, N, self.pix)
            if pt is None:
                return None, 2
            D, a, b = pt
            if tr.pixel_checker(snap(add(Pl, D)), keep(a), keep(b), mp[1], mp[2]) is None:
                return None, 2
        # 3. every light except ambient ones reached the point whole
        for li in self.lights:
            if li['kind'] == 'ambient':
                continue
            if li['kind'] in mo.AREA:
                # an area light: the lane goes on, and each of the sample's m points (this sample's
                # k) faces the hit and is unblocked; every shadow ray is traced here, so one rayreel
                # skips (its cone meets no occluder) counts as unblocked, as the rule says
                qs = self.area_points(li, P)
                if qs is None:
                    return None, '3 area lane'
                for q in qs:
                    L, dist = towards(q, P)
                    if dot(N, L) <= 0:  # N·L > 0 needed (NaN counts as > 0, as for a point light)
                        return None, '3 area N·L'
                    if self.blocked(P, normalize(L), dist, ob):
                        return None, '3 area blocked'
                continue
            if li['kind'] in ('point', 'spot'):
                L, dist = towards(li['q'], P)
            else:
                L = li['L']; dist = mr.INF
            if li['kind'] == 'spot':
                scale = mr.spot_scale(li, L)
                if scale == 0:  # does not count: its scale is continuous there
                    continue
            if dot(N, L) <= 0:  # N·L > 0 needed (NaN counts as > 0)
                return None, 3
            if self.blocked(P, normalize(L), dist, ob):
                return None, 3
        # 4. the path ends at the hit, or its reflection ray sees a constant background
        w = 1.0 * mat['refl']
        if not (w < 1e-30 or self.max_depth == 1):
            r = normalize(sub(d, smul(2.0 * dot(d, N), N)))
            if self.nearest(P, r, ob) is not None or self.sky is not None:
                return None, 4
        return ob['idx'], 'smooth'

    # ---- tracer.md "Adaptive passes" and "Pixel"
    def render(self):
        W, H, n, N = self.W, self.H, self.samples, self.max_samples
        mean = np.zeros((H, W, 3), dtype=np.float32)
        spread = np.zeros((H, W), dtype=np.float32)
        sums = {}
        smooth = [[None] * W for _ in range(H)]
        self.fails = {}
        for i in range(H):
            for j in range(W):
                self.pix = self.pixel_rays(i, j)
                acc = (0.0, 0.0, 0.0)
                lo = [math.inf] * 3; hi = [-math.inf] * 3
                on = set()
                for k in range(n):
                    d, c = self.sample(i, j, k)
                    acc = add(acc, c)
                    lo = [c[q] if c[q] < lo[q] else lo[q] for q in range(3)]
                    hi = [c[q] if c[q] > hi[q] else hi[q] for q in range(3)]
                    if self.smooth_rule:
                        X, why = self.smooth_on(self.pos, d)
                        self.fails[why] = self.fails.get(why, 0) + 1
                        on.add(X)
                m = acc if n == 1 else tr.sdiv(acc, float(n))
                mean[i, j] = [f32(x) for x in m]
                if n > 1:
                    r = [hi[q] - lo[q] for q in range(3)]
                    g = r[0] if r[0] > r[1] else r[1]
                    spread[i, j] = f32(g if g > r[2] else r[2])
                if self.smooth_rule and len(on) == 1 and None not in on:
                    smooth[i][j] = on.pop()
        thr = f32(self.threshold); thr2 = f32(2) * thr
        def second(c, a, b):  # in f32, per channel
            return bool((np.abs((f32(2) * c - a) - b) > thr2).any())
        marked = np.zeros((H, W), dtype=bool); old = np.zeros((H, W), dtype=bool)
        skipped = skipped_firing = 0
        for i in range(H):
            for j in range(W):
                s = spread[i, j] > thr
                mk = om = s
                triples = []
                if 0 < j < W - 1:
                    triples.append(((i, j - 1), (i, j + 1)))
                if 0 < i < H - 1:
                    triples.append(((i - 1, j), (i + 1, j)))
                for (a, b) in triples:
                    fires = second(mean[i, j], mean[a], mean[b])
                    om = om or fires
                    X = smooth[i][j]
                    if X is not None and smooth[a[0]][a[1]] == X and smooth[b[0]][b[1]] == X:
                        skipped += 1
                        skipped_firing += fires
                        continue
                    mk = mk or fires
                marked[i, j] = mk; old[i, j] = om
        img = mean.astype(np.float64)
        for i in range(H):
            for j in range(W):
                if not marked[i, j]:
                    continue
                self.pix = self.pixel_rays(i, j)
                acc = (0.0, 0.0, 0.0)
                for k in range(n, N):
                    acc = add(acc, self.sample(i, j, k)[1])
                mm = [float(x) for x in mean[i, j]]
                img[i, j] = [float(f32((mm[q] * float(n) + acc[q]) / float(N))) for q in range(3)]
        self.stats = dict(marked=int(marked.sum()), marked_old=int(old.sum()), skipped=skipped,
                          skipped_firing=skipped_firing,
                          smooth_px=sum(x is not None for row in smooth for x in row))
        return img


def encode16(img):  # output.md: linear, M = 65535, in f32
    c = img.astype(np.float32)
    c = np.where(np.isnan(c), np.float32(0), c)
    y = np.minimum(np.maximum(c, np.float32(0)), np.float32(1)) * np.float32(65535)
    w = np.trunc(y)
    return (w + (y - w >= np.float32(0.5))).astype(np.int64)


# ---------------------------------------------------------------- files and scenes
def make_files():
    os.makedirs(ADIR, exist_ok=True)
    p = os.path.join(ADIR, 'swatch.png')  # 8 × 4 8-bit RGB: an image beside a checker
    if not os.path.exists(p):
        rng = np.random.RandomState(20261204)
        Image.fromarray(rng.randint(0, 256, (4, 8, 3)).astype(np.uint8)).save(p)
    p = os.path.join(ADIR, 'quad_uv.obj')
    if not os.path.exists(p):
        open(p, 'w').write('# a quad in y = 0 with texture coordinates, CCW from +y\n'
                           'v -1 0 1\nv 1 0 1\nv 1 0 -1\nv -1 0 -1\n'
                           'vt 0 0\nvt 2 0\nvt 2 1\nvt 0 1\n'
                           'f 1/1 2/2 3/3 4/4\n')

CHK = {'checker': {'size': 1, 'colors': [[0.9, 0.85, 0.8], [0.1, 0.15, 0.3]]}}
MATS = {
    'tiles': {'diffuse': CHK, 'ambient': [0.1, 0.1, 0.1], 'specular': [0.3, 0.3, 0.3], 'shininess': 40},
    'tiles_refl': {'diffuse': CHK, 'ambient': [0.1, 0.1, 0.1], 'specular': [0.3, 0.3, 0.3], 'shininess': 40, 'reflection': 0.35},
    'tiles_tiny': {'diffuse': CHK, 'ambient': [0.1, 0.1, 0.1], 'specular': [0.3, 0.3, 0.3], 'shininess': 40, 'reflection': 1e-31},
    'tiles_two': {'diffuse': {'checker': {'size': 0.3, 'colors': [[0.2, 0.8, 0.3], [0.9, 0.2, 0.1]]}},
                  'ambient': {'checker': {'size': 0.17, 'colors': [[0.3, 0.3, 0.3], [0.0, 0.0, 0.1]]}},
                  'specular': [0.5, 0.5, 0.5], 'shininess': 100},
    'tiles_both': {'diffuse': CHK, 'ambient': {'checker': {'size': 1, 'colors': [[0.35, 0.3, 0.3], [0.02, 0.02, 0.12]]}},
                   'specular': [0.3, 0.3, 0.3], 'shininess': 40},
    'tiles_img': {'diffuse': CHK, 'ambient': {'image': 'swatch.png'}, 'specular': [0.3, 0.3, 0.3], 'shininess': 40},
    'clay': {'ambient': [0.1, 0.08, 0.06], 'diffuse': [0.8, 0.6, 0.5], 'specular': [0.5, 0.5, 0.5], 'shininess': 40},
    'blue': {'ambient': [0.05, 0.05, 0.15], 'diffuse': [0.2, 0.3, 0.8], 'specular': [0.9, 0.9, 0.9], 'shininess': 200},
    'mirror': {'ambient': [0.02, 0.02, 0.02], 'diffuse': [0.1, 0.1, 0.1], 'specular': [1, 1, 1], 'shininess': 400, 'reflection': 0.8},
    'glass': {'ambient': [0, 0, 0], 'diffuse': [0.03, 0.03, 0.03], 'specular': [1, 1, 1], 'shininess': 300, 'reflection': 0.1,
              'transmission': 0.85, 'ior': 1.5},
}
POINT = {'point': {'position': [3, 6, 4], 'ambient': [0.25, 0.25, 0.25], 'diffuse': [0.9, 0.9, 0.9], 'specular': [1, 1, 1]}}
DIRL = {'directional': {'direction': [-1, -2, -0.5], 'diffuse': [0.3, 0.3, 0.3], 'specular': [0.3, 0.3, 0.3]}}
AMB = {'ambient': {'color': [0.1, 0.1, 0.12]}}
LIGHTS = [POINT, DIRL, AMB]

def scene(objects, camera, samples, threshold, max_samples, w=64, h=36, max_depth=3, lights=LIGHTS,
          background=(0.4, 0.55, 0.8)):
    used = {o[k]['material'] for o in objects for k in o}  # only the materials the objects use
    return {'render': {'width': w, 'height': h, 'samples': samples, 'encoding': 'linear', 'max_depth': max_depth,
                       'background': background if isinstance(background, dict) else list(background),
                       'adaptive': {'threshold': threshold, 'max_samples': max_samples}},
            'camera': camera, 'materials': {k: v for k, v in MATS.items() if k in used},
            'objects': objects, 'lights': lights}

FLOOR = {'plane': {'point': [0, 0, 0], 'normal': [0, 1, 0], 'material': 'tiles'}}
SCENES = {
    # (a), (f) R2 first pass: a plain sphere's shadow across a lit checker floor that runs to the
    # horizon (where the pixel's mean gives no value: clause 2); shadow edges stay marked
    'shadow_s2': scene([
        FLOOR,
        {'sphere': {'center': [0.2, 0.8, -1.5], 'radius': 0.8, 'material': 'clay'}},
    ], {'position': [0, 1.6, 3.5], 'look_at': [0, 0.2, -2], 'fov': 70}, 2, 0.03, 8),
    # (b), (f) stratified first pass: checker spheres lit from the side (the terminator: N·L ≤ 0),
    # one with two checkers (diffuse and ambient, both must give the pixel's mean), on a plain floor
    'spheres_s4': scene([
        {'plane': {'point': [0, -1, 0], 'normal': [0, 1, 0], 'material': 'clay'}},
        {'sphere': {'center': [-0.9, 0, -1], 'radius': 1, 'material': 'tiles'}},
        {'sphere': {'center': [1.2, 0, -1.6], 'radius': 0.9, 'material': 'tiles_two'}},
    ], {'position': [0, 0.6, 3], 'look_at': [0, 0, -1.2], 'fov': 60}, 4, 0.03, 16, w=48, h=27,
        lights=[{'point': {'position': [-4, 2.5, 2.5], 'ambient': [0.2, 0.2, 0.2], 'diffuse': [0.9, 0.9, 0.9],
                           'specular': [1, 1, 1]}}, AMB]),
    # (c) a reflective checker floor: smooth where its reflection ray leaves into the constant
    # background, not where it meets a sphere
    'mirror_floor': scene([
        {'plane': {'point': [0, 0, 0], 'normal': [0, 1, 0], 'material': 'tiles_refl'}},
        {'sphere': {'center': [-0.8, 0.7, -1.5], 'radius': 0.7, 'material': 'blue'}},
        {'sphere': {'center': [1.0, 0.5, -0.8], 'radius': 0.5, 'material': 'tiles'}},
    ], {'position': [0, 1.2, 3], 'look_at': [0, 0.3, -1.5], 'fov': 65}, 2, 0.03, 8),
    # (d) a sky: a reflective floor is never smooth (its reflection ray sees the sky), a checker
    # sphere without reflection is, and so is one whose w·r0 = 1e-31 < 1e-30 ends the path
    'sky': scene([
        {'plane': {'point': [0, 0, 0], 'normal': [0, 1, 0], 'material': 'tiles_refl'}},
        {'sphere': {'center': [-1.0, 0.8, -1.5], 'radius': 0.8, 'material': 'tiles'}},
        {'sphere': {'center': [1.1, 0.7, -1.2], 'radius': 0.7, 'material': 'tiles_tiny'}},
    ], {'position': [0, 1.2, 3], 'look_at': [0, 0.5, -1.5], 'fov': 65}, 2, 0.03, 8,
        background={'gradient': {'zenith': [0.1, 0.2, 0.7], 'horizon': [0.9, 0.85, 0.8], 'ground': [0.2, 0.3, 0.1]}}),
    # (e) spot lights, one sample a first pass: a spot from above whose cone holds a checker
    # sphere's shadow; a spot below the floor aimed up (inside its cone N·L ≤ 0 on the floor, so
    # not whole, and the floor's ambient checker shows there; outside it, scale 0: it does not count)
    'spots_s1': scene([
        {'plane': {'point': [0, 0, 0], 'normal': [0, 1, 0], 'material': 'tiles_both'}},
        {'sphere': {'center': [0.6, 0.6, -1.2], 'radius': 0.6, 'material': 'tiles'}},
    ], {'position': [0, 2.2, 3], 'look_at': [0, 0, -1.2], 'fov': 65}, 1, 0.03, 4,
        lights=[{'spot': {'position': [0.8, 4, -1.5], 'direction': [0, -1, 0.1], 'inner_angle': 14, 'outer_angle': 24,
                          'ambient': [0.1, 0.1, 0.1], 'diffuse': [0.9, 0.9, 0.8], 'specular': [1, 1, 1]}},
                {'spot': {'position': [-1.2, -1, 0], 'direction': [0, 1, 0], 'inner_angle': 20, 'outer_angle': 35,
                          'ambient': [0.15, 0.05, 0.05], 'diffuse': [1, 0.3, 0.3], 'specular': [1, 1, 1]}},
                {'ambient': {'color': [0.25, 0.25, 0.25]}}]),
    # clause 2, one sample a first pass (spread 0): fine checkers on spheres (two on one of them,
    # the finer in the ambient) where the pixel's mean gives no value near the cells' corners (three
    # axes vary), and a floor to the horizon (more than 32 rows)
    'corners_s1': scene([
        {'plane': {'point': [0, 0, 0], 'normal': [0, 1, 0], 'material': 'tiles_both'}},
        {'sphere': {'center': [-0.7, 0.9, -1.2], 'radius': 0.9, 'material': 'tiles_two'}},
        {'sphere': {'center': [1.2, 0.6, -1.8], 'radius': 0.6, 'material': 'tiles_two'}},
    ], {'position': [0, 1.1, 2.2], 'look_at': [0, 0.7, -1.2], 'fov': 70}, 1, 0.02, 4),
    # (g) checker objects side by side: a checker sphere resting on the checker floor and two
    # overlapping spheres of one material (different objects: no exemption across a boundary),
    # and a plain sphere
    'neighbours': scene([
        FLOOR,
        {'sphere': {'center': [-1.2, 0.7, -1.2], 'radius': 0.7, 'material': 'tiles'}},
        {'sphere': {'center': [0.5, 0.65, -1.6], 'radius': 0.65, 'material': 'tiles'}},
        {'sphere': {'center': [1.2, 0.6, -1.0], 'radius': 0.6, 'material': 'tiles'}},
        {'sphere': {'center': [0.0, 0.3, 0.2], 'radius': 0.3, 'material': 'clay'}},
    ], {'position': [0, 1.5, 3], 'look_at': [0, 0.4, -1.2], 'fov': 60}, 2, 0.02, 8),
    # clause 4, max_depth 1: a reflective checker floor traces no reflection ray, so it is smooth
    # even where it would reflect the sphere
    'depth1': scene([
        {'plane': {'point': [0, 0, 0], 'normal': [0, 1, 0], 'material': 'tiles_refl'}},
        {'sphere': {'center': [0, 0.7, -1.5], 'radius': 0.7, 'material': 'mirror'}},
    ], {'position': [0, 1.2, 3], 'look_at': [0, 0.4, -1.5], 'fov': 60}, 2, 0.03, 8, w=48, h=27, max_depth=1),
    # clause 1: a checker with an image ambient and a checker mesh are never smooth; the floor is
    'image_mesh': scene([
        FLOOR,
        {'sphere': {'center': [-1.0, 0.7, -1.3], 'radius': 0.7, 'material': 'tiles_img'}},
        {'mesh': {'file': 'quad_uv.obj', 'material': 'tiles', 'shading': 'flat', 'translate': [1.1, 0.8, -1.5],
                  'scale': 0.7, 'rotate': [70, -30, 0]}},
    ], {'position': [0, 1.4, 3], 'look_at': [0, 0.5, -1.3], 'fov': 60}, 2, 0.03, 8, w=48, h=27),
    # (h) glass: trees, so no exemption anywhere
    'glass': scene([
        FLOOR,
        {'sphere': {'center': [0, 0.7, -1], 'radius': 0.7, 'material': 'glass'}},
    ], {'position': [0, 1.2, 3], 'look_at': [0, 0.6, -1], 'fov': 55}, 2, 0.03, 8, w=40, h=24, max_depth=4),
    # a glass material that no object uses: the scene still has "a material that spawns trees",
    # so no exemption (the literal reading of "Smooth pixels"; rayreel agrees)
    'unused_glass': scene([
        FLOOR,
        {'sphere': {'center': [0.2, 0.8, -1.5], 'radius': 0.8, 'material': 'clay'}},
    ], {'position': [0, 1.6, 3.5], 'look_at': [0, 0.2, -2], 'fov': 70}, 2, 0.03, 8, w=40, h=24),
    # no checker: the rule never applies (plain adaptive sampling, R2 first pass)
    'plain_s2': scene([
        {'plane': {'point': [0, -1, 0], 'normal': [0, 1, 0], 'material': 'clay'}},
        {'sphere': {'center': [-0.8, 0, -1], 'radius': 1, 'material': 'blue'}},
        {'sphere': {'center': [1.1, -0.3, -0.6], 'radius': 0.7, 'material': 'mirror'}},
    ], {'position': [0, 0.8, 3], 'look_at': [0, 0, -1], 'fov': 60}, 2, 0.03, 8, w=48, h=27),
    # area lights (tracer.md "Area lights"; clause 3: the lane goes on and every one of the
    # sample's m points faces the hit, N·L > 0, with its shadow ray unblocked):
    # a sphere light (16 points) over a plain sphere: its soft shadow on the checker floor (the
    # penumbra is not smooth, the floor in full light is) and a checker sphere beside it
    'area_sphere': scene([
        FLOOR,
        {'sphere': {'center': [0.3, 0.7, -1.6], 'radius': 0.7, 'material': 'clay'}},
        {'sphere': {'center': [-1.3, 0.5, -1.0], 'radius': 0.5, 'material': 'tiles'}},
    ], {'position': [0, 1.8, 3], 'look_at': [0, 0.3, -1.4], 'fov': 60}, 2, 0.03, 8, w=64, h=48,
        lights=[{'sphere': {'center': [-0.6, 3.2, -0.4], 'radius': 0.6, 'ambient': [0.2, 0.2, 0.2],
                            'diffuse': [0.9, 0.9, 0.85], 'specular': [0.8, 0.8, 0.8], 'samples': 16}}, AMB]),
    # a tilted rect light (8 points) whose plane cuts the floor: where (P − c)·n ≤ 0 the lane does
    # not go on (the ambient term alone, not smooth); its other side is lit whole except in the
    # shadow of a sphere; stratified first pass
    'area_rect_s4': scene([
        FLOOR,
        {'sphere': {'center': [-0.6, 0.45, -1.4], 'radius': 0.45, 'material': 'clay'}},
        {'sphere': {'center': [-1.6, 0.5, -2.4], 'radius': 0.5, 'material': 'tiles'}},
    ], {'position': [0, 1.6, 3], 'look_at': [0, 0.2, -1.5], 'fov': 65}, 4, 0.03, 16, w=64, h=48,
        lights=[{'rect': {'corner': [0.8, 0.4, -3.0], 'edge_u': [0, 0, 2.5], 'edge_v': [0.6, 1.6, 0],
                          'ambient': [0.15, 0.15, 0.15], 'diffuse': [1.0, 0.95, 0.9], 'specular': [0.6, 0.6, 0.6],
                          'samples': 8}}, AMB]),
    # a sphere light low over the floor, partly below it, beside a checker sphere: from most of the
    # floor and the sphere some of its points are below the hit's horizon (N·L ≤ 0), the floor
    # under it is inside the light (δ ≤ R: the lane does not go on); one sample a first pass
    'area_horizon_s1': scene([
        FLOOR,
        {'sphere': {'center': [0.9, 0.6, -1.6], 'radius': 0.6, 'material': 'tiles'}},
    ], {'position': [0, 1.5, 2.5], 'look_at': [0, 0.2, -1.4], 'fov': 60}, 1, 0.03, 4, w=64, h=48,
        lights=[{'sphere': {'center': [-0.5, 0.3, -1.3], 'radius': 0.4, 'ambient': [0.1, 0.1, 0.1],
                            'diffuse': [1.2, 1.1, 0.9], 'specular': [0.8, 0.8, 0.8], 'samples': 8}},
                {'ambient': {'color': [0.15, 0.15, 0.18]}}]),
    # a point light (with ambient), a spot whose cone leaves most of the floor at scale 0 (it does
    # not count there), a rect light and a sphere light (one point) in one file, over a reflective
    # checker floor (clause 4: its reflection ray sees the spheres or the background)
    'area_mixed': scene([
        {'plane': {'point': [0, 0, 0], 'normal': [0, 1, 0], 'material': 'tiles_refl'}},
        {'sphere': {'center': [-0.8, 0.6, -1.6], 'radius': 0.6, 'material': 'tiles'}},
        {'sphere': {'center': [0.9, 0.4, -1.2], 'radius': 0.4, 'material': 'clay'}},
    ], {'position': [0, 1.5, 3], 'look_at': [0, 0.3, -1.4], 'fov': 60}, 2, 0.03, 8, w=64, h=48,
        lights=[POINT,
                {'rect': {'corner': [-2, 3, -2], 'edge_u': [1.2, 0, 0], 'edge_v': [0, 0, 1.5],
                          'diffuse': [0.5, 0.5, 0.55], 'specular': [0.4, 0.4, 0.4], 'samples': 4}},
                {'spot': {'position': [1.5, 3, -0.5], 'direction': [0, -1, -0.2], 'inner_angle': 8, 'outer_angle': 15,
                          'ambient': [0.05, 0.05, 0.05], 'diffuse': [0.6, 0.5, 0.4], 'specular': [0.5, 0.5, 0.5]}},
                {'sphere': {'center': [2.5, 2, 1], 'radius': 0.4, 'ambient': [0.05, 0.05, 0.05],
                            'diffuse': [0.3, 0.3, 0.3], 'specular': [0.3, 0.3, 0.3], 'samples': 1}},
                AMB]),
}
SCENES['unused_glass']['materials'] = dict(SCENES['unused_glass']['materials'], glass=MATS['glass'])


def main():
    make_files()
    names = sys.argv[1:] or list(SCENES)
    rr_bin = os.environ.get('RAYREEL')
    total = [0, 0]
    t_all = time.time()
    for name in names:
        d = SCENES[name]
        ypath = os.path.join(ADIR, name + '.yaml')
        open(ypath, 'w').write(mr.to_yaml(d))
        t0 = time.time()
        sc = AdaptiveScene(d)
        img = sc.render()
        dt = time.time() - t0
        out = mr.encode_linear(img)
        Image.fromarray(out).save(os.path.join(ADIR, 'ref_' + name + '.png'))
        st = sc.stats
        fails = ', '.join(f'{k}: {v}' for k, v in sorted(sc.fails.items(), key=lambda kv: str(kv[0])))
        print(f'{name}: {sc.W}x{sc.H}, samples {sc.samples} to {sc.max_samples}, smooth rule '
              f'{"on" if sc.smooth_rule else "off"}; {st["marked"]} pixels marked ({st["marked_old"]} without '
              f'the exemption), {st["skipped"]} second-difference tests skipped as smooth ({st["skipped_firing"]} of '
              f'them over the threshold), {st["smooth_px"]} smooth pixels; first-pass samples by first failing '
              f'clause: {{{fails}}}; {dt:.1f} s')
        if not rr_bin:
            print(f'{name}: rendered (no RAYREEL to compare with)')
            continue
        for bits in (8, 16):
            rpath = os.path.join(ADIR, f'rayreel_{name}_{bits}.png')
            subprocess.run([rr_bin, 'render', ypath, '-o', rpath, '--bit-depth', str(bits), '--force', '--quiet'],
                           check=True)
            rr = tr.read_png(rpath)[0] if bits == 16 else np.asarray(Image.open(rpath).convert('RGB')).astype(int)
            mine = encode16(img) if bits == 16 else out.astype(int)
            diff = np.abs(rr - mine)
            nch = diff.size; neq = int((diff == 0).sum())
            total[0] += neq; total[1] += nch
            px = np.argwhere(diff.max(axis=2) > 0)
            print(f'{name}: {bits}-bit: {neq}/{nch} channel values equal, {len(px)} of {sc.W * sc.H} pixels differ, '
                  f'max abs {diff.max()}')
            for (a, b) in px[:12]:
                print('   ', a, b, 'rayreel', rr[a, b], 'ref', mine[a, b], 'ref·M', np.round((2 ** bits - 1) * img[a, b], 4))
    print(f'time: {time.time() - t_all:.1f} s')
    if rr_bin:
        print(f'total: {total[0]}/{total[1]} channel bytes equal')
    tr.check_libm()

if __name__ == '__main__':
    main()
