#!/usr/bin/env python3
# An independent implementation of frames with moving objects and lights, written from
# docs/spec/motion.md, docs/spec/timeline.md, docs/spec/tracer.md, docs/spec/mesh.md,
# docs/spec/f32.md, docs/spec/output.md, docs/spec/texture.md and docs/sequence-file.md ("Things
# that move") alone, never from rayreel's code. It builds on the other references (imported, not
# copied):
#   - camera_reference.py: the tracks of timeline.md (centripetal Catmull-Rom shapes with their
#     Gauss-Legendre arc length, Fritsch-Carlson rates m_k, stops, turn-backs);
#   - mesh_reference.py: the f64 tracer (spheres, planes, OBJ meshes and their placement,
#     point / directional / spot / ambient lights, paths);
#   - film_reference.py: film frames' Owen-scrambled Sobol' points and seeds, the rounds of
#     adaptive sampling and the film filter; with film_f32_reference.py, lens frames of a posed
#     scene in f64 and f32 (their scene globals set to the poses at t);
#   - texture_reference.py: image maps on planes (the footprint cone, the lookup), used for posed
#     scenes whose materials have maps (the posed scene at t is a still scene).
# What it adds (motion.md): keys -> key values (carried over, first key from the still thing,
# normals and directions normalised, numbers as (r, 0, 0), a spot's angles one track), key
# times (`time: x`, `time: a/b`, `frame: n`, fractional fps and first_frame), the thing at time
# t (a mesh's up axis and origin offset included), the shutter's 256 instants and which frames
# become film frames because things (or the camera) move while the shutter is open, each sample
# traced in the scene posed at its own instant; and, since mesh_reference has none, sphere and
# rect area lights (tracer.md "Area lights"), keyed like the others: a rect's edges are straight
# tracks and its normal at each pose comes from the rect normal rule on the posed edges; a plane
# with `u_axis` whose normal is keyed gets its axis turned by output.md's shortest turn from the
# still normal, then loaded as a written u_axis (motion.md "The thing at time t"). f32.md: a frame whose
# things move while the shutter is open is traced in f64, so `blur_f32` must equal f64 bytes.
#
# Where the docs leave an f64 operation order open (tracks' formulas), this file states the
# reading it takes ("readings" below); pixels cannot tell those apart (a pose an ulp off moves an
# f32 pixel value with probability ~1e-9), so they are written down for the spec's authors.
#
# Usage: python3 motion_reference.py [CASE ...]     (needs numpy and Pillow; OpenEXR optional)
#   writes motion/CASE.yaml; with RAYREEL=path/to/rayreel it renders each case's frames with
#   rayreel and compares every channel byte of the 8-bit PNG and, with the OpenEXR module,
#   every byte of the 32-bit float EXR values; the last line is `total: E/N channel bytes equal`.
import copy, json, math, os, re, shutil, subprocess, sys, tempfile
import numpy as np
from PIL import Image

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import camera_reference as cr  # noqa: E402
import film_reference as fr  # noqa: E402
import mesh_reference as mr  # noqa: E402
import texture_reference as tex  # noqa: E402  (before the mesh-file cache below: it subclasses mr.MeshFile)
import importlib  # noqa: E402
from mesh_reference import normalize  # noqa: E402

MOTIONDIR = os.path.join(HERE, 'motion')
mr.MESHDIR = MOTIONDIR
tex.TEXDIR = MOTIONDIR  # the image maps of the motion cases live beside them

# mesh files are read once, whatever the number of posed scenes built from them
_MESH_FILES = {}
_MeshFile = mr.MeshFile
def _cached_mesh_file(path):
    if path not in _MESH_FILES:
        _MESH_FILES[path] = _MeshFile(path)
    return _MESH_FILES[path]
mr.MeshFile = _cached_mesh_file

M64 = (1 << 64) - 1
FR_SAMPLE_COLOUR = fr.sample_colour  # film_reference's own tracer, for lens frames

# ---------------------------------------------------------------- readings of open points
# Where the docs leave a choice, this file reads them so (the first reading taken; none was
# changed after comparing with rayreel):
# - f64 operation order of tracks (timeline.md gives formulas, not their order): a straight
#   shape "p1 + (p2 − p1)·σ/L_k" as ((p2 − p1)·σ)/L_k per component; smooth timing with
#   u2 = u·u, u3 = u2·u, 3u² = 3·u2, sums left to right (ThingTrack.value); curved shapes are
#   camera_reference's Curve (bisection for the arc length, x**3). Pixels cannot tell these
#   apart: against camera_reference's own order about 6 % of pose components differ by ulps
#   (worst 2.5e-14 relative) and not one f32 pixel value changes.
# - "a curved track turning straight back" (motion.md) read as timeline.md's rule for every
#   track under smooth timing, straight ones included (as fov): the blue sphere of BLUR has a
#   radius that goes up then down; without the stop 44 to 214 bytes of its frames change.
# - Default sampling of a frame where only things move under a shutter: the "shutter on a
#   moving camera" case of sequence-file.md (2 samples, rounds up to 64 at 0.025, the film
#   filter); 4 samples would change 657 bytes of blur_default.
# - The shutter's interval at a fractional fps, Δ = (θ/360)/fps with fps = num/den as one f64.
# - A key that sets no keyable field (`{ time: 0 }`) is a key holding the carried values.
# ---------------------------------------------------------------- keys and tracks (motion.md)
# the track each keyable field belongs to, per kind of thing, and whether its shape is curved
# under `smooth` (motion.md "Keyable fields")
FIELDS = {
    'mesh': {'scale': 'scale', 'rotate': 'rotate', 'translate': 'translate'},
    'sphere': {'center': 'center', 'radius': 'radius'},
    'plane': {'point': 'point', 'normal': 'normal'},
    'point': {'position': 'position', 'ambient': 'ambient', 'diffuse': 'diffuse', 'specular': 'specular'},
    'directional': {'direction': 'direction', 'ambient': 'ambient', 'diffuse': 'diffuse', 'specular': 'specular'},
    'spot': {'position': 'position', 'direction': 'direction', 'inner_angle': 'angles', 'outer_angle': 'angles',
             'ambient': 'ambient', 'diffuse': 'diffuse', 'specular': 'specular'},
    'ambient': {'color': 'color'},
    'light:sphere': {'center': 'center', 'radius': 'radius', 'ambient': 'ambient', 'diffuse': 'diffuse', 'specular': 'specular'},
    'light:rect': {'corner': 'corner', 'edge_u': 'edge_u', 'edge_v': 'edge_v',
                   'ambient': 'ambient', 'diffuse': 'diffuse', 'specular': 'specular'},
}
CURVED = {'mesh': {'rotate', 'translate'}, 'sphere': {'center'}, 'plane': {'point'}, 'point': {'position'},
          'directional': set(), 'spot': {'position'}, 'ambient': set(), 'light:sphere': {'center'}, 'light:rect': {'corner'}}


def vec(x):
    return [float(c) for c in x]


