//! x86-64 lanes: 4 × f64 or 8 × f32 in AVX registers, 8 × f64 or 16 × f32 in AVX-512
//! registers, each type one expansion of `x86_lanes!`. Their methods are `#[inline(always)]`:
//! inlined into a `#[target_feature]` entry point, each becomes one instruction (or a few).
//!
//! # Safety
//!
//! Every method executes instructions of its type's CPU feature, which is undefined behaviour
//! on a CPU without it, while the `Lanes` and `Mask` traits are safe to call. What keeps them
//! sound is who can reach them. This module is `pub(crate)` inside the crate-private `lanes`,
//! so nothing outside the crate can name these types; inside it, the only code that names them
//! is the kernel selection, `tracer::kernel::Kernel::run`, which instantiates them only within
//! `#[target_feature]` entry points and only after `Kernel::supported` (run-time detection with
//! `is_x86_feature_detected!`) said the CPU has the feature. The test
//! `only_the_kernel_selection_names_the_wide_types` keeps it that way. Each expansion states
//! this for its feature in its `safety` argument, which every `unsafe` block in the expansion
//! refers to; the few blocks outside the expansions (tests) carry their own.

use super::{F32x1, F64x1, Lanes, Mask};
use std::arch::x86_64::*;
use std::ops::{Add, Div, Mul, Neg, Sub};

