//! The paper's simulations (section 3, eq. 15-16; and the `ETh` detection
//! probability of section 2), reproduced with the paper's values beside ours.
//!
//! Protocol (eq. 15): `n` points `x_i = x_s i`, `y_i = m_L x_i + nu_i` with
//! `m_L = 0` and `nu_i ~ N(0, sigma²)`; outliers (Table 3) are a fraction
//! `P_O` of the points, chosen uniformly, placed at `3 sigma` from the
//! reference line with a random sign. Both PCA and least squares fit every
//! data set; the error of each (eq. 16) is the rms vertical residual. A row
//! reports the mean error over the runs, the mean relative difference
//! `(Err_PCA - Err_LS) / Err_PCA`, and the time per fit.

use pcaline_fitting::{Moments, fit_least_squares, fit_pca_slope_intercept, vertical_rms_error};
use pcaline_geometry::{Point2, SlopeIntercept};
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use rand_distr::{Distribution, Normal};
use rayon::prelude::*;
use std::time::Instant;

/// One row of the paper's Tables 1-3.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitRow {
    /// Point spacing `x_s`, metres.
    pub spacing_m: f64,
    /// Number of points `n`.
    pub n: usize,
    /// Noise `sigma`, metres.
    pub sigma_m: f64,
    /// Outlier fraction `P_O`.
    pub outlier_fraction: f64,
    /// The paper's `Err_PCA`, metres.
    pub paper_err_pca_m: f64,
    /// The paper's `(Err_PCA - Err_LS) / Err_PCA`, percent.
    pub paper_rel_diff_percent: f64,
    /// The paper's PCA and LS times per fit, milliseconds (Table 1 only).
    pub paper_times_ms: Option<(f64, f64)>,
}

impl FitRow {
    /// The data set's length `L = n x_s`, metres.
    pub fn length_m(&self) -> f64 {
        self.n as f64 * self.spacing_m
    }
}

const fn row(
    xs: f64,
    n: usize,
    sigma: f64,
    po: f64,
    err: f64,
    rel: f64,
    t: Option<(f64, f64)>,
) -> FitRow {
    FitRow {
        spacing_m: xs,
        n,
        sigma_m: sigma,
        outlier_fraction: po,
        paper_err_pca_m: err,
        paper_rel_diff_percent: rel,
        paper_times_ms: t,
    }
}

/// Table 1: point spacing and count at sigma 4 cm.
pub const TABLE1: [FitRow; 15] = [
    row(0.005, 200, 0.04, 0.0, 0.040, 2.41e-1, Some((0.10, 0.02))),
    row(0.005, 1000, 0.04, 0.0, 0.040, 9.60e-3, Some((0.12, 0.04))),
    row(0.005, 2000, 0.04, 0.0, 0.040, 2.00e-5, Some((0.59, 0.34))),
    row(0.01, 100, 0.04, 0.0, 0.040, 2.41e-1, Some((0.09, 0.02))),
    row(0.01, 500, 0.04, 0.0, 0.040, 9.60e-3, Some((0.11, 0.03))),
    row(0.01, 1000, 0.04, 0.0, 0.040, 2.41e-3, Some((0.12, 0.04))),
    row(0.025, 40, 0.04, 0.0, 0.039, 2.41e-1, Some((0.09, 0.02))),
    row(0.025, 200, 0.04, 0.0, 0.040, 9.61e-3, Some((0.10, 0.02))),
    row(0.025, 400, 0.04, 0.0, 0.040, 2.40e-3, Some((0.10, 0.03))),
    row(0.05, 20, 0.04, 0.0, 0.038, 2.42e-1, Some((0.09, 0.02))),
    row(0.05, 100, 0.04, 0.0, 0.040, 9.60e-3, Some((0.09, 0.02))),
    row(0.05, 200, 0.04, 0.0, 0.040, 2.40e-3, Some((0.10, 0.03))),
    row(0.1, 10, 0.04, 0.0, 0.036, 2.41e-1, Some((0.09, 0.02))),
    row(0.1, 50, 0.04, 0.0, 0.039, 9.60e-3, Some((0.09, 0.02))),
    row(0.1, 100, 0.04, 0.0, 0.036, 2.41e-1, Some((0.08, 0.02))),
];

