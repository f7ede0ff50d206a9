//! How far along its shape a track is at a time: arc length s as a function of time.
//!
//! Smooth timing is a monotone C1 cubic Hermite through the keys (Fritsch–Carlson). Segment k
//! runs from key time τ_k to τ_{k+1} (h_k = τ_{k+1} − τ_k) over arc length L_k, with mean
//! rate δ_k = L_k / h_k. The rate m_k = ds/dt at key k is
//! * 0 at a stop, or where either neighbouring segment has zero length;
//! * inside: (δ_{k−1} + δ_k)/2, limited to 3·min(δ_{k−1}, δ_k) so s never decreases
//!   (Fritsch and Carlson's sufficient square α, β ≤ 3);
//! * at the first and last key unless they stop: zero acceleration ("natural" end),
//!   m_0 = (3δ_0 − m_1)/2 and m_{n−1} = (3δ_{n−2} − m_{n−2})/2; with two free ends and
//!   one segment both are δ_0.
//!
//! Linear timing (`interpolation: linear`) is piecewise linear in time, eased only next to a
//! stop.

/// Largest mean rate kept: keys a hair apart in time would otherwise overflow the tangents.
const MAX_RATE: f64 = 1e300;

/// δ = length / duration, finite whatever the inputs.
pub(crate) fn mean_rate(length: f64, duration: f64) -> f64 {
    if length <= 0.0 {
        0.0
    } else if duration > 0.0 {
        (length / duration).min(MAX_RATE)
    } else {
        MAX_RATE
    }
}

/// The rate ds/dt at every key (see the module doc).
pub(crate) fn slopes(times: &[f64], lengths: &[f64], stops: &[bool]) -> Vec<f64> {
    let n = times.len();
    let delta: Vec<f64> = (0..n - 1)
        .map(|k| mean_rate(lengths[k], times[k + 1] - times[k]))
        .collect();
    let mut m = vec![0.0; n];
    for k in 1..n - 1 {
        let (a, b) = (delta[k - 1], delta[k]);
        if !stops[k] && a > 0.0 && b > 0.0 {
            m[k] = (0.5 * (a + b)).min(3.0 * a).min(3.0 * b);
        }
    }
    let last = n - 1;
    let free_first = !stops[0] && delta[0] > 0.0;
    let free_last = !stops[last] && delta[last - 1] > 0.0;
    if n == 2 && free_first && free_last {
        m[0] = delta[0];
        m[1] = delta[0];
        return m;
    }
    if free_first {
        m[0] = 0.5 * (3.0 * delta[0] - m[1]);
    }
    if free_last {
        m[last] = 0.5 * (3.0 * delta[last - 1] - m[last - 1]);
    }
    m
}

/// Arc length covered and its rate ds/dt at fraction u ∈ [0, 1] of a segment of duration h and
/// length `length`, with rates m0 and m1 at its ends.
pub(crate) fn hermite(u: f64, h: f64, length: f64, m0: f64, m1: f64) -> (f64, f64) {
    let (u2, u3) = (u * u, u * u * u);
    let h01 = 3.0 * u2 - 2.0 * u3;
    let h10 = u3 - 2.0 * u2 + u;
    let h11 = u3 - u2;
    let s = length * h01 + h * (m0 * h10 + m1 * h11);
    let d01 = 6.0 * u - 6.0 * u2;
    let d10 = 3.0 * u2 - 4.0 * u + 1.0;
    let d11 = 3.0 * u2 - 2.0 * u;
    let rate = mean_rate(length, h) * d01 + m0 * d10 + m1 * d11;
    (s.clamp(0.0, length), rate.max(0.0))
}

/// Linear timing: the fraction e(u) of the segment covered and de/du. A stop at either end
/// eases that end (u², u(2 − u), or u²(3 − 2u) for both), so the camera does halt there.
pub(crate) fn eased(u: f64, stop_start: bool, stop_end: bool) -> (f64, f64) {
    match (stop_start, stop_end) {
        (false, false) => (u, 1.0),
        (true, false) => (u * u, 2.0 * u),
        (false, true) => (u * (2.0 - u), 2.0 - 2.0 * u),
        (true, true) => (u * u * (3.0 - 2.0 * u), 6.0 * u * (1.0 - u)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// s at n points across every segment never decreases and hits every key exactly.
    fn assert_monotone(times: &[f64], lengths: &[f64], stops: &[bool]) {
        let m = slopes(times, lengths, stops);
        for k in 0..times.len() - 1 {
            let h = times[k + 1] - times[k];
            let mut last = 0.0;
            for i in 0..=1000 {
                let (s, rate) = hermite(i as f64 / 1000.0, h, lengths[k], m[k], m[k + 1]);
                assert!(s >= last, "segment {k} goes back at {i}: {s} < {last}");
                assert!(rate >= 0.0);
                last = s;
            }
            assert_eq!(last, lengths[k]);
        }
    }

    #[test]
    fn arc_length_never_decreases() {
        assert_monotone(&[0.0, 1.0, 2.0, 3.0], &[1.0, 4.0, 1.0], &[false; 4]);
        assert_monotone(&[0.0, 1.0, 2.0, 3.0], &[4.0, 0.1, 4.0], &[false; 4]);
        assert_monotone(&[0.0, 0.1, 3.0, 3.2], &[5.0, 0.2, 9.0], &[false; 4]);
        assert_monotone(&[0.0, 1.0, 2.0], &[1.0, 1.0], &[false, true, false]);
        assert_monotone(
            &[0.0, 1.0, 2.0, 5.0],
            &[1.0, 0.0, 3.0],
            &[true, false, false, true],
        );
    }

    #[test]
    fn even_keys_give_constant_speed_and_stops_give_zero() {
        let m = slopes(&[0.0, 1.0, 2.0, 3.0], &[2.0, 2.0, 2.0], &[false; 4]);
        assert_eq!(m, vec![2.0; 4]);
        let m = slopes(&[0.0, 1.0, 2.0], &[2.0, 2.0], &[false, true, false]);
        assert_eq!(m, vec![3.0, 0.0, 3.0]);
        assert_eq!(slopes(&[0.0, 2.0], &[3.0], &[false, false]), vec![1.5, 1.5]);
        assert_eq!(slopes(&[0.0, 2.0], &[3.0], &[false, true]), vec![2.25, 0.0]);
    }

    #[test]
    fn keys_a_hair_apart_stay_finite() {
        let m = slopes(&[0.0, 1e-300, 1.0], &[1e100, 1.0], &[false; 3]);
        assert!(m.iter().all(|v| v.is_finite()), "{m:?}");
        let (s, rate) = hermite(0.5, 1e-300, 1e100, m[0], m[1]);
        assert!(s.is_finite() && rate.is_finite());
    }
}
