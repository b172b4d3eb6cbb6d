//! A small sliding-window least squares over the last scans' poses (beyond
//! the paper), the alternative to the iterated EKF of `pose_update.rs`: the
//! source's increments are factors between consecutive poses, each scan's
//! consistent matches are factors on its pose, and the oldest pose carries a
//! prior. Every pose in the window is relinearised at each solve, so a match
//! seen now also corrects the poses before it. The oldest pose leaves the
//! window with its marginal covariance as the next prior.

use crate::LineMeasurement;
use nalgebra::{DMatrix, DVector};
use pcaline_geometry::{Matrix3, Pose2, Vector3, wrap_angle};
use std::collections::VecDeque;

/// A scan's consistent matches measured at a pose (shared, so a window
/// can be cloned).
pub type MeasureAt = std::sync::Arc<dyn Fn(&Pose2) -> Vec<LineMeasurement> + Send + Sync>;

/// One scan in the window: the source's increment from the previous pose
/// (body frame) with its covariance, and the scan's matches as a function
/// of its pose.
#[non_exhaustive]
pub struct WindowStep {
    /// The increment from the previous pose, previous body frame.
    pub increment: Pose2,
    /// Its covariance, previous body frame.
    pub noise: Matrix3<f64>,
    /// The scan's consistent matches measured at a pose.
    pub measure: MeasureAt,
    /// The current estimate of the scan's pose.
    pub pose: Pose2,
}

impl Clone for WindowStep {
    fn clone(&self) -> Self {
        WindowStep {
            increment: self.increment,
            noise: self.noise,
            measure: self.measure.clone(),
            pose: self.pose,
        }
    }
}

impl std::fmt::Debug for WindowStep {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("WindowStep")
            .field("increment", &self.increment)
            .field("pose", &self.pose)
            .finish()
    }
}

/// The window: an anchor pose with a prior, then up to `capacity` steps.
#[derive(Debug, Clone)]
pub struct PoseWindow {
    capacity: usize,
    /// The prior's mean and covariance on the oldest pose.
    anchor: Pose2,
    anchor_covariance: Matrix3<f64>,
    /// The oldest pose's estimate.
    anchor_pose: Pose2,
    steps: VecDeque<WindowStep>,
    /// The marginal covariance of the pose that slides out next, from the
    /// last solve.
    pub oldest_covariance: Option<Matrix3<f64>>,
}

fn diff(a: &Pose2, b: &Pose2) -> Vector3<f64> {
    Vector3::new(a.x() - b.x(), a.y() - b.y(), wrap_angle(a.heading() - b.heading()))
}

fn huber_weight(m: &LineMeasurement, k: f64) -> Option<nalgebra::Matrix2<f64>> {
    let w = m.covariance.try_inverse()?;
    let z = (m.residual.transpose() * w * m.residual)[(0, 0)].max(0.0).sqrt();
    Some(if z > k { w * (k / z) } else { w })
}

impl PoseWindow {
    /// A window anchored at `pose` with covariance `covariance`, holding up
    /// to `capacity` steps (at least 1).
    pub fn new(pose: Pose2, covariance: Matrix3<f64>, capacity: usize) -> Self {
        PoseWindow {
            capacity: capacity.max(1),
            anchor: pose,
            anchor_covariance: covariance,
            anchor_pose: pose,
            steps: VecDeque::new(),
            oldest_covariance: None,
        }
    }

    /// The newest pose.
    pub fn head(&self) -> Pose2 {
        self.steps.back().map_or(self.anchor, |s| s.pose)
    }

    /// Adds a step, sliding the oldest out (its marginal covariance from the
    /// last solve, `oldest_covariance`, becomes the prior) when full.
    pub fn push(&mut self, step: WindowStep, oldest_covariance: Option<Matrix3<f64>>) {
        if self.steps.len() == self.capacity
            && let Some(first) = self.steps.pop_front()
        {
            self.anchor = first.pose;
            self.anchor_pose = first.pose;
            if let Some(c) = oldest_covariance {
                self.anchor_covariance = c;
            }
        }
        self.steps.push_back(step);
    }

