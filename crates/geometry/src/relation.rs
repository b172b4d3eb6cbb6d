//! [`Relation`]: a measured relative pose between two instants, the unit of
//! Kuemmerle et al.'s relation metric (2009).

use crate::Pose2;

/// The pose at `t2_s` expressed in the frame of the pose at `t1_s`
/// (`world_from_a.between(&world_from_b)`), as a ground-truth relation file
/// states it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Relation {
    /// Time of the first pose, seconds.
    pub t1_s: f64,
    /// Time of the second pose, seconds.
    pub t2_s: f64,
    /// The second pose in the frame of the first (x, y, yaw).
    pub relative: Pose2,
}
