//! Lane types: N values of f64 (or of f32) under one instruction. Every operation here is one
//! IEEE-754 operation per lane (add, sub, mul, div, sqrt, compare, select, sign-bit copies): no
//! fused multiply-add, no approximation, so lane k of any width computes exactly the bits the
//! one-lane type of its precision computes. That is what lets the widest kernel the CPU has
//! write the same bytes as the scalar oracle (`F64x1`, `F32x1`).
//!
//! Values enter and leave as f64 whatever the lane type: `splat` and `load` round to the
//! lane's precision (to nearest, as `as f32`), `store` and `lane` widen exactly. So one
//! generic kernel serves both precisions, and scene data is rounded once, where it enters.
//!
//! Comparisons are ordered (false when either side is NaN), like Rust's `<` on f64; `min` and
//! `max` follow x86 (`if a < b { a } else { b }`), which is only used where no NaN can occur.
//!
//! The floor every stage above stands on (the camera's primary rays, the tracer's kernels):
//! this module uses nothing else of the crate. It is private to the crate (`mod lanes` in
//! `lib.rs`); its items are `pub` only so that public signatures of the tracer may name them
//! in bounds, and nothing outside the crate can reach them.

use std::ops::{Add, Div, Mul, Neg, Sub};

mod vec3;
#[cfg(target_arch = "x86_64")]
pub(crate) mod x86;

pub(crate) use vec3::V3;

/// The most lanes a packet has (16 f32 in each of two AVX-512 registers): the size of the
/// per-lane arrays around the kernels.
pub const MAX_LANES: usize = 32;

/// `Lanes::outlined` for types that need no CPU feature.
#[inline(never)]
fn outlined<R>(f: impl FnOnce() -> R) -> R {
    f()
}

/// Whether `V`'s lanes hold f32 (else f64).
#[inline(always)]
pub(crate) fn single<V: Lanes>() -> bool {
    V::BOX_SLACK != 0.0
}

/// A set of lanes, the result of a comparison.
pub trait Mask: Copy {
    fn none_set() -> Self;
    /// Lanes 0..n set.
    fn first(n: usize) -> Self;
    /// Lane k set where bit k is.
    fn from_bits(bits: u32) -> Self;
    fn and(self, o: Self) -> Self;
    fn or(self, o: Self) -> Self;
    /// self ∧ ¬o
    fn andnot(self, o: Self) -> Self;
    /// Bit k for lane k.
    fn bits(self) -> u32;
    #[inline(always)]
    fn any(self) -> bool {
        self.bits() != 0
    }
    #[inline(always)]
    fn count(self) -> u64 {
        u64::from(self.bits().count_ones())
    }
    #[inline(always)]
    fn lane(self, k: usize) -> bool {
        self.bits() >> k & 1 == 1
    }
}

