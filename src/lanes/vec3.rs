//! Three coordinates, each a lane type: N vectors in structure-of-arrays form. Every method
//! performs glam's `DVec3` operations in glam's order (dot = (x·x + y·y) + z·z, normalize =
//! v · (1 / √(v·v))), so a lane holds exactly what the scalar `DVec3` code held. `a * b` is
//! the component-wise product, `a * s` and `a / s` scale by one lane value per vector.

use super::{Lanes, MAX_LANES};
use glam::DVec3;
use std::ops::{Add, Div, Mul, Neg, Sub};

#[derive(Clone, Copy)]
pub struct V3<V> {
    pub x: V,
    pub y: V,
    pub z: V,
}

impl<V: Lanes> V3<V> {
    #[inline(always)]
    pub fn splat(v: DVec3) -> V3<V> {
        V3 {
            x: V::splat(v.x),
            y: V::splat(v.y),
            z: V::splat(v.z),
        }
    }

    #[inline(always)]
    pub fn zero() -> V3<V> {
        V3::splat(DVec3::ZERO)
    }

    #[inline(always)]
    pub fn dot(self, o: V3<V>) -> V {
        self.x * o.x + self.y * o.y + self.z * o.z
    }

    #[inline(always)]
    pub fn length(self) -> V {
        self.dot(self).sqrt()
    }

    #[inline(always)]
    pub fn normalize(self) -> V3<V> {
        let recip = V::splat(1.0) / self.length();
        V3 {
            x: self.x * recip,
            y: self.y * recip,
            z: self.z * recip,
        }
    }

    /// Lane-wise `if m { a } else { b }`.
    #[inline(always)]
    pub fn select(m: V::M, a: V3<V>, b: V3<V>) -> V3<V> {
        V3 {
            x: V::select(m, a.x, b.x),
            y: V::select(m, a.y, b.y),
            z: V::select(m, a.z, b.z),
        }
    }

    /// Lanes `from` … `from + N − 1` of per-axis arrays.
    #[inline(always)]
    pub fn load(a: &[[f64; MAX_LANES]; 3], from: usize) -> V3<V> {
        V3 {
            x: V::load(&a[0][from..]),
            y: V::load(&a[1][from..]),
            z: V::load(&a[2][from..]),
        }
    }

    /// Into lanes `from` … `from + N − 1` of per-axis arrays.
    #[inline(always)]
    pub fn store(self, a: &mut [[f64; MAX_LANES]; 3], from: usize) {
        self.x.store(&mut a[0][from..]);
        self.y.store(&mut a[1][from..]);
        self.z.store(&mut a[2][from..]);
    }

    /// Lane `k` as a `DVec3`.
    #[inline(always)]
    pub fn lane(self, k: usize) -> DVec3 {
        DVec3::new(self.x.lane(k), self.y.lane(k), self.z.lane(k))
    }

    /// Lanes from a function of the lane index.
    #[inline(always)]
    pub fn from_fn(mut f: impl FnMut(usize) -> DVec3) -> V3<V> {
        let mut v = [DVec3::ZERO; MAX_LANES];
        for (k, x) in v.iter_mut().enumerate().take(V::N) {
            *x = f(k);
        }
        V3 {
            x: V::from_fn(|k| v[k].x),
            y: V::from_fn(|k| v[k].y),
            z: V::from_fn(|k| v[k].z),
        }
    }
}

macro_rules! componentwise {
    ($trait:ident, $f:ident, $op:tt) => {
        impl<V: Lanes> $trait for V3<V> {
            type Output = V3<V>;
            #[inline(always)]
            fn $f(self, o: V3<V>) -> V3<V> {
                V3 {
                    x: self.x $op o.x,
                    y: self.y $op o.y,
                    z: self.z $op o.z,
                }
            }
        }
    };
}
componentwise!(Add, add, +);
componentwise!(Sub, sub, -);
componentwise!(Mul, mul, *);

/// v · s per component (glam's `f64 * DVec3`; the product is the same either way round).
impl<V: Lanes> Mul<V> for V3<V> {
    type Output = V3<V>;
    #[inline(always)]
    fn mul(self, s: V) -> V3<V> {
        V3 {
            x: s * self.x,
            y: s * self.y,
            z: s * self.z,
        }
    }
}

/// v / s per component (glam's `DVec3 / f64`).
impl<V: Lanes> Div<V> for V3<V> {
    type Output = V3<V>;
    #[inline(always)]
    fn div(self, s: V) -> V3<V> {
        V3 {
            x: self.x / s,
            y: self.y / s,
            z: self.z / s,
        }
    }
}

impl<V: Lanes> Neg for V3<V> {
    type Output = V3<V>;
    #[inline(always)]
    fn neg(self) -> V3<V> {
        V3 {
            x: -self.x,
            y: -self.y,
            z: -self.z,
        }
    }
}
