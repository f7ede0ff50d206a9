//! Owen-scrambled Sobol' points in five dimensions: where the samples of a frame with motion
//! blur or depth of field fall, jointly in the pixel (u, v), on the lens (a, b) and in time (τ).
//!
//! Sobol's first five dimensions with Joe and Kuo's direction numbers, each dimension
//! scrambled by Burley's hash-based nested uniform scramble ("Practical Hash-based Owen
//! Scrambling", JCGT 2020) seeded per pixel. Every power-of-two prefix of a pixel's samples
//! is then a scrambled (t, m, 5)-net: the first 4
//! samples fall in the four quarters of the pixel's width, its height, the shutter interval
//! and the lens's two sides at once, and each doubling keeps that, which is what adaptive rounds extend.

/// Bits of the direction numbers: a coordinate is a 32-bit fraction.
const BITS: usize = 32;

/// Sobol' direction numbers v_j (as 32-bit fractions) of dimension `d` (0-based), from the
/// primitive polynomial of degree s with coefficient bits a and initial m_1..m_s (Joe and
/// Kuo's new-joe-kuo-6.21201 table; dimension 0 is the van der Corput sequence).
const fn directions(s: usize, a: u32, m0: [u32; 3]) -> [u32; BITS] {
    let mut m = [0u32; BITS];
    let mut k = 0;
    while k < BITS {
        m[k] = if k < s {
            m0[k]
        } else {
            // m_k = 2^s m_(k−s) ⊕ m_(k−s) ⊕ the XOR over j = 1..s−1 of 2^j a_j m_(k−j),
            // a_j the j-th of a's s − 1 bits from the most significant.
            let mut x = m[k - s] ^ (m[k - s] << s);
            let mut j = 1;
            while j < s {
                if (a >> (s - 1 - j)) & 1 == 1 {
                    x ^= m[k - j] << j;
                }
                j += 1;
            }
            x
        };
        k += 1;
    }
    let mut v = [0u32; BITS];
    let mut j = 0;
    while j < BITS {
        v[j] = m[j] << (BITS - 1 - j);
        j += 1;
    }
    v
}

/// The direction numbers of the five dimensions (polynomials 1, x + 1, x² + x + 1,
/// x³ + x + 1, x³ + x² + 1).
const V: [[u32; BITS]; 5] = [
    van_der_corput(),
    directions(1, 0, [1, 0, 0]),
    directions(2, 1, [1, 3, 0]),
    directions(3, 1, [1, 3, 1]),
    directions(3, 2, [1, 1, 1]),
];

/// Dimension 0: v_j = 2^(31−j), the index's bits reversed.
const fn van_der_corput() -> [u32; BITS] {
    let mut v = [0u32; BITS];
    let mut j = 0;
    while j < BITS {
        v[j] = 1 << (BITS - 1 - j);
        j += 1;
    }
    v
}

/// Sobol' point `i` in the five dimensions, unscrambled: the XOR of the direction numbers of
/// i's set bits.
#[inline(always)]
pub fn point(i: u32) -> [u32; 5] {
    let mut x = [0u32; 5];
    let mut bits = i;
    while bits != 0 {
        let j = bits.trailing_zeros() as usize;
        x[0] ^= V[0][j];
        x[1] ^= V[1][j];
        x[2] ^= V[2][j];
        x[3] ^= V[3][j];
        x[4] ^= V[4][j];
        bits &= bits - 1;
    }
    x
}

/// Laine and Karras's permutation with Burley's constants: each output bit depends only on
/// the input bits at and below it.
#[inline(always)]
fn laine_karras(mut x: u32, seed: u32) -> u32 {
    x = x.wrapping_add(seed);
    x ^= x.wrapping_mul(0x6c50_b47c);
    x ^= x.wrapping_mul(0xb82f_1e52);
    x ^= x.wrapping_mul(0xc7af_e638);
    x ^= x.wrapping_mul(0x8d22_f6e6);
    x
}

/// Owen's nested uniform scramble of a 32-bit fraction: bit j (from the top) flipped by a
/// hash of the bits above it. `Packet::at` computes it with the bits already reversed.
#[cfg(test)]
fn scramble(x: u32, seed: u32) -> u32 {
    laine_karras(x.reverse_bits(), seed).reverse_bits()
}