/// N lanes of f64 or f32; values enter through `splat` and `load` (rounded to the lanes'
/// precision) and leave through `store` and `lane` (exactly).
pub trait Lanes:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    const N: usize;
    type M: Mask;
    /// One lane of the same precision: what per-lane scalar code computes in, so a lane's
    /// value never depends on the width.
    type One: Lanes<M = bool>;
    /// f64 lanes under the same CPU feature (this type itself in f64, at most `N` lanes):
    /// where an f32 kernel needs f64 arithmetic per lane (an area light's points), it runs in
    /// these, `N / F64::N` groups at a time.
    type F64: Lanes;
    /// Half the lanes: a `Pair`'s register type; for any other type, the type itself.
    type Half: Lanes<One = Self::One>;
    /// Whether this type is two `Half`s side by side (a mesh leaf whose lanes all lie in one
    /// half tests that half alone).
    const HALVES: bool;
    /// A magnitude whose reciprocal is finite in this precision: it stands in for a zero
    /// direction component in the slab test.
    const TINY: f64;
    /// How much earlier than computed a ray may enter a box and still be tested against its
    /// spheres: 0 in f64, whose boxes are padded enough; 2^-16 in f32 (see `accel::Slabs`).
    const BOX_SLACK: f64;
    fn splat(x: f64) -> Self;
    /// Lanes from `x[..N]`.
    fn load(x: &[f64]) -> Self;
    /// Lanes from the integers `x[..N]`, each at most `i32::MAX` (pixel rows and columns):
    /// rounded as `load` rounds the same integers as f64, so the same lanes, without the
    /// round trip through an f64 array (its scalar stores stall the vector loads).
    #[inline(always)]
    fn from_u32(x: &[u32]) -> Self {
        Self::from_fn(|k| f64::from(x[k]))
    }
    /// Lanes into `out[..N]`.
    fn store(self, out: &mut [f64]);
    /// Lanes rounded to f32 (to nearest, as `as f32`) into `out[..N]`.
    fn store_f32(self, out: &mut [f32]);
    fn sqrt(self) -> Self;
    /// |self| with the sign of `s`.
    fn copysign(self, s: Self) -> Self;
    fn lt(self, o: Self) -> Self::M;
    fn le(self, o: Self) -> Self::M;
    fn gt(self, o: Self) -> Self::M;
    fn eq(self, o: Self) -> Self::M;
    /// Lane-wise `if m { a } else { b }`.
    fn select(m: Self::M, a: Self, b: Self) -> Self;
    fn min(self, o: Self) -> Self;
    fn max(self, o: Self) -> Self;
    /// Half `i` of the lanes (0: lanes `0..N/2`, 1: the rest); without halves, the lanes.
    fn half(self, i: usize) -> Self::Half;
    /// These lanes with half `i` replaced by `h`; without halves, `h`.
    fn with_half(self, i: usize, h: Self::Half) -> Self;
    /// The lanes in `[..N]` of an array.
    #[inline(always)]
    fn array(self) -> [f64; MAX_LANES] {
        let mut out = [0.0; MAX_LANES];
        self.store(&mut out);
        out
    }
    /// The value of lane `k`.
    #[inline(always)]
    fn lane(self, k: usize) -> f64 {
        self.array()[k]
    }
    /// Calls `f` out of line, in a function compiled for this type's CPU feature. The kernels
    /// call their large stages (a packet's path, a shadow walk) through this, so that each is
    /// compiled once per lane type instead of once per call site: inlined everywhere, they
    /// made a release build take 20 minutes. Pass an `#[inline(always)]` closure so its body is
    /// compiled with the feature (`tests/kernels.rs` checks the binary for lane operations
    /// left out of line).
    #[inline(always)]
    fn outlined<R>(f: impl FnOnce() -> R) -> R {
        outlined(f)
    }
    /// Lanes from a function of the lane index.
    #[inline(always)]
    fn from_fn(f: impl FnMut(usize) -> f64) -> Self {
        let mut f = f;
        let mut v = [0.0; MAX_LANES];
        for (k, x) in v.iter_mut().enumerate().take(Self::N) {
            *x = f(k);
        }
        Self::load(&v)
    }
}

/// Two lane vectors side by side, one packet of 2N lanes: every operation issues two
/// independent instructions, which hides the latency of the square root → division chains
/// that dominate the kernel (measured: 16 lanes in two AVX-512 registers beat 8 in one).
#[derive(Clone, Copy)]
pub struct Pair<L>(L, L);

/// The mask of a `Pair`: the low half's lanes, then the high half's.
#[derive(Clone, Copy)]
pub struct PairMask<M>(M, M);

impl<M: Mask> Mask for PairMask<M> {
    #[inline(always)]
    fn none_set() -> Self {
        PairMask(M::none_set(), M::none_set())
    }
    #[inline(always)]
    fn first(n: usize) -> Self {
        Self::from_bits(if n >= 32 { u32::MAX } else { (1u32 << n) - 1 })
    }
    #[inline(always)]
    fn from_bits(bits: u32) -> Self {
        let half = Self::half();
        PairMask(M::from_bits(bits), M::from_bits(bits >> half))
    }
    #[inline(always)]
    fn and(self, o: Self) -> Self {
        PairMask(self.0.and(o.0), self.1.and(o.1))
    }
    #[inline(always)]
    fn or(self, o: Self) -> Self {
        PairMask(self.0.or(o.0), self.1.or(o.1))
    }
    #[inline(always)]
    fn andnot(self, o: Self) -> Self {
        PairMask(self.0.andnot(o.0), self.1.andnot(o.1))
    }
    #[inline(always)]
    fn bits(self) -> u32 {
        self.0.bits() | self.1.bits() << Self::half()
    }
}

impl<M: Mask> PairMask<M> {
    /// Lanes in one half: the bit width of `M::first(32)`.
    #[inline(always)]
    fn half() -> u32 {
        M::first(32).bits().count_ones()
    }
}

macro_rules! pair_op {
    ($trait:ident, $f:ident) => {
        impl<L: Lanes> $trait for Pair<L> {
            type Output = Pair<L>;
            #[inline(always)]
            fn $f(self, o: Pair<L>) -> Pair<L> {
                Pair(self.0.$f(o.0), self.1.$f(o.1))
            }
        }
    };
}
pair_op!(Add, add);
pair_op!(Sub, sub);
pair_op!(Mul, mul);
pair_op!(Div, div);

