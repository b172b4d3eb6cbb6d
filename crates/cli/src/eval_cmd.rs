//! `pcaline eval`: line detection against ground truth on the shipped scenes
//! (design, section 5), for the paper preset, the default and the
//! split-and-merge baseline.

use crate::exit::BadInput;
use anyhow::Result;
use pcaline::{Config, LineDetector, LineSegment, RangeNoise, Scan};
use pcaline_eval::{DetectFn, DetectionCriteria, DetectionEval, evaluate_detectors};
use pcaline_io::parse_scene;
use serde::Serialize;
use std::path::Path;

/// The scenes, embedded.
const SCENES: [(&str, &str); 4] = [
    ("corridor-doors", include_str!("../../../sim-scenes/corridor-doors.toml")),
    ("office-clutter", include_str!("../../../sim-scenes/office-clutter.toml")),
    ("hall-pillars", include_str!("../../../sim-scenes/hall-pillars.toml")),
    ("paper-maze", include_str!("../../../sim-scenes/paper-maze.toml")),
];

/// Arguments of `pcaline eval`.
#[derive(Debug, clap::Args)]
pub struct EvalArgs {
    /// Range noise of the simulated sensor, millimetres (repeat for several).
    #[arg(long = "sigma-mm", default_values_t = [10.0, 30.0])]
    sigma_mm: Vec<f64>,
    /// Seeds per scene.
    #[arg(long, default_value_t = 3)]
    seeds: u64,
    /// Scans per scene and seed.
    #[arg(long, default_value_t = 60)]
    scans: usize,
    /// Print JSON instead of tables.
    #[arg(long)]
    json: bool,
    /// Evaluate on real data instead: raw and aided odometry of the MIT
    /// CSAIL log against its corrected poses.
    #[arg(long)]
    real: bool,
    /// Seed of the synthetic drift added to the Intel log's poses (for --real).
    #[arg(long, default_value_t = 1)]
    drift_seed: u64,
    /// The datasets folder (for --real); `$PCALINE_DATA` or `../shared/data`.
    #[arg(long)]
    data: Option<std::path::PathBuf>,
}

#[derive(Debug, Serialize)]
struct Row {
    sigma_mm: f64,
    detector: &'static str,
    scans: usize,
    true_walls: usize,
    recall: f64,
    false_positive_fraction: f64,
    fragmentation: f64,
    alpha_median_deg: f64,
    alpha_rms_deg: f64,
    d_median_mm: f64,
    d_rms_mm: f64,
    time_per_scan_us: f64,
}

/// Runs `pcaline eval`.
pub fn run(args: &EvalArgs, _quiet: bool) -> Result<()> {
    if args.real {
        let data = args
            .data
            .clone()
            .or_else(|| std::env::var_os("PCALINE_DATA").map(Into::into))
            .unwrap_or_else(|| "../shared/data".into());
        let report = crate::eval_real::evaluate(&data, args.drift_seed)?;
        if args.json {
            println!("{}", serde_json::to_string_pretty(&report)?);
        } else {
            print_real(&report);
        }
        return Ok(());
    }
    if args.sigma_mm.iter().any(|s| !(s.is_finite() && *s >= 0.0)) {
        return Err(BadInput("--sigma-mm must be finite and >= 0".into()).into());
    }
    let scenes = SCENES
        .iter()
        .map(|(name, text)| parse_scene(Path::new(&format!("{name}.toml")), text))
        .collect::<Result<Vec<_>, _>>()?;
    let mut rows = Vec::new();
    for &sigma_mm in &args.sigma_mm {
        let sigma = sigma_mm / 1000.0;
        let presets: [(&'static str, Config); 4] = [
            ("paper", Config::paper()),
            ("split-and-merge", Config::split_and_merge()),
            ("default (UTM model)", Config::default()),
            ("default (told sigma)", Config::noise_aware(RangeNoise::constant(sigma.max(1e-3)))),
        ];
        let mut detectors: Vec<LineDetector> =
            presets.iter().map(|(_, c)| LineDetector::new(*c)).collect::<Result<_, _>>()?;
        let mut closures: Vec<Box<DetectFn<'_>>> = detectors
            .iter_mut()
            .map(|d| {
                Box::new(move |s: &Scan| -> Vec<LineSegment> {
                    d.detect(s).lines.iter().map(|l| l.line).collect()
                }) as Box<DetectFn<'_>>
            })
            .collect();
        let mut refs: Vec<&mut DetectFn<'_>> = closures.iter_mut().map(|c| c.as_mut()).collect();
        let eval = DetectionEval {
            sigma_m: sigma,
            seeds: args.seeds,
            scans: args.scans,
            criteria: DetectionCriteria::default(),
        };
        let results =
            evaluate_detectors(&scenes, &eval, &mut refs).map_err(|e| BadInput(e.to_string()))?;
        for ((name, _), r) in presets.iter().zip(results) {
            let s = &r.score;
            let (am, ar) = s.alpha_error();
            let (dm, dr) = s.d_error();
            rows.push(Row {
                sigma_mm,
                detector: name,
                scans: s.scans,
                true_walls: s.true_walls,
                recall: s.recall(),
                false_positive_fraction: s.false_positive_fraction(),
                fragmentation: s.fragmentation(),
                alpha_median_deg: am.to_degrees(),
                alpha_rms_deg: ar.to_degrees(),
                d_median_mm: dm * 1e3,
                d_rms_mm: dr * 1e3,
                time_per_scan_us: r.time_per_scan_us,
            });
        }
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&rows)?);
        return Ok(());
    }
    print_detection(&rows);
    print_fit_accuracy(&args.sigma_mm);
    Ok(())
}

