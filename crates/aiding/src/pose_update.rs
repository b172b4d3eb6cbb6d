//! The estimator's measurement step (beyond the paper): the matches a
//! scan agrees on (joint consistency over single matches and pairs), the
//! iterated EKF update of the pose with them, and the innovation test of
//! the correction against the source's uncertainty.

use crate::LineMeasurement;
use pcaline_geometry::{Matrix3, Pose2, Vector3, wrap_angle};

/// A small regularisation of the prior covariance before it is inverted:
/// a pose known exactly (the first one) still has an information matrix.
const PRIOR_FLOOR: [f64; 3] = [1e-10, 1e-10, 1e-12];

/// The information matrix of a prior covariance.
fn information(covariance: &Matrix3<f64>) -> Matrix3<f64> {
    let p = covariance + Matrix3::from_diagonal(&PRIOR_FLOOR.into());
    p.try_inverse().unwrap_or_else(|| Matrix3::from_diagonal(&PRIOR_FLOOR.map(|v| 1.0 / v).into()))
}

/// The normal equations of the matches at a linearisation point: the
/// information `H^T R^-1 H` and the vector `H^T R^-1 r`.
fn normal_equations(
    measurements: impl Iterator<Item = LineMeasurement>,
) -> Option<(Matrix3<f64>, Vector3<f64>)> {
    let (mut info, mut b) = (Matrix3::zeros(), Vector3::zeros());
    for m in measurements {
        let w = m.covariance.try_inverse()?;
        let ht = m.jacobian.transpose();
        info += ht * w * m.jacobian;
        b += ht * w * m.residual;
    }
    Some((info, b))
}

/// One Gauss-Newton step of the prior-plus-matches least squares at a
/// linearisation point `offset` from the prior: the step and the posterior
/// covariance.
fn solve(
    prior_information: &Matrix3<f64>,
    offset: &Vector3<f64>,
    measurements: impl Iterator<Item = LineMeasurement>,
) -> Option<(Vector3<f64>, Matrix3<f64>)> {
    let (info, b) = normal_equations(measurements)?;
    let cov = (prior_information + info).try_inverse()?;
    let step = cov * (b - prior_information * offset);
    step.iter().all(|v| v.is_finite()).then_some((step, (cov + cov.transpose()) * 0.5))
}

/// The squared Mahalanobis distance between the prior and what the matches
/// alone say, in the directions the matches constrain:
/// `b^T (I^+ - (P^-1 + I)^-1) b` with `I = H^T R^-1 H`, `b = H^T R^-1 r` at
/// the prior (`I^+` the pseudo-inverse: a corridor says nothing along it).
fn prior_disagreement2(
    prior_information: &Matrix3<f64>,
    info: &Matrix3<f64>,
    b: &Vector3<f64>,
) -> f64 {
    let scale = info.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let Ok(pinv) = info.pseudo_inverse(scale * 1e-9) else { return f64::INFINITY };
    let Some(post) = (prior_information + info).try_inverse() else { return f64::INFINITY };
    (b.transpose() * (pinv - post) * b)[(0, 0)].max(0.0)
}

/// Squared Mahalanobis distance of match `m`'s residual after the
/// correction `delta` whose covariance is `sigma`.
fn distance2(m: &LineMeasurement, delta: &Vector3<f64>, sigma: &Matrix3<f64>) -> f64 {
    let e = m.residual - m.jacobian * delta;
    let s = m.covariance + m.jacobian * sigma * m.jacobian.transpose();
    s.try_inverse().map_or(f64::INFINITY, |si| (e.transpose() * si * e)[(0, 0)])
}

/// Squared Mahalanobis distance of one match before any correction, with
/// the prior covariance of the pose: the individual gate.
pub fn gate_distance2(m: &LineMeasurement, prior_covariance: &Matrix3<f64>) -> f64 {
    distance2(m, &Vector3::zeros(), prior_covariance)
}

