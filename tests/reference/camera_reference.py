# An independent implementation of docs/spec/timeline.md (once the README's "Camera motion,
# exactly"), written from that text, not from rayreel's code: it prints the camera of every
# frame of a keyframed sequence as `rayreel camera --format csv` does. tests/camera_motion.rs
# compares the CSV files it wrote (camera_*.csv here) with rayreel to 1e-9.
# Usage: python3 camera_reference.py SEQUENCE.yaml > OUT.csv   (needs PyYAML)
# It differs from rayreel on purpose where the text leaves a choice: it finds the arc-length
# parameter by bisection rather than Newton steps, and sums in its own order.
import math, sys

NODES = [0.1834346424956498, 0.5255324099163290, 0.7966664774136267, 0.9602898564975363]
WEIGHTS = [0.3626837833783620, 0.3137066458778873, 0.2223810344533745, 0.1012285362903763]

def sub(a, b): return [a[i] - b[i] for i in range(3)]
def add(a, b): return [a[i] + b[i] for i in range(3)]
def mul(a, s): return [a[i] * s for i in range(3)]
def length(a): return math.sqrt(sum(x * x for x in a))
def unit(a):
    l = length(a)
    return mul(a, 1.0 / l) if l > 0 else None

class Curve:
    def __init__(self, p0, p1, p2, p3):
        self.p1, self.p2 = p1, p2
        v = sub(p2, p1)
        b = math.sqrt(length(v))
        if p0 is None or p0 == p1:
            self.t1 = v
        else:
            u = sub(p1, p0); a = math.sqrt(length(u))
            self.t1 = mul(add(unit(u), unit(v)), a * b * b / (a + b))
        if p3 is None or p3 == p2:
            self.t2 = v
        else:
            w = sub(p3, p2); c = math.sqrt(length(w))
            self.t2 = mul(add(unit(v), unit(w)), b * b * c / (b + c))
        self.parts = [0.0]
        for j in range(16):
            self.parts.append(self.parts[-1] + self.gauss(j / 16, (j + 1) / 16))
        self.length = self.parts[16]

    def point(self, x):
        h = [2*x**3 - 3*x**2 + 1, x**3 - 2*x**2 + x, -2*x**3 + 3*x**2, x**3 - x**2]
        return [h[0]*self.p1[i] + h[1]*self.t1[i] + h[2]*self.p2[i] + h[3]*self.t2[i] for i in range(3)]

    def speed(self, x):
        d = [(6*x*x - 6*x) * (self.p1[i] - self.p2[i]) + (3*x*x - 4*x + 1) * self.t1[i]
             + (3*x*x - 2*x) * self.t2[i] for i in range(3)]
        return length(d)

    def gauss(self, a, b):
        m, r = (a + b) / 2, (b - a) / 2
        return r * sum(w * (self.speed(m - r * x) + self.speed(m + r * x)) for x, w in zip(NODES, WEIGHTS))

    def at(self, s):
        if s <= 0: return self.p1
        if s >= self.length: return self.p2
        j = max(i for i in range(16) if self.parts[i] <= s)
        lo, hi = j / 16, (j + 1) / 16
        for _ in range(200):
            mid = (lo + hi) / 2
            if mid in (lo, hi): break
            if self.parts[j] + self.gauss(j / 16, mid) < s: lo = mid
            else: hi = mid
        return self.point((lo + hi) / 2)