/// Fit accuracy against the Cramer-Rao bound and covariance consistency, for
/// walls of 1, 2 and 5 m sampled as a UTM-30LX-EW at 5 m (2.2 cm spacing).
fn print_fit_accuracy(sigmas_mm: &[f64]) {
    println!();
    println!(
        "Fit accuracy (PCA, 4000 runs a row, noise across the wall) against the Cramer-Rao bound"
    );
    println!(
        "{:>6} {:>6} {:>6} {:>12} {:>12} {:>12} {:>12} {:>9}",
        "sigma", "L m", "points", "std alpha", "CRB alpha", "std offset", "CRB offset", "NEES"
    );
    for &sigma_mm in sigmas_mm {
        for length in [1.0, 2.0, 5.0] {
            let n = (length / (5.0 * 0.25f64.to_radians())) as usize + 1;
            let r = pcaline_eval::fit_accuracy(n, length, sigma_mm / 1000.0, 4000, 1);
            let expected_nees = 2.0 * (n as f64 - 2.0) / (n as f64 - 4.0);
            println!(
                "{:>4}mm {:>6} {:>6} {:>10.4}° {:>10.4}° {:>10.2}mm {:>10.2}mm {:>5.2}/{:.2}",
                sigma_mm,
                length,
                n,
                r.std_alpha_rad.to_degrees(),
                r.crb_alpha_rad.to_degrees(),
                r.std_offset_m * 1e3,
                r.crb_offset_m * 1e3,
                r.mean_nees,
                expected_nees
            );
        }
    }
}

fn print_detection(rows: &[Row]) {
    println!(
        "{:>6}  {:<22} {:>6} {:>6} {:>7} {:>6} {:>6} {:>9} {:>9} {:>8} {:>8} {:>9}",
        "sigma",
        "detector",
        "scans",
        "walls",
        "recall",
        "FP",
        "frag",
        "|da| med",
        "da rms",
        "|dd| med",
        "dd rms",
        "us/scan"
    );
    for r in rows {
        println!(
            "{:>4}mm  {:<22} {:>6} {:>6} {:>7.3} {:>6.3} {:>6.2} {:>8.3}° {:>8.3}° {:>6.1}mm {:>6.1}mm {:>9.1}",
            r.sigma_mm,
            r.detector,
            r.scans,
            r.true_walls,
            r.recall,
            r.false_positive_fraction,
            r.fragmentation,
            r.alpha_median_deg,
            r.alpha_rms_deg,
            r.d_median_mm,
            r.d_rms_mm,
            r.time_per_scan_us
        );
    }
}

fn print_real(r: &crate::eval_real::RealReport) {
    println!(
        "MIT CSAIL: {} scans with corrected poses; absolute errors after aligning at the first, relation metric between consecutive corrected scans",
        r.csail_pairs
    );
    println!(
        "{:<32} {:>11} {:>11} {:>9} {:>9} {:>17} {:>17}",
        "trajectory",
        "heading rms",
        "heading max",
        "pos rms",
        "pos final",
        "rel. trans (m)",
        "rel. rot (deg)"
    );
    for t in &r.csail {
        let f = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.2}"));
        println!(
            "{:<32} {:>9} ° {:>9} ° {:>7} m {:>7} m {:>8.3} ± {:<6.3} {:>8.3} ± {:<6.3}",
            t.name,
            f(t.heading_rms_deg),
            f(t.heading_max_deg),
            f(t.position_rms_m),
            f(t.position_final_m),
            t.relations.translation_mean_m,
            t.relations.translation_std_m,
            t.relations.rotation_mean_deg,
            t.relations.rotation_std_deg
        );
    }
    println!();
    println!(
        "Intel: relation metric against intel.relations (drift seed {}; mean ± std)",
        r.intel_drift_seed
    );
    println!(
        "{:<32} {:>9} {:>9} {:>17} {:>17}",
        "trajectory", "relations", "unmatched", "trans (m)", "rot (deg)"
    );
    for t in &r.intel {
        println!(
            "{:<32} {:>9} {:>9} {:>8.3} ± {:<6.3} {:>8.3} ± {:<6.3}",
            t.name,
            t.relations.scored,
            t.relations.unmatched,
            t.relations.translation_mean_m,
            t.relations.translation_std_m,
            t.relations.rotation_mean_deg,
            t.relations.rotation_std_deg
        );
    }
    println!();
    let u = &r.utm;
    let [p10, p50, p90] = u.residual_std_p10_p50_p90_m;
    println!(
        "UTM-30LX-EW bag {}: {} scans, {} lines (median {} points)",
        u.log, u.scans, u.lines, u.median_points
    );
    println!(
        "per-line residual std: 10% {:.1} mm, median {:.1} mm, 90% {:.1} mm; {:.1}% of lines under 2 cm",
        p10 * 1e3,
        p50 * 1e3,
        p90 * 1e3,
        100.0 * u.fraction_under_2cm
    );
}