def still_value(kind, still, track):
    """The first key's default for a track: the thing as the loader built it."""
    if track == 'scale':
        s = still.get('scale', 1)
        return vec(s) if isinstance(s, list) else [float(s)] * 3
    if track in ('rotate', 'translate'):
        return vec(still.get(track, [0, 0, 0]))
    if track == 'radius':
        return [float(still['radius']), 0.0, 0.0]
    if track in ('normal', 'direction'):
        return list(normalize(vec(still[track])))
    if track == 'angles':
        return [float(still['inner_angle']), float(still['outer_angle']), 0.0]
    if track in ('ambient', 'diffuse', 'specular') and kind != 'ambient':
        return vec(still.get(track, [0, 0, 0]))
    return vec(still[track])


def key_value(track, key, previous):
    """The value a key gives a track, converted as the loader converts a still field."""
    if track == 'scale':
        s = key['scale']
        return vec(s) if isinstance(s, list) else [float(s)] * 3
    if track == 'radius':
        return [float(key['radius']), 0.0, 0.0]
    if track in ('normal', 'direction'):
        return list(normalize(vec(key[track])))
    if track == 'angles':
        return [float(key.get('inner_angle', previous[0])), float(key.get('outer_angle', previous[1])), 0.0]
    return vec(key[track])


class Clock:
    """timeline.md "Frames": `fps` a number or a fraction num/den, `first_frame`."""
    def __init__(self, tl):
        fps = tl.get('fps', 24)
        self.first = int(tl.get('first_frame', 0))
        self.frac = (fps.a, fps.b) if isinstance(fps, Frac) else None
        self.rate = float(fps.a) / float(fps.b) if self.frac else float(fps)  # one f64, as frame counts use it

    def time(self, n):
        i = n - self.first
        if self.frac:
            return (float(i) * float(self.frac[1])) / float(self.frac[0])
        return float(i) / self.rate


def key_time(key, clock):
    """timeline.md "Inputs": `time: x`, `time: a/b` (one f64 division), `frame: n`."""
    if 'frame' in key:
        return clock.time(key['frame'])
    x = key['time']
    if isinstance(x, Frac):
        return float(x.a) / float(x.b)
    return float(x)


class Frac:
    """A key's `time: a/b`, written unquoted in the YAML."""
    def __init__(self, a, b):
        self.a, self.b = a, b


class ThingTrack(cr.Track):
    """camera_reference's track (shapes, lengths, stops, rates) evaluated with the operation
    order the readings above state: the value at t only."""
    def value(self, t):
        T, n, q = self.times, len(self.q), self.q
        if n == 1 or t < T[0]:
            return q[0]
        if t >= T[-1]:
            return q[-1]
        k = max(i for i in range(n - 1) if T[i] <= t)
        h = T[k + 1] - T[k]
        u = (t - T[k]) / h
        L = self.L[k]
        if self.timing == 'linear':
            a, b = self.stops[k], self.stops[k + 1]
            if a and b:
                e = (u * u) * (3.0 - 2.0 * u)
            elif a:
                e = u * u
            elif b:
                e = u * (2.0 - u)
            else:
                e = u
            s = L * e
        else:
            m0, m1 = self.m[k], self.m[k + 1]
            u2 = u * u
            u3 = u2 * u
            s = L * (3.0 * u2 - 2.0 * u3) + h * (m0 * ((u3 - 2.0 * u2) + u) + m1 * (u3 - u2))
            s = min(max(s, 0.0), L)
        shape = self.shapes[k]
        if shape is None:
            return q[k]
        if shape == 'line':
            p1, p2 = q[k], q[k + 1]
            return [p1[c] + ((p2[c] - p1[c]) * s) / L for c in range(3)]
        return shape.at(s)


class Thing:
    """One object or light with keys: its tracks through the key values."""
    def __init__(self, tag, index, entry, clock, default_interp):
        (self.kind, self.still), = [(k, v) for k, v in entry.items() if k not in ('keys', 'interpolation')]
        self.tag, self.index = tag, index
        kind = 'light:' + self.kind if tag == 1 and self.kind in ('sphere', 'rect') else self.kind
        interp = entry.get('interpolation', default_interp)
        keys = entry['keys']
        fields = FIELDS[kind]
        self.tracks = []
        for tr in dict.fromkeys(fields[f] for k in keys for f in k if f in fields):
            prev = still_value(self.kind, self.still, tr)
            values = []
            for k in keys:
                if any(fields.get(f) == tr for f in k):
                    prev = key_value(tr, k, prev)
                values.append(prev)
            times = [key_time(k, clock) for k in keys]
            stops = [k.get('ease', 'pass') == 'stop' for k in keys]
            curved = interp == 'smooth' and tr in CURVED[kind]
            self.tracks.append((tr, ThingTrack(times, values, stops, curved, interp)))

    def pose(self, t):
        """The keyed fields of the thing at t, as still fields (motion.md "The thing at time t")."""
        out = {}
        for tr, track in self.tracks:
            v = [float(c) for c in track.value(t)]
            if tr == 'radius':
                out['radius'] = v[0]
            elif tr == 'angles':
                out['inner_angle'] = min(v[0], v[1])
                out['outer_angle'] = v[1]
            else:
                # normals and directions: the loader (mesh_reference.Scene) normalises them again
                out[tr] = v
        return out


def things_of(d):
    tl = d.get('timeline', {})
    clock = Clock(tl)
    interp = tl.get('interpolation', 'smooth')
    out = []
    for tag, group in ((0, 'objects'), (1, 'lights')):
        for i, e in enumerate(d[group]):
            if 'keys' in e:
                out.append(Thing(tag, i, e, clock, interp))
    return out, clock


def posed_scene(d, things, t, camera=None):
    """The still scene dict at t (keys dropped, keyed fields replaced) for mesh_reference.Scene."""
    s = {k: v for k, v in d.items() if k not in ('objects', 'lights', 'timeline')}
    s['objects'] = [{k: copy.deepcopy(v) for k, v in e.items() if k not in ('keys', 'interpolation')} for e in d['objects']]
    s['lights'] = [{k: copy.deepcopy(v) for k, v in e.items() if k not in ('keys', 'interpolation')} for e in d['lights']]
    poses = []
    for th in things:
        p = th.pose(t)
        poses.append(p)
        (kind, fields), = s['objects' if th.tag == 0 else 'lights'][th.index].items()
        fields.update(p)
        if kind == 'plane' and 'u_axis' in fields and 'normal' in p:
            fields['u_axis'] = list(plane_axis_at(th.still, p['normal']))
        if kind == 'rect' and th.tag == 1 and rect_normal(fields['edge_u'], fields['edge_v']) is None:
            # motion.md: an ℓ rounding to 0 or to no number at a pose keeps the still light's normal
            fields['normal_kept'] = rect_normal(th.still['edge_u'], th.still['edge_v'])
    if camera is not None:
        s['camera'] = camera
    return s, poses