/// The scramble seeds of a pixel whose hash state is `state`: w₀ = mix(state ⊕ KEY),
/// w₁ = mix(w₀), w₂ = mix(w₁); dimensions 0 to 4 take w₀'s high 32 bits, then its low
/// bits, w₁'s high and low, w₂'s high.
pub fn seeds(state: u64) -> [u32; 5] {
    use super::sample::mix;
    const KEY: u64 = 0x3c6e_f372_fe94_f82b;
    let w0 = mix(state ^ KEY);
    let w1 = mix(w0);
    let w2 = mix(w1);
    let (hi, lo) = (|w: u64| (w >> 32) as u32, |w: u64| w as u32);
    [hi(w0), lo(w0), hi(w1), lo(w1), hi(w2)]
}

/// The scramble seeds of up to 32 pixels traced together, dimension by dimension with the
/// pixels innermost, so that scrambling sample k for all of them is five loops the compiler
/// turns into vector instructions. Sample k of every pixel is the same Sobol' point
/// scrambled by its own seeds.
#[derive(Clone, Copy)]
pub struct Packet<const N: usize> {
    seeds: [[u32; N]; 5],
}

impl<const N: usize> Packet<N> {
    /// The seeds of pixels `state(0..n)` (lanes from n on repeat lane 0).
    pub fn new(n: usize, state: impl Fn(usize) -> u64) -> Packet<N> {
        let mut seeds = [[0u32; N]; 5];
        let lead = self::seeds(state(0));
        for lane in 0..N {
            let s = if lane == 0 || lane >= n {
                lead
            } else {
                self::seeds(state(lane))
            };
            for (dim, seed) in seeds.iter_mut().zip(s) {
                dim[lane] = seed;
            }
        }
        Packet { seeds }
    }