/// The largest subset of `matches` that one pose correction explains.
///
/// Hypotheses are the corrections that each single match and each pair of
/// matches imply together with the prior (among the first
/// `max_hypothesis_matches` matches: pass them sorted by weight). Each
/// hypothesis' support (the matches whose residual after its correction is
/// within `chi2`, squared Mahalanobis distance with two degrees of freedom)
/// is then refitted jointly and trimmed, the worst match first, until every
/// member agrees with the joint fit: a set of matches that each agree with
/// a loose hypothesis but not with each other is not consistent. The
/// largest trimmed set wins; ties go to the smaller total distance.
/// Deterministic: no random sampling.
///
/// Returns one flag per match (true: in the consistent set); all false
/// when nothing is consistent or `matches` is empty.
pub fn joint_consistent(
    matches: &[LineMeasurement],
    prior_covariance: &Matrix3<f64>,
    chi2: f64,
    max_hypothesis_matches: usize,
) -> Vec<bool> {
    let prior = information(prior_covariance);
    let fit = |set: &[bool]| -> Option<Vec<f64>> {
        let chosen = matches.iter().zip(set).filter(|(_, f)| **f).map(|(m, _)| *m);
        let (delta, sigma) = solve(&prior, &Vector3::zeros(), chosen)?;
        Some(matches.iter().map(|m| distance2(m, &delta, &sigma)).collect())
    };
    let k = matches.len().min(max_hypothesis_matches);
    let mut best: Option<(usize, f64, Vec<bool>)> = None;
    let mut tried: Vec<Vec<bool>> = Vec::new();
    let mut consider = |subset: &[usize]| {
        let mut set = vec![false; matches.len()];
        subset.iter().for_each(|&i| set[i] = true);
        let Some(d2) = fit(&set) else { return };
        let mut set: Vec<bool> = d2.iter().map(|d| *d <= chi2).collect();
        if tried.contains(&set) {
            return;
        }
        tried.push(set.clone());
        // Trim the joint fit of the support until its members agree with it.
        let mut cost = 0.0;
        while set.iter().any(|f| *f) {
            let Some(d2) = fit(&set) else { return };
            let worst = (0..set.len())
                .filter(|&i| set[i])
                .max_by(|&a, &b| d2[a].total_cmp(&d2[b]))
                .unwrap_or(0);
            if d2[worst] <= chi2 {
                cost = (0..set.len()).filter(|&i| set[i]).map(|i| d2[i]).sum();
                break;
            }
            set[worst] = false;
        }
        let support = set.iter().filter(|f| **f).count();
        if support > 0
            && best.as_ref().is_none_or(|(s, c, _)| support > *s || (support == *s && cost < *c))
        {
            best = Some((support, cost, set));
        }
    };
    for i in 0..k {
        consider(&[i]);
        for j in i + 1..k {
            consider(&[i, j]);
        }
    }
    best.map_or_else(|| vec![false; matches.len()], |(_, _, flags)| flags)
}

/// Huber's weight on a match: beyond `k` standard deviations (squared
/// Mahalanobis distance of its residual under its own covariance above
/// `k²`) its covariance grows so that it pulls linearly, not quadratically.
/// Real matches have heavy tails.
fn huber(mut m: LineMeasurement, k: f64) -> LineMeasurement {
    let z2 = m
        .covariance
        .try_inverse()
        .map_or(0.0, |w| (m.residual.transpose() * w * m.residual)[(0, 0)]);
    let z = z2.max(0.0).sqrt();
    if z > k {
        m.covariance *= z / k;
    }
    m
}

/// The result of [`iterated_update`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoseUpdate {
    /// The corrected pose.
    pub pose: Pose2,
    /// Its covariance.
    pub covariance: Matrix3<f64>,
    /// Squared Mahalanobis distance between the prior and what the matches
    /// alone say, in the directions they constrain (the innovation test's
    /// statistic; at most three degrees of freedom): how surprising the
    /// matches are to the source.
    pub correction_distance2: f64,
    /// The directions the matches constrain (the statistic's degrees of
    /// freedom, 1 to 3).
    pub correction_dof: usize,
    /// Sum over the matches of their squared Mahalanobis residuals at the
    /// corrected pose, under their own covariances (without Huber's
    /// weights): what the matches scatter about the solution.
    pub residual2: f64,
    /// Its degrees of freedom: two per match less the constrained
    /// directions (at least 1).
    pub residual_dof: usize,
}

