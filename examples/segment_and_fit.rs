//! Line detection with the segmentation and fitting crates alone, without
//! the facade: polar to Cartesian (eq. 1), level-1 break-points, a split at
//! the farthest point, and a PCA fit with the elongation test (eq. 3-6) for
//! each piece.
//!
//! ```sh
//! cargo run --release --example segment_and_fit
//! ```

// An example prints its results.
#![allow(clippy::print_stdout)]

use pcaline_fitting::{Moments, fit_pca, is_elongated};
use pcaline_geometry::{BearingTable, RangeNoise, Scan, ScanPoints};
use pcaline_segmentation::{BreakRule, level1_clusters, split_at_farthest};

fn main() {
    // A corner 2 m ahead and 3 m to the left: 181 beams over 90°.
    let ranges: Vec<f32> = (0..181)
        .map(|i| {
            let bearing = (i as f64 * 0.5f64).to_radians();
            (2.0 / bearing.cos()).min(3.0 / bearing.sin()) as f32
        })
        .collect();
    let scan = Scan::new(0.0, 0.5f32.to_radians(), 0.1, 30.0, ranges);

    let mut points = ScanPoints::default();
    points.fill_from(&scan, &mut BearingTable::default());
    let noise = RangeNoise::constant(0.01);
    let rule = BreakRule::Adaptive {
        lambda_rad: 10f64.to_radians(),
        sigma_factor: 3.0,
        noise,
        grazing: true,
    };
    let (mut breaks, mut clusters) = (Vec::new(), Vec::new());
    level1_clusters(&points, &rule, 5, &mut breaks, &mut clusters);
    let (mut stack, mut pieces) = (Vec::new(), Vec::new());
    for cluster in clusters {
        split_at_farthest(&points, cluster, &noise, 4.0, 0.0, &mut stack, &mut pieces);
    }
    for piece in pieces {
        let xy = &points.xy[piece.clone()];
        if xy.len() < 5 || !is_elongated(&Moments::from_points(xy).eigen(), 10.0) {
            continue;
        }
        if let Some(line) = fit_pca(xy) {
            println!(
                "beams {:?}: alpha {:+.3} rad, d {:.3} m, {:.2} m long",
                piece,
                line.alpha,
                line.d,
                line.length()
            );
        }
    }
}
