//! Translation from line matches (beyond the paper): the shift that puts the
//! new lines' centroids on their map lines, by robust weighted least squares,
//! applied only along the directions the matches constrain.

use pcaline_fitting::SymmetricEigen2;
use pcaline_geometry::Vector2;

/// One constraint: the new line's centroid should move by `offset_m` along
/// the map line's unit `normal`, with weight `weight`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NormalConstraint {
    /// Unit normal of the map line.
    pub normal: Vector2<f64>,
    /// `d_map - normal . centroid_new`, metres.
    pub offset_m: f64,
    /// Inverse variance of the offset, 1/m².
    pub weight: f64,
}

/// The translation and how many directions the constraints fixed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TranslationFix {
    /// The shift to add to the position, metres.
    pub translation: Vector2<f64>,
    /// 0 (nothing), 1 (e.g. a corridor: only across it) or 2.
    pub constrained_directions: usize,
}

/// Solves `min sum w_i rho((n_i . t - r_i) / scale)` for the shift `t` by
/// iteratively reweighted least squares with Cauchy weights (`scale_m` sets
/// where a residual starts to count as an outlier), then keeps only the
/// components of `t` along eigen-directions of the information matrix whose
/// information is at least `min_ratio` of the largest (a corridor constrains
/// only the direction across it; along it the shift stays zero).
///
/// Non-finite constraints are skipped; no constraint gives a zero shift with
/// no constrained direction.
pub fn solve_translation(
    constraints: &[NormalConstraint],
    scale_m: f64,
    min_ratio: f64,
    iterations: usize,
) -> TranslationFix {
    let usable = |c: &&NormalConstraint| {
        c.normal.iter().all(|v| v.is_finite())
            && c.offset_m.is_finite()
            && c.weight.is_finite()
            && c.weight > 0.0
    };
    let mut t = Vector2::zeros();
    let mut constrained = 0;
    for _ in 0..iterations.max(1) {
        let (mut a, mut b, mut c_, mut bx, mut by) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for c in constraints.iter().filter(usable) {
            let e = c.normal.dot(&t) - c.offset_m;
            let w = c.weight / (1.0 + (e / scale_m).powi(2));
            a += w * c.normal.x * c.normal.x;
            b += w * c.normal.x * c.normal.y;
            c_ += w * c.normal.y * c.normal.y;
            bx += w * c.normal.x * c.offset_m;
            by += w * c.normal.y * c.offset_m;
        }
        let eig = SymmetricEigen2::new(a, b, c_);
        if !(eig.lambda_max > 0.0 && eig.lambda_max.is_finite()) {
            return TranslationFix { translation: Vector2::zeros(), constrained_directions: 0 };
        }
        let v1 = eig.major;
        let v2 = Vector2::new(-v1.y, v1.x);
        let rhs = Vector2::new(bx, by);
        let mut next = v1 * (v1.dot(&rhs) / eig.lambda_max);
        constrained = 1;
        if eig.lambda_min >= min_ratio * eig.lambda_max && eig.lambda_min > 0.0 {
            next += v2 * (v2.dot(&rhs) / eig.lambda_min);
            constrained = 2;
        }
        t = next;
    }
    TranslationFix { translation: t, constrained_directions: constrained }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn c(nx: f64, ny: f64, r: f64) -> NormalConstraint {
        let n = Vector2::new(nx, ny).normalize();
        NormalConstraint { normal: n, offset_m: r, weight: 1.0 }
    }

    #[test]
    fn two_walls_fix_both_directions() {
        let f = solve_translation(&[c(1.0, 0.0, 0.1), c(0.0, 1.0, -0.2)], 0.05, 0.05, 5);
        assert_eq!(f.constrained_directions, 2);
        assert!((f.translation - Vector2::new(0.1, -0.2)).norm() < 1e-9);
    }

    #[test]
    fn corridor_fixes_only_the_crossing_direction() {
        let f = solve_translation(&[c(0.0, 1.0, 0.1), c(0.0, -1.0, -0.1)], 0.05, 0.05, 5);
        assert_eq!(f.constrained_directions, 1);
        assert!(f.translation.x.abs() < 1e-12 && (f.translation.y - 0.1).abs() < 1e-9);
    }

    #[test]
    fn outlier_is_down_weighted() {
        let mut cs = vec![c(1.0, 0.0, 0.1); 8];
        cs.extend(vec![c(0.0, 1.0, 0.0); 8]);
        cs.push(c(1.0, 0.0, 0.9)); // a wrong match
        let f = solve_translation(&cs, 0.05, 0.05, 8);
        assert!((f.translation.x - 0.1).abs() < 0.01, "{f:?}");
    }

    #[test]
    fn nothing_usable() {
        let f = solve_translation(&[], 0.05, 0.05, 3);
        assert_eq!(f.constrained_directions, 0);
        let f = solve_translation(&[c(1.0, 0.0, f64::NAN)], 0.05, 0.05, 3);
        assert_eq!(f.translation, Vector2::zeros());
    }
}
