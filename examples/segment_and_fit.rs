//! Line detection with the segmentation and fitting crates alone, without
//! the facade: each crate's one entry point over its own configuration,
//! `segment` (eq. 1-2: points, level-1 and level-2 clusters) then
//! `fit_lines` (eq. 3-7: PCA fits, the elongation test, the merge).
//!
//! ```sh
//! cargo run --release --example segment_and_fit
//! ```

// An example prints its results.
#![allow(clippy::print_stdout)]

use pcaline_fitting::{FitConfig, LineFits, fit_lines};
use pcaline_segmentation::{BearingTable, Scan, ScanPoints, SegmentationConfig, Segments, segment};

fn main() {
    // A corner 2 m ahead and 3 m to the left: 181 beams over 90°.
    let ranges: Vec<f32> = (0..181)
        .map(|i| {
            let bearing = (i as f64 * 0.5f64).to_radians();
            (2.0 / bearing.cos()).min(3.0 / bearing.sin()) as f32
        })
        .collect();
    let scan = Scan::new(0.0, 0.5f32.to_radians(), 0.1, 30.0, ranges);

    // Detection: these buffers are kept across scans, so a stream of scans
    // allocates nothing once they have grown.
    let (mut points, mut segments, mut fits) =
        (ScanPoints::default(), Segments::default(), LineFits::default());
    points.fill_from(&scan, &mut BearingTable::default());
    segment(&scan, &mut points, &SegmentationConfig::default(), &mut segments);
    let s = &mut segments;
    let (fit, noise) = (FitConfig::default(), None);
    fit_lines(
        &points,
        &s.clusters,
        &mut s.sub_clusters,
        s.ring_without_break,
        &fit,
        noise,
        &mut fits,
    );

    for l in &fits.lines {
        println!(
            "beams {}..={}: alpha {:+.3} rad, d {:.3} m, {:.2} m long",
            l.first_beam,
            l.last_beam,
            l.line.alpha(),
            l.line.d(),
            l.line.length()
        );
    }
}
