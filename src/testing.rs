//! What unit tests share: a small deterministic generator of their random inputs.

/// Uniform values in [0, 1) from `seed`: a 64-bit linear congruential step (Knuth's MMIX
/// constants), then the state's top 53 bits as a fraction. Tests only: cheap and the same on
/// every machine, not a generator for frames.
pub(crate) fn uniform(seed: u64) -> impl FnMut() -> f64 {
    let mut s = seed;
    move || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    }
}
