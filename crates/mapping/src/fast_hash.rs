//! [`FastHash`]: the hasher of the map's own hash tables (grid cells keyed by
//! integer coordinates, line ids). The standard library's SipHash resists
//! collision attacks, which keys the map makes itself do not need, and it cost
//! 13% of a map update (perf, `benches/mapping.rs`). This is the
//! multiply-rotate hash of rustc's `FxHasher`: one rotate, xor and multiply
//! per word.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// A hash map with [`FastHash`].
pub(crate) type FastMap<K, V> = HashMap<K, V, BuildHasherDefault<FastHash>>;

/// Multiply-rotate hashing of integer words (rustc's `FxHasher`). Not for keys
/// an adversary chooses.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct FastHash(u64);

impl FastHash {
    #[inline]
    fn add(&mut self, word: u64) {
        self.0 = (self.0.rotate_left(5) ^ word).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
}

impl Hasher for FastHash {
    #[inline]
    fn write(&mut self, bytes: &[u8]) {
        for chunk in bytes.chunks(8) {
            let mut word = [0u8; 8];
            word[..chunk.len()].copy_from_slice(chunk);
            self.add(u64::from_le_bytes(word));
        }
    }
    #[inline]
    fn write_u32(&mut self, n: u32) {
        self.add(u64::from(n));
    }
    #[inline]
    fn write_u64(&mut self, n: u64) {
        self.add(n);
    }
    #[inline]
    fn write_usize(&mut self, n: usize) {
        self.add(n as u64);
    }
    #[inline]
    fn finish(&self) -> u64 {
        self.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::hash::{BuildHasher, Hash};

    #[test]
    fn equal_keys_hash_equal_and_neighbours_differ() {
        let build = BuildHasherDefault::<FastHash>::default();
        let hash = |k: &(i32, i32)| build.hash_one(k);
        assert_eq!(hash(&(3, -4)), hash(&(3, -4)));
        let mut seen: Vec<u64> =
            (-20..20).flat_map(|i| (-20..20).map(move |j| (i, j))).map(|k| hash(&k)).collect();
        seen.sort_unstable();
        seen.dedup();
        assert_eq!(seen.len(), 1600, "neighbouring cells collide");
        let mut h = FastHash::default();
        b"seven bytes and more".hash(&mut h);
        assert_ne!(h.finish(), 0);
    }
}
