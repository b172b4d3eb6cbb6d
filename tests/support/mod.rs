//! Shared helpers for the end-to-end tests: an analytic ray caster for small
//! hand-made scenes (the full simulator lives in `pcaline-sim`), bounded
//! proptest strategies, and the real datasets' location.

#![allow(dead_code)]
#![allow(clippy::print_stderr)] // the loud report of a missing dataset

use pcaline::{Point2, Scan};
use proptest::prelude::*;
use rand::{SeedableRng, rngs::StdRng};
use rand_distr::{Distribution, Normal};

/// A wall from `.0` to `.1`, in the sensor frame.
pub type Wall = (Point2<f64>, Point2<f64>);

/// Range along the ray at `angle` from the origin to the nearest wall, if any.
pub fn cast(walls: &[Wall], angle: f64) -> Option<f64> {
    let (s, c) = angle.sin_cos();
    let mut best: Option<f64> = None;
    for (a, b) in walls {
        let e = b - a;
        let denom = c * e.y - s * e.x;
        if denom.abs() < 1e-15 {
            continue;
        }
        let t = (a.x * e.y - a.y * e.x) / denom; // range along the ray
        let u = (a.x * s - a.y * c) / denom; // position along the wall
        if t > 0.0 && (0.0..=1.0).contains(&u) && best.is_none_or(|r| t < r) {
            best = Some(t);
        }
    }
    best
}

/// A scan of `walls` with `n` beams from `angle_min` in steps of `inc`, with
/// Gaussian range noise `sigma_m` (seeded); no hit is reported as +inf.
pub fn scan_of(
    walls: &[Wall],
    angle_min: f64,
    inc: f64,
    n: usize,
    sigma_m: f64,
    seed: u64,
) -> Scan {
    let mut rng = StdRng::seed_from_u64(seed);
    let noise = Normal::new(0.0, sigma_m.max(1e-300)).unwrap();
    let ranges = (0..n)
        .map(|i| match cast(walls, angle_min + i as f64 * inc) {
            Some(r) if sigma_m > 0.0 => (r + noise.sample(&mut rng)) as f32,
            Some(r) => r as f32,
            None => f32::INFINITY,
        })
        .collect();
    Scan::new(angle_min as f32, inc as f32, 0.1, 30.0, ranges)
}

/// A UTM-30LX-EW style scan (1081 beams, -135° to +135°).
pub fn utm_scan(walls: &[Wall], sigma_m: f64, seed: u64) -> Scan {
    scan_of(walls, -135f64.to_radians(), 0.25f64.to_radians(), 1081, sigma_m, seed)
}

/// The four walls of an axis-aligned rectangle `[x0, x1] x [y0, y1]`.
pub fn rectangle(x0: f64, y0: f64, x1: f64, y1: f64) -> Vec<Wall> {
    let p = |x, y| Point2::new(x, y);
    vec![
        (p(x0, y0), p(x1, y0)),
        (p(x1, y0), p(x1, y1)),
        (p(x1, y1), p(x0, y1)),
        (p(x0, y1), p(x0, y0)),
    ]
}

/// A rectangular room of 2-20 m sides with the sensor strictly inside.
pub fn room() -> impl Strategy<Value = Vec<Wall>> {
    (2.0f64..20.0, 2.0f64..20.0, 0.1f64..0.9, 0.1f64..0.9)
        .prop_map(|(w, h, fx, fy)| rectangle(-fx * w, -fy * h, (1.0 - fx) * w, (1.0 - fy) * h))
}

/// Any f32 a driver might publish: ordinary ranges, zeros, negatives, huge,
/// tiny, NaN and both infinities.
pub fn any_range() -> impl Strategy<Value = f32> {
    prop_oneof![
        8 => 0.0f32..35.0,
        1 => Just(f32::NAN),
        1 => Just(f32::INFINITY),
        1 => Just(f32::NEG_INFINITY),
        1 => prop::num::f32::ANY,
    ]
}

/// The real dataset `rel` under `$PCALINE_DATA` (default `../shared/data`).
/// A missing dataset fails under `CI=true` and is reported loudly, and
/// skipped, otherwise.
pub fn data(rel: &str) -> Option<std::path::PathBuf> {
    let root =
        std::env::var_os("PCALINE_DATA").map(std::path::PathBuf::from).unwrap_or_else(|| {
            std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/data")
        });
    let path = root.join(rel);
    if path.exists() {
        return Some(path);
    }
    let msg = format!("MISSING DATASET {} (set PCALINE_DATA)", path.display());
    if std::env::var("CI").is_ok_and(|v| v == "true") {
        panic!("{msg}");
    }
    eprintln!("\n!!! {msg}: test skipped !!!\n");
    None
}
