//! x86-64 lanes: 4 × f64 or 8 × f32 in AVX registers, 8 × f64 or 16 × f32 in AVX-512
//! registers. Their methods are `#[inline(always)]` and only ever run inside the
//! `#[target_feature]` entry points of `tracer::kernel`, after run-time detection said the CPU
//! has the feature; inlined there, each becomes one instruction.

use super::{Lanes, Mask};
use std::arch::x86_64::*;
use std::ops::{Add, Div, Mul, Neg, Sub};

macro_rules! binary_ops {
    ($t:ident, $add:ident, $sub:ident, $mul:ident, $div:ident) => {
        binary_ops!(@one $t, Add, add, $add);
        binary_ops!(@one $t, Sub, sub, $sub);
        binary_ops!(@one $t, Mul, mul, $mul);
        binary_ops!(@one $t, Div, div, $div);
    };
    (@one $t:ident, $trait:ident, $f:ident, $intr:ident) => {
        impl $trait for $t {
            type Output = $t;
            #[inline(always)]
            fn $f(self, o: $t) -> $t {
                // SAFETY: only reached from kernels the CPU was checked to support.
                unsafe { $t($intr(self.0, o.0)) }
            }
        }
    };
}

// ---------------------------------------------------------------- 4 lanes (AVX)

/// A 4-lane mask: all-ones or all-zeros per 64-bit lane, as AVX compares produce.
#[derive(Clone, Copy)]
pub struct M4(__m256d);

impl Mask for M4 {
    #[inline(always)]
    fn none_set() -> M4 {
        unsafe { M4(_mm256_setzero_pd()) }
    }
    #[inline(always)]
    fn first(n: usize) -> M4 {
        M4::from_bits((1u32 << n.min(4)) - 1)
    }
    #[inline(always)]
    fn from_bits(bits: u32) -> M4 {
        let lane = |k: usize| if bits >> k & 1 == 1 { -1i64 } else { 0 };
        unsafe {
            M4(_mm256_castsi256_pd(_mm256_setr_epi64x(
                lane(0),
                lane(1),
                lane(2),
                lane(3),
            )))
        }
    }
    #[inline(always)]
    fn and(self, o: M4) -> M4 {
        unsafe { M4(_mm256_and_pd(self.0, o.0)) }
    }
    #[inline(always)]
    fn or(self, o: M4) -> M4 {
        unsafe { M4(_mm256_or_pd(self.0, o.0)) }
    }
    #[inline(always)]
    fn andnot(self, o: M4) -> M4 {
        unsafe { M4(_mm256_andnot_pd(o.0, self.0)) }
    }
    #[inline(always)]
    fn bits(self) -> u32 {
        unsafe { _mm256_movemask_pd(self.0) as u32 }
    }
}

#[derive(Clone, Copy)]
pub struct F64x4(__m256d);
binary_ops!(
    F64x4,
    _mm256_add_pd,
    _mm256_sub_pd,
    _mm256_mul_pd,
    _mm256_div_pd
);

impl Neg for F64x4 {
    type Output = F64x4;
    #[inline(always)]
    fn neg(self) -> F64x4 {
        unsafe { F64x4(_mm256_xor_pd(self.0, _mm256_set1_pd(-0.0))) }
    }
}

impl Lanes for F64x4 {
    const N: usize = 4;
    type One = super::F64x1;
    const TINY: f64 = 1e-300;
    const BOX_SLACK: f64 = 0.0;
    type M = M4;
    #[inline(always)]
    fn splat(x: f64) -> Self {
        unsafe { F64x4(_mm256_set1_pd(x)) }
    }
    #[inline(always)]
    fn load(x: &[f64]) -> Self {
        assert!(x.len() >= 4);
        unsafe { F64x4(_mm256_loadu_pd(x.as_ptr())) }
    }
    #[inline(always)]
    fn store(self, out: &mut [f64]) {
        assert!(out.len() >= 4);
        unsafe { _mm256_storeu_pd(out.as_mut_ptr(), self.0) }
    }
    #[inline(always)]
    fn store_f32(self, out: &mut [f32]) {
        assert!(out.len() >= 4);
        unsafe { _mm_storeu_ps(out.as_mut_ptr(), _mm256_cvtpd_ps(self.0)) }
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        unsafe { F64x4(_mm256_sqrt_pd(self.0)) }
    }
    #[inline(always)]
    fn copysign(self, s: Self) -> Self {
        unsafe {
            let sign = _mm256_set1_pd(-0.0);
            F64x4(_mm256_or_pd(
                _mm256_andnot_pd(sign, self.0),
                _mm256_and_pd(sign, s.0),
            ))
        }
    }
    #[inline(always)]
    fn lt(self, o: Self) -> M4 {
        unsafe { M4(_mm256_cmp_pd::<_CMP_LT_OQ>(self.0, o.0)) }
    }
    #[inline(always)]
    fn le(self, o: Self) -> M4 {
        unsafe { M4(_mm256_cmp_pd::<_CMP_LE_OQ>(self.0, o.0)) }
    }
    #[inline(always)]
    fn gt(self, o: Self) -> M4 {
        unsafe { M4(_mm256_cmp_pd::<_CMP_GT_OQ>(self.0, o.0)) }
    }
    #[inline(always)]
    fn eq(self, o: Self) -> M4 {
        unsafe { M4(_mm256_cmp_pd::<_CMP_EQ_OQ>(self.0, o.0)) }
    }
    #[inline(always)]
    fn select(m: M4, a: Self, b: Self) -> Self {
        unsafe { F64x4(_mm256_blendv_pd(b.0, a.0, m.0)) }
    }
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        unsafe { F64x4(_mm256_min_pd(self.0, o.0)) }
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        unsafe { F64x4(_mm256_max_pd(self.0, o.0)) }
    }
}

