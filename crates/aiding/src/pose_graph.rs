//! [`PoseGraph`]: keyframe poses joined by relative-pose edges with
//! covariances, optimized by nonlinear least squares (Levenberg-Marquardt
//! from the `factrs` crate), with loop-closure edges under a robust kernel
//! and a chi-square test that switches off the loops the optimum disagrees
//! with.
//!
//! Conventions: a node is `world_from_keyframe`; an edge from `a` to `b`
//! measures `a_from_b`, with its covariance in `(x, y, heading)` of that
//! measurement. The first node is held fixed.

use pcaline_geometry::{Matrix3, Pose2, Vector3, wrap_angle};

use factrs::core::{BetweenResidual, LevenMarquardt, PriorResidual, SE2, Values};
use factrs::linalg::Matrix3 as FMatrix3;
use factrs::noise::GaussianNoise;
use factrs::optimizers::{LevenParams, OptError};
use factrs::robust::Cauchy;
use factrs::traits::Optimizer;
use factrs::{assign_symbols, fac};

assign_symbols!(K: SE2);

/// What an edge stands for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
#[non_exhaustive]
pub enum EdgeKind {
    /// Consecutive keyframes: the estimator's motion between them.
    Sequential,
    /// A loop closure: a line-map alignment with an older keyframe.
    Loop,
}

/// One relative-pose constraint.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoseEdge {
    /// The node the measurement is expressed in.
    pub from: usize,
    /// The node measured.
    pub to: usize,
    /// The measured `from_from_to`.
    pub from_from_to: Pose2,
    /// Its covariance, `(x, y, heading)`.
    pub covariance: Matrix3<f64>,
    /// What the edge stands for.
    pub kind: EdgeKind,
    /// False once the optimizer's chi-square test switched the edge off
    /// (loops only).
    pub active: bool,
}

impl PoseEdge {
    /// The edge's error `measured^-1 * (from^-1 * to)` for the nodes' poses,
    /// as `(x, y, heading)`.
    pub fn error(&self, from: &Pose2, to: &Pose2) -> Vector3<f64> {
        let e = self.from_from_to.between(&from.between(to));
        Vector3::new(e.x(), e.y(), wrap_angle(e.heading()))
    }

    /// The squared Mahalanobis distance of [`PoseEdge::error`] (infinite if
    /// the covariance cannot be inverted).
    pub fn distance2(&self, from: &Pose2, to: &Pose2) -> f64 {
        let e = self.error(from, to);
        match self.covariance.try_inverse() {
            Some(info) => (e.transpose() * info * e)[0],
            None => f64::INFINITY,
        }
    }
}

/// Tuning of [`PoseGraph::optimize`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct OptimizerConfig {
    /// Levenberg-Marquardt iterations per round.
    pub max_iterations: usize,
    /// Scale of the Cauchy kernel on loop edges, in standard deviations.
    pub loop_kernel_sigmas: f64,
    /// A loop edge whose squared Mahalanobis error at the optimum exceeds
    /// this is switched off and the graph optimized again (chi-square, 3
    /// degrees of freedom; 16.3 is the 99.9% quantile).
    pub loop_chi2: f64,
    /// Rounds of switching off and optimizing again.
    pub rounds: usize,
}

impl OptimizerConfig {
    /// 30 iterations, Cauchy at 3 sigmas, loops off beyond chi-square 16.3, 3
    /// rounds.
    pub fn standard() -> Self {
        OptimizerConfig { max_iterations: 30, loop_kernel_sigmas: 3.0, loop_chi2: 16.3, rounds: 3 }
    }

    /// Checks every field; errors name `prefix.field`.
    pub fn validate(&self, prefix: &str) -> Result<(), pcaline_geometry::ConfigError> {
        use pcaline_geometry::ConfigError;
        ConfigError::check_field(
            (1..=1000).contains(&self.max_iterations),
            prefix,
            "max_iterations",
            self.max_iterations as f64,
            "must be in 1..=1000",
        )?;
        ConfigError::check_field(
            self.loop_kernel_sigmas > 0.0 && self.loop_kernel_sigmas.is_finite(),
            prefix,
            "loop_kernel_sigmas",
            self.loop_kernel_sigmas,
            "must be finite and > 0",
        )?;
        ConfigError::check_field(
            self.loop_chi2 > 0.0 && self.loop_chi2.is_finite(),
            prefix,
            "loop_chi2",
            self.loop_chi2,
            "must be > 0",
        )?;
        ConfigError::check_field(
            (1..=20).contains(&self.rounds),
            prefix,
            "rounds",
            self.rounds as f64,
            "must be in 1..=20",
        )
    }
}