/// One lane type `$t` over the register `$reg`, with its mask `$m` (an integer for
/// AVX-512's mask registers, or a vector mask over `$mreg` defined by the expansion) and
/// the one-lane type `$one` of its precision. Each operation is given as the intrinsic(s) it
/// becomes; `safety` is the argument every `unsafe` block of the expansion rests on.
macro_rules! x86_lanes {
    (
        $(#[$doc:meta])*
        $t:ident($reg:ty): $n:literal lanes, one $one:ident, wide $wide:ident, tiny $tiny:expr, slack $slack:expr;
        safety: $safety:literal;
        outlined $outlined:ident;
        mask $m:ident $(($mreg:ty) {
            none: $none:ident, lanes: $int:ty, from_lanes: $from:ident($load:ident),
            and: $mand:ident, or: $mor:ident, andnot: $mandnot:ident, bits: $movemask:ident
        })?;
        add $add:ident, sub $sub:ident, mul $mul:ident, div $div:ident, sqrt $sqrt:ident,
        min $min:ident, max $max:ident;
        splat |$sx:ident| $splat:expr;
        load |$lx:ident| $load_lanes:expr;
        integers |$ix:ident| $integers:expr;
        store |$sv:ident, $so:ident| $store:expr;
        store_f32 |$fv:ident, $fo:ident| $store_f32:expr;
        neg |$na:ident| $neg:expr;
        copysign |$ca:ident, $cs:ident| $copysign:expr;
        compare<$p:ident> |$pa:ident, $pb:ident| $compare:expr;
        select |$sm:ident, $sa:ident, $sb:ident| $select:expr;
    ) => {
        $(#[$doc])*
        #[doc = ""]
        #[doc = concat!("Safety: ", $safety)]
        #[derive(Clone, Copy)]
        pub(crate) struct $t($reg);

        $(
            #[doc = concat!("The mask of `", stringify!($t), "`: all-ones or all-zeros per lane,")]
            #[doc = "as AVX compares produce."]
            #[derive(Clone, Copy)]
            pub(crate) struct $m($mreg);

            impl Mask for $m {
                #[inline(always)]
                fn none_set() -> $m {
                    // SAFETY: the `safety` argument of this expansion.
                    unsafe { $m($none()) }
                }
                #[inline(always)]
                fn first(n: usize) -> $m {
                    $m::from_bits((1u32 << n.min($n)) - 1)
                }
                #[inline(always)]
                fn from_bits(bits: u32) -> $m {
                    let set = |k: usize| -<$int>::from(bits >> k & 1 == 1);
                    let lanes: [$int; $n] = std::array::from_fn(set);
                    // SAFETY: the `safety` argument of this expansion; `lanes` fills a register.
                    unsafe { $m($from($load(lanes.as_ptr().cast()))) }
                }
                #[inline(always)]
                fn and(self, o: $m) -> $m {
                    // SAFETY: the `safety` argument of this expansion.
                    unsafe { $m($mand(self.0, o.0)) }
                }
                #[inline(always)]
                fn or(self, o: $m) -> $m {
                    // SAFETY: the `safety` argument of this expansion.
                    unsafe { $m($mor(self.0, o.0)) }
                }
                #[inline(always)]
                fn andnot(self, o: $m) -> $m {
                    // SAFETY: the `safety` argument of this expansion.
                    unsafe { $m($mandnot(o.0, self.0)) }
                }
                #[inline(always)]
                fn bits(self) -> u32 {
                    // SAFETY: the `safety` argument of this expansion.
                    unsafe { $movemask(self.0) as u32 }
                }
            }
        )?

        x86_lanes!(@op $t, Add, add, $add);
        x86_lanes!(@op $t, Sub, sub, $sub);
        x86_lanes!(@op $t, Mul, mul, $mul);
        x86_lanes!(@op $t, Div, div, $div);

        impl Neg for $t {
            type Output = $t;
            #[inline(always)]
            fn neg(self) -> $t {
                let $na = self.0;
                // SAFETY: the `safety` argument of this expansion.
                unsafe { $t($neg) }
            }
        }

        impl $t {
            /// The ordered comparison `$p` (`_CMP_LT_OQ`, …) of each pair of lanes.
            #[inline(always)]
            fn compare<const $p: i32>(self, o: $t) -> $m {
                let ($pa, $pb) = (self.0, o.0);
                // SAFETY: the `safety` argument of this expansion.
                unsafe { $compare }
            }
        }

        impl Lanes for $t {
            const N: usize = $n;
            type M = $m;
            type One = $one;
            type F64 = $wide;
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
                let $sx = x;
                // SAFETY: the `safety` argument of this expansion.
                unsafe { $t($splat) }
            }
            #[inline(always)]
            fn load(x: &[f64]) -> Self {
                assert!(x.len() >= $n);
                let $lx = x;
                // SAFETY: the `safety` argument of this expansion; `x` holds the lanes read.
                unsafe { $t($load_lanes) }
            }
            #[inline(always)]
            fn from_u32(x: &[u32]) -> Self {
                assert!(x.len() >= $n && x[..$n].iter().all(|&v| v <= i32::MAX as u32));
                let $ix = x.as_ptr().cast();
                // SAFETY: the `safety` argument of this expansion; `x` holds the lanes read.
                unsafe { $t($integers) }
            }
            #[inline(always)]
            fn store(self, out: &mut [f64]) {
                assert!(out.len() >= $n);
                let ($sv, $so) = (self.0, out);
                // SAFETY: the `safety` argument of this expansion; `out` holds the lanes written.
                unsafe { $store }
            }
            #[inline(always)]
            fn store_f32(self, out: &mut [f32]) {
                assert!(out.len() >= $n);
                let ($fv, $fo) = (self.0, out);
                // SAFETY: the `safety` argument of this expansion; `out` holds the lanes written.
                unsafe { $store_f32 }
            }
            #[inline(always)]
            fn sqrt(self) -> Self {
                // SAFETY: the `safety` argument of this expansion.
                unsafe { $t($sqrt(self.0)) }
            }
            #[inline(always)]
            fn copysign(self, s: Self) -> Self {
                let ($ca, $cs) = (self.0, s.0);
                // SAFETY: the `safety` argument of this expansion.
                unsafe { $t($copysign) }
            }
            #[inline(always)]
            fn lt(self, o: Self) -> $m {
                self.compare::<_CMP_LT_OQ>(o)
            }
            #[inline(always)]
            fn le(self, o: Self) -> $m {
                self.compare::<_CMP_LE_OQ>(o)
            }
            #[inline(always)]
            fn gt(self, o: Self) -> $m {
                self.compare::<_CMP_GT_OQ>(o)
            }
            #[inline(always)]
            fn eq(self, o: Self) -> $m {
                self.compare::<_CMP_EQ_OQ>(o)
            }
            #[inline(always)]
            fn select(m: $m, a: Self, b: Self) -> Self {
                let ($sm, $sa, $sb) = (m, a.0, b.0);
                // SAFETY: the `safety` argument of this expansion.
                unsafe { $t($select) }
            }
            #[inline(always)]
            fn min(self, o: Self) -> Self {
                // SAFETY: the `safety` argument of this expansion.
                unsafe { $t($min(self.0, o.0)) }
            }
            #[inline(always)]
            fn max(self, o: Self) -> Self {
                // SAFETY: the `safety` argument of this expansion.
                unsafe { $t($max(self.0, o.0)) }
            }
            #[inline(always)]
            fn outlined<R>(f: impl FnOnce() -> R) -> R {
                // SAFETY: the `safety` argument of this expansion; `$outlined` enables no
                // feature beyond this type's.
                unsafe { $outlined(f) }
            }
        }
    };
    (@op $t:ident, $trait:ident, $f:ident, $intrinsic:ident) => {
        impl $trait for $t {
            type Output = $t;
            #[inline(always)]
            fn $f(self, o: $t) -> $t {
                // SAFETY: the `safety` argument of this expansion.
                unsafe { $t($intrinsic(self.0, o.0)) }
            }
        }
    };
}

/// `Lanes::outlined` for the AVX types.
///
/// # Safety
/// The CPU must have AVX2.
#[target_feature(enable = "avx2")]
#[inline(never)]
unsafe fn avx2<R>(f: impl FnOnce() -> R) -> R {
    f()
}

/// `Lanes::outlined` for the AVX-512 types.
///
/// # Safety
/// The CPU must have AVX-512F.
#[target_feature(enable = "avx512f")]
#[inline(never)]
unsafe fn avx512<R>(f: impl FnOnce() -> R) -> R {
    f()
}

x86_lanes! {
    /// 4 × f64 in an AVX register.
    F64x4(__m256d): 4 lanes, one F64x1, wide F64x4, tiny 1e-300, slack 0.0;
    safety: "AVX instructions; only named by `Kernel::run` for `Kernel::Avx2`, inside its \
        `avx2` entry point, after `Kernel::supported` detected AVX2 (which implies AVX).";
    outlined avx2;
    mask M4(__m256d) {
        none: _mm256_setzero_pd, lanes: i64, from_lanes: _mm256_castsi256_pd(_mm256_loadu_si256),
        and: _mm256_and_pd, or: _mm256_or_pd, andnot: _mm256_andnot_pd, bits: _mm256_movemask_pd
    };
    add _mm256_add_pd, sub _mm256_sub_pd, mul _mm256_mul_pd, div _mm256_div_pd,
    sqrt _mm256_sqrt_pd, min _mm256_min_pd, max _mm256_max_pd;
    splat |x| _mm256_set1_pd(x);
    load |x| _mm256_loadu_pd(x.as_ptr());
    integers |x| _mm256_cvtepi32_pd(_mm_loadu_si128(x));
    store |v, out| _mm256_storeu_pd(out.as_mut_ptr(), v);
    store_f32 |v, out| _mm_storeu_ps(out.as_mut_ptr(), _mm256_cvtpd_ps(v));
    neg |a| _mm256_xor_pd(a, _mm256_set1_pd(-0.0));
    copysign |a, s| {
        let sign = _mm256_set1_pd(-0.0);
        _mm256_or_pd(_mm256_andnot_pd(sign, a), _mm256_and_pd(sign, s))
    };
    compare<P> |a, b| M4(_mm256_cmp_pd::<P>(a, b));
    select |m, a, b| _mm256_blendv_pd(b, a, m.0);
}

x86_lanes! {
    /// 8 × f32 in an AVX register.
    F32x8(__m256): 8 lanes, one F32x1, wide F64x4, tiny 1e-30, slack 1.0 / 65536.0;
    safety: "AVX instructions; only named by `Kernel::run` for `Kernel::Avx2`, inside its \
        `avx2` entry point, after `Kernel::supported` detected AVX2 (which implies AVX).";
    outlined avx2;
    mask M8(__m256) {
        none: _mm256_setzero_ps, lanes: i32, from_lanes: _mm256_castsi256_ps(_mm256_loadu_si256),
        and: _mm256_and_ps, or: _mm256_or_ps, andnot: _mm256_andnot_ps, bits: _mm256_movemask_ps
    };
    add _mm256_add_ps, sub _mm256_sub_ps, mul _mm256_mul_ps, div _mm256_div_ps,
    sqrt _mm256_sqrt_ps, min _mm256_min_ps, max _mm256_max_ps;
    splat |x| _mm256_set1_ps(x as f32);
    load |x| _mm256_loadu_ps(narrow::<8>(x).as_ptr());
    integers |x| _mm256_cvtepi32_ps(_mm256_loadu_si256(x));
    store |v, out| {
        let mut lanes = [0f32; 8];
        _mm256_storeu_ps(lanes.as_mut_ptr(), v);
        widen(lanes, out)
    };
    store_f32 |v, out| _mm256_storeu_ps(out.as_mut_ptr(), v);
    neg |a| _mm256_xor_ps(a, _mm256_set1_ps(-0.0));
    copysign |a, s| {
        let sign = _mm256_set1_ps(-0.0);
        _mm256_or_ps(_mm256_andnot_ps(sign, a), _mm256_and_ps(sign, s))
    };
    compare<P> |a, b| M8(_mm256_cmp_ps::<P>(a, b));
    select |m, a, b| _mm256_blendv_ps(b, a, m.0);
}

x86_lanes! {
    /// 8 × f64 in an AVX-512 register. AVX-512F has no float bitwise operations (those are
    /// AVX-512DQ's), so the sign bits are handled as integers.
    F64x8(__m512d): 8 lanes, one F64x1, wide F64x8, tiny 1e-300, slack 0.0;
    safety: "AVX-512F instructions; only named by `Kernel::run` for `Kernel::Avx512`, inside \
        its `avx512` entry point, after `Kernel::supported` detected AVX-512F.";
    outlined avx512;
    mask u8;
    add _mm512_add_pd, sub _mm512_sub_pd, mul _mm512_mul_pd, div _mm512_div_pd,
    sqrt _mm512_sqrt_pd, min _mm512_min_pd, max _mm512_max_pd;
    splat |x| _mm512_set1_pd(x);
    load |x| _mm512_loadu_pd(x.as_ptr());
    integers |x| _mm512_cvtepi32_pd(_mm256_loadu_si256(x));
    store |v, out| _mm512_storeu_pd(out.as_mut_ptr(), v);
    store_f32 |v, out| _mm256_storeu_ps(out.as_mut_ptr(), _mm512_cvtpd_ps(v));
    neg |a| {
        let bits = _mm512_xor_si512(_mm512_castpd_si512(a), _mm512_set1_epi64(i64::MIN));
        _mm512_castsi512_pd(bits)
    };
    copysign |a, s| {
        let sign = _mm512_set1_epi64(i64::MIN);
        let magnitude = _mm512_andnot_si512(sign, _mm512_castpd_si512(a));
        let sign_of_s = _mm512_and_si512(sign, _mm512_castpd_si512(s));
        _mm512_castsi512_pd(_mm512_or_si512(magnitude, sign_of_s))
    };
    compare<P> |a, b| _mm512_cmp_pd_mask::<P>(a, b);
    select |m, a, b| _mm512_mask_blend_pd(m, b, a);
}

x86_lanes! {
    /// 16 × f32 in an AVX-512 register, sign bits handled as integers as in `F64x8`.
    F32x16(__m512): 16 lanes, one F32x1, wide F64x8, tiny 1e-30, slack 1.0 / 65536.0;
    safety: "AVX-512F instructions; only named by `Kernel::run` for `Kernel::Avx512`, inside \
        its `avx512` entry point, after `Kernel::supported` detected AVX-512F.";
    outlined avx512;
    mask u16;
    add _mm512_add_ps, sub _mm512_sub_ps, mul _mm512_mul_ps, div _mm512_div_ps,
    sqrt _mm512_sqrt_ps, min _mm512_min_ps, max _mm512_max_ps;
    splat |x| _mm512_set1_ps(x as f32);
    load |x| _mm512_loadu_ps(narrow::<16>(x).as_ptr());
    integers |x| _mm512_cvtepi32_ps(_mm512_loadu_si512(x));
    store |v, out| {
        let mut lanes = [0f32; 16];
        _mm512_storeu_ps(lanes.as_mut_ptr(), v);
        widen(lanes, out)
    };
    store_f32 |v, out| _mm512_storeu_ps(out.as_mut_ptr(), v);
    neg |a| {
        let bits = _mm512_xor_si512(_mm512_castps_si512(a), _mm512_set1_epi32(i32::MIN));
        _mm512_castsi512_ps(bits)
    };
    copysign |a, s| {
        let sign = _mm512_set1_epi32(i32::MIN);
        let magnitude = _mm512_andnot_si512(sign, _mm512_castps_si512(a));
        let sign_of_s = _mm512_and_si512(sign, _mm512_castps_si512(s));
        _mm512_castsi512_ps(_mm512_or_si512(magnitude, sign_of_s))
    };
    compare<P> |a, b| _mm512_cmp_ps_mask::<P>(a, b);
    select |m, a, b| _mm512_mask_blend_ps(m, b, a);
}

/// AVX-512's mask registers: bit k for lane k, plain integers.
macro_rules! integer_mask {
    ($($m:ident),*) => {$(
        impl Mask for $m {
            #[inline(always)]
            fn none_set() -> $m {
                0
            }
            #[inline(always)]
            fn first(n: usize) -> $m {
                if n >= $m::BITS as usize { $m::MAX } else { (1 << n) - 1 }
            }
            #[inline(always)]
            fn from_bits(bits: u32) -> $m {
                bits as $m
            }
            #[inline(always)]
            fn and(self, o: $m) -> $m {
                self & o
            }
            #[inline(always)]
            fn or(self, o: $m) -> $m {
                self | o
            }
            #[inline(always)]
            fn andnot(self, o: $m) -> $m {
                self & !o
            }
            #[inline(always)]
            fn bits(self) -> u32 {
                u32::from(self)
            }
        }
    )*};
}
integer_mask!(u8, u16);

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
    // Integers to lanes: those exact in f32, those that round in it, and the largest allowed.
    let ints: Vec<u32> = (0..40u32)
        .chain([
            16383,
            (1 << 24) - 1,
            (1 << 24) + 1,
            (1 << 25) + 3,
            i32::MAX as u32 - 1,
        ])
        .chain([i32::MAX as u32])
        .collect();
    for chunk in ints.windows(V::N) {
        let want = V::load(&chunk.iter().map(|&i| f64::from(i)).collect::<Vec<_>>());
        let got = V::from_u32(chunk);
        assert!(
            (0..V::N).all(|k| same(got.lane(k), want.lane(k))),
            "{chunk:?}"
        );
    }
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

#[cfg(test)]
mod tests {
    use std::path::Path;

    /// The safety argument of every expansion: outside `lanes/`, only the kernel selection
    /// names the wide types (and so only it can make or run them).
    #[test]
    fn only_the_kernel_selection_names_the_wide_types() {
        let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
        let mut naming = Vec::new();
        let mut dirs = vec![src.clone()];
        while let Some(dir) = dirs.pop() {
            for entry in std::fs::read_dir(&dir).expect("src/ is readable").flatten() {
                let path = entry.path();
                if path.is_dir() {
                    dirs.push(path);
                    continue;
                }
                let file = path.strip_prefix(&src).expect("below src/");
                let allowed = file.starts_with("lanes") || file == Path::new("tracer/kernel.rs");
                let text = std::fs::read_to_string(&path).unwrap_or_default();
                let words = text.split(|c: char| !c.is_alphanumeric() && c != '_');
                let wide = ["F64x4", "F32x8", "F64x8", "F32x16", "M4", "M8"];
                if !allowed && words.into_iter().any(|w| wide.contains(&w)) {
                    naming.push(file.display().to_string());
                }
            }
        }
        assert!(naming.is_empty(), "{naming:?} name the x86 lane types");
    }
}