// ---------------------------------------------------------------- 8 lanes (AVX-512F)

impl Mask for u8 {
    #[inline(always)]
    fn none_set() -> u8 {
        0
    }
    #[inline(always)]
    fn first(n: usize) -> u8 {
        if n >= 8 { 0xff } else { (1u8 << n) - 1 }
    }
    #[inline(always)]
    fn from_bits(bits: u32) -> u8 {
        bits as u8
    }
    #[inline(always)]
    fn and(self, o: u8) -> u8 {
        self & o
    }
    #[inline(always)]
    fn or(self, o: u8) -> u8 {
        self | o
    }
    #[inline(always)]
    fn andnot(self, o: u8) -> u8 {
        self & !o
    }
    #[inline(always)]
    fn bits(self) -> u32 {
        u32::from(self)
    }
}

#[derive(Clone, Copy)]
pub struct F64x8(__m512d);
binary_ops!(
    F64x8,
    _mm512_add_pd,
    _mm512_sub_pd,
    _mm512_mul_pd,
    _mm512_div_pd
);

impl Neg for F64x8 {
    type Output = F64x8;
    #[inline(always)]
    fn neg(self) -> F64x8 {
        unsafe {
            F64x8(_mm512_castsi512_pd(_mm512_xor_si512(
                _mm512_castpd_si512(self.0),
                _mm512_set1_epi64(i64::MIN),
            )))
        }
    }
}

impl Lanes for F64x8 {
    const N: usize = 8;
    type One = super::F64x1;
    const TINY: f64 = 1e-300;
    const BOX_SLACK: f64 = 0.0;
    type M = u8;
    #[inline(always)]
    fn splat(x: f64) -> Self {
        unsafe { F64x8(_mm512_set1_pd(x)) }
    }
    #[inline(always)]
    fn load(x: &[f64]) -> Self {
        assert!(x.len() >= 8);
        unsafe { F64x8(_mm512_loadu_pd(x.as_ptr())) }
    }
    #[inline(always)]
    fn store(self, out: &mut [f64]) {
        assert!(out.len() >= 8);
        unsafe { _mm512_storeu_pd(out.as_mut_ptr(), self.0) }
    }
    #[inline(always)]
    fn store_f32(self, out: &mut [f32]) {
        assert!(out.len() >= 8);
        unsafe { _mm256_storeu_ps(out.as_mut_ptr(), _mm512_cvtpd_ps(self.0)) }
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        unsafe { F64x8(_mm512_sqrt_pd(self.0)) }
    }
    #[inline(always)]
    fn copysign(self, s: Self) -> Self {
        unsafe {
            let sign = _mm512_set1_epi64(i64::MIN);
            let magnitude = _mm512_andnot_si512(sign, _mm512_castpd_si512(self.0));
            let sign_of_s = _mm512_and_si512(sign, _mm512_castpd_si512(s.0));
            F64x8(_mm512_castsi512_pd(_mm512_or_si512(magnitude, sign_of_s)))
        }
    }
    #[inline(always)]
    fn lt(self, o: Self) -> u8 {
        unsafe { _mm512_cmp_pd_mask::<_CMP_LT_OQ>(self.0, o.0) }
    }
    #[inline(always)]
    fn le(self, o: Self) -> u8 {
        unsafe { _mm512_cmp_pd_mask::<_CMP_LE_OQ>(self.0, o.0) }
    }
    #[inline(always)]
    fn gt(self, o: Self) -> u8 {
        unsafe { _mm512_cmp_pd_mask::<_CMP_GT_OQ>(self.0, o.0) }
    }
    #[inline(always)]
    fn eq(self, o: Self) -> u8 {
        unsafe { _mm512_cmp_pd_mask::<_CMP_EQ_OQ>(self.0, o.0) }
    }
    #[inline(always)]
    fn select(m: u8, a: Self, b: Self) -> Self {
        unsafe { F64x8(_mm512_mask_blend_pd(m, b.0, a.0)) }
    }
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        unsafe { F64x8(_mm512_min_pd(self.0, o.0)) }
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        unsafe { F64x8(_mm512_max_pd(self.0, o.0)) }
    }
}

