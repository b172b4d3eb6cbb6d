//! Simulates a custom scene (a room with a pillar, as a scene file's text)
//! with the UTM-30LX-EW model, detects every scan's lines with the default
//! detector, and scores them against the exact ground truth with the
//! project's protocol: recall, false positives, orientation error
//! (median and rms).
//!
//! ```sh
//! cargo run --release --example simulate_and_score
//! ```

// An example prints its results.
#![allow(clippy::print_stdout)]

use pcaline::{Config, LineDetector};
use pcaline_eval::{DetectionCriteria, DetectionScore, true_walls};
use pcaline_sim::Simulator;

const SCENE: &str = r#"
name = "room-with-pillar"
[[walls]]
name = "room"
closed = true
points = [[0, 0], [8, 0], [8, 5], [0, 5]]
[[obstacles]]
name = "pillar"
closed = true
points = [[4, 2], [4.6, 2], [4.6, 2.6], [4, 2.6]]
[trajectory]
start = { x = 1, y = 1, heading_deg = 0 }
waypoints = [[7, 1], [7, 4], [1, 4]]
"#;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let scene = pcaline_io::parse_scene(std::path::Path::new("room-with-pillar.toml"), SCENE)?;
    scene.validate()?;
    let sim = Simulator::new(&scene, 7)?;
    let mut detector = LineDetector::new(Config::default())?;
    let criteria = DetectionCriteria::default();
    let mut score = DetectionScore::default();
    for frame in sim.frames() {
        let truth = true_walls(&frame, sim.world(), &criteria);
        let lines: Vec<_> = detector.detect(&frame.scan).lines.iter().map(|l| l.line).collect();
        score.add_scan(&truth, &lines, &criteria);
    }
    let (alpha_median, alpha_rms) = score.alpha_error();
    println!(
        "{} scans: recall {:.3}, false positives {:.3}, orientation error {:.3}° median, {:.3}° rms",
        score.scans,
        score.recall(),
        score.false_positive_fraction(),
        alpha_median.to_degrees(),
        alpha_rms.to_degrees()
    );
    Ok(())
}