    /// Sample `k` of every lane: its five coordinates in [0, 1), the pixel (u, v) on
    /// dimensions 0 and 1, the only pair that is a (0, 2)-sequence; the lens (a, b) on 2
    /// and 3, the best of the other pairs (t ≤ 2 for the first 1024 points, 1 mostly); time
    /// τ on 4, whose projection alone is as even as any.
    /// Only lanes 0..n are written: the packet's lanes, so no work goes to the others.
    #[inline(always)]
    pub fn at(&self, k: u32, n: usize, out: &mut [[f64; N]; 5]) {
        // Reversed, the direction numbers' XOR is already what Laine-Karras permutes.
        let x = point(k).map(u32::reverse_bits);
        for ((out, seeds), x) in out.iter_mut().zip(&self.seeds).zip(x) {
            for (o, &seed) in out.iter_mut().zip(seeds).take(n) {
                let y = laine_karras(x, seed).reverse_bits();
                *o = f64::from(y) * (1.0 / 4_294_967_296.0);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The first points of the unscrambled sequence as scipy.stats.qmc.Sobol(5,
    /// scramble=False) gives them, in Gray-code order (point n is our point n ⊕ n/2). All
    /// 4096 points of scipy 1.x agreed when this was written.
    #[test]
    fn unscrambled_points_are_sobols() {
        let want: [[f64; 5]; 8] = [
            [0.0, 0.0, 0.0, 0.0, 0.0],
            [0.5, 0.5, 0.5, 0.5, 0.5],
            [0.75, 0.25, 0.25, 0.25, 0.75],
            [0.25, 0.75, 0.75, 0.75, 0.25],
            [0.375, 0.375, 0.625, 0.875, 0.375],
            [0.875, 0.875, 0.125, 0.375, 0.875],
            [0.625, 0.125, 0.875, 0.625, 0.625],
            [0.125, 0.625, 0.375, 0.125, 0.125],
        ];
        for (i, w) in want.iter().enumerate() {
            let i = i as u32;
            let got = point(i ^ (i >> 1)).map(|x| f64::from(x) / 4_294_967_296.0);
            assert_eq!(&got, w, "point {i}");
        }
    }

    #[test]
    fn every_power_of_two_prefix_is_stratified_in_each_dimension() {
        for state in [1u64, 77, 0xdead_beef_0000_1234] {
            let p = Packet::<4>::new(1, |_| state);
            let at = |k: u32| {
                let mut out = [[0.0; 4]; 5];
                p.at(k, 4, &mut out);
                let seeds = seeds(state);
                let want = point(k);
                for d in 0..5 {
                    let x = scramble(want[d], seeds[d]);
                    assert_eq!(out[d][0], f64::from(x) / 4_294_967_296.0);
                    assert_eq!(out[d][3], out[d][0], "lanes past n repeat lane 0");
                }
                out.map(|d| (d[0] * 4_294_967_296.0) as u32)
            };
            for m in 0..=8u32 {
                for d in 0..5 {
                    let mut seen = vec![false; 1 << m];
                    for k in 0..1u32 << m {
                        let cell = if m == 0 { 0 } else { at(k)[d] >> (32 - m) };
                        assert!(!seen[cell as usize], "state {state} m {m} dim {d}");
                        seen[cell as usize] = true;
                    }
                }
            }
            // Pixel position and lens: every 16 samples fill a 4×4 grid of each pair.
            for pair in [(0, 1), (2, 3)] {
                let mut seen = [false; 16];
                for k in 0..16 {
                    let x = at(k);
                    let cell = (x[pair.0] >> 30) * 4 + (x[pair.1] >> 30);
                    assert!(!seen[cell as usize], "state {state} pair {pair:?}");
                    seen[cell as usize] = true;
                }
            }
        }
    }

    #[test]
    fn scrambling_is_a_bijection_that_keeps_prefixes() {
        // Bits from the top depend only on the bits above them.
        for seed in [0u32, 1, 0x1234_5678, u32::MAX] {
            for x in [0u32, 5, 0x8000_0000, 0xffff_0000] {
                let y = scramble(x, seed);
                let z = scramble(x ^ 1, seed);
                assert_eq!(y >> 1, z >> 1, "seed {seed} x {x}");
                assert_ne!(y, z);
            }
        }
    }

    /// Film-frame Sobol' points through the API the tracer uses (the pixel's seed, then
    /// `Packet::at`), bit for bit as tests/reference/sample_dims_reference.py prints them,
    /// written from "Film frames" in docs/spec/tracer.md alone.
    #[test]
    fn film_points_are_the_specs() {
        let cases: [(u64, u64, u32, [u64; 5]); 5] = [
            (
                7,
                12345,
                0,
                [
                    0x3fc7ffffed800000,
                    0x3fe068508f400000,
                    0x3feaf14fb4200000,
                    0x3fe2a72d34a00000,
                    0x3fe16a7ca0c00000,
                ],
            ),
            (
                7,
                12345,
                1,
                [
                    0x3fe1a9fa93e00000,
                    0x3fdf9f183ac00000,
                    0x3faffa39c8000000,
                    0x3fda577426800000,
                    0x3fdd4dac35000000,
                ],
            ),
            (
                7,
                12345,
                5,
                [
                    0x3fe6416e05e00000,
                    0x3fe7934dace00000,
                    0x3fde131021800000,
                    0x3fd5962c63400000,
                    0x3fd1458441400000,
                ],
            ),
            (
                3,
                999,
                63,
                [
                    0x3fde1f11ef400000,
                    0x3fc138e4b0000000,
                    0x3fe90232f8e00000,
                    0x3fee95acd9600000,
                    0x3fea0f1376800000,
                ],
            ),
            (
                3,
                999,
                4095,
                [
                    0x3fdef833dc400000,
                    0x3fd7473cde800000,
                    0x3fe9b8a9f5600000,
                    0x3fe5218f58e00000,
                    0x3fd8e8b939400000,
                ],
            ),
        ];
        for (frame, pixel, k, want) in cases {
            let z = super::super::sample::state(frame, pixel);
            let mut out = [[0.0f64; 1]; 5];
            Packet::<1>::new(1, |_| z).at(k, 1, &mut out);
            assert_eq!(
                out.map(|d| d[0].to_bits()),
                want,
                "frame {frame} pixel {pixel} sample {k}"
            );
        }
    }
}