/// Table 2: noise level, n = 20, x_s = 5 cm.
pub const TABLE2: [FitRow; 5] = [
    row(0.05, 20, 0.005, 0.0, 0.005, 4.00e-3, None),
    row(0.05, 20, 0.01, 0.0, 0.009, 1.50e-2, None),
    row(0.05, 20, 0.05, 0.0, 0.048, 3.79e-1, None),
    row(0.05, 20, 0.1, 0.0, 0.096, 1.56, None),
    row(0.05, 20, 0.2, 0.0, 0.204, 6.85, None),
];

/// Table 3: outliers, n = 200, x_s = 2.5 cm, sigma 4 cm.
pub const TABLE3: [FitRow; 4] = [
    row(0.025, 200, 0.04, 0.01, 0.041, 1.0e-2, None),
    row(0.025, 200, 0.04, 0.05, 0.047, 1.4e-2, None),
    row(0.025, 200, 0.04, 0.10, 0.053, 1.7e-2, None),
    row(0.025, 200, 0.04, 0.20, 0.062, 2.4e-2, None),
];

/// Our result for a row.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct FitRowResult {
    /// The row.
    pub row: FitRow,
    /// Runs.
    pub runs: usize,
    /// Mean `Err_PCA` (eq. 16a), metres.
    pub err_pca_m: f64,
    /// Mean `Err_LS` (eq. 16b), metres.
    pub err_ls_m: f64,
    /// Mean `(Err_PCA - Err_LS) / Err_PCA`, percent.
    pub rel_diff_percent: f64,
    /// Median time of one PCA fit, nanoseconds (single thread).
    pub t_pca_ns: f64,
    /// Median time of one LS fit, nanoseconds (single thread).
    pub t_ls_ns: f64,
}

/// A data set of the protocol, from its own seeded stream.
pub fn dataset(row: &FitRow, seed: u64, run: u64, out: &mut Vec<Point2<f64>>) {
    let mut rng = StdRng::seed_from_u64(seed ^ run.wrapping_mul(0x9E37_79B9_7F4A_7C15));
    let noise =
        Normal::new(0.0, row.sigma_m).unwrap_or_else(|_| Normal::new(0.0, 0.0).expect("sigma 0"));
    out.clear();
    for i in 1..=row.n {
        out.push(Point2::new(row.spacing_m * i as f64, noise.sample(&mut rng)));
    }
    let outliers = (row.outlier_fraction * row.n as f64).round() as usize;
    // A uniform choice of distinct indices (partial Fisher-Yates on indices).
    let mut idx: Vec<usize> = (0..row.n).collect();
    for k in 0..outliers.min(row.n) {
        let j = rng.random_range(k..row.n);
        idx.swap(k, j);
        let sign = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
        out[idx[k]].y = sign * 3.0 * row.sigma_m;
    }
}

/// The PCA fit as `y = m x + n` (eq. 3-6), as the paper times it.
fn pca_line(points: &[Point2<f64>]) -> Option<SlopeIntercept> {
    fit_pca_slope_intercept(points)
}

/// Runs one row: `runs` data sets in parallel (results identical for any
/// number of threads), then a single-threaded timing pass over up to 2000
/// data sets in batches.
pub fn run_fit_row(row: &FitRow, runs: usize, seed: u64) -> FitRowResult {
    let per_run: Vec<(f64, f64, f64)> = (0..runs as u64)
        .into_par_iter()
        .map_init(Vec::new, |pts, run| {
            dataset(row, seed, run, pts);
            let pca = pca_line(pts).map_or(f64::NAN, |f| vertical_rms_error(pts, &f));
            let ls = fit_least_squares(pts).map_or(f64::NAN, |f| vertical_rms_error(pts, &f));
            (pca, ls, if pca > 0.0 { (pca - ls) / pca } else { 0.0 })
        })
        .collect();
    let n = per_run.len().max(1) as f64;
    let (mut e_pca, mut e_ls, mut rel) = (0.0, 0.0, 0.0);
    for (p, l, r) in &per_run {
        e_pca += p;
        e_ls += l;
        rel += r;
    }
    let (t_pca_ns, t_ls_ns) = time_fits(row, runs.min(2000), seed);
    FitRowResult {
        row: *row,
        runs,
        err_pca_m: e_pca / n,
        err_ls_m: e_ls / n,
        rel_diff_percent: 100.0 * rel / n,
        t_pca_ns,
        t_ls_ns,
    }
}

