//! PCA against least squares at every Table 1 size (the paper's protocol,
//! sigma 4 cm), and the full PCA fit (Hessian form, endpoints, covariance).

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use pcaline::fitting::{fit_least_squares, fit_pca, fit_pca_slope_intercept};
use pcaline_eval::{TABLE1, dataset};
use std::hint::black_box;

fn fitting(c: &mut Criterion) {
    let mut sizes: Vec<_> = TABLE1.iter().collect();
    sizes.sort_by_key(|r| r.n);
    sizes.dedup_by_key(|r| r.n);
    let mut group = c.benchmark_group("fit");
    for row in sizes {
        let mut pts = Vec::new();
        dataset(row, 1, 0, &mut pts);
        group.bench_with_input(BenchmarkId::new("pca_eq5_6", row.n), &pts, |b, p| {
            b.iter(|| black_box(fit_pca_slope_intercept(black_box(p))))
        });
        group.bench_with_input(BenchmarkId::new("least_squares", row.n), &pts, |b, p| {
            b.iter(|| black_box(fit_least_squares(black_box(p))))
        });
        group.bench_with_input(BenchmarkId::new("pca_full_segment", row.n), &pts, |b, p| {
            b.iter(|| black_box(fit_pca(black_box(p))))
        });
    }
    group.finish();
}

criterion_group!(benches, fitting);
criterion_main!(benches);