impl<L: Lanes> Neg for Pair<L> {
    type Output = Pair<L>;
    #[inline(always)]
    fn neg(self) -> Pair<L> {
        Pair(-self.0, -self.1)
    }
}

impl<L: Lanes> Lanes for Pair<L> {
    const N: usize = 2 * L::N;
    type M = PairMask<L::M>;
    type One = L::One;
    type F64 = Pair<L::F64>;
    type Half = L;
    const HALVES: bool = true;
    const TINY: f64 = L::TINY;
    const BOX_SLACK: f64 = L::BOX_SLACK;
    #[inline(always)]
    fn splat(x: f64) -> Self {
        Pair(L::splat(x), L::splat(x))
    }
    #[inline(always)]
    fn load(x: &[f64]) -> Self {
        Pair(L::load(x), L::load(&x[L::N..]))
    }
    #[inline(always)]
    fn from_u32(x: &[u32]) -> Self {
        Pair(L::from_u32(x), L::from_u32(&x[L::N..]))
    }
    #[inline(always)]
    fn store(self, out: &mut [f64]) {
        self.0.store(out);
        self.1.store(&mut out[L::N..]);
    }
    #[inline(always)]
    fn store_f32(self, out: &mut [f32]) {
        self.0.store_f32(out);
        self.1.store_f32(&mut out[L::N..]);
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        Pair(self.0.sqrt(), self.1.sqrt())
    }
    #[inline(always)]
    fn copysign(self, s: Self) -> Self {
        Pair(self.0.copysign(s.0), self.1.copysign(s.1))
    }
    #[inline(always)]
    fn lt(self, o: Self) -> Self::M {
        PairMask(self.0.lt(o.0), self.1.lt(o.1))
    }
    #[inline(always)]
    fn le(self, o: Self) -> Self::M {
        PairMask(self.0.le(o.0), self.1.le(o.1))
    }
    #[inline(always)]
    fn gt(self, o: Self) -> Self::M {
        PairMask(self.0.gt(o.0), self.1.gt(o.1))
    }
    #[inline(always)]
    fn eq(self, o: Self) -> Self::M {
        PairMask(self.0.eq(o.0), self.1.eq(o.1))
    }
    #[inline(always)]
    fn select(m: Self::M, a: Self, b: Self) -> Self {
        Pair(L::select(m.0, a.0, b.0), L::select(m.1, a.1, b.1))
    }
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        Pair(self.0.min(o.0), self.1.min(o.1))
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        Pair(self.0.max(o.0), self.1.max(o.1))
    }
    #[inline(always)]
    fn half(self, i: usize) -> L {
        if i == 0 { self.0 } else { self.1 }
    }
    #[inline(always)]
    fn with_half(self, i: usize, h: L) -> Self {
        if i == 0 {
            Pair(h, self.1)
        } else {
            Pair(self.0, h)
        }
    }
    #[inline(always)]
    fn outlined<R>(f: impl FnOnce() -> R) -> R {
        L::outlined(f)
    }
}

/// One lane of f64: the scalar oracle every wider f64 type must match bit for bit.
#[derive(Debug, Clone, Copy)]
pub struct F64x1(pub f64);

/// One lane of f32: the scalar oracle of the f32 types.
#[derive(Debug, Clone, Copy)]
pub struct F32x1(pub f32);

impl Mask for bool {
    #[inline(always)]
    fn none_set() -> bool {
        false
    }
    #[inline(always)]
    fn first(n: usize) -> bool {
        n > 0
    }
    #[inline(always)]
    fn from_bits(bits: u32) -> bool {
        bits & 1 == 1
    }
    #[inline(always)]
    fn and(self, o: bool) -> bool {
        self & o
    }
    #[inline(always)]
    fn or(self, o: bool) -> bool {
        self | o
    }
    #[inline(always)]
    fn andnot(self, o: bool) -> bool {
        self & !o
    }
    #[inline(always)]
    fn bits(self) -> u32 {
        u32::from(self)
    }
}