def turned(v, n, n2):
    """output.md "forward.u/v", a plane's shortest turn from unit normal n to n2, applied to v:
    c = n × n2, d = n·n2, w = (v·d + c × v) + c·((c·v)/(1 + d)) per component; v itself when
    1 + d ≤ 1e-9 (or NaN)."""
    c, d = mr.cross(n, n2), mr.dot(n, n2)
    if not (1.0 + d > 1e-9):
        return tuple(v)
    k = mr.dot(c, v) / (1.0 + d)
    return mr.add(mr.add(mr.vmul(v, d), mr.cross(c, v)), mr.vmul(c, k))


def plane_axis_at(still, v_normal):
    """motion.md "The thing at time t": a plane with `u_axis` whose normal is keyed gets the
    written axis a = turned(U, N0, N), U and N0 the still plane's axis and unit normal as the
    loader built them (texture.md "Coordinates": normalize(a' − N0·(a'·N0)), a' the written axis
    made unit), N = v_normal.normalize(); the loader (texture_reference.TexScene) then makes of
    a what it makes of a written u_axis."""
    N0 = normalize(vec(still['normal']))
    a = normalize(vec(still['u_axis']))
    U = normalize(mr.sub(a, mr.vmul(N0, mr.dot(a, N0))))
    return turned(U, N0, normalize(vec(v_normal)))


def rect_normal(u, v):
    """tracer.md "Area lights", the rect normal rule: w = u × v, ℓ = |w|; when ℓ is not both > 0
    and finite, w = (u/m_u) × (v/m_v) (m the largest |component|) and ℓ = |w| again; n = w·(1/ℓ)
    per component, or None when ℓ is still not finite and > 0."""
    u, v = vec(u), vec(v)
    w = mr.cross(u, v)
    ell = math.sqrt(mr.dot(w, w))
    if not (ell > 0 and math.isfinite(ell)):
        mu, mv = max(abs(c) for c in u), max(abs(c) for c in v)
        w = mr.cross([c / mu for c in u], [c / mv for c in v])
        ell = math.sqrt(mr.dot(w, w))
        if not (ell > 0 and math.isfinite(ell)):
            return None
    r = 1.0 / ell
    return (w[0] * r, w[1] * r, w[2] * r)


def camera_tracks(d, clock):
    """timeline.md: a keyframed camera's position, look_at, up and fov tracks (keys carried
    over, the first from `camera:`, up normalised), or None for a still `camera:`."""
    tl = d.get('timeline', {})
    keys = tl.get('keyframes')
    if not keys:
        return None
    cam = d.get('camera', {})
    prev = {'position': vec(cam['position']), 'look_at': vec(cam['look_at']),
            'up': vec(cam.get('up', [0, 1, 0])), 'fov': [float(cam.get('fov', 90)), 0.0, 0.0]}
    values = {f: [] for f in prev}
    for k in keys:
        for f in prev:
            if f in k:
                prev[f] = [float(k['fov']), 0.0, 0.0] if f == 'fov' else vec(k[f])
            values[f].append(list(normalize(prev[f])) if f == 'up' else prev[f])
    times = [key_time(k, clock) for k in keys]
    stops = [k.get('ease', 'pass') == 'stop' for k in keys]
    interp = tl.get('interpolation', 'smooth')
    return {f: ThingTrack(times, values[f], stops, interp == 'smooth' and f != 'fov', interp) for f in values}


def camera_at(tracks, t):
    c = {f: [float(x) for x in tr.value(t)] for f, tr in tracks.items()}
    c['fov'] = c['fov'][0]
    return c


# mesh.md "Placement": the file's up axis U (R <- R·U) and `origin`'s offset, which
# mesh_reference.Placement leaves out; motion.md: the offset is computed once, from the unkeyed
# scale and rotation, and subtracted from the keyed translate
UP_ANGLES = {'y': (0, 0, 0), 'z': (-90, 0, 0), 'x': (0, 0, 90), '-y': (180, 0, 0), '-z': (90, 0, 0), '-x': (0, 0, -90)}


def placement(mf, scale, rotate, translate, up):
    pl = mr.Placement(mf, scale, rotate, translate)
    up = up.lstrip('+')
    if up != 'y':
        pl.R = mr.matmul(pl.R, mr.Placement(mf, 1, UP_ANGLES[up], (0, 0, 0)).R)
        pl.A = [[pl.R[k][i] / pl.s[i] for k in range(3)] for i in range(3)]
    return pl


def origin_offset(mf, still):
    origin = still.get('origin', 'file')
    if origin == 'file':
        return (0.0, 0.0, 0.0)
    pl = placement(mf, still.get('scale', 1), still.get('rotate', (0, 0, 0)), (0, 0, 0), still.get('up', 'y'))
    used = sorted({k for t in mf.tris for k in t})
    q = [pl.point(mf.P[k]) for k in used]  # T + R·(s ∘ p) with T = 0: the sum 0 + v taken
    lo = tuple(min(p[c] for p in q) for c in range(3))
    hi = tuple(max(p[c] for p in q) for c in range(3))
    c = mr.vmul(mr.add(lo, hi), 0.5)
    return c if origin == 'center' else (c[0], lo[1], c[2])


def place_meshes(sc, posed):
    """Rebuild the placements of meshes with `up` or `origin` (the posed fields as the loader)."""
    for m in sc.meshes:
        o = posed['objects'][m['idx']]['mesh']
        if 'up' not in o and 'origin' not in o:
            continue
        mf = m['pl'].mf
        T = mr.sub(tuple(map(float, o.get('translate', (0, 0, 0)))), origin_offset(mf, o))
        m['pl'] = placement(mf, o.get('scale', 1), o.get('rotate', (0, 0, 0)), T, o.get('up', 'y'))


# ---------------------------------------------------------------- area lights (tracer.md "Area lights")
# mesh_reference's light loop has no sphere or rect lights; scenes with them are lit by this
# loop, which knows the frame, pixel and sample index k (the other lights of such a scene by
# mesh_reference's loop, one light at a time; adaptive_reference.py uses it too).
def sobol2(g):
    out, v, i = 0, 1 << 31, 0
    while g >> i:
        if (g >> i) & 1:
            out ^= v
        v ^= v >> 1
        i += 1
    return out


def area_light(ell, kind, o):
    """A `sphere` or `rect` light of the file's lights (ℓ its index there, every kind counted)."""
    col = lambda k: tuple(map(float, o.get(k, (0, 0, 0))))
    li = dict(kind=kind, ell=ell, m=int(o.get('samples', 16)), ia=col('ambient'), id=col('diffuse'), is_=col('specular'))
    if kind == 'sphere':
        li.update(C=tuple(map(float, o['center'])), R=float(o['radius']))
    else:
        c, u, v = (tuple(map(float, o[k])) for k in ('corner', 'edge_u', 'edge_v'))
        li.update(c=c, u=u, v=v, n=tuple(o['normal_kept']) if 'normal_kept' in o else rect_normal(u, v))
    return li


