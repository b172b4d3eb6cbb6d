//! Seed derivation: every random stream of the simulator is a pure function of
//! the user's seed, a stream tag and an index, so results do not depend on the
//! order or the thread in which scans are simulated.

use rand::SeedableRng;
use rand::rngs::StdRng;

/// The random streams of the simulator.
#[derive(Debug, Clone, Copy)]
#[repr(u64)]
pub(crate) enum Stream {
    /// Range noise and faults of one scan.
    Scan = 1,
    /// Odometry corruption of one step.
    Odometry = 2,
    /// Maze generation.
    Maze = 3,
}

/// SplitMix64 finaliser: a bijective, well-mixing map of 64-bit values.
fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The generator of stream `stream`, item `index`, for the user seed `seed`.
pub(crate) fn stream_rng(seed: u64, stream: Stream, index: u64) -> StdRng {
    StdRng::seed_from_u64(mix(mix(seed ^ mix(stream as u64)) ^ index))
}
