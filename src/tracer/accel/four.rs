//! A wide node's 4 children side by side: the box tests of one ray (`single`) and of a
//! packet's bounds (`frustum`) run on all 4 at once. Each operation is the scalar one it
//! replaces, lane by lane: `sub`, `mul`, `min` (a < b ? a : b, as `Real::min`), `max`
//! (a > b ? a : b) and ≤, the f32 planes widened exactly in f64. Written as loops over the
//! children, the f32 tests stayed scalar (a tenth of a single ray's instructions were its box
//! tests), so f32 runs in an SSE register (x86-64's baseline, so every kernel has it); the
//! f64 loops LLVM turns into one 256-bit register by itself, so f64 stays a loop (`Plain`).

use super::wide::WIDTH;

/// Four values of one precision.
pub(crate) trait Four: Copy {
    type R: Copy;
    /// A row of 4 f32 plane coordinates (exactly, in f64).
    fn load(row: &[f32; WIDTH]) -> Self;
    fn splat(x: Self::R) -> Self;
    fn sub(self, o: Self) -> Self;
    fn mul(self, o: Self) -> Self;
    fn min(self, o: Self) -> Self;
    fn max(self, o: Self) -> Self;
    /// Bit c set where self[c] ≤ o[c].
    fn le(self, o: Self) -> u32;
    fn array(self) -> [Self::R; WIDTH];
}

#[cfg(target_arch = "x86_64")]
mod sse {
    use super::{Four, WIDTH};
    use std::arch::x86_64::*;

    /// Four f32 in one register.
    #[derive(Clone, Copy)]
    pub(crate) struct Four32(__m128);

    // SAFETY (every `unsafe` below): SSE is part of x86-64, so these intrinsics run on any
    // CPU this binary runs on; loads and stores go through references to `[f32; 4]`, which
    // are in bounds.
    impl Four for Four32 {
        type R = f32;
        #[inline(always)]
        fn load(row: &[f32; WIDTH]) -> Self {
            Four32(unsafe { _mm_loadu_ps(row.as_ptr()) })
        }
        #[inline(always)]
        fn splat(x: f32) -> Self {
            Four32(unsafe { _mm_set1_ps(x) })
        }
        #[inline(always)]
        fn sub(self, o: Self) -> Self {
            Four32(unsafe { _mm_sub_ps(self.0, o.0) })
        }
        #[inline(always)]
        fn mul(self, o: Self) -> Self {
            Four32(unsafe { _mm_mul_ps(self.0, o.0) })
        }
        #[inline(always)]
        fn min(self, o: Self) -> Self {
            Four32(unsafe { _mm_min_ps(self.0, o.0) })
        }
        #[inline(always)]
        fn max(self, o: Self) -> Self {
            Four32(unsafe { _mm_max_ps(self.0, o.0) })
        }
        #[inline(always)]
        fn le(self, o: Self) -> u32 {
            unsafe { _mm_movemask_ps(_mm_cmple_ps(self.0, o.0)) as u32 }
        }
        #[inline(always)]
        fn array(self) -> [f32; WIDTH] {
            let mut out = [0f32; WIDTH];
            unsafe { _mm_storeu_ps(out.as_mut_ptr(), self.0) };
            out
        }
    }
}

#[cfg(target_arch = "x86_64")]
pub(crate) use sse::Four32;

/// Plain arrays with the same lane-by-lane definitions: f64 everywhere (a pair of SSE2
/// registers in their place cost 10% more instructions on f64 mesh frames), f32 off x86-64.
mod plain {
    use super::{Four, WIDTH};

    #[derive(Clone, Copy)]
    pub(crate) struct Plain<R>([R; WIDTH]);
    #[cfg(not(target_arch = "x86_64"))]
    pub(crate) type Four32 = Plain<f32>;
    pub(crate) type Four64 = Plain<f64>;

    /// `out[c] = f(a[c], b[c])`, written as a loop: closures passed to `array::map` or
    /// `from_fn` may be compiled outside the kernel's target feature.
    macro_rules! each {
        ($a:expr, $b:expr, |$x:ident, $y:ident| $e:expr) => {{
            let mut out = $a;
            for c in 0..WIDTH {
                let ($x, $y) = ($a[c], $b[c]);
                out[c] = $e;
            }
            Plain(out)
        }};
    }