/// The iterated EKF update (Gauss-Newton on prior plus matches, relinearised
/// `iterations` times, each match reweighted by Huber's rule with `huber_k`
/// standard deviations): `measure(pose)` gives the consistent matches'
/// measurements at a pose. `None` when the normal equations are singular or
/// not finite.
pub fn iterated_update(
    prior_pose: &Pose2,
    prior_covariance: &Matrix3<f64>,
    iterations: usize,
    huber_k: f64,
    mut measure: impl FnMut(&Pose2) -> Vec<LineMeasurement>,
) -> Option<PoseUpdate> {
    let prior = information(prior_covariance);
    let mut pose = *prior_pose;
    let mut covariance = *prior_covariance;
    let (info, b) = normal_equations(measure(prior_pose).into_iter())?;
    let correction_distance2 = prior_disagreement2(&prior, &info, &b);
    let eig = info.symmetric_eigen().eigenvalues;
    let largest = eig.max();
    let correction_dof = eig.iter().filter(|v| **v > largest * 1e-9).count().max(1);
    for _ in 0..iterations.max(1) {
        let offset = Vector3::new(
            pose.x() - prior_pose.x(),
            pose.y() - prior_pose.y(),
            wrap_angle(pose.heading() - prior_pose.heading()),
        );
        let weighted = measure(&pose).into_iter().map(|m| huber(m, huber_k));
        let (step, cov) = solve(&prior, &offset, weighted)?;
        pose = Pose2::new(pose.x() + step.x, pose.y() + step.y, pose.heading() + step.z);
        covariance = cov;
        if step.xy().norm() < 1e-6 && step.z.abs() < 1e-8 {
            break;
        }
    }
    let at_solution = measure(&pose);
    let residual2 = at_solution
        .iter()
        .map(|m| {
            m.covariance
                .try_inverse()
                .map_or(0.0, |w| (m.residual.transpose() * w * m.residual)[(0, 0)])
        })
        .sum();
    let residual_dof = (2 * at_solution.len()).saturating_sub(correction_dof).max(1);
    (pose.is_finite() && covariance.iter().all(|v| v.is_finite())).then_some(PoseUpdate {
        pose,
        covariance,
        residual2,
        residual_dof,
        correction_distance2,
        correction_dof,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use pcaline_geometry::{Matrix2, Vector2};

    /// A wall with normal angle `alpha` at offset residual `r`.
    fn wall(alpha: f64, heading_residual: f64, offset_residual: f64) -> LineMeasurement {
        let (s, c) = alpha.sin_cos();
        LineMeasurement {
            residual: Vector2::new(heading_residual, offset_residual),
            jacobian: nalgebra::Matrix2x3::new(0.0, 0.0, 1.0, c, s, 0.0),
            covariance: Matrix2::new(1e-6, 0.0, 0.0, 1e-4),
        }
    }

    #[test]
    fn one_wrong_match_is_left_out() {
        // Four walls agree on a 1 cm shift in x and no rotation; one claims 30 cm.
        let mut ms = vec![
            wall(0.0, 0.0, 0.01),
            wall(std::f64::consts::FRAC_PI_2, 0.0, 0.0),
            wall(0.0, 0.0, 0.01),
            wall(std::f64::consts::FRAC_PI_2, 0.0, 0.0),
        ];
        ms.push(wall(0.0, 0.0, 0.3));
        let prior = Matrix3::from_diagonal(&[0.04, 0.04, 0.001].into());
        let flags = joint_consistent(&ms, &prior, 9.21, 12);
        assert_eq!(flags, vec![true, true, true, true, false]);
    }

    #[test]
    fn the_update_weighs_the_prior() {
        // A wall 0.1 m further along x than the prior pose says.
        let ms = |p: &Pose2| vec![wall(0.0, 0.0, 0.1 - p.x())];
        let tight = Matrix3::from_diagonal(&[1e-8, 1e-8, 1e-8].into());
        let loose = Matrix3::from_diagonal(&[1.0, 1.0, 1e-8].into());
        let fixed = iterated_update(&Pose2::identity(), &tight, 3, 1e9, ms).unwrap();
        assert!(fixed.pose.x().abs() < 1e-3, "a confident source barely moves: {:?}", fixed.pose);
        assert!(fixed.correction_distance2 > 1.0);
        let pulled = iterated_update(&Pose2::identity(), &loose, 3, 1e9, ms).unwrap();
        assert!(pulled.correction_distance2 < 1.0, "{pulled:?}");
        assert!(
            (pulled.pose.x() - 0.1).abs() < 1e-3,
            "an uncertain one follows: {:?}",
            pulled.pose
        );
        // Along the wall nothing is measured: y stays.
        assert!(pulled.pose.y().abs() < 1e-9);
    }

    #[test]
    fn nothing_consistent_or_empty() {
        assert!(joint_consistent(&[], &Matrix3::identity(), 9.21, 12).is_empty());
        let nan = LineMeasurement { residual: Vector2::new(f64::NAN, 0.0), ..wall(0.0, 0.0, 0.0) };
        assert_eq!(joint_consistent(&[nan], &Matrix3::identity(), 9.21, 12), vec![false]);
    }
}
