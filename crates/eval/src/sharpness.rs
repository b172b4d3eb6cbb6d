//! A map's sharpness without ground truth: the number of occupied cells
//! when every valid return of a log is placed in the world with the
//! trajectory. A wall seen from poses that agree covers few cells; poses
//! that disagree smear it into fans that cover many. Fewer is sharper.

use pcaline_geometry::{Point2, Pose2, Scan, polar_to_cartesian};
use std::collections::HashSet;

/// Occupied cells of `cell_m` metres, filled scan by scan.
///
/// ```
/// use pcaline_eval::OccupiedCells;
/// use pcaline_geometry::{Pose2, Scan};
/// let scan = Scan::new(-0.5, 0.01, 0.1, 30.0, vec![2.0; 101]);
/// let mut still = OccupiedCells::new(0.05);
/// let mut turning = OccupiedCells::new(0.05);
/// for k in 0..10 {
///     still.add(&scan, &Pose2::identity());
///     // The same scan with a pose that turns: a smeared arc.
///     turning.add(&scan, &Pose2::new(0.0, 0.0, 0.02 * k as f64));
/// }
/// assert!(still.count() < turning.count());
/// ```
#[derive(Debug, Clone)]
pub struct OccupiedCells {
    cell_m: f64,
    cells: HashSet<(i64, i64)>,
}

impl OccupiedCells {
    /// No cells yet. A cell size that is not positive and finite is taken as 5 cm.
    pub fn new(cell_m: f64) -> Self {
        let cell_m = if cell_m.is_finite() && cell_m > 0.0 { cell_m } else { 0.05 };
        OccupiedCells { cell_m, cells: HashSet::new() }
    }

    /// Places every valid return of `scan` with `world_from_sensor`
    /// (invalid returns and a non-finite pose add nothing).
    pub fn add(&mut self, scan: &Scan, world_from_sensor: &Pose2) {
        if !world_from_sensor.is_finite() {
            return;
        }
        for (i, &r) in scan.ranges.iter().enumerate() {
            if !scan.is_valid_range(r) {
                continue;
            }
            let p: Point2<f64> =
                world_from_sensor.transform_point(&polar_to_cartesian(f64::from(r), scan.angle(i)));
            let key = |v: f64| (v / self.cell_m).floor().clamp(-1e15, 1e15) as i64;
            self.cells.insert((key(p.x), key(p.y)));
        }
    }

    /// Cells occupied so far.
    pub fn count(&self) -> usize {
        self.cells.len()
    }
}