// ---------------------------------------------------------------- 8 × f32 (AVX)

/// An 8-lane mask: all-ones or all-zeros per 32-bit lane, as AVX compares produce.
#[derive(Clone, Copy)]
pub struct M8(__m256);

impl Mask for M8 {
    #[inline(always)]
    fn none_set() -> M8 {
        unsafe { M8(_mm256_setzero_ps()) }
    }
    #[inline(always)]
    fn first(n: usize) -> M8 {
        M8::from_bits((1u32 << n.min(8)) - 1)
    }
    #[inline(always)]
    fn from_bits(bits: u32) -> M8 {
        let lane = |k: usize| if bits >> k & 1 == 1 { -1i32 } else { 0 };
        unsafe {
            M8(_mm256_castsi256_ps(_mm256_setr_epi32(
                lane(0),
                lane(1),
                lane(2),
                lane(3),
                lane(4),
                lane(5),
                lane(6),
                lane(7),
            )))
        }
    }
    #[inline(always)]
    fn and(self, o: M8) -> M8 {
        unsafe { M8(_mm256_and_ps(self.0, o.0)) }
    }
    #[inline(always)]
    fn or(self, o: M8) -> M8 {
        unsafe { M8(_mm256_or_ps(self.0, o.0)) }
    }
    #[inline(always)]
    fn andnot(self, o: M8) -> M8 {
        unsafe { M8(_mm256_andnot_ps(o.0, self.0)) }
    }
    #[inline(always)]
    fn bits(self) -> u32 {
        unsafe { _mm256_movemask_ps(self.0) as u32 }
    }
}

#[derive(Clone, Copy)]
pub struct F32x8(__m256);
binary_ops!(
    F32x8,
    _mm256_add_ps,
    _mm256_sub_ps,
    _mm256_mul_ps,
    _mm256_div_ps
);

impl Neg for F32x8 {
    type Output = F32x8;
    #[inline(always)]
    fn neg(self) -> F32x8 {
        unsafe { F32x8(_mm256_xor_ps(self.0, _mm256_set1_ps(-0.0))) }
    }
}

/// f64 values rounded to f32 (to nearest, as `as f32`), `N` of them.
#[inline(always)]
fn narrow<const N: usize>(x: &[f64]) -> [f32; N] {
    let mut out = [0f32; N];
    for (o, v) in out.iter_mut().zip(&x[..N]) {
        *o = *v as f32;
    }
    out
}

/// f32 values widened to f64 (exactly) into `out[..N]`.
#[inline(always)]
fn widen<const N: usize>(x: [f32; N], out: &mut [f64]) {
    for (o, v) in out[..N].iter_mut().zip(x) {
        *o = f64::from(v);
    }
}