AREA = ('sphere', 'rect')


class AreaScene(mr.Scene):
    def __init__(self, d):
        # mesh_reference loads the other lights; the area lights take their places in file order
        is_area = lambda l: any(k in l for k in AREA)
        super().__init__(dict(d, lights=[l for l in d['lights'] if not is_area(l)]))
        others = iter(self.lights)
        self.lights = [area_light(ell, *next(iter(l.items()))) if is_area(l) else next(others)
                       for ell, l in enumerate(d['lights'])]
        self.area = any(li['kind'] in AREA for li in self.lights)
        self.ctx = (0, 0, 0)  # (frame, pixel, k) of the sample being traced

    def area_points(self, li, P):
        """The m points q of area light li for the sample self.ctx seen from P, in order, or None
        when the lane does not go on (behind a rect, inside or on a sphere light)."""
        sub = mr.sub
        frame, pixel, k = self.ctx
        if li['kind'] == 'rect':
            if not (mr.dot(sub(P, li['c']), li['n']) > 0):
                return None
        else:
            C, R = li['C'], li['R']
            v = sub(C, P)
            delta = math.sqrt((v[0] * v[0] + v[1] * v[1]) + v[2] * v[2])
            if not (delta > R):
                return None
            r = 1.0 / delta
            w = (v[0] * r, v[1] * r, v[2] * r)
            sg = math.copysign(1.0, w[2])
            a = -1.0 / (sg + w[2])
            b = (w[0] * w[1]) * a
            e1 = (1.0 + ((sg * w[0]) * w[0]) * a, sg * b, (-sg) * w[0])
            e2 = (b, sg + (w[1] * w[1]) * a, -w[1])
        z = fr.mix(fr.mix(fr.mix(0x9e3779b97f4a7c15 ^ frame) ^ pixel) ^ 0xbb67ae8584caa73b)
        h = fr.mix(z ^ li['ell'])
        sx, sy = h >> 32, h & 0xffffffff
        m = li['m']
        qs = []
        for j in range(m):
            g = k * m + j
            x = (fr.rev32(g) ^ sx) * 2.0 ** -32
            y = (sobol2(g) ^ sy) * 2.0 ** -32
            if li['kind'] == 'rect':
                c, u, vv = li['c'], li['u'], li['v']
                q = tuple((c[i] + x * u[i]) + y * vv[i] for i in range(3))
            else:
                a2, b2 = 2.0 * x - 1.0, 2.0 * y - 1.0
                if a2 == 0.0 and b2 == 0.0:
                    al = be = 0.0
                else:
                    # tracer.md: the concentric map of Thin lens (Taylor sin and cos)
                    if max(a2, 0.0 - a2) > max(b2, 0.0 - b2):
                        sn, cs = fr.sin_cos(fr.QUARTER_PI * (b2 / a2))
                        al, be = a2 * cs, a2 * sn
                    else:
                        sn, cs = fr.sin_cos(fr.QUARTER_PI * (a2 / b2))
                        al, be = b2 * sn, b2 * cs
                q = tuple(C[i] + R * ((al * e1[i]) + (be * e2[i])) for i in range(3))
            qs.append(q)
        return qs

    def one_light(self, li, P, N, d, mat, origin, leaving, **fields):
        """mesh_reference's loop for light li alone (with `fields` replaced), from local = 0."""
        keep, self.lights = self.lights, [dict(li, **fields)]
        try:
            return mr.Scene.light_sum(self, P, N, d, mat, origin, leaving)
        finally:
            self.lights = keep

    def light_sum(self, P, N, d, mat, origin, leaving):
        if not self.area:
            return mr.Scene.light_sum(self, P, N, d, mat, origin, leaving)
        add, had, vmul = mr.add, mr.had, mr.vmul
        zero = (0.0, 0.0, 0.0)
        local = zero
        for li in self.lights:
            if li['kind'] == 'ambient':
                local = add(local, had(mat['ka'], li['a']))
                continue
            if li['kind'] not in AREA:
                # a point, directional or spot light, in two parts so that local sums as "Each
                # light" says, (local + (scale·ka)∘ia) + term: alone with diffuse and specular 0
                # its loop gives (0 + (scale·ka)∘ia) + 0, and with ambient 0, (0 + 0) + term
                local = add(local, self.one_light(li, P, N, d, mat, origin, leaving, id=zero, is_=zero))
                local = add(local, self.one_light(li, P, N, d, mat, origin, leaving, ia=zero))
                continue
            local = add(local, had(mat['ka'], li['ia']))
            qs = self.area_points(li, P)
            if qs is None:
                continue
            m = li['m']
            share = 1.0 / m
            for q in qs:
                # "Each point is a point light at q, exactly as above": mesh_reference's loop for
                # one point light without ambient gives (0 + ka∘0) + term = term, or 0 when the
                # point adds nothing (N·L ≤ 0, blocked), and local + 0 = local
                term = self.one_light(dict(kind='point', q=q), P, N, d, mat, origin, leaving, ia=zero, id=li['id'], is_=li['is_'])
                local = add(local, vmul(term, share) if m != 1 else term)
        return local


class AreaTexScene(AreaScene, tex.TexScene):
    """Area lights on texture_reference's tracer (its cone and lookups, AreaScene's light loop)."""


# the posed scene at t is a still scene: image maps (texture.md) by texture_reference's tracer
SCENE_CLASSES = {(False, False): mr.Scene, (True, False): AreaScene, (False, True): tex.TexScene, (True, True): AreaTexScene}


# ---------------------------------------------------------------- frames (motion.md "Frames, the shutter and samples")
def unit(b):
    return float(b >> 11) * 2.0 ** -53


