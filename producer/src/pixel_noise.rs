//! The camera's noise stream: one generator per (seed, frame, row), drawn once per pixel.
//! xoshiro256++ (Blackman and Vigna, "Scrambled linear pseudorandom number generators", 2021):
//! 256 bits of state, period 2^256 - 1, passes BigCrush; eleven integer instructions a draw,
//! where ChaCha8 (a cryptographic generator, which a sensor's noise does not need) took about
//! three times as many. Its state is filled from the row's 64-bit key by SplitMix64, as the
//! authors advise (no all-zero state, distinct keys give unrelated streams). The normal draws
//! on it are `rand_distr`'s ziggurat (`StandardNormal`), exact to f64 resolution, tails
//! included.

use rand::RngCore;

/// A xoshiro256++ stream.
#[derive(Clone, Debug)]
pub struct PixelNoise {
    state: [u64; 4],
}

impl PixelNoise {
    /// The stream of the 64-bit `key` (the state filled by SplitMix64 from it).
    pub fn from_key(key: u64) -> Self {
        let mut z = key;
        let state = std::array::from_fn(|_| {
            z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
            splitmix64_finish(z)
        });
        PixelNoise { state }
    }
}

/// SplitMix64's output function (Steele, Lea and Flood 2014): a bijective mix of 64 bits.
pub fn splitmix64_finish(z: u64) -> u64 {
    let z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    let z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

impl RngCore for PixelNoise {
    #[inline(always)]
    fn next_u64(&mut self) -> u64 {
        let s = &mut self.state;
        let result = s[0].wrapping_add(s[3]).rotate_left(23).wrapping_add(s[0]);
        let t = s[1] << 17;
        s[2] ^= s[0];
        s[3] ^= s[1];
        s[1] ^= s[2];
        s[0] ^= s[3];
        s[2] ^= t;
        s[3] = s[3].rotate_left(45);
        result
    }

    #[inline(always)]
    fn next_u32(&mut self) -> u32 {
        // The high bits: the low ones of the ++ scrambler are its weakest.
        (self.next_u64() >> 32) as u32
    }

    fn fill_bytes(&mut self, dst: &mut [u8]) {
        rand::rand_core::impls::fill_bytes_via_next(self, dst)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The reference implementation's first outputs (xoshiro256plusplus.c) from the state
    /// {1, 2, 3, 4}: the generator is the published one.
    #[test]
    fn matches_the_reference_outputs() {
        let mut rng = PixelNoise {
            state: [1, 2, 3, 4],
        };
        let expected: [u64; 4] = [
            41_943_041,
            58_720_359,
            3_588_806_011_781_223,
            3_591_011_842_654_386,
        ];
        for e in expected {
            assert_eq!(rng.next_u64(), e);
        }
    }

    /// SplitMix64 from 0 gives the published first output.
    #[test]
    fn state_is_filled_by_splitmix64() {
        let rng = PixelNoise::from_key(0);
        assert_eq!(rng.state[0], 0xE220_A839_7B1D_CDAF);
    }
}