impl Lanes for F32x8 {
    const N: usize = 8;
    type M = M8;
    type One = super::F32x1;
    const TINY: f64 = 1e-30;
    const BOX_SLACK: f64 = 1.0 / 65536.0;
    #[inline(always)]
    fn splat(x: f64) -> Self {
        unsafe { F32x8(_mm256_set1_ps(x as f32)) }
    }
    #[inline(always)]
    fn load(x: &[f64]) -> Self {
        let v = narrow::<8>(x);
        unsafe { F32x8(_mm256_loadu_ps(v.as_ptr())) }
    }
    #[inline(always)]
    fn store(self, out: &mut [f64]) {
        let mut v = [0f32; 8];
        self.store_f32(&mut v);
        widen(v, out);
    }
    #[inline(always)]
    fn store_f32(self, out: &mut [f32]) {
        assert!(out.len() >= 8);
        unsafe { _mm256_storeu_ps(out.as_mut_ptr(), self.0) }
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        unsafe { F32x8(_mm256_sqrt_ps(self.0)) }
    }
    #[inline(always)]
    fn copysign(self, s: Self) -> Self {
        unsafe {
            let sign = _mm256_set1_ps(-0.0);
            F32x8(_mm256_or_ps(
                _mm256_andnot_ps(sign, self.0),
                _mm256_and_ps(sign, s.0),
            ))
        }
    }
    #[inline(always)]
    fn lt(self, o: Self) -> M8 {
        unsafe { M8(_mm256_cmp_ps::<_CMP_LT_OQ>(self.0, o.0)) }
    }
    #[inline(always)]
    fn le(self, o: Self) -> M8 {
        unsafe { M8(_mm256_cmp_ps::<_CMP_LE_OQ>(self.0, o.0)) }
    }
    #[inline(always)]
    fn gt(self, o: Self) -> M8 {
        unsafe { M8(_mm256_cmp_ps::<_CMP_GT_OQ>(self.0, o.0)) }
    }
    #[inline(always)]
    fn eq(self, o: Self) -> M8 {
        unsafe { M8(_mm256_cmp_ps::<_CMP_EQ_OQ>(self.0, o.0)) }
    }
    #[inline(always)]
    fn select(m: M8, a: Self, b: Self) -> Self {
        unsafe { F32x8(_mm256_blendv_ps(b.0, a.0, m.0)) }
    }
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        unsafe { F32x8(_mm256_min_ps(self.0, o.0)) }
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        unsafe { F32x8(_mm256_max_ps(self.0, o.0)) }
    }
}

// ---------------------------------------------------------------- 16 × f32 (AVX-512F)

impl Mask for u16 {
    #[inline(always)]
    fn none_set() -> u16 {
        0
    }
    #[inline(always)]
    fn first(n: usize) -> u16 {
        if n >= 16 { 0xffff } else { (1u16 << n) - 1 }
    }
    #[inline(always)]
    fn from_bits(bits: u32) -> u16 {
        bits as u16
    }
    #[inline(always)]
    fn and(self, o: u16) -> u16 {
        self & o
    }
    #[inline(always)]
    fn or(self, o: u16) -> u16 {
        self | o
    }
    #[inline(always)]
    fn andnot(self, o: u16) -> u16 {
        self & !o
    }
    #[inline(always)]
    fn bits(self) -> u32 {
        u32::from(self)
    }
}

#[derive(Clone, Copy)]
pub struct F32x16(__m512);
binary_ops!(
    F32x16,
    _mm512_add_ps,
    _mm512_sub_ps,
    _mm512_mul_ps,
    _mm512_div_ps
);

impl Neg for F32x16 {
    type Output = F32x16;
    #[inline(always)]
    fn neg(self) -> F32x16 {
        unsafe {
            F32x16(_mm512_castsi512_ps(_mm512_xor_si512(
                _mm512_castps_si512(self.0),
                _mm512_set1_epi32(i32::MIN),
            )))
        }
    }
}

impl Lanes for F32x16 {
    const N: usize = 16;
    type M = u16;
    type One = super::F32x1;
    const TINY: f64 = 1e-30;
    const BOX_SLACK: f64 = 1.0 / 65536.0;
    #[inline(always)]
    fn splat(x: f64) -> Self {
        unsafe { F32x16(_mm512_set1_ps(x as f32)) }
    }
    #[inline(always)]
    fn load(x: &[f64]) -> Self {
        let v = narrow::<16>(x);
        unsafe { F32x16(_mm512_loadu_ps(v.as_ptr())) }
    }
    #[inline(always)]
    fn store(self, out: &mut [f64]) {
        let mut v = [0f32; 16];
        self.store_f32(&mut v);
        widen(v, out);
    }
    #[inline(always)]
    fn store_f32(self, out: &mut [f32]) {
        assert!(out.len() >= 16);
        unsafe { _mm512_storeu_ps(out.as_mut_ptr(), self.0) }
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        unsafe { F32x16(_mm512_sqrt_ps(self.0)) }
    }
    #[inline(always)]
    fn copysign(self, s: Self) -> Self {
        unsafe {
            let sign = _mm512_set1_epi32(i32::MIN);
            let magnitude = _mm512_andnot_si512(sign, _mm512_castps_si512(self.0));
            let sign_of_s = _mm512_and_si512(sign, _mm512_castps_si512(s.0));
            F32x16(_mm512_castsi512_ps(_mm512_or_si512(magnitude, sign_of_s)))
        }
    }
    #[inline(always)]
    fn lt(self, o: Self) -> u16 {
        unsafe { _mm512_cmp_ps_mask::<_CMP_LT_OQ>(self.0, o.0) }
    }
    #[inline(always)]
    fn le(self, o: Self) -> u16 {
        unsafe { _mm512_cmp_ps_mask::<_CMP_LE_OQ>(self.0, o.0) }
    }
    #[inline(always)]
    fn gt(self, o: Self) -> u16 {
        unsafe { _mm512_cmp_ps_mask::<_CMP_GT_OQ>(self.0, o.0) }
    }
    #[inline(always)]
    fn eq(self, o: Self) -> u16 {
        unsafe { _mm512_cmp_ps_mask::<_CMP_EQ_OQ>(self.0, o.0) }
    }
    #[inline(always)]
    fn select(m: u16, a: Self, b: Self) -> Self {
        unsafe { F32x16(_mm512_mask_blend_ps(m, b.0, a.0)) }
    }
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        unsafe { F32x16(_mm512_min_ps(self.0, o.0)) }
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        unsafe { F32x16(_mm512_max_ps(self.0, o.0)) }
    }
}

