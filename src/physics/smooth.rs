//! The C² smooth step and the regularised Heaviside function (MODEL.md §5).
//!
//! Every switch of the model (phases, domain indicators, contact and adhesion bands) is one
//! of these, so the DAE is C² in time and space and a variable-step BDF meets no kinks
//! except at the ends of the switches, which are announced as breakpoints.

use super::{Real, cst, re};

/// Smooth step `S(s; a, b)`: 0 for `s ≤ a`, 1 for `s ≥ b`, and in between
/// `S = 6ξ⁵ − 15ξ⁴ + 10ξ³`, `ξ = (s − a)/(b − a)`.
///
/// `S` is C² (first and second derivatives vanish at both ends) and monotone.
/// Requires `a < b`; with `b ≤ a` it degenerates to the hard step `s > a`.
#[inline]
pub fn smooth_step<T: Real>(s: T, a: f64, b: f64) -> T {
    let sr = re(s);
    if sr >= b && sr > a {
        cst(1.0)
    } else if sr <= a {
        cst(0.0)
    } else {
        let xi = (s - a) / (b - a);
        xi * xi * xi * (xi * (xi * 6.0 - 15.0) + 10.0)
    }
}

/// Regularised Heaviside `H_ε(d) = S(d; −ε, ε)`: 0 for `d ≤ −ε`, 1 for `d ≥ ε`,
/// `H_ε(0) = ½`. Requires `ε > 0`.
#[inline]
pub fn heaviside<T: Real>(d: T, eps: f64) -> T {
    smooth_step(d, -eps, eps)
}

/// Smooth step with its derivatives, for `f64`: `(S, dS/ds, d²S/ds²)` with
/// `S' = 30ξ²(1 − ξ)²/(b − a)` and `S'' = 60ξ(1 − ξ)(1 − 2ξ)/(b − a)²`.
/// Requires `a < b`.
#[inline]
pub(crate) fn smooth_step_d(s: f64, a: f64, b: f64) -> (f64, f64, f64) {
    if s <= a {
        (0.0, 0.0, 0.0)
    } else if s >= b {
        (1.0, 0.0, 0.0)
    } else {
        let w = b - a;
        let xi = (s - a) / w;
        let om = 1.0 - xi;
        let v = xi * xi * xi * (xi * (xi * 6.0 - 15.0) + 10.0);
        let d1 = 30.0 * xi * xi * om * om / w;
        let d2 = 60.0 * xi * om * (1.0 - 2.0 * xi) / (w * w);
        (v, d1, d2)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use num_dual::Dual2_64;

    #[test]
    fn values_at_ends_and_middle() {
        let (a, b) = (2.0, 5.0);
        assert_eq!(smooth_step(-1.0, a, b), 0.0);
        assert_eq!(smooth_step(a, a, b), 0.0);
        assert_eq!(smooth_step(b, a, b), 1.0);
        assert_eq!(smooth_step(9.0, a, b), 1.0);
        assert!((smooth_step(3.5_f64, a, b) - 0.5).abs() < 1e-15);
        // ξ = 1/4: 6/1024 − 15/256 + 10/64
        let xi: f64 = 0.25;
        let expect = 6.0 * xi.powi(5) - 15.0 * xi.powi(4) + 10.0 * xi.powi(3);
        assert!((smooth_step(a + 0.25 * 3.0, a, b) - expect).abs() < 1e-15);
        assert_eq!(heaviside(0.0, 0.1), 0.5);
        assert_eq!(heaviside(-0.1, 0.1), 0.0);
        assert_eq!(heaviside(0.1, 0.1), 1.0);
        // symmetry H(d) + H(−d) = 1
        for d in [0.01_f64, 0.037, 0.08] {
            assert!((heaviside(d, 0.1) + heaviside(-d, 0.1) - 1.0).abs() < 1e-15);
        }
    }

    #[test]
    fn c2_at_both_ends() {
        let (a, b) = (-0.3, 0.7);
        // One-sided limits of S, S', S'' from inside tend to the outside values (0 or 1, 0, 0).
        for delta in [1e-3, 1e-4, 1e-5] {
            let (v0, d10, d20) = smooth_step_d(a + delta, a, b);
            let (v1, d11, d21) = smooth_step_d(b - delta, a, b);
            // S ~ 10 δ³, S' ~ 30 δ², S'' ~ 60 δ (unit width). Near b the value is a sum of
            // O(10) terms close to 1: allow the round-off of those (a few ulps of 10).
            assert!(v0.abs() <= 10.0 * delta.powi(3) * 1.01);
            assert!((1.0 - v1).abs() <= 10.0 * delta.powi(3) * 1.01 + 16.0 * f64::EPSILON);
            assert!(d10.abs() <= 30.0 * delta * delta * 1.01);
            assert!(d11.abs() <= 30.0 * delta * delta * 1.01);
            assert!(d20.abs() <= 60.0 * delta * 1.01);
            assert!(d21.abs() <= 60.0 * delta * 1.01);
        }
    }

    #[test]
    fn derivatives_match_second_order_duals() {
        // The generic version under Dual2 gives S' and S''; compare with the closed forms.
        let (a, b) = (1.0, 4.0);
        for s in [0.5, 1.2, 2.0, 2.5, 3.3, 3.99, 4.5] {
            let x = Dual2_64::from_re(s).derivative();
            let y = smooth_step(x, a, b);
            let (v, d1, d2) = smooth_step_d(s, a, b);
            assert!((y.re - v).abs() < 1e-14);
            assert!((y.v1 - d1).abs() < 1e-13, "S' at {s}");
            assert!((y.v2 - d2).abs() < 1e-13, "S'' at {s}");
        }
        // and S' against a central difference
        let h = 1e-6;
        for s in [1.3, 2.2, 3.7] {
            let fd = (smooth_step(s + h, a, b) - smooth_step(s - h, a, b)) / (2.0 * h);
            assert!((fd - smooth_step_d(s, a, b).1).abs() < 1e-8);
        }
    }

    #[test]
    fn monotone() {
        let (a, b) = (0.0, 1.0);
        let mut prev = smooth_step(-0.1, a, b);
        for i in 0..=1200 {
            let s = -0.1 + 1.2 * i as f64 / 1200.0;
            let v = smooth_step(s, a, b);
            assert!(v >= prev, "not monotone at {s}");
            assert!(smooth_step_d(s, a, b).1 >= 0.0);
            prev = v;
        }
    }
}
