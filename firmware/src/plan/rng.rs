//! The flight software's random generator: SplitMix64 (Steele, Lea, Flood, "Fast splittable pseudorandom number
//! generators", OOPSLA 2014), the 64-bit mixer of Java's `SplittableRandom`.
//!
//! A `rand_core` generator with a 64-bit state and no parameters: the state advances by the golden-ratio increment
//! `0x9E37_79B9_7F4A_7C15` and each draw is the state passed through the murmur3-style finaliser. The navigator
//! samples with it (seeded from `Configure.planner.rng_seed` and the goal id, its state kept in the suspended
//! search); the benchmark workloads use it too. `next_u32` is the upper half of `next_u64`; `fill_bytes` writes
//! successive `next_u64` draws little-endian.

use core::convert::Infallible;

/// SplitMix64: the state is the tuple field (the seed when constructed).
#[derive(Debug, Clone)]
pub struct SplitMix64(pub u64);

impl rand_core::TryRng for SplitMix64 {
    type Error = Infallible;
    fn try_next_u32(&mut self) -> Result<u32, Infallible> {
        self.try_next_u64().map(|x| (x >> 32) as u32)
    }
    fn try_next_u64(&mut self) -> Result<u64, Infallible> {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        Ok(z ^ (z >> 31))
    }
    fn try_fill_bytes(&mut self, dst: &mut [u8]) -> Result<(), Infallible> {
        for chunk in dst.chunks_mut(8) {
            let bytes = self.try_next_u64()?.to_le_bytes();
            for (d, s) in chunk.iter_mut().zip(bytes) {
                *d = s;
            }
        }
        Ok(())
    }
}