class Frame:
    def __init__(self, d, n):
        self.d, self.n = d, n
        self.things, self.clock = things_of(d)
        r = d['render']
        self.W, self.H = r['width'], r['height']
        self.t = self.clock.time(n)  # n as the timeline numbers it (from first_frame)
        self.cams = camera_tracks(d, self.clock)
        cam = lambda x: camera_at(self.cams, x) if self.cams else None
        self.scene_t, self.pose_t = posed_scene(d, self.things, self.t, cam(self.t))
        self.pose_t = (self.pose_t, cam(self.t))
        self.instants = None
        theta = float(r.get('shutter', 0))
        if theta > 0:
            delta = (theta / 360.0) / self.clock.rate
            o = float(r.get('shutter_offset', 0))
            tm = [self.t + delta * ((o - 0.5) + (m + 0.5) / 256.0) for m in range(256)]
            if any((posed_scene(d, self.things, x)[1], cam(x)) != self.pose_t for x in tm):
                self.instants = tm  # things (or the camera) move while the shutter is open: a film frame
        self._scenes = {}

    def scene(self, m):
        """The scene posed at instant m (None: at the frame's time t)."""
        if m not in self._scenes:
            t = self.t if m is None else self.instants[m]
            c = camera_at(self.cams, t) if self.cams else None
            posed = posed_scene(self.d, self.things, t, c)[0]
            area = any(k in l for l in posed['lights'] for k in ('sphere', 'rect'))
            maps = any(isinstance(mat.get(k), dict) for mat in posed['materials'].values() for k in ('diffuse', 'ambient'))
            self._scenes[m] = SCENE_CLASSES[area, maps](posed)
            place_meshes(self._scenes[m], posed)
        return self._scenes[m]

    def trace(self, sc, i, j, u, v, k=0):
        W, H = self.W, self.H
        sc.ctx = (self.n, i * W + j, k)
        x = -1.0 + (2.0 * (j + u)) / W
        y = ((1.0 - (2.0 * (i + v)) / H) * H) / W
        dd = normalize(mr.add(mr.add(sc.fwd, mr.smul(x * sc.s, sc.right)), mr.smul(y * sc.s, sc.up_c)))
        if hasattr(sc, "pixel_rays"):  # texture.md "The pixel": this sample's camera's pixel
            sc.pix = sc.pixel_rays(i, j)
        return sc.trace_tree(sc.pos, dd) if sc.trees else sc.trace(sc.pos, dd)

    def render(self):
        r = self.d['render']
        if self.instants is None:
            return self.render_still(int(r.get('samples', 1)))
        return self.render_film()

    def render_still(self, n):
        """tracer.md: one sample at the centre, or n = k² jittered samples (Sample offsets)."""
        k2 = math.isqrt(n)
        assert k2 * k2 == n, 'the reference does 1 or k² samples on still frames'
        sc = self.scene(None)
        img = np.zeros((self.H, self.W, 3))
        for i in range(self.H):
            for j in range(self.W):
                seed = fr.mix(fr.mix(0x9e3779b97f4a7c15 ^ self.n) ^ (i * self.W + j))
                acc = (0.0, 0.0, 0.0)
                for k in range(n):
                    if n == 1:
                        u = v = 0.5
                    else:
                        h = fr.mix(seed ^ k)
                        u = ((k % k2) + unit(h)) / k2
                        v = ((k // k2) + unit(fr.mix(h))) / k2
                    acc = mr.add(acc, self.trace(sc, i, j, u, v, k))
                img[i, j] = acc if n == 1 else tuple(c / n for c in acc)
        return img

    def film_sample(self, i, j, k, seeds):
        """Sample k of a film frame: Sobol' (u, v, a, b, τ); the scene posed at instant m."""
        x = fr.sobol_point(k, seeds)
        m = min(int(x[4] * 256.0), 255)
        return self.trace(self.scene(m), i, j, x[0], x[1], k)

    def lone_sample(self, i, j):
        """The lone sample of a one-sample film frame: offset (0.5, 0.5), τ = random3's first."""
        z = fr.mix(fr.mix(fr.mix(0x9e3779b97f4a7c15 ^ self.n) ^ (i * self.W + j)) ^ 0x6a09e667f3bcc909)
        tau = unit(fr.mix(z ^ 0))
        m = min(int(tau * 256.0), 255)
        return self.trace(self.scene(m), i, j, 0.5, 0.5)

    def render_film(self):
        r = self.d['render']
        ad = r.get('adaptive')
        sampling_set = 'samples' in r or 'adaptive' in r or 'quality' in r
        if sampling_set:
            n = int(r.get('samples', 1))
            max_s = int(ad.get('max_samples', 32)) if ad else n
            thr = float(ad.get('threshold', 0.03)) if ad else 0.03
        else:
            # sequence-file.md: "on film, 2 (a shutter on a camera that moves or in a scene whose
            # objects or lights have keys) with adaptive rounds up to 64 at threshold 0.025"
            n, max_s, thr = 2, 64, 0.025
        denoise = r.get('denoise', True)
        fr.FRAME, fr.W, fr.H = self.n, self.W, self.H
        img = np.zeros((self.H, self.W, 3))
        if n == 1:
            assert not ad
            for i in range(self.H):
                for j in range(self.W):
                    img[i, j] = self.lone_sample(i, j)
            return img
        fr.sample_colour = self.film_sample
        keep_filter = fr.film_filter
        if not denoise:
            fr.film_filter = lambda mean, est, lens=True: mean
        try:
            if not denoise and max_s == n:
                px = fr.render_uniform(n)
            else:
                # no lens here (lens frames go through render_lens): the filter's one pass
                px = fr.render_rounds(n, max_s, thr, lens=False)
        finally:
            fr.film_filter = keep_filter
        for p, c in enumerate(px):
            img[p // self.W, p % self.W] = c
        return img


# ---------------------------------------------------------------- lens frames of posed scenes
def render_lens(d, n):
    """A frame with a lens (aperture > 0, no shutter) of a posed scene, by film_reference.py (f64)
    or film_f32_reference.py (`precision: f32`): their scene globals are set to the scene posed
    at the frame's time (spheres and planes, point lights, black background, film's default
    sampling for a lens: 4 samples, rounds up to 64 at 0.035, the film filter)."""
    f = Frame(d, n)
    assert f.instants is None and 'samples' not in d['render']
    sc = f.scene(None)
    cam = d['camera']
    fr.W, fr.H, fr.FRAME, fr.MAX_DEPTH = f.W, f.H, n, sc.max_depth
    fr.CAM_POS, fr.FWD, fr.UPC, fr.RIGHT, fr.S = sc.pos, sc.fwd, sc.up_c, sc.right, sc.s
    fr.RHO = 0.5 * float(cam['aperture'])
    fr.FOCUS = fr.length(fr.sub(sc.pos, tuple(map(float, cam['look_at']))))
    assert sc.bg == (0.0, 0.0, 0.0) and not sc.meshes
    fr.OBJECTS = [('sphere', o['c'], o['r2'], o['m']) for o in sc.spheres] + [('plane', o['p'], o['n'], o['m']) for o in sc.planes]
    fr.MATERIALS = {str(i): o[3] for i, o in enumerate(fr.OBJECTS)}
    assert all(li['kind'] == 'point' for li in sc.lights)
    fr.LIGHTS = [dict(pos=li['q'], ia=li['ia'], id=li['id'], is_=li['is_']) for li in sc.lights]
    fr.sample_colour = FR_SAMPLE_COLOUR
    if d['render'].get('precision') == 'f32':
        f32 = importlib.reload(sys.modules['film_f32_reference']) if 'film_f32_reference' in sys.modules \
            else importlib.import_module('film_f32_reference')
        px = f32.render(4, True)
    else:
        px = fr.render_rounds(4, 64, 0.035)
    img = np.zeros((f.H, f.W, 3))
    for p, c in enumerate(px):
        img[p // f.W, p % f.W] = c
    return img


# ---------------------------------------------------------------- the cases
MATS = {k: mr.MATERIALS[k] for k in ('clay', 'blue', 'green', 'gold', 'floor', 'mirror', 'glass')}
TEX_MATS = dict(MATS, rgb8=tex.MATERIALS['rgb8'])  # an 8-bit sRGB image in diffuse and ambient
LIGHTS = copy.deepcopy(mr.LIGHTS)
FLOOR = {'plane': {'point': [0, -1, 0], 'normal': [0, 1, 0], 'material': 'floor'}}
CAMERA = {'position': [0, 1.2, 5], 'look_at': [0, -0.1, 0], 'fov': 60}


def case(objects, lights=LIGHTS, w=48, h=27, camera=CAMERA, materials=MATS, **render):
    r = {'width': w, 'height': h, 'samples': 1, 'encoding': 'linear', 'max_depth': 3,
         'background': [0.05, 0.07, 0.1]}
    r.update(render)
    r = {k: v for k, v in r.items() if v is not None}
    return {'render': r, 'camera': copy.deepcopy(camera), 'materials': materials,
            'objects': copy.deepcopy(objects), 'lights': copy.deepcopy(lights)}


# a sphere keyed by centre (curved under smooth) and radius (straight), keys by frame and by a
# rational time; a second one linear with ease stop; the floor's keys hold it still
SPHERES = [
    FLOOR,
    {'sphere': {'center': [-1.5, -0.2, 0], 'radius': 0.5, 'material': 'clay'},
     'keys': [{'frame': 6, 'center': [-1.6, 0, 0.3]},
              {'frame': 30, 'center': [-0.3, 0.5, -0.4], 'radius': 0.7},
              {'time': Frac(71, 24), 'center': [0.9, 0.1, 0.6], 'radius': 0.4},
              {'time': 4, 'center': [1.7, -0.3, -0.2]}]},
    {'sphere': {'center': [0.8, 0.9, -1.5], 'radius': 0.45, 'material': 'mirror'},
     'interpolation': 'linear',
     'keys': [{'time': 0.5, 'center': [0.8, 0.9, -1.5]},
              {'time': 2, 'center': [-0.7, 1.1, -1.2], 'radius': 0.3, 'ease': 'stop'},
              {'time': 3.25, 'center': [0.2, -0.2, -0.6], 'ease': 'stop'}]},
]
# light keys: a point light's position (curved) and colours, a spot's position, direction and
# angles (one track), a directional light's direction (turning), an ambient light's colour
LIGHTS_KEYED = [
    {'point': {'position': [4, 6, 5], 'ambient': [0.2, 0.2, 0.2], 'diffuse': [1, 1, 1], 'specular': [1, 1, 1]},
     'keys': [{'time': 0, 'diffuse': [1, 0.9, 0.8]},
              {'time': 1, 'position': [-3, 4, 4], 'diffuse': [0.6, 0.3, 0.1]},
              {'time': 2, 'position': [0, 2, 6], 'specular': [0.3, 0.3, 1]}]},
    {'spot': {'position': [-1, 3, 2], 'direction': [0.3, -1, -0.6], 'inner_angle': 15, 'outer_angle': 30,
              'ambient': [0.1, 0.1, 0.1], 'diffuse': [0.8, 0.8, 0.6], 'specular': [1, 1, 1]},
     'interpolation': 'linear',
     'keys': [{'frame': 0},
              {'frame': 24, 'position': [1.5, 3, 1], 'direction': [-0.5, -1, -0.2], 'inner_angle': 5, 'outer_angle': 12},
              {'frame': 48, 'outer_angle': 40, 'ease': 'stop'}]},
    {'directional': {'direction': [1, -1.5, -0.7], 'diffuse': [0.3, 0.25, 0.2], 'specular': [0.4, 0.4, 0.4]},
     'keys': [{'time': 0.25}, {'time': 1.75, 'direction': [-1, -1, 0.5], 'diffuse': [0.1, 0.3, 0.35]}]},
    {'ambient': {'color': [0.05, 0.05, 0.07]},
     'keys': [{'time': 0, 'color': [0, 0, 0]}, {'time': 2, 'color': [0.2, 0.1, 0.05]}]},
]
STILL_OBJECTS = [
    FLOOR,
    {'sphere': {'center': [-0.9, -0.3, 0], 'radius': 0.7, 'material': 'clay'}},
    {'sphere': {'center': [1.0, -0.5, -0.6], 'radius': 0.5, 'material': 'blue'}},
]
# a turntable (rotate 0 -> 360 about y, linear, keyed by frame) and a mesh whose translate
# (curved) and scale (straight, per factor) move under smooth with a stop; a tilting plane
MESHES = [
    FLOOR,
    {'mesh': {'file': 'arrow.obj', 'material': 'gold', 'shading': 'flat', 'translate': [-0.9, -0.2, 0], 'rotate': [0, 0, 10]},
     'interpolation': 'linear',
     'keys': [{'frame': 0, 'rotate': [0, 0, 10]}, {'frame': 48, 'rotate': [0, 360, 10]}]},
    {'mesh': {'file': 'arrow.obj', 'material': 'clay', 'shading': 'phong', 'translate': [1.2, 0, -0.5], 'scale': 0.8},
     'keys': [{'time': 0},
              {'time': 0.75, 'translate': [0.9, 0.4, 0], 'scale': [0.6, 1.1, 0.8], 'ease': 'stop'},
              {'time': 2, 'translate': [1.4, -0.3, 0.5], 'scale': [0.9, 0.5, 0.7], 'rotate': [30, -20, 45]}]},
    {'plane': {'point': [0, 0, -3], 'normal': [0, 0, 1], 'material': 'green'},
     'keys': [{'time': 0.5}, {'time': 1.5, 'point': [0, 0, -2.5], 'normal': [0.4, 0.2, 1]}]},
]
# motion blur: a fast sphere under an open shutter, the camera still
BLUR = [
    FLOOR,
    {'sphere': {'center': [0, 0, 0], 'radius': 0.45, 'material': 'clay'},
     'interpolation': 'linear',
     'keys': [{'time': 0.1, 'center': [-5, 0, 0]}, {'time': 0.4, 'center': [5, 0.5, 0]}]},
    {'sphere': {'center': [0.6, -0.6, 1.2], 'radius': 0.3, 'material': 'blue'},
     'keys': [{'time': 0.2, 'radius': 0.3}, {'time': 0.6, 'radius': 0.5}, {'time': 1, 'radius': 0.2}]},
]
# glass trees under an open shutter: a glass sphere crossing in front of a moving mirror
GLASS = [
    FLOOR,
    {'sphere': {'center': [0, 0, 1], 'radius': 0.5, 'material': 'glass'},
     'interpolation': 'linear',
     'keys': [{'time': 0.1, 'center': [-4, 0, 1]}, {'time': 0.4, 'center': [4, 0.3, 1]}]},
    {'sphere': {'center': [0.3, 0.2, -1.2], 'radius': 0.8, 'material': 'mirror'},
     'keys': [{'time': 0, 'center': [0.6, 0.2, -1.2]}, {'time': 0.5, 'center': [-0.6, 0.4, -1.4]}]},
    {'sphere': {'center': [-1.3, -0.5, -0.3], 'radius': 0.5, 'material': 'clay'}},
]
SPIN = [
    FLOOR,
    {'mesh': {'file': 'arrow.obj', 'material': 'gold', 'shading': 'phong', 'scale': 1.3},
     'interpolation': 'linear',
     'keys': [{'frame': 0, 'rotate': [0, 0, 0]}, {'frame': 12, 'rotate': [0, 360, 0]}]},
]

# the file's up axis under a keyed rotation (R(v_rotate)·U), and `origin: bottom` / `center`
# under keyed translates (the offset from the unkeyed placement)
PLACED = [
    dict(FLOOR, keys=[{'time': 1, 'point': [0, -1.1, 0]}]),  # one key: held at every time
    {'mesh': {'file': 'arrow.obj', 'material': 'gold', 'shading': 'flat', 'up': 'z', 'translate': [-1.2, 0, 0], 'rotate': [20, 0, 0]},
     'keys': [{'time': 0}, {'time': 1, 'rotate': [20, 180, 30]}, {'time': 2, 'rotate': [-40, 300, 30], 'ease': 'stop'}]},
    {'mesh': {'file': 'arrow.obj', 'material': 'clay', 'shading': 'phong', 'up': '-x', 'origin': 'bottom', 'scale': [0.8, 1.2, 0.9],
              'rotate': [0, 35, 0], 'translate': [1, -1, 0]},
     'keys': [{'time': 0.5}, {'time': 1.25, 'translate': [0.6, -0.5, 0.8]}, {'time': 2, 'translate': [1.3, -1, -0.4]}]},
    {'mesh': {'file': 'arrow.obj', 'material': 'blue', 'shading': 'gouraud', 'origin': 'center', 'scale': 0.6, 'translate': [0, 1, -1]},
     'interpolation': 'linear',
     'keys': [{'time': 0}, {'time': 2, 'translate': [0.3, 0.2, -1.5], 'ease': 'stop'}]},
]

# the first sphere again, its frame keys renumbered from the studio's first frame 1001
NTSC = [FLOOR, dict(SPHERES[1], keys=[dict(k, frame=k['frame'] + 1001) if 'frame' in k else k for k in SPHERES[1]['keys']])]
# area lights with keys: a sphere light's centre (curved), radius and colour, a rect light's
# corner (curved; its edges stay) and colours
AREA_LIGHTS = [
    {'sphere': {'center': [-2, 4, 3], 'radius': 0.6, 'ambient': [0.1, 0.1, 0.1], 'diffuse': [0.9, 0.9, 0.8], 'specular': [1, 1, 1], 'samples': 4},
     'keys': [{'time': 0}, {'time': 1, 'center': [0.5, 3, 2], 'radius': 1.2, 'diffuse': [0.5, 0.6, 1]},
              {'time': 2, 'center': [2.5, 4, 1], 'radius': 0.3}]},
    {'rect': {'corner': [1, 3, -1], 'edge_u': [1.2, 0, 0], 'edge_v': [0, -0.3, 1.2], 'diffuse': [0.6, 0.4, 0.3], 'specular': [0.5, 0.5, 0.5], 'samples': 3},
     'keys': [{'time': 0.5}, {'time': 1.5, 'corner': [-2, 2.5, 0], 'specular': [1, 0.2, 0.2], 'ambient': [0.05, 0, 0]}]},
    {'ambient': {'color': [0.03, 0.03, 0.04]}},
]

# a rect light whose edges turn (straight tracks under smooth timing) while its corner moves:
# its normal at each pose by the rect normal rule from the posed edges (motion.md)
AREA_EDGES = [
    {'rect': {'corner': [1, 3, -1], 'edge_u': [1.2, 0, 0], 'edge_v': [0, -0.3, 1.2], 'ambient': [0.05, 0.05, 0.05],
              'diffuse': [0.9, 0.7, 0.5], 'specular': [0.6, 0.6, 0.6], 'samples': 3},
     'keys': [{'time': 0.25},
              {'time': 1, 'corner': [0, 3, 0], 'edge_u': [1.0, 0.3, 0.4], 'edge_v': [-0.2, -0.5, 1.0]},
              {'time': 2, 'edge_u': [-0.3, 0.2, 1.3], 'edge_v': [-1.1, -0.2, 0.1], 'ease': 'stop'}]},
    {'ambient': {'color': [0.04, 0.04, 0.05]}},
]
# an image-mapped wall with u_axis whose normal is keyed: its texture's axis turns with it by the
# shortest turn from the still normal (motion.md); the mirror-ish floor sees it reflected
PLANE_AXIS = [
    FLOOR,
    {'plane': {'point': [0, 0, -3], 'normal': [0, 0.2, 1], 'u_axis': [1, 0.5, 0], 'material': 'rgb8'},
     'keys': [{'time': 0},
              {'time': 1, 'normal': [0.5, 0.3, 1]},
              {'time': 2, 'normal': [-0.4, 0.1, 1], 'point': [0, 0, -2.5]}]},
    {'sphere': {'center': [-0.9, -0.3, 0], 'radius': 0.7, 'material': 'clay'}},
]

# a lens (film frame without a shutter), still in f32: the poses at t, then f32.md's
# camera-relative rounding; the same frame in f64
LENS = [
    FLOOR,
    SPHERES[1],
    {'sphere': {'center': [1.0, -0.5, -0.6], 'radius': 0.5, 'material': 'blue'},
     'keys': [{'time': 0.5, 'radius': 0.3}, {'time': 2, 'radius': 0.6, 'center': [0.8, -0.4, -1]}]},
]
LENS_LIGHTS = [LIGHTS_KEYED[0]]
LENS_CAMERA = dict(CAMERA, aperture=0.12)

CASES = {
    # name: (scene, frames)
    'spheres': (case(SPHERES, max_depth=3), [0, 4, 6, 17, 30, 52, 71, 80, 96]),
    'lights': (case(STILL_OBJECTS, lights=LIGHTS_KEYED), [0, 6, 24, 30, 41, 48]),
    'meshes': (case(MESHES, w=40, h=24), [0, 7, 18, 30, 48]),
    'placed': (case(PLACED, w=40, h=24), [0, 17, 30, 44]),
    'area': (case(STILL_OBJECTS, lights=AREA_LIGHTS, w=40, h=24), [0, 18, 30, 48]),
    # a rect light sweeping under an open shutter: each sample's points at its own instant, k
    'area_blur': (case(STILL_OBJECTS, lights=AREA_LIGHTS, w=32, h=18, shutter=180, samples=4, denoise=False), [20]),
    # rect edges keyed: still frames, and a sweep under an open shutter (each instant its own normal)
    'area_edges': (case(STILL_OBJECTS, lights=AREA_EDGES, w=40, h=24), [12, 36]),
    'area_edges_blur': (case(STILL_OBJECTS, lights=AREA_EDGES, w=32, h=18, shutter=180, samples=4, denoise=False), [36]),
    # a plane with u_axis and a keyed normal (a key at frame 0: turned by the zero turn), 1 and 4 samples
    'plane_axis': (case(PLANE_AXIS, w=40, h=24, materials=TEX_MATS), [0, 18, 40]),
    'plane_axis_s4': (case(PLANE_AXIS, w=32, h=18, materials=TEX_MATS, samples=4), [30]),
    # a point light sweeping and changing colour under an open shutter
    'lights_blur': (case(STILL_OBJECTS, lights=LIGHTS_KEYED, w=32, h=18, shutter=180, samples=4, denoise=False), [12]),
    'glass_blur': (case(GLASS, w=32, h=18, shutter=180, samples=4, denoise=False, max_depth=5), [6]),
    'lens': (case(LENS, lights=LENS_LIGHTS, camera=LENS_CAMERA, w=32, h=18, samples=None, background=[0, 0, 0]), [30]),
    'lens_f32': (case(LENS, lights=LENS_LIGHTS, camera=LENS_CAMERA, w=32, h=18, samples=None, background=[0, 0, 0],
                      precision='f32'), [30]),
    'blur': (case(BLUR, w=40, h=24, shutter=180, samples=4, denoise=False), [5, 6]),
    'blur_filter': (case(BLUR, w=40, h=24, shutter=180, samples=4), [6]),
    'blur_rounds': (case(BLUR, w=32, h=18, shutter=270, shutter_offset=0.5, samples=2,
                         adaptive={'threshold': 0.05, 'max_samples': 8}, denoise=False), [5]),
    'blur_one': (case(BLUR, w=40, h=24, shutter=180, samples=1), [6]),
    # f32.md: things move while the shutter is open, so the frame is traced in f64
    'blur_f32': (case(BLUR, w=40, h=24, shutter=180, samples=4, denoise=False, precision='f32'), [6]),
    # no sampling set: film's default (rounds, the film filter)
    'blur_default': (case(BLUR, w=32, h=18, shutter=180, samples=None), [6]),
    # after the last key nothing moves while the shutter is open: a still frame (n² jitter)
    'blur_held': (dict(case(BLUR, w=40, h=24, shutter=90, samples=4, denoise=False),
                       timeline={'fps': 24, 'duration': 2, 'keyframes': [{'time': 0}]}), [26]),
    # the camera pans (linear keys) while the sphere crosses: each sample's camera and things
    # are those of its instant
    'pan': (dict(case(BLUR, w=40, h=24, shutter=180, samples=4, denoise=False),
                 timeline={'fps': 24, 'interpolation': 'linear',
                           'keyframes': [{'time': 0, 'position': [-1, 1.2, 5], 'look_at': [-0.5, -0.1, 0]},
                                         {'time': 0.5, 'position': [1, 1.5, 4.5], 'look_at': [0.5, 0, 0], 'fov': 50}]}),
            [6]),
    # NTSC rate and studio numbering: frame keys at ((n − 1001)·1001)/24000, a rational time
    # key, samples seeded by the frame's own number, the shutter's interval at 24000/1001
    'ntsc': (dict(case(NTSC, w=32, h=18, shutter=180, samples=4, denoise=False),
                  timeline={'fps': Frac(24000, 1001), 'first_frame': 1001, 'keyframes': [{'frame': 1001}]}),
             [1017, 1071, 1072]),
    'spin': (case(SPIN, w=40, h=24, shutter=180, samples=4, denoise=False,
                  camera={'position': [0, 1.5, 3.5], 'look_at': [0, 0, 0], 'fov': 50}), [5]),
}


def to_yaml(d):
    def flow(x):
        s = json.dumps(x, default=lambda f: '%d/%d' % (f.a, f.b))
        return re.sub(r'"(time|fps)": "(\d+)/(\d+)"', r'"\1": \2/\3', s)
    out = ['render: ' + flow(d['render']), 'output: out_####.png', 'camera: ' + flow(d['camera'])]
    if 'timeline' in d:
        out.append('timeline: ' + flow(d['timeline']))
    out.append('materials:')
    out += ['  %s: %s' % (k, flow(v)) for k, v in d['materials'].items()]
    out += ['objects:'] + ['  - ' + flow(o) for o in d['objects']]
    out += ['lights:'] + ['  - ' + flow(l) for l in d['lights']]
    return '\n'.join(out) + '\n'


def rayreel(rr, ypath, frame, out, *extra):
    subprocess.run([rr, 'render', ypath, '--frames', str(frame), '-o', out, '--force', '--quiet', *extra], check=True)


def main():
    names = sys.argv[1:] or list(CASES)
    rr = os.environ.get('RAYREEL')
    try:
        import OpenEXR
    except ImportError:
        OpenEXR = None
        print('no OpenEXR module: comparing the 8-bit PNG bytes only')
    tmp = tempfile.mkdtemp(prefix='motion_reference_')
    total = [0, 0]
    for name in names:
        d, frames = CASES[name]
        ypath = os.path.join(MOTIONDIR, name + '.yaml')
        open(ypath, 'w').write(to_yaml(d))
        for n in frames:
            f = Frame(d, n)
            img = render_lens(d, n) if 'aperture' in d['camera'] else f.render()
            out = mr.encode_linear(img)
            tag = '%s@%d' % (name, n)
            kind = 'film: things move while the shutter is open' if f.instants else 'still'
            if not rr:
                print(f'{tag}: rendered ({kind}; no RAYREEL to compare with)')
                continue
            rpath = os.path.join(tmp, '%s_%d.png' % (name, n))
            rayreel(rr, ypath, n, rpath)
            got = np.asarray(Image.open(rpath).convert('RGB'))
            eq = int((got == out).sum())
            total[0] += eq; total[1] += out.size
            line = f'{tag} ({kind}): png {eq}/{out.size} channel bytes equal'
            bad = np.argwhere((got != out).any(axis=2))
            if OpenEXR is not None:
                epath = os.path.join(tmp, '%s_%d.exr' % (name, n))
                rayreel(rr, ypath, n, epath, '--exr-precision', 'float')
                ex = np.ascontiguousarray(OpenEXR.File(epath).channels()['RGB'].pixels, dtype='<f4')
                mine = np.ascontiguousarray(img.astype('<f4'))
                eb = ex.view(np.uint8); mb = mine.view(np.uint8)
                e2 = int((eb == mb).sum())
                total[0] += e2; total[1] += mb.size
                line += f', exr float {e2}/{mb.size} bytes equal'
                bad = np.argwhere((ex != mine).any(axis=2))
                for (a, b) in bad[:8]:
                    line += f'\n   ({a}, {b}) rayreel {ex[a, b]} reference {mine[a, b]}'
            else:
                for (a, b) in bad[:8]:
                    line += f'\n   ({a}, {b}) rayreel {got[a, b]} reference {out[a, b]}'
            print(line, flush=True)
    shutil.rmtree(tmp, ignore_errors=True)
    if rr:
        print(f'total: {total[0]}/{total[1]} channel bytes equal')


if __name__ == '__main__':
    main()