/// Median time per fit over batches of 50 data sets, PCA and LS on the same data.
fn time_fits(row: &FitRow, runs: usize, seed: u64) -> (f64, f64) {
    let batch = 50;
    let mut sets: Vec<Vec<Point2<f64>>> = vec![Vec::new(); batch];
    let (mut t_pca, mut t_ls) = (Vec::new(), Vec::new());
    let mut sink = 0.0;
    for start in (0..runs).step_by(batch) {
        for (k, set) in sets.iter_mut().enumerate() {
            dataset(row, seed, (start + k) as u64, set);
        }
        let t0 = Instant::now();
        for set in &sets {
            sink += pca_line(set).map_or(0.0, |f| f.m);
        }
        t_pca.push(t0.elapsed().as_secs_f64() * 1e9 / batch as f64);
        let t0 = Instant::now();
        for set in &sets {
            sink += fit_least_squares(set).map_or(0.0, |f| f.m);
        }
        t_ls.push(t0.elapsed().as_secs_f64() * 1e9 / batch as f64);
    }
    std::hint::black_box(sink);
    (median(&mut t_pca), median(&mut t_ls))
}

fn median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The `ETh` experiment of section 2: a wall of `length_m` at `range_m`,
/// sampled at the UTM-30LX-EW's 0.25° (spacing `range x 0.25°`), with
/// `sigma_m` noise across it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EthExperiment {
    /// Wall length, metres (paper: 0.75).
    pub length_m: f64,
    /// Range, metres (paper: 10).
    pub range_m: f64,
    /// Noise across the wall, metres (paper: 0.04).
    pub sigma_m: f64,
    /// The threshold `ETh`.
    pub eth: f64,
    /// The paper's detection probability, percent.
    pub paper_percent: f64,
}

/// The paper's two `ETh` settings.
pub const ETH_EXPERIMENTS: [EthExperiment; 2] = [
    EthExperiment { length_m: 0.75, range_m: 10.0, sigma_m: 0.04, eth: 100.0, paper_percent: 1.35 },
    EthExperiment { length_m: 0.75, range_m: 10.0, sigma_m: 0.04, eth: 380.0, paper_percent: 0.0 },
];

/// Our result of an `ETh` experiment.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct EthResult {
    /// The experiment.
    pub experiment: EthExperiment,
    /// Points on the wall.
    pub points: usize,
    /// Runs.
    pub runs: usize,
    /// Runs in which `lambda_max / lambda_min > ETh`.
    pub detected: usize,
}

impl EthResult {
    /// Detection probability, percent.
    pub fn percent(&self) -> f64 {
        100.0 * self.detected as f64 / self.runs.max(1) as f64
    }
}

/// Runs an `ETh` experiment: the fraction of runs whose eigenvalue ratio
/// exceeds `ETh` (the wall would be detected).
pub fn run_eth(e: &EthExperiment, runs: usize, seed: u64) -> EthResult {
    let spacing = e.range_m * 0.25f64.to_radians();
    let points = (e.length_m / spacing).floor() as usize + 1;
    let row = FitRow {
        spacing_m: spacing,
        n: points,
        sigma_m: e.sigma_m,
        outlier_fraction: 0.0,
        paper_err_pca_m: 0.0,
        paper_rel_diff_percent: 0.0,
        paper_times_ms: None,
    };
    let detected = (0..runs as u64)
        .into_par_iter()
        .map_init(Vec::new, |pts, run| {
            dataset(&row, seed, run, pts);
            let eig = Moments::from_points(pts).eigen();
            usize::from(pcaline_fitting::is_elongated(&eig, e.eth))
        })
        .sum();
    EthResult { experiment: *e, points, runs, detected }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn datasets_are_seeded_and_have_the_outlier_count() {
        let row = TABLE3[3];
        let (mut a, mut b) = (Vec::new(), Vec::new());
        dataset(&row, 1, 5, &mut a);
        dataset(&row, 1, 5, &mut b);
        assert_eq!(a, b);
        let outliers = a.iter().filter(|p| (p.y.abs() - 0.12).abs() < 1e-12).count();
        assert_eq!(outliers, 40);
    }

    #[test]
    fn results_do_not_depend_on_threads() {
        let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
        let a = one.install(|| run_fit_row(&TABLE1[0], 300, 9));
        let b = run_fit_row(&TABLE1[0], 300, 9);
        assert_eq!(a.err_pca_m.to_bits(), b.err_pca_m.to_bits());
        assert_eq!(a.rel_diff_percent.to_bits(), b.rel_diff_percent.to_bits());
    }
}