class Track:
    def __init__(self, times, q, stops, curved, timing):
        self.times, self.q, self.timing = times, q, timing
        n = len(q)
        self.shapes, self.L = [], []
        for k in range(n - 1):
            if q[k] == q[k + 1]:
                self.shapes.append(None); self.L.append(0.0)
            elif curved:
                c = Curve(q[k - 1] if k > 0 else None, q[k], q[k + 1], q[k + 2] if k + 2 < n else None)
                self.shapes.append(c); self.L.append(c.length)
            else:
                self.shapes.append('line'); self.L.append(length(sub(q[k + 1], q[k])))
        self.stops = list(stops)
        if timing == 'smooth':
            for k in range(1, n - 1):
                u, v = unit(sub(q[k], q[k - 1])), unit(sub(q[k + 1], q[k]))
                if u and v and length(add(u, v)) < 1e-12: self.stops[k] = True
        self.S = [0.0]
        for l in self.L: self.S.append(self.S[-1] + l)
        if timing == 'smooth' and n > 1: self.m = self.rates()

    def delta(self, k):
        h = self.times[k + 1] - self.times[k]
        if self.L[k] == 0: return 0.0
        return min(self.L[k] / h, 1e300) if h > 0 else 1e300

    def rates(self):
        n = len(self.q); d = [self.delta(k) for k in range(n - 1)]; m = [0.0] * n
        for k in range(1, n - 1):
            if not self.stops[k] and d[k - 1] > 0 and d[k] > 0:
                m[k] = min((d[k - 1] + d[k]) / 2, 3 * d[k - 1], 3 * d[k])
        free0, free1 = not self.stops[0] and d[0] > 0, not self.stops[n - 1] and d[n - 2] > 0
        if n == 2 and free0 and free1: return [d[0], d[0]]
        if free0: m[0] = (3 * d[0] - m[1]) / 2
        if free1: m[n - 1] = (3 * d[n - 2] - m[n - 2]) / 2
        return m

    def place(self, k, s):
        shape = self.shapes[k]
        if shape is None: return self.q[k]
        if shape == 'line':
            return self.q[k + 1] if s >= self.L[k] else add(self.q[k], mul(sub(self.q[k + 1], self.q[k]), s / self.L[k]))
        return shape.at(s)

    def at(self, t):
        """(value, dσ/dt)."""
        T, n = self.times, len(self.q)
        if n == 1 or t < T[0]: return self.q[0], 0.0
        if t > T[-1]: return self.q[-1], 0.0
        if self.timing == 'constant':
            rate = self.S[-1] / (T[-1] - T[0])
            s = min(max(self.S[-1] * ((t - T[0]) / (T[-1] - T[0])), 0.0), self.S[-1])
            k = min(max(i for i in range(n) if self.S[i] <= s), n - 2)
            value, s = k, s - self.S[k]
        else:
            k = min(max(i for i in range(n) if T[i] <= t), n - 2)
            h = T[k + 1] - T[k]; u = (t - T[k]) / h; L = self.L[k]
            if self.timing == 'linear':
                a, b = self.stops[k], self.stops[k + 1]
                e, de = {(False, False): (u, 1.0), (True, False): (u * u, 2 * u),
                         (False, True): (u * (2 - u), 2 - 2 * u),
                         (True, True): (u * u * (3 - 2 * u), 6 * u * (1 - u))}[(a, b)]
                s, rate = L * e, self.delta(k) * de
            else:
                m0, m1 = self.m[k], self.m[k + 1]
                s = L * (3*u*u - 2*u**3) + h * (m0 * (u**3 - 2*u*u + u) + m1 * (u**3 - u*u))
                s = min(max(s, 0.0), L)
                rate = max(self.delta(k) * (6*u - 6*u*u) + m0 * (3*u*u - 4*u + 1) + m1 * (3*u*u - 2*u), 0.0)
        if t == T[-1]: return self.q[-1], rate
        return self.place(k, s), rate

def main(path):
    import yaml  # here, so that importing the tracks needs no PyYAML
    seq = yaml.safe_load(open(path))
    tl, cam = seq['timeline'], seq.get('camera') or {}
    fps = float(tl.get('fps', 24)); smooth = tl.get('interpolation', 'smooth') == 'smooth'
    prev = {'position': cam.get('position'), 'look_at': cam.get('look_at'),
            'up': cam.get('up', [0, 1, 0]), 'fov': cam.get('fov', 90)}
    if 'focus_distance' in cam: prev['focus_distance'] = cam['focus_distance']
    keys = []
    for k in tl['keyframes']:
        pose = {f: [float(x) for x in k.get(f, prev[f])] if f != 'fov' else float(k.get(f, prev[f]))
                for f in ('position', 'look_at', 'up', 'fov')}
        pose['up'] = unit(pose['up'])
        # A key without focus_distance keeps the previous key's; before any, its look_at's.
        focus = k.get('focus_distance', prev.get('focus_distance'))
        if focus is not None: pose['focus_distance'] = float(focus)
        keys.append((float(k['time']), pose, k.get('ease', 'pass') == 'stop')); prev = pose
    times = [k[0] for k in keys]; stops = [k[2] for k in keys]
    values = lambda f: [k[1][f] if f != 'fov' else [k[1][f], 0.0, 0.0] for k in keys]
    timing = 'smooth' if smooth else 'linear'
    constant = tl.get('speed') == 'constant'
    position = Track(times, values('position'), stops, smooth, 'constant' if constant else timing)
    passes = times
    if constant:
        S = position.S
        passes = [times[0] + (times[-1] - times[0]) * (s / S[-1]) for s in S]; passes[-1] = times[-1]
    others = [Track(passes, values(f), stops, smooth and f != 'fov', timing) for f in ('look_at', 'up', 'fov')]
    focus = None
    if any('focus_distance' in k[1] for k in keys):
        at_key = [[k[1].get('focus_distance', length(sub(k[1]['look_at'], k[1]['position']))), 0.0, 0.0] for k in keys]
        focus = Track(passes, at_key, stops, False, timing)
    if 'duration' in tl: frames = round(float(tl['duration']) * fps)
    else: frames = max(0, math.ceil(times[-1] * fps - 1e-6)) + 1
    print("frame,time,position_x,position_y,position_z,look_at_x,look_at_y,look_at_z,up_x,up_y,up_z,fov,speed,focus_distance")
    for n in range(frames):
        t = n / fps
        p, speed = position.at(t)
        l, u, f = (tr.at(t)[0] for tr in others)
        d = focus.at(t)[0][0] if focus else length(sub(l, p))
        cells = [n, t, *p, *l, *u, f[0], speed, d]
        print(",".join(repr(float(c)) if i else str(c) for i, c in enumerate(cells)))

if __name__ == '__main__':  # importable: motion_reference.py uses its tracks
    main(sys.argv[1])