/// Applies every operation to all pairs of `values` in every width the CPU has and checks
/// each lane against `F64x1`, bit for bit (NaN against NaN).
#[cfg(test)]
pub(crate) fn check_against_scalar(values: &[f64]) {
    if is_x86_feature_detected!("avx") {
        // SAFETY: AVX is present.
        unsafe { check_avx(values) }
    }
    if is_x86_feature_detected!("avx512f") {
        // SAFETY: AVX-512F is present.
        unsafe { check_avx512(values) }
    }
}

#[cfg(test)]
use super::{F32x1, F64x1};

#[cfg(test)]
#[target_feature(enable = "avx")]
unsafe fn check_avx(values: &[f64]) {
    check_width::<F64x4, F64x1>(values);
    check_width::<super::Pair<F64x4>, F64x1>(values);
    check_width::<F32x8, F32x1>(values);
    check_width::<super::Pair<F32x8>, F32x1>(values);
}

#[cfg(test)]
#[target_feature(enable = "avx512f")]
unsafe fn check_avx512(values: &[f64]) {
    check_width::<F64x8, F64x1>(values);
    check_width::<super::Pair<F64x8>, F64x1>(values);
    check_width::<F32x16, F32x1>(values);
}

#[cfg(test)]
#[inline(always)]
fn check_width<V: Lanes, S: Lanes<M = bool>>(values: &[f64]) {
    let same = |a: f64, b: f64| a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan());
    for chunk_a in values.chunks_exact(V::N) {
        for i in 0..values.len() {
            let a = V::load(chunk_a);
            let b = V::from_fn(|k| values[(i + k) % values.len()]);
            type Op<S> = fn(S, S) -> S;
            let ops: [(V, Op<S>); 7] = [
                (a + b, |x, y| x + y),
                (a - b, |x, y| x - y),
                (a * b, |x, y| x * y),
                (a / b, |x, y| x / y),
                (a.sqrt(), |x, _| x.sqrt()),
                (a.copysign(b), |x, y| x.copysign(y)),
                (-a, |x, _| -x),
            ];
            for (wide, scalar) in ops {
                for k in 0..V::N {
                    let (x, y) = (S::splat(a.lane(k)), S::splat(b.lane(k)));
                    let want = scalar(x, y).lane(0);
                    assert!(same(wide.lane(k), want), "{} {}", a.lane(k), b.lane(k));
                }
            }
            let masks = [
                (a.lt(b), S::lt as fn(S, S) -> bool),
                (a.le(b), S::le),
                (a.gt(b), S::gt),
                (a.eq(b), S::eq),
            ];
            for (wide, scalar) in masks {
                for k in 0..V::N {
                    let (x, y) = (S::splat(a.lane(k)), S::splat(b.lane(k)));
                    assert_eq!(wide.lane(k), scalar(x, y), "{} {}", a.lane(k), b.lane(k));
                    let picked = V::select(wide, a, b).lane(k);
                    assert!(same(picked, S::select(scalar(x, y), x, y).lane(0)));
                }
            }
            let (mut wide, mut one) = ([0f32; 16], [0f32; 1]);
            a.store_f32(&mut wide);
            for (k, w) in wide.iter().enumerate().take(V::N) {
                S::splat(a.lane(k)).store_f32(&mut one);
                assert!(w.to_bits() == one[0].to_bits() || one[0].is_nan());
            }
            // min and max are used only where no NaN can occur.
            for k in (0..V::N).filter(|&k| !a.lane(k).is_nan() && !b.lane(k).is_nan()) {
                let (x, y) = (S::splat(a.lane(k)), S::splat(b.lane(k)));
                assert!(same(a.min(b).lane(k), x.min(y).lane(0)));
                assert!(same(a.max(b).lane(k), x.max(y).lane(0)));
            }
        }
    }
}
