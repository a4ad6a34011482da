//! SplitMix64 (Steele, Lea & Flood 2014; Vigna's reference constants).

/// SplitMix64: a small, fast, seedable generator, deterministic across platforms. The field is
/// the whole state: `SplitMix64(seed)` seeds it, and a stream never changes from one version to
/// the next (fixtures made from it are compared byte for byte).
///
/// # Examples
/// ```
/// use numerics::SplitMix64;
/// let mut r = SplitMix64(0);
/// // Vigna's reference output for seed 0.
/// assert_eq!(r.next_u64(), 0xE220_A839_7B1D_CDAF);
/// let u = r.uniform();
/// assert!(u > 0.0 && u < 1.0);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct SplitMix64(pub u64);

impl SplitMix64 {
    /// The golden-ratio increment added to the state at each step.
    pub const GAMMA: u64 = 0x9E37_79B9_7F4A_7C15;

    /// SplitMix64's finaliser: a bijective 64-bit mix (every input bit affects every output
    /// bit), usable as a hash of a `u64`.
    ///
    /// # Examples
    /// ```
    /// use numerics::SplitMix64;
    /// assert_eq!(SplitMix64::mix(SplitMix64::GAMMA), SplitMix64(0).next_u64());
    /// ```
    pub const fn mix(mut z: u64) -> u64 {
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(Self::GAMMA);
        Self::mix(self.0)
    }

    /// Uniform in `[0, 1)` on a grid of 2⁻⁵³ (the top 53 bits of [`SplitMix64::next_u64`]).
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in the open interval `(0, 1)`: the centres of the 2⁻⁵³ grid, so never 0 (safe
    /// under a logarithm) and never 1.
    pub fn uniform(&mut self) -> f64 {
        ((self.next_u64() >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }

    /// A standard normal draw (Box–Muller, cosine branch, from two [`SplitMix64::uniform`]
    /// draws).
    pub fn normal(&mut self) -> f64 {
        let (u, v) = (self.uniform(), self.uniform());
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_stream_matches_the_reference_implementation() {
        // Vigna's splitmix64.c, seed 1234567 (the first five outputs).
        let mut r = SplitMix64(1_234_567);
        let want = [
            6_457_827_717_110_365_317,
            3_203_168_211_198_807_973,
            9_817_491_932_198_370_423,
            4_593_380_528_125_082_431,
            16_408_922_859_458_223_821,
        ];
        for w in want {
            assert_eq!(r.next_u64(), w);
        }
    }

    #[test]
    fn uniform_draws_lie_in_their_intervals_and_average_a_half() {
        let mut r = SplitMix64(42);
        let (mut a, mut b) = (0.0, 0.0);
        for _ in 0..10_000 {
            let (x, y) = (r.next_f64(), r.uniform());
            assert!((0.0..1.0).contains(&x) && y > 0.0 && y < 1.0, "{x} {y}");
            a += x;
            b += y;
        }
        assert!((a / 1e4 - 0.5).abs() < 0.01 && (b / 1e4 - 0.5).abs() < 0.01, "{a} {b}");
    }

    #[test]
    fn normal_draws_have_unit_variance() {
        let mut r = SplitMix64(9);
        let v: Vec<f64> = (0..20_000).map(|_| r.normal()).collect();
        let mean = v.iter().sum::<f64>() / v.len() as f64;
        let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / v.len() as f64;
        assert!(mean.abs() < 0.03 && (var - 1.0).abs() < 0.05, "{mean} {var}");
    }

    #[test]
    fn mix_is_the_finaliser_of_next() {
        let mut r = SplitMix64(99);
        let s = r.0;
        assert_eq!(r.next_u64(), SplitMix64::mix(s.wrapping_add(SplitMix64::GAMMA)));
        assert_ne!(SplitMix64::mix(1), SplitMix64::mix(2));
    }
}