    /// Gauss-Newton over every pose of the window, `iterations` times, with
    /// Huber weights at `huber_k`. Returns the newest pose's covariance and
    /// the covariance of the pose that slides out next; `None` when the
    /// normal equations are singular or not finite (the estimates are then
    /// left as they were).
    pub fn solve(
        &mut self,
        iterations: usize,
        huber_k: f64,
    ) -> Option<(Matrix3<f64>, Matrix3<f64>)> {
        let n = self.steps.len() + 1;
        let prior = (self.anchor_covariance
            + Matrix3::from_diagonal(&[1e-10, 1e-10, 1e-12].into()))
        .try_inverse()?;
        let mut poses: Vec<Pose2> =
            std::iter::once(self.anchor_pose).chain(self.steps.iter().map(|s| s.pose)).collect();
        let anchor = self.anchor;
        let mut cov = DMatrix::zeros(3 * n, 3 * n);
        for _ in 0..iterations.max(1) {
            let mut a = DMatrix::<f64>::zeros(3 * n, 3 * n);
            let mut b = DVector::<f64>::zeros(3 * n);
            // Prior on the anchor: r = anchor - x0, dr/dx0 = -I.
            let r0 = diff(&anchor, &poses[0]);
            {
                let mut v = a.fixed_view_mut::<3, 3>(0, 0);
                v += prior;
            }
            {
                let mut v = b.fixed_rows_mut::<3>(0);
                v += prior * r0;
            }
            for (k, step) in self.steps.iter().enumerate() {
                let (i, j) = (3 * k, 3 * (k + 1));
                let prev = poses[k];
                // Odometry: e = x_{k+1} - (x_k + R u); residual r = -e.
                let predicted = prev.compose(&step.increment);
                let r = diff(&predicted, &poses[k + 1]);
                let (s, c) = prev.heading().sin_cos();
                let (ux, uy) = (step.increment.x(), step.increment.y());
                #[rustfmt::skip]
                let f = Matrix3::new(1.0, 0.0, -s * ux - c * uy, 0.0, 1.0, c * ux - s * uy, 0.0, 0.0, 1.0);
                #[rustfmt::skip]
                let g = Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0);
                let q = g * step.noise * g.transpose()
                    + Matrix3::from_diagonal(&[1e-10, 1e-10, 1e-12].into());
                let w = q.try_inverse()?;
                // r(x) = f(x_k) - x_{k+1}: dr/dx_k = F, dr/dx_{k+1} = -I;
                // normal equations of min |r - J dx|² with J = -dr/dx.
                let jk = -f;
                let jl = Matrix3::identity();
                let mut add = |p: usize, q_: usize, m: Matrix3<f64>| {
                    let mut v = a.fixed_view_mut::<3, 3>(p, q_);
                    v += m;
                };
                add(i, i, jk.transpose() * w * jk);
                add(i, j, jk.transpose() * w * jl);
                add(j, i, jl.transpose() * w * jk);
                add(j, j, jl.transpose() * w * jl);
                {
                    let mut v = b.fixed_rows_mut::<3>(i);
                    v += jk.transpose() * w * r;
                }
                {
                    let mut v = b.fixed_rows_mut::<3>(j);
                    v += jl.transpose() * w * r;
                }
                // The scan's matches on x_{k+1}: residual changes by -H dx.
                for m in (step.measure)(&poses[k + 1]) {
                    let wm = huber_weight(&m, huber_k)?;
                    let ht = m.jacobian.transpose();
                    {
                        let mut v = a.fixed_view_mut::<3, 3>(j, j);
                        v += ht * wm * m.jacobian;
                    }
                    {
                        let mut v = b.fixed_rows_mut::<3>(j);
                        v += ht * wm * m.residual;
                    }
                }
            }
            let chol = a.cholesky()?;
            let dx = chol.solve(&b);
            if !dx.iter().all(|v| v.is_finite()) {
                return None;
            }
            for (k, p) in poses.iter_mut().enumerate() {
                *p = Pose2::new(
                    p.x() + dx[3 * k],
                    p.y() + dx[3 * k + 1],
                    p.heading() + dx[3 * k + 2],
                );
            }
            cov = chol.inverse();
        }
        self.anchor_pose = poses[0];
        for (s, p) in self.steps.iter_mut().zip(&poses[1..]) {
            s.pose = *p;
        }
        let block = |k: usize| -> Matrix3<f64> {
            let m: Matrix3<f64> = cov.fixed_view::<3, 3>(3 * k, 3 * k).into();
            (m + m.transpose()) * 0.5
        };
        Some((block(n - 1), block(1.min(n - 1))))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix2, Matrix2x3, Vector2};

    fn step(
        measure: impl Fn(&Pose2) -> Vec<LineMeasurement> + Send + Sync + 'static,
    ) -> WindowStep {
        WindowStep {
            increment: Pose2::new(1.0, 0.0, 0.0),
            noise: Matrix3::from_diagonal(&[0.01, 0.01, 1e-4].into()),
            measure: std::sync::Arc::new(measure),
            pose: Pose2::identity(),
        }
    }

    #[test]
    fn without_matches_the_window_follows_the_source() {
        let mut w = PoseWindow::new(Pose2::identity(), Matrix3::identity() * 1e-6, 3);
        for _ in 0..5 {
            w.push(step(|_| Vec::new()), None);
            let (head, _) = w.solve(3, 2.0).unwrap();
            assert!(head[(0, 0)] > 0.0);
        }
        // The anchor slid twice; the head is three steps past it.
        let h = w.head();
        assert!((h.x() - 5.0).abs() < 1e-9 && h.y().abs() < 1e-9, "{h:?}");
    }

    #[test]
    fn a_match_on_the_newest_pose_corrects_it() {
        let mut w = PoseWindow::new(Pose2::identity(), Matrix3::identity() * 1e-6, 4);
        w.push(step(|_| Vec::new()), None);
        // A wall along y says the second pose is at x = 1.9, not 2.
        w.push(
            step(|p: &Pose2| {
                vec![LineMeasurement {
                    residual: Vector2::new(0.0, 1.9 - p.x()),
                    jacobian: Matrix2x3::new(0.0, 0.0, 1.0, 1.0, 0.0, 0.0),
                    covariance: Matrix2::new(1e-6, 0.0, 0.0, 1e-6),
                }]
            }),
            None,
        );
        w.solve(3, 1e9).unwrap();
        assert!((w.head().x() - 1.9).abs() < 1e-3, "{:?}", w.head());
    }
}