/// The one-lane type over the float `$f`.
macro_rules! scalar_lanes {
    ($t:ident, $f:ident, $tiny:expr, $slack:expr) => {
        impl Add for $t {
            type Output = $t;
            #[inline(always)]
            fn add(self, o: $t) -> $t {
                $t(self.0 + o.0)
            }
        }
        impl Sub for $t {
            type Output = $t;
            #[inline(always)]
            fn sub(self, o: $t) -> $t {
                $t(self.0 - o.0)
            }
        }
        impl Mul for $t {
            type Output = $t;
            #[inline(always)]
            fn mul(self, o: $t) -> $t {
                $t(self.0 * o.0)
            }
        }
        impl Div for $t {
            type Output = $t;
            #[inline(always)]
            fn div(self, o: $t) -> $t {
                $t(self.0 / o.0)
            }
        }
        impl Neg for $t {
            type Output = $t;
            #[inline(always)]
            fn neg(self) -> $t {
                $t(-self.0)
            }
        }
        impl Lanes for $t {
            const N: usize = 1;
            type M = bool;
            type One = $t;
            type F64 = F64x1;
            type Half = $t;
            const HALVES: bool = false;
            const TINY: f64 = $tiny;
            const BOX_SLACK: f64 = $slack;
            #[inline(always)]
            fn half(self, _: usize) -> $t {
                self
            }
            #[inline(always)]
            fn with_half(self, _: usize, h: $t) -> $t {
                h
            }
            #[inline(always)]
            fn splat(x: f64) -> Self {
                $t(x as $f)
            }
            #[inline(always)]
            fn load(x: &[f64]) -> Self {
                $t(x[0] as $f)
            }
            #[inline(always)]
            fn store(self, out: &mut [f64]) {
                out[0] = f64::from(self.0);
            }
            #[inline(always)]
            fn store_f32(self, out: &mut [f32]) {
                out[0] = self.0 as f32;
            }
            #[inline(always)]
            fn sqrt(self) -> Self {
                $t(self.0.sqrt())
            }
            #[inline(always)]
            fn copysign(self, s: Self) -> Self {
                $t(self.0.copysign(s.0))
            }
            #[inline(always)]
            fn lt(self, o: Self) -> bool {
                self.0 < o.0
            }
            #[inline(always)]
            fn le(self, o: Self) -> bool {
                self.0 <= o.0
            }
            #[inline(always)]
            fn gt(self, o: Self) -> bool {
                self.0 > o.0
            }
            #[inline(always)]
            fn eq(self, o: Self) -> bool {
                self.0 == o.0
            }
            #[inline(always)]
            fn select(m: bool, a: Self, b: Self) -> Self {
                if m { a } else { b }
            }
            #[inline(always)]
            fn min(self, o: Self) -> Self {
                if self.0 < o.0 { self } else { o }
            }
            #[inline(always)]
            fn max(self, o: Self) -> Self {
                if self.0 > o.0 { self } else { o }
            }
            #[inline(always)]
            fn lane(self, _: usize) -> f64 {
                f64::from(self.0)
            }
        }
    };
}
scalar_lanes!(F64x1, f64, 1e-300, 0.0);
scalar_lanes!(F32x1, f32, 1e-30, 1.0 / 65536.0);

/// Asks the memory for the first and the last cache line of `items` ahead of their use: a
/// hint, which changes no result. A walk that will test a node's children or a leaf's
/// triangles soon then issues their loads together, instead of one miss after another. The
/// lines between (a leaf's middle triangles) are not asked for: asking for every line cost
/// more instructions and saved no measured time.
#[inline(always)]
pub fn fetch<T>(items: &[T]) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        let start = items.as_ptr().cast::<i8>();
        let last = start.wrapping_add(std::mem::size_of_val(items).saturating_sub(1));
        // SAFETY: a prefetch reads nothing and never faults.
        unsafe {
            _mm_prefetch::<_MM_HINT_T0>(start);
            _mm_prefetch::<_MM_HINT_T0>(last);
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = items;
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every lane of every width the CPU has computes what the scalar type computes, for
    /// values that include zeros of both signs, infinities, NaN and subnormals.
    #[test]
    fn wide_lanes_match_the_scalar_oracle() {
        #[cfg(target_arch = "x86_64")]
        x86::check_against_scalar(&special_values());
    }

    pub(crate) fn special_values() -> Vec<f64> {
        let mut v = vec![
            0.0,
            -0.0,
            1.0,
            -1.0,
            0.5,
            3.0,
            1e-310,
            -1e-310,
            1e308,
            -1e308,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            f64::EPSILON,
            2.0f64.sqrt(),
        ];
        let mut s = 0x243f_6a88_85a3_08d3u64;
        for _ in 0..200 {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            v.push(f64::from_bits(s));
        }
        v
    }
}
