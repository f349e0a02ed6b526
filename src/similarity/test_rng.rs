//! The seeded generator the similarity tests draw their random runs and
//! values from (Marsaglia's xorshift64, shifts 13, 7, 17): the same
//! sequence every run, so a failing case is reproducible from its seed.

/// A xorshift64 state; `seed` must not be 0 (0 stays 0).
pub(crate) struct XorShift(u64);

impl XorShift {
    /// A generator starting from `seed`.
    pub(crate) fn new(seed: u64) -> XorShift {
        XorShift(seed)
    }

    /// The next 64 bits.
    pub(crate) fn next_u64(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }

    /// The next value below `m` (`m` > 0; the small modulo bias is of no
    /// account to a test).
    pub(crate) fn below(&mut self, m: u32) -> u32 {
        (self.next_u64() % u64::from(m)) as u32
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The first values of the generator are xorshift64's (13, 7, 17)
    /// sequence from the seed, and `below` stays below its bound.
    #[test]
    fn the_sequence_is_xorshift64_and_below_stays_below() {
        let mut g = XorShift::new(1);
        // 1 → 1 ^ (1 << 13) = 8193 → 8193 ^ (8193 >> 7) = 8257 → 8257 ^ (8257 << 17).
        assert_eq!(g.next_u64(), 8257 ^ (8257 << 17));
        let mut g = XorShift::new(0x2545_f491_4f6c_dd1d);
        let mut seen = [false; 7];
        for _ in 0..1000 {
            let v = g.below(7);
            assert!(v < 7);
            seen[v as usize] = true;
        }
        assert!(seen.iter().all(|s| *s), "{seen:?}");
    }
}