impl Default for OptimizerConfig {
    fn default() -> Self {
        Self::standard()
    }
}

/// Why [`PoseGraph::optimize`] kept the poses as they were.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
#[non_exhaustive]
pub enum NotOptimized {
    /// Fewer than two nodes, or no active loop edge: nothing to optimize.
    NothingToDo,
    /// Some node is not joined to the first by active edges.
    Disconnected,
    /// A node pose or an edge is not finite, or a covariance not positive
    /// definite.
    Degenerate,
    /// The solver failed to take a step or produced non-finite poses.
    SolverFailed,
}

/// What one optimization did.
#[derive(Debug, Clone, PartialEq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct OptimizeReport {
    /// Why the poses were kept, if they were.
    pub kept: Option<NotOptimized>,
    /// Rounds run.
    pub rounds: usize,
    /// Edges switched off by the chi-square test in this optimization.
    pub switched_off: Vec<usize>,
    /// Sum of the edges' squared Mahalanobis errors before and after.
    pub cost_before: f64,
    /// The same after.
    pub cost_after: f64,
    /// Largest position change of a node, metres.
    pub max_shift_m: f64,
}

/// Keyframe poses and the edges between them.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PoseGraph {
    /// `world_from_keyframe` of each node.
    pub nodes: Vec<Pose2>,
    /// The constraints.
    pub edges: Vec<PoseEdge>,
}

/// Covariance bounds an edge is clamped into before the solver sees it, so
/// that the normal equations stay well conditioned: standard deviations of
/// at least 1 mm and 0.01°.
const MIN_SIGMA_M: f64 = 1e-3;
const MIN_SIGMA_RAD: f64 = 1.745e-4;

impl PoseGraph {
    /// An empty graph.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds a node and returns its index.
    pub fn add_node(&mut self, world_from_keyframe: Pose2) -> usize {
        self.nodes.push(world_from_keyframe);
        self.nodes.len() - 1
    }

    /// Adds an active edge and returns its index.
    pub fn add_edge(
        &mut self,
        from: usize,
        to: usize,
        from_from_to: Pose2,
        covariance: Matrix3<f64>,
        kind: EdgeKind,
    ) -> usize {
        self.edges.push(PoseEdge { from, to, from_from_to, covariance, kind, active: true });
        self.edges.len() - 1
    }

    /// Sum of the active edges' squared Mahalanobis errors.
    pub fn cost(&self) -> f64 {
        self.edges
            .iter()
            .filter(|e| e.active)
            .map(|e| e.distance2(&self.nodes[e.from], &self.nodes[e.to]))
            .sum()
    }

    /// Whether every node is joined to node 0 by active edges.
    pub fn is_connected(&self) -> bool {
        let n = self.nodes.len();
        let mut parent: Vec<usize> = (0..n).collect();
        fn root(p: &mut [usize], mut i: usize) -> usize {
            while p[i] != i {
                p[i] = p[p[i]];
                i = p[i];
            }
            i
        }
        for e in self.edges.iter().filter(|e| e.active) {
            let (a, b) = (root(&mut parent, e.from), root(&mut parent, e.to));
            parent[a] = b;
        }
        let r = if n == 0 { 0 } else { root(&mut parent, 0) };
        (0..n).all(|i| root(&mut parent, i) == r)
    }

    fn check(&self) -> Option<NotOptimized> {
        let loops = self.edges.iter().filter(|e| e.active && e.kind == EdgeKind::Loop).count();
        if self.nodes.len() < 2 || loops == 0 {
            return Some(NotOptimized::NothingToDo);
        }
        let n = self.nodes.len();
        let bad_edge = |e: &PoseEdge| {
            e.from >= n
                || e.to >= n
                || e.from == e.to
                || !e.from_from_to.is_finite()
                || !e.covariance.iter().all(|v| v.is_finite())
                || e.covariance.cholesky().is_none()
        };
        if self.nodes.iter().any(|p| !p.is_finite()) || self.edges.iter().any(bad_edge) {
            return Some(NotOptimized::Degenerate);
        }
        (!self.is_connected()).then_some(NotOptimized::Disconnected)
    }

