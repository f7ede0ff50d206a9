# An independent transcription of "Time and lens coordinates" in docs/spec/tracer.md (once in
# the README's "The arithmetic, exactly"), written from that text: it prints the bits that
# src/tracer/sample.rs's test time_and_lens_coordinates_are_the_readmes pins. Usage: python3 sample_dims_reference.py
import math, struct

M64 = (1 << 64) - 1; M32 = (1 << 32) - 1
def mix(z):
    z = (z + 0x9e3779b97f4a7c15) & M64
    z = ((z ^ (z >> 30)) * 0xbf58476d1ce4e5b9) & M64
    z = ((z ^ (z >> 27)) * 0x94d049bb133111eb) & M64
    return z ^ (z >> 31)
def unit(b): return (b >> 11) * 2.0 ** -53
def random3(h): return [unit(h), unit(mix(h)), unit(mix(mix(h)))]
def perm(i, l, p):
    w = l - 1
    for s in (1, 2, 4, 8, 16): w |= w >> s
    while True:
        i ^= p; i = (i * 0xe170893d) & M32; i ^= p >> 16; i ^= (i & w) >> 4; i ^= p >> 8
        i = (i * 0x0929eb3f) & M32; i ^= p >> 23; i ^= (i & w) >> 1; i = (i * (1 | p >> 27)) & M32
        i = (i * 0x6935fa69) & M32; i ^= (i & w) >> 11; i = (i * 0x74dcb303) & M32; i ^= (i & w) >> 2
        i = (i * 0x9e501cc3) & M32; i ^= (i & w) >> 2; i = (i * 0xc860a3df) & M32; i &= w; i ^= i >> 5
        if i < l: return (i + p % l) % l
def state(frame, pixel): return mix(mix(mix(0x9e3779b97f4a7c15 ^ frame) ^ pixel) ^ 0x6a09e667f3bcc909)
def grid(frame, pixel, n, k):
    z = state(frame, pixel); jt, ja, jb = random3(mix(z ^ k))
    s = perm(k, n * n, z >> 32); c = perm(k, n * n, z & M32)
    return [(s + jt) / (n * n), ((c % n) + ja) / n, ((c // n) + jb) / n]
def r2(frame, pixel, k):
    z = state(frame, pixel); sh = random3(mix(z ^ M32))
    B = [0.8191725133961645, 0.6710436067037893, 0.5497004779019703]
    return [math.fmod(sh[d] + (k + 1) * B[d], 1.0) for d in range(3)]
def one(frame, pixel, k): return random3(mix(state(frame, pixel) ^ k))
for k in range(4): print("grid", k, [x.hex() for x in grid(7, 12345, 2, k)])
for k in (0, 5, 31): print("r2", k, [x.hex() for x in r2(7, 12345, k)])
print("centre", [x.hex() for x in one(7, 12345, 0)])
print("grid3", 8, [x.hex() for x in grid(3, 999, 3, 8)])
def bits(x): return "0x%016x" % struct.unpack("<Q", struct.pack("<d", x))[0]
print("RUST")
rows = [("Pattern::Grid(2)", 7, 12345, k, grid(7, 12345, 2, k)) for k in (0, 3)]
rows += [("Pattern::Grid(3)", 3, 999, 8, grid(3, 999, 3, 8))]
rows += [("Pattern::R2", 7, 12345, k, r2(7, 12345, k)) for k in (0, 31)]
rows += [("Pattern::Centre", 7, 12345, 0, one(7, 12345, 0))]
for p, f, px, k, v in rows:
    print(f"        ({p}, {f}, {px}, {k}, [{', '.join(bits(x) for x in v)}]),")
