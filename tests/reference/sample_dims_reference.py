# An independent transcription of docs/spec/tracer.md's "Sample offsets." (mix, unit, the
# pixel's seed), "Film frames" (the Owen-scrambled Sobol' points: direction numbers, point,
# seeds, scramble) and "Time and lens coordinates" (R3 and the lone sample), written from that
# text alone: it prints the bits that src/tracer/sobol.rs's test film_points_are_the_specs and
# src/tracer/sample.rs's test time_and_lens_coordinates_are_the_readmes pin.
# Usage: python3 sample_dims_reference.py
import math, struct

M64 = (1 << 64) - 1; M32 = (1 << 32) - 1
# Sample offsets: splitmix64's finaliser, unit, the pixel's seed.
def mix(z):
    z = (z + 0x9e3779b97f4a7c15) & M64
    z = ((z ^ (z >> 30)) * 0xbf58476d1ce4e5b9) & M64
    z = ((z ^ (z >> 27)) * 0x94d049bb133111eb) & M64
    return z ^ (z >> 31)
def unit(b): return (b >> 11) * 2.0 ** -53
def seed(frame, pixel): return mix(mix(0x9e3779b97f4a7c15 ^ frame) ^ pixel)

# Film frames: direction numbers v[d][j], j = 0 .. 31.
JOE_KUO = [(1, 0, [1]), (2, 1, [1, 3]), (3, 1, [1, 3, 1]), (3, 2, [1, 1, 1])]
def directions():
    v = [[1 << (31 - j) for j in range(32)]]
    for s, a, m0 in JOE_KUO:
        m = list(m0)
        for k in range(s, 32):
            x = m[k - s] ^ (m[k - s] << s)
            for i in range(1, s):
                if (a >> (s - 1 - i)) & 1: x ^= m[k - i] << i
            m.append(x)
        v.append([(m[j] << (31 - j)) & M32 for j in range(32)])
    return v
V = directions()
def point(d, k):
    p = 0
    for j in range(32):
        if (k >> j) & 1: p ^= V[d][j]
    return p
def seeds(frame, pixel):
    w0 = mix(seed(frame, pixel) ^ 0x3c6ef372fe94f82b); w1 = mix(w0); w2 = mix(w1)
    return [w0 >> 32, w0 & M32, w1 >> 32, w1 & M32, w2 >> 32]
def rev(x): return int(format(x, "032b")[::-1], 2)
def lk(x, s):
    x = (x + s) & M32
    for c in (0x6c50b47c, 0xb82f1e52, 0xc7afe638, 0x8d22f6e6): x ^= (x * c) & M32
    return x
def scramble(x, s): return rev(lk(rev(x), s))
def film(frame, pixel, k):
    s = seeds(frame, pixel)
    return [scramble(point(d, k), s[d]) * 2.0 ** -32 for d in range(5)]

# Time and lens coordinates: the pixel's state, random3, R3 and the lone sample.
def state(frame, pixel): return mix(seed(frame, pixel) ^ 0x6a09e667f3bcc909)
def random3(h): return [unit(h), unit(mix(h)), unit(mix(mix(h)))]
def fract(x): return x - math.trunc(x)
def r3(frame, pixel, k):
    sg = random3(mix(state(frame, pixel) ^ M32))
    B = [0.8191725133961645, 0.6710436067037893, 0.5497004779019703]
    return [fract(sg[d] + (k + 1) * B[d]) for d in range(3)]
def one(frame, pixel, k): return random3(mix(state(frame, pixel) ^ k))

def bits(x): return "0x%016x" % struct.unpack("<Q", struct.pack("<d", x))[0]
FILM = [(7, 12345, 0), (7, 12345, 1), (7, 12345, 5), (3, 999, 63), (3, 999, 4095)]
for f, px, k in FILM: print("film", f, px, k, [x.hex() for x in film(f, px, k)])
for k in (0, 5, 31): print("r3", k, [x.hex() for x in r3(7, 12345, k)])
print("centre", [x.hex() for x in one(7, 12345, 0)])
print("RUST")
for f, px, k in FILM:
    print(f"        ({f}, {px}, {k}, [{', '.join(bits(x) for x in film(f, px, k))}]),")
rows = [("Pattern::R2", 7, 12345, k, r3(7, 12345, k)) for k in (0, 31)]
rows += [("Pattern::Centre", 7, 12345, 0, one(7, 12345, 0))]
for p, f, px, k, v in rows:
    print(f"        ({p}, {f}, {px}, {k}, [{', '.join(bits(x) for x in v)}]),")
