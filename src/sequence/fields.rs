//! Checks of single values, each naming the field's path: numbers, vectors, colours, angles.

use super::*;

pub(super) fn number(path: &str, v: f64) -> Check<f64> {
    if !v.is_finite() {
        invalid(path, format!("must be a finite number {}", got_num(v)))
    } else if v.abs() > MAX_MAGNITUDE {
        invalid(
            path,
            format!(
                "must be within ±{MAX_MAGNITUDE:e} (lengths are squared) {}",
                got_num(v)
            ),
        )
    } else {
        Ok(v)
    }
}

pub(super) fn vector(path: &str, v: raw::V3) -> Check<DVec3> {
    for (i, x) in v.iter().enumerate() {
        number(&format!("{path}[{i}]"), *x)?;
    }
    Ok(DVec3::from(v))
}

pub(super) fn unit(path: &str, v: raw::V3) -> Check<DVec3> {
    direction(path, v).map(|d| d.normalize())
}

/// A vector that has a direction, kept as written: a camera's `up` is used exactly as printed
/// by `rayreel camera`, so a still camera given those numbers renders the same frame.
pub(super) fn direction(path: &str, v: raw::V3) -> Check<DVec3> {
    let d = vector(path, v)?;
    let n = d.normalize_or_zero();
    if n == DVec3::ZERO || !n.is_finite() {
        return invalid(
            path,
            format!("must have a non-zero length {}", got(fmt3(v))),
        );
    }
    Ok(d)
}

pub(super) fn color(path: &str, v: raw::V3) -> Check<DVec3> {
    // Not `vector`: a colour's limit is MAX_COLOR, not the squared lengths' 1e100.
    let c = DVec3::from(v);
    if !c.is_finite() || c.min_element() < 0.0 || c.max_element() > MAX_COLOR {
        return invalid(
            path,
            format!("components must be in [0, {MAX_COLOR}] {}", got(fmt3(v))),
        );
    }
    Ok(c)
}

pub(super) fn in_range(path: &str, v: f64, lo: f64, hi: f64, what: &str) -> Check<f64> {
    number(path, v)?;
    if v < lo || v > hi {
        return invalid(path, format!("must be {what} {}", got_num(v)));
    }
    Ok(v)
}

pub(super) fn positive(path: &str, v: f64) -> Check<f64> {
    if number(path, v)? <= 0.0 {
        return invalid(path, format!("must be greater than 0 {}", got_num(v)));
    }
    Ok(v)
}

pub(super) fn fov(path: &str, v: f64) -> Check<f64> {
    number(path, v)?;
    if !(v > 0.0 && v < 180.0) {
        return invalid(
            path,
            format!(
                "must be between 0 and 180 degrees, exclusive {}",
                got_num(v)
            ),
        );
    }
    Ok(v)
}
