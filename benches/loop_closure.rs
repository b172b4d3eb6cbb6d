//! Loop closure's two costly steps: the pose-graph optimization (factrs
//! Levenberg-Marquardt with the chi-square switching of loops) on graphs of
//! the size of the MIT CSAIL log's (about 800 keyframes) and four times
//! that, and the line-set alignment that verifies one loop candidate.

use criterion::{BatchSize, BenchmarkId, Criterion, criterion_group, criterion_main};
use pcaline::aiding::{AlignmentConfig, EdgeKind, OptimizerConfig, PoseGraph, align_lines};
use pcaline::geometry::{Matrix3, Vector3};
use pcaline::{LineSegment, Point2, Pose2};
use std::hint::black_box;

/// Laps of a 20 m x 10 m rectangle in 0.5 m steps with a heading error per
/// step, a loop edge every 10 keyframes from the second lap on.
fn graph(nodes: usize) -> PoseGraph {
    let perimeter = 120;
    let truth: Vec<Pose2> = (0..nodes)
        .map(|k| {
            let s = (k % perimeter) as f64 * 0.5;
            match s {
                s if s < 20.0 => Pose2::new(s, 0.0, 0.0),
                s if s < 30.0 => Pose2::new(20.0, s - 20.0, std::f64::consts::FRAC_PI_2),
                s if s < 50.0 => Pose2::new(50.0 - s, 10.0, std::f64::consts::PI),
                s => Pose2::new(0.0, 60.0 - s, -std::f64::consts::FRAC_PI_2),
            }
        })
        .collect();
    let cov = |x: f64, h: f64| Matrix3::from_diagonal(&Vector3::new(x * x, x * x, h * h));
    let mut g = PoseGraph::new();
    g.add_node(truth[0]);
    for k in 1..nodes {
        let z = truth[k - 1].between(&truth[k]);
        let z = Pose2::new(z.x() * 1.01, z.y(), z.heading() + 0.002);
        let previous = g.nodes[k - 1];
        g.add_node(previous.compose(&z));
        g.add_edge(k - 1, k, z, cov(0.025, 0.009), EdgeKind::Sequential);
    }
    for k in (perimeter..nodes).step_by(10) {
        let j = k % perimeter;
        g.add_edge(j, k, truth[j].between(&truth[k]), cov(0.05, 0.009), EdgeKind::Loop);
    }
    g
}

fn seg(a: (f64, f64), b: (f64, f64)) -> LineSegment {
    LineSegment::between(Point2::new(a.0, a.1), Point2::new(b.0, b.1))
}

fn loop_closure(c: &mut Criterion) {
    let mut group = c.benchmark_group("pose_graph_optimize");
    for nodes in [800, 3200] {
        let g = graph(nodes);
        group.bench_with_input(BenchmarkId::from_parameter(nodes), &g, |b, g| {
            b.iter_batched(
                || g.clone(),
                |mut g| black_box(g.optimize(&OptimizerConfig::standard())),
                BatchSize::LargeInput,
            )
        });
    }
    group.finish();

    // Six keyframes' view of an L-shaped room with a pillar (36 lines), seen
    // again from 0.4 m and 5° away.
    let room = [
        seg((0.0, 0.0), (6.0, 0.0)),
        seg((6.0, 0.0), (6.0, 3.0)),
        seg((6.0, 3.0), (3.0, 3.0)),
        seg((3.0, 3.0), (3.0, 5.0)),
        seg((3.0, 5.0), (0.0, 5.0)),
        seg((0.0, 5.0), (0.0, 0.0)),
    ];
    let candidate: Vec<LineSegment> = (0..6).flat_map(|_| room).collect();
    let offset = Pose2::new(0.4, -0.2, 5f64.to_radians());
    let current: Vec<LineSegment> =
        candidate.iter().map(|l| l.transformed(&offset.inverse())).collect();
    c.bench_function("align_lines_36_x_36", |b| {
        b.iter(|| black_box(align_lines(&current, &candidate, None, &AlignmentConfig::standard())))
    });
}

criterion_group!(benches, loop_closure);
criterion_main!(benches);