    /// Optimizes the node poses; node 0 stays fixed. Loop edges carry a
    /// Cauchy kernel; after each round, the active loop edge with the
    /// largest chi-square error above [`OptimizerConfig::loop_chi2`] is
    /// switched off and the graph optimized again from the original poses.
    ///
    /// Edge cases: a graph with fewer than two nodes or no active loop, a
    /// disconnected or degenerate graph (non-finite values, a covariance that
    /// is not positive definite) keeps its poses, and the report says why
    /// ([`NotOptimized`]). Non-finite values never reach the solver.
    pub fn optimize(&mut self, config: &OptimizerConfig) -> OptimizeReport {
        let mut report = OptimizeReport { cost_before: self.cost(), ..Default::default() };
        if let Some(why) = self.check() {
            report.kept = Some(why);
            report.cost_after = report.cost_before;
            return report;
        }
        let original = self.nodes.clone();
        for round in 1..=config.rounds {
            report.rounds = round;
            let Some(solved) = self.solve(&original, config) else {
                self.nodes = original;
                report.kept = Some(NotOptimized::SolverFailed);
                report.cost_after = report.cost_before;
                return report;
            };
            self.nodes = solved;
            let worst = self
                .edges
                .iter()
                .enumerate()
                .filter(|(_, e)| e.active && e.kind == EdgeKind::Loop)
                .map(|(i, e)| (i, e.distance2(&self.nodes[e.from], &self.nodes[e.to])))
                .filter(|(_, d2)| *d2 > config.loop_chi2)
                .max_by(|a, b| a.1.total_cmp(&b.1));
            let Some((edge, _)) = worst else { break };
            self.edges[edge].active = false;
            report.switched_off.push(edge);
            if self.check().is_some() {
                // No loop left (or the graph fell apart): the chain alone.
                self.nodes = original.clone();
                break;
            }
            if round == config.rounds {
                // Out of rounds with a loop just switched off: solve once more
                // without it.
                if let Some(solved) = self.solve(&original, config) {
                    self.nodes = solved;
                }
            }
        }
        report.cost_after = self.cost();
        report.max_shift_m = self
            .nodes
            .iter()
            .zip(&original)
            .map(|(a, b)| (a.x() - b.x()).hypot(a.y() - b.y()))
            .fold(0.0, f64::max);
        report
    }

    /// One Levenberg-Marquardt solve from `start`; `None` when the solver
    /// failed or produced non-finite poses.
    fn solve(&self, start: &[Pose2], config: &OptimizerConfig) -> Option<Vec<Pose2>> {
        let se2 = |p: &Pose2| SE2::new(p.heading(), p.x(), p.y());
        let mut values = Values::new();
        for (i, p) in start.iter().enumerate() {
            values.insert(K(i as u32), se2(p));
        }
        let mut graph = factrs::core::Graph::new();
        let prior = GaussianNoise::<3>::from_scalar_sigma(1e-6);
        graph.add_factor(fac![PriorResidual::new(se2(&start[0])), K(0), prior]);
        for e in self.edges.iter().filter(|e| e.active) {
            let noise =
                GaussianNoise::<3>::from_matrix_cov(solver_covariance(&e.covariance).as_view())?;
            let (a, b) = (e.from as u32, e.to as u32);
            let residual = BetweenResidual::new(se2(&e.from_from_to));
            let factor = match e.kind {
                EdgeKind::Loop => {
                    fac![residual, (K(a), K(b)), noise, Cauchy::new(config.loop_kernel_sigmas)]
                }
                _ => fac![residual, (K(a), K(b)), noise],
            };
            graph.add_factor(factor);
        }
        // One iteration per call: factrs's LM drops its values when it finds
        // no step that lowers the error (as at convergence), so the loop
        // keeps the last good values itself. The damping carries over.
        let mut params = LevenParams::default();
        params.base.max_iterations = 1;
        let mut optimizer = LevenMarquardt::new(params, graph);
        let mut error = optimizer.graph().error(&values);
        for _ in 0..config.max_iterations {
            match optimizer.optimize(values.clone()) {
                Ok(v) => {
                    values = v;
                    break;
                }
                Err(OptError::MaxIterations(v)) => {
                    let next = optimizer.graph().error(&v);
                    let decrease = error - next;
                    let converged = decrease.is_nan() || decrease <= 1e-9 * error.max(1e-12);
                    values = v;
                    error = next;
                    if converged {
                        break;
                    }
                }
                Err(OptError::FailedToStep) => break,
                Err(_) => return None,
            }
        }
        // Node 0 is held by a prior of 1e-6 m; it is put back exactly.
        let out: Vec<Pose2> = std::iter::once(start[0])
            .chain((1..start.len()).map(|i| {
                values
                    .get::<_, SE2>(K(i as u32))
                    .map(|p| Pose2::new(p.x(), p.y(), wrap_angle(p.theta())))
                    .unwrap_or(start[i])
            }))
            .collect();
        out.iter().all(Pose2::is_finite).then_some(out)
    }
}

