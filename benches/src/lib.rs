//! Shared fixtures for the criterion benchmarks: seeded, reproducible inputs.
//!
//! Benchmarks must measure the same work on every run, so every random input
//! comes from [`SplitMix64`] with a fixed seed instead of an entropy source.

/// A tiny deterministic generator (SplitMix64) for benchmark inputs.
///
/// Not for statistics: it only has to be cheap, seeded and identical on every machine.
#[derive(Clone, Debug)]
pub struct SplitMix64 {
    state: u64,
}

impl SplitMix64 {
    /// a generator whose sequence is fixed by `seed`.
    pub fn new(seed: u64) -> Self {
        Self { state: seed }
    }

    /// next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// uniform sample in `[lo, hi)`.
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        // 53 random bits give every representable step of [0, 1).
        let unit = (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64);
        lo + (hi - lo) * unit
    }
}

#[cfg(test)]
mod tests {
    use super::SplitMix64;

    #[test]
    fn uniform_stays_in_range_and_is_reproducible() {
        let mut a = SplitMix64::new(7);
        let mut b = SplitMix64::new(7);
        for _ in 0..10_000 {
            let x = a.uniform(-2.0, 3.0);
            assert!((-2.0..3.0).contains(&x));
            assert_eq!(x.to_bits(), b.uniform(-2.0, 3.0).to_bits());
        }
    }
}
