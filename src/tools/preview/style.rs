//! The preview's colours, the material tints of objects, and how numbers are written on it.

use super::*;

/// The camera path's colour; nothing else in a panel uses it, so tests can find the trace.
pub const PATH: Rgb<u8> = Rgb([0, 92, 230]);

/// The path where the camera is inside an object, and warning text.
pub const BAD: Rgb<u8> = Rgb([225, 25, 25]);

pub(super) const BACKGROUND: Rgb<u8> = Rgb([246, 246, 244]);

pub(super) const PANEL: Rgb<u8> = Rgb([255, 255, 255]);

pub(super) const GRID: Rgb<u8> = Rgb([234, 234, 234]);

pub(super) const AXIS: Rgb<u8> = Rgb([200, 200, 200]);

pub(super) const BORDER: Rgb<u8> = Rgb([150, 150, 150]);

pub(super) const INK: Rgb<u8> = Rgb([30, 30, 30]);

pub(super) const MUTED: Rgb<u8> = Rgb([120, 120, 120]);

pub(super) const LABEL: Rgb<u8> = Rgb([80, 80, 80]);

pub(super) const KEYFRAME: Rgb<u8> = Rgb([20, 20, 20]);

pub(super) const TARGET: Rgb<u8> = Rgb([240, 130, 0]);

pub(super) const TARGET_LINK: Rgb<u8> = Rgb([250, 200, 150]);

pub(super) const TICK: Rgb<u8> = Rgb([160, 80, 10]);

pub(super) const START: Rgb<u8> = Rgb([0, 170, 70]);

pub(super) const END: Rgb<u8> = Rgb([150, 40, 200]);

pub(super) const LIGHT: Rgb<u8> = Rgb([255, 205, 0]);

/// The path of a moving object (teal) or light (amber, darker than the light's own yellow so
/// it reads on white).
pub const OBJECT_PATH: Rgb<u8> = Rgb([0, 150, 136]);
pub const LIGHT_PATH: Rgb<u8> = Rgb([215, 150, 0]);

/// The material's diffuse colour brightened to full and mixed with white: `amount` of colour.
pub(super) fn tint(m: &Material, amount: f64) -> Rgb<u8> {
    let base = hue(m);
    to_rgb(base * amount + DVec3::ONE * (1.0 - amount))
}

/// The material's colour darkened, for outlines.
pub(super) fn shade(m: &Material) -> Rgb<u8> {
    to_rgb(hue(m) * 0.6)
}

/// The diffuse colour brightened towards full strength as far as it is saturated: a dark red
/// reads as red, a grey stays grey instead of turning white.
pub(super) fn hue(m: &Material) -> DVec3 {
    let d = m.diffuse.clamp(DVec3::ZERO, DVec3::ONE);
    let top = d.max_element();
    if top < 1e-6 {
        return DVec3::ZERO;
    }
    let saturation = (top - d.min_element()) / top;
    d + (d / top) * (1.0 - top) * saturation
}

pub(super) fn to_rgb(c: DVec3) -> Rgb<u8> {
    let q = |v: f64| (v.clamp(0.0, 1.0) * 255.0).round() as u8;
    Rgb([q(c.x), q(c.y), q(c.z)])
}

/// 1, 2 or 5 × 10^k, the nearest to `raw`.
pub(super) fn nice_step(raw: f64) -> f64 {
    let e = 10f64.powf(raw.log10().floor());
    let m = raw / e;
    let k = if m < 1.5 {
        1.0
    } else if m < 3.5 {
        2.0
    } else if m < 7.5 {
        5.0
    } else {
        10.0
    };
    k * e
}

/// A number in at most 3 decimals without trailing zeros, or in exponent form when tiny or huge.
pub(super) fn fmt_num(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 {
        return "0".into();
    }
    if !(1e-3..1e7).contains(&a) {
        return format!("{v:.1e}");
    }
    let s = format!("{v:.3}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

pub(super) fn fmt_vec(v: DVec3) -> String {
    format!("({}, {}, {})", fmt_num(v.x), fmt_num(v.y), fmt_num(v.z))
}

pub(super) fn dist(a: (f64, f64), b: (f64, f64)) -> f64 {
    (a.0 - b.0).hypot(a.1 - b.1)
}
#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steps_are_nice() {
        assert_eq!(nice_step(0.45), 0.5);
        assert_eq!(nice_step(1.2), 1.0);
        assert!((nice_step(0.00023) - 0.0002).abs() < 1e-12);
    }
}