/// `(x, y, heading)` covariance into the solver's `(heading, x, y)` order,
/// with the standard deviations clamped from below and the correlations
/// kept under 0.99.
fn solver_covariance(c: &Matrix3<f64>) -> FMatrix3 {
    let sigma = [
        c[(0, 0)].max(0.0).sqrt().max(MIN_SIGMA_M),
        c[(1, 1)].max(0.0).sqrt().max(MIN_SIGMA_M),
        c[(2, 2)].max(0.0).sqrt().max(MIN_SIGMA_RAD),
    ];
    let order = [2, 0, 1];
    let mut out = FMatrix3::zeros();
    for (r, &i) in order.iter().enumerate() {
        for (k, &j) in order.iter().enumerate() {
            out[(r, k)] = if i == j {
                sigma[i] * sigma[i]
            } else {
                let rho = c[(i, j)] / (c[(i, i)].sqrt() * c[(j, j)].sqrt());
                let rho = if rho.is_finite() { rho.clamp(-0.99, 0.99) } else { 0.0 };
                rho * sigma[i] * sigma[j]
            };
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn diag(x: f64, h: f64) -> Matrix3<f64> {
        Matrix3::from_diagonal(&Vector3::new(x * x, x * x, h * h))
    }

    /// A square loop of `n` steps per side with a heading error per step,
    /// closed by one loop edge from the last node to the first.
    fn square(n: usize, heading_error: f64) -> (PoseGraph, Vec<Pose2>) {
        let mut truth = vec![Pose2::identity()];
        for k in 1..4 * n {
            let turn = if k % n == 0 { std::f64::consts::FRAC_PI_2 } else { 0.0 };
            let step = Pose2::new(1.0, 0.0, turn);
            truth.push(truth[k - 1].compose(&step));
        }
        let mut g = PoseGraph::new();
        g.add_node(truth[0]);
        for k in 1..truth.len() {
            let z = truth[k - 1].between(&truth[k]);
            let z = Pose2::new(z.x(), z.y(), z.heading() + heading_error);
            let prev = g.nodes[k - 1];
            g.add_node(prev.compose(&z));
            g.add_edge(k - 1, k, z, diag(0.02, 0.01), EdgeKind::Sequential);
        }
        let last = truth.len() - 1;
        g.add_edge(last, 0, truth[last].between(&truth[0]), diag(0.01, 0.005), EdgeKind::Loop);
        (g, truth)
    }

    fn rms(a: &[Pose2], b: &[Pose2]) -> f64 {
        let s: f64 =
            a.iter().zip(b).map(|(p, q)| (p.x() - q.x()).powi(2) + (p.y() - q.y()).powi(2)).sum();
        (s / a.len() as f64).sqrt()
    }

    #[test]
    fn a_loop_edge_pulls_a_drifted_square_back() {
        let (mut g, truth) = square(10, 0.004);
        let before = rms(&g.nodes, &truth);
        let r = g.optimize(&OptimizerConfig::standard());
        assert_eq!(r.kept, None);
        assert!(r.switched_off.is_empty());
        let after = rms(&g.nodes, &truth);
        assert!(after < 0.25 * before, "{before} -> {after}");
        assert!(r.cost_after < r.cost_before);
        assert_eq!(g.nodes[0], truth[0]);
    }

    #[test]
    fn a_false_loop_is_switched_off() {
        let (mut g, truth) = square(10, 0.0);
        // Node 20 claimed to be 5 m from node 5, where it is not.
        g.add_edge(5, 20, Pose2::new(5.0, 3.0, 1.0), diag(0.01, 0.005), EdgeKind::Loop);
        let r = g.optimize(&OptimizerConfig::standard());
        assert_eq!(r.switched_off, vec![g.edges.len() - 1]);
        assert!(!g.edges.last().unwrap().active);
        assert!(rms(&g.nodes, &truth) < 0.05);
    }

    #[test]
    fn graphs_that_cannot_be_optimized_keep_their_poses() {
        let config = OptimizerConfig::standard();
        let mut empty = PoseGraph::new();
        assert_eq!(empty.optimize(&config).kept, Some(NotOptimized::NothingToDo));

        let (mut g, _) = square(3, 0.01);
        g.add_node(Pose2::new(100.0, 0.0, 0.0));
        let before = g.nodes.clone();
        assert_eq!(g.optimize(&config).kept, Some(NotOptimized::Disconnected));
        assert_eq!(g.nodes, before);

        let (mut g, _) = square(3, 0.01);
        g.edges[2].from_from_to = g.edges[2].from_from_to.with_translation(f64::NAN, 0.0);
        assert_eq!(g.optimize(&config).kept, Some(NotOptimized::Degenerate));

        let (mut g, _) = square(3, 0.01);
        g.edges[1].covariance = Matrix3::zeros();
        assert_eq!(g.optimize(&config).kept, Some(NotOptimized::Degenerate));
    }
}