    macro_rules! plain {
        ($r:ty) => {
            impl Four for Plain<$r> {
                type R = $r;
                #[inline(always)]
                fn load(row: &[f32; WIDTH]) -> Self {
                    each!([0.0 as $r; WIDTH], row, |_x, p| <$r>::from(p))
                }
                #[inline(always)]
                fn splat(x: $r) -> Self {
                    Plain([x; WIDTH])
                }
                #[inline(always)]
                fn sub(self, o: Self) -> Self {
                    each!(self.0, o.0, |p, q| p - q)
                }
                #[inline(always)]
                fn mul(self, o: Self) -> Self {
                    each!(self.0, o.0, |p, q| p * q)
                }
                #[inline(always)]
                fn min(self, o: Self) -> Self {
                    each!(self.0, o.0, |p, q| if p < q { p } else { q })
                }
                #[inline(always)]
                fn max(self, o: Self) -> Self {
                    each!(self.0, o.0, |p, q| if p > q { p } else { q })
                }
                #[inline(always)]
                fn le(self, o: Self) -> u32 {
                    let mut m = 0;
                    for c in 0..WIDTH {
                        m |= u32::from(self.0[c] <= o.0[c]) << c;
                    }
                    m
                }
                #[inline(always)]
                fn array(self) -> [$r; WIDTH] {
                    self.0
                }
            }
        };
    }
    #[cfg(not(target_arch = "x86_64"))]
    plain!(f32);
    plain!(f64);
}

#[cfg(not(target_arch = "x86_64"))]
pub(crate) use plain::Four32;
pub(crate) use plain::Four64;

#[cfg(test)]
mod tests {
    use super::*;

    /// Each operation against its scalar definition, NaN, infinities and signed zeros
    /// included (min and max return the second operand on a NaN or a tie, as `Real`'s do).
    /// A NaN result is compared as NaN: its sign and payload are not defined (and no box test
    /// meets one: planes, origins and reciprocal directions are finite).
    #[test]
    fn four_lanes_match_the_scalar_rules() {
        let values = [
            0.0f32,
            -0.0,
            1.5,
            -2.25,
            f32::INFINITY,
            -f32::INFINITY,
            f32::NAN,
            3e-39,
        ];
        for &a in &values {
            for &b in &values {
                let (x, y) = ([a, b, -a, 1.0], [b, a, b, -0.0]);
                check(Four32::load(&x), Four32::load(&y), x, y);
                let w = |v: [f32; 4]| v.map(f64::from);
                check(Four64::load(&x), Four64::load(&y), w(x), w(y));
            }
        }
    }

    fn check<F: Four>(a: F, b: F, x: [F::R; WIDTH], y: [F::R; WIDTH])
    where
        F::R: PartialOrd + std::ops::Sub<Output = F::R> + std::ops::Mul<Output = F::R>,
        F::R: Into<f64>,
    {
        let bits = |v: [F::R; WIDTH]| {
            v.map(|r| match r.into() {
                r if r.is_nan() => f64::NAN.to_bits(),
                r => r.to_bits(),
            })
        };
        let each = |f: fn(F::R, F::R) -> F::R| std::array::from_fn(|c| f(x[c], y[c]));
        assert_eq!(bits(a.array()), bits(x));
        assert_eq!(bits(a.sub(b).array()), bits(each(|p, q| p - q)));
        assert_eq!(bits(a.mul(b).array()), bits(each(|p, q| p * q)));
        assert_eq!(
            bits(a.min(b).array()),
            bits(each(|p, q| if p < q { p } else { q }))
        );
        assert_eq!(
            bits(a.max(b).array()),
            bits(each(|p, q| if p > q { p } else { q }))
        );
        let le = (0..WIDTH).fold(0, |m, c| m | u32::from(x[c] <= y[c]) << c);
        assert_eq!(a.le(b), le);
        let s = F::splat(x[2]).array();
        assert_eq!(bits(s), bits([x[2]; WIDTH]));
    }
}
