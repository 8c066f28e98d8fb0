//! The adhesion exposure before adhesion acts, integrated beside the system.
//!
//! The adhesion coefficient follows `μ̇_as = a(t) g(μ_as)` with the drive
//! `a(t) = μ_as0 H_ε(d(x(t)) + e_f)` at the node's current position and the cap
//! `g(μ) = 1 − S(μ; 0.98 μ_as,max, μ_as,max)`. In the exposure `A(t) = ∫ a dt` it is
//! autonomous, `dμ/dA = g(μ)`, so `μ_as = Φ(A)` with Φ the flow from 0, in closed form
//! ([`cap`]). The model's unknown is therefore A, whose row `Ȧ − a(x) = 0` is linear in A
//! and smooth: the cap's sharp knee (0.98 → 1 μ_as,max within 28 s of exposure) sits in
//! Φ, evaluated exactly, instead of in an ODE that IDA must resolve (in the spreading
//! phase of push-pull a μ_as unknown held the largest weighted local error in 640 of
//! 1 359 steps).
//!
//! μ_as enters the momentum balance only through `b_as = t_as μ_as …`, and the switch
//! `t_as = S(t; T_g0, T_as0)` is zero until T_g0. Before T_g0 the exposure rows only
//! follow the motion of their nodes, so the model leaves them out and integrates A here,
//! along the accepted steps of the integrator; at T_g0 they join the system with the
//! values reached ([`super::CellModel::with_adhesion_unknowns`]). Each accepted step
//! [t₀, t₁] adds `ΔA = ∫ a dt` by Simpson's rule, the midpoint position from the cubic
//! Hermite interpolant of the positions and velocities at both ends (error O(h⁵) for a
//! smooth drive). The values between the last two accepted steps (the output times, the
//! inertia switch) are integrated the same way over the part of the step.

use nalgebra::SVector;

use crate::physics::{Adhesion, Surface, layer};

/// A substrate the exposure's drive can be evaluated over: `μ_as0` times its fibronectin
/// layer indicator ([`layer`]) at a position in `D` dimensions.
pub trait LayerField<const D: usize>: Surface<D> + Copy + std::fmt::Debug {}

impl<S: Surface<D> + Copy + std::fmt::Debug, const D: usize> LayerField<D> for S {}

/// A time the exposure history does not hold (it keeps the last accepted step only).
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[error("the adhesion history holds t in [{from}, {to}], not t = {t}")]
pub struct OutsideHistory {
    /// The time asked for \[s\].
    pub t: f64,
    /// The start of the last step \[s\].
    pub from: f64,
    /// Its end \[s\].
    pub to: f64,
}

/// Positions and velocities of the membrane nodes at one time.
#[derive(Debug, Clone)]
struct Sample<const D: usize> {
    t: f64,
    x: Vec<[f64; D]>,
    xdot: Vec<[f64; D]>,
}

impl<const D: usize> Sample<D> {
    /// Position of node `k` at `t` in [self.t, next.t] on the cubic Hermite interpolant.
    fn hermite(&self, next: &Sample<D>, k: usize, t: f64) -> [f64; D] {
        let h = next.t - self.t;
        if h <= 0.0 {
            return next.x[k];
        }
        let s = (t - self.t) / h;
        let (s2, s3) = (s * s, s * s * s);
        let h00 = 2.0 * s3 - 3.0 * s2 + 1.0;
        let h10 = s3 - 2.0 * s2 + s;
        let h01 = -2.0 * s3 + 3.0 * s2;
        let h11 = s3 - s2;
        std::array::from_fn(|c| {
            h00 * self.x[k][c]
                + h10 * h * self.xdot[k][c]
                + h01 * next.x[k][c]
                + h11 * h * next.xdot[k][c]
        })
    }
}

/// The exposure at the membrane nodes while it is not an unknown of the system, for
/// nodes in `D` dimensions over the substrate `S`.
#[derive(Debug, Clone)]
pub struct AdhesionHistoryOf<const D: usize, S: LayerField<D>> {
    adhesion: Adhesion,
    substrate: S,
    /// The exposure A at `last.t`, per membrane node.
    exposure: Vec<f64>,
    last: Sample<D>,
    /// The sample and μ_as before the last step (none before the first step).
    prev: Option<(Sample<D>, Vec<f64>)>,
}

impl<const D: usize, S: LayerField<D>> AdhesionHistoryOf<D, S> {
    /// Starts at time `t` with exposure `exposure` and the nodes at `x` moving with `xdot`.
    pub fn new(
        adhesion: Adhesion,
        substrate: S,
        t: f64,
        exposure: Vec<f64>,
        x: Vec<[f64; D]>,
        xdot: Vec<[f64; D]>,
    ) -> Self {
        assert!(exposure.len() == x.len() && x.len() == xdot.len());
        Self {
            adhesion,
            substrate,
            exposure,
            last: Sample { t, x, xdot },
            prev: None,
        }
    }

    /// Time of the last sample.
    pub fn t(&self) -> f64 {
        self.last.t
    }

    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.exposure.len()
    }

    /// Whether there are no nodes.
    pub fn is_empty(&self) -> bool {
        self.exposure.is_empty()
    }

    /// The drive `a = μ_as0 H_ε(d(x) + e_f)` at position `x`.
    fn drive(&self, x: [f64; D]) -> f64 {
        self.adhesion.mu_as0 * layer(&self.adhesion, self.substrate.eval(&SVector::from(x)).0)
    }

    /// The exposure at time `t` in [s0.t, s1.t] from `mu0` at `s0.t`.
    fn integrate(&self, s0: &Sample<D>, mu0: &[f64], s1: &Sample<D>, t: f64) -> Vec<f64> {
        let h = t - s0.t;
        if h <= 0.0 {
            return mu0.to_vec();
        }
        let tm = s0.t + 0.5 * h;
        (0..mu0.len())
            .map(|k| {
                let a0 = self.drive(s0.x[k]);
                let am = self.drive(s0.hermite(s1, k, tm));
                let a1 = self.drive(s0.hermite(s1, k, t));
                mu0[k] + h / 6.0 * (a0 + 4.0 * am + a1)
            })
            .collect()
    }

    /// Advances over an accepted step to time `t`, where the nodes are at `x` moving with
    /// `xdot`. A step that does not move forward is ignored.
    pub fn advance(&mut self, t: f64, x: Vec<[f64; D]>, xdot: Vec<[f64; D]>) {
        if t <= self.last.t {
            return;
        }
        let next = Sample { t, x, xdot };
        let a = self.integrate(&self.last, &self.exposure, &next, t);
        let old_mu = std::mem::replace(&mut self.exposure, a);
        let old = std::mem::replace(&mut self.last, next);
        self.prev = Some((old, old_mu));
    }

    /// The exposure per node at time `t`, which lies within the last step (or at its end).
    pub fn at(&self, t: f64) -> Result<Vec<f64>, OutsideHistory> {
        let tol = 1e-12 * t.abs().max(1.0);
        if (t - self.last.t).abs() <= tol {
            return Ok(self.exposure.clone());
        }
        match &self.prev {
            Some((s0, mu0)) if t >= s0.t - tol && t <= self.last.t => {
                Ok(self.integrate(s0, mu0, &self.last, t.max(s0.t)))
            }
            _ => Err(OutsideHistory {
                t,
                from: self.prev.as_ref().map_or(self.last.t, |p| p.0.t),
                to: self.last.t,
            }),
        }
    }

    /// The history continued from time `t` (within the last step) on a restarted system
    /// whose nodes are at `x` moving with `xdot`.
    pub fn restarted(
        &self,
        t: f64,
        x: Vec<[f64; D]>,
        xdot: Vec<[f64; D]>,
    ) -> Result<Self, OutsideHistory> {
        let a = self.at(t)?;
        Ok(Self::new(self.adhesion, self.substrate, t, a, x, xdot))
    }
}

/// μ moved by `da ≥ 0` along `dμ/dA = 1 − S(μ; 0.98 m, m)` with `m = mu_max`, by RK4
/// sub-steps (the reference for [`cap`] in the tests).
#[cfg(test)]
fn along_cap(mu: f64, da: f64, mu_max: f64) -> f64 {
    let a = 0.98 * mu_max;
    let w = 0.02 * mu_max;
    if mu + da <= a {
        return mu + da;
    }
    let (mut xi, mut left) = if mu < a {
        (0.0, (da - (a - mu)) / w)
    } else {
        ((mu - a) / w, da / w)
    };
    // dξ/ds = q(ξ) = 1 − S(ξ) = (1 − ξ)³(6ξ² + 3ξ + 1), q' = −30 ξ²(1 − ξ)².
    let q = |x: f64| {
        let x = x.clamp(0.0, 1.0);
        let z = 1.0 - x;
        z * z * z * (6.0 * x * x + 3.0 * x + 1.0)
    };
    while left > 0.0 && xi < 1.0 {
        let z = 1.0 - xi;
        let slope = 30.0 * xi * xi * z * z;
        let ds = (0.05 / slope.max(1.0)).min(left).max(1e-12);
        let k1 = q(xi);
        let k2 = q(xi + 0.5 * ds * k1);
        let k3 = q(xi + 0.5 * ds * k2);
        let k4 = q(xi + ds * k3);
        xi = (xi + ds / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)).min(1.0);
        left -= ds;
        // Far on the cap the step is set by the slope alone; once q is below round-off
        // of ξ, μ no longer moves.
        if q(xi) * left < 1e-17 {
            break;
        }
    }
    a + w * xi
}

/// μ_as and dμ_as/dA after the exposure `A = ∫ μ_as0 H_ε dt` from μ_as = 0: the flow of
/// `dμ/dA = g(μ) = 1 − S(μ; 0.98 m, m)` (`m = mu_max`) in closed form. Below 0.98 m,
/// μ = A. On the cap, with `ξ = (μ − 0.98 m)/(0.02 m)` and `z = 1 − ξ`,
/// `1 − S = z³ p(z)`, `p(z) = 6z² − 15z + 10`, and the time on the cap
/// `s = (A − 0.98 m)/(0.02 m) = Ψ(1) − Ψ(z)` with the antiderivative of `1/(z³ p)`
/// (partial fractions):
/// `Ψ(z) = −1/(20 z²) − 0.15/z + 0.165 ln z − 0.0825 ln p(z) + 0.3375/(6k) atan((z − 1.25)/k)`,
/// `k² = 10/96`. Ψ is increasing; z is found by safeguarded Newton in `1/z`.
pub fn cap(a: f64, mu_max: f64) -> (f64, f64) {
    let lin = 0.98 * mu_max;
    if a <= lin {
        return (a, 1.0);
    }
    let w = 0.02 * mu_max;
    let s = (a - lin) / w;
    let k = (10.0f64 / 96.0).sqrt();
    let p = |z: f64| (6.0 * z - 15.0) * z + 10.0;
    let psi = |z: f64| {
        -0.05 / (z * z) - 0.15 / z + 0.165 * z.ln() - 0.0825 * p(z).ln()
            + 0.3375 / (6.0 * k) * ((z - 1.25) / k).atan()
    };
    let target = psi(1.0) - s;
    // f(v) = Ψ(1/v) − target, decreasing in v ≥ 1; f'(v) = −Ψ'(z)/v² = −1/(z p(z)) · z… :
    // dΨ/dz = 1/(z³ p), dz/dv = −z², so df/dv = −1/(z p(z)).
    let f = |v: f64| psi(1.0 / v) - target;
    // Ψ(z) ≈ −0.05/z² far along the cap, so v ≈ √(s/0.05): the bracket starts there
    // (f(1) = s ≥ 0 bounds it below).
    let mut v = (s / 0.05).sqrt().max(1.0);
    let (mut lo, mut hi) = (1.0f64, v);
    while f(hi) > 0.0 {
        lo = hi;
        hi *= 2.0;
    }
    v = v.clamp(lo, hi);
    for _ in 0..100 {
        let fv = f(v);
        if fv > 0.0 {
            lo = v;
        } else {
            hi = v;
        }
        let z = 1.0 / v;
        let step = fv * z * p(z);
        let mut next = v + step;
        if !(next > lo && next < hi) {
            next = 0.5 * (lo + hi);
        }
        if (next - v).abs() <= 1e-15 * v {
            v = next;
            break;
        }
        v = next;
    }
    let z = 1.0 / v;
    (lin + w * (1.0 - z), z * z * z * p(z))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::smooth_step;

    /// A reference solution of dμ/dA = 1 − S(μ) by RK4 with tiny fixed steps.
    fn fine(mu: f64, da: f64, m: f64) -> f64 {
        let n = 200_000;
        let h = da / n as f64;
        let g = |u: f64| 1.0 - smooth_step(u, 0.98 * m, m);
        let mut u = mu;
        for _ in 0..n {
            let k1 = g(u);
            let k2 = g(u + 0.5 * h * k1);
            let k3 = g(u + 0.5 * h * k2);
            let k4 = g(u + h * k3);
            u += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
        }
        u
    }

    #[test]
    fn below_the_cap_mu_grows_by_the_integral_of_the_drive() {
        assert_eq!(along_cap(0.0, 100.0, 1400.0), 100.0);
        assert_eq!(along_cap(1000.0, 372.0, 1400.0), 1372.0);
        assert_eq!(along_cap(5.0, 0.0, 1400.0), 5.0);
    }

    #[test]
    fn on_the_cap_mu_follows_the_ode() {
        let m = 1400.0;
        for (mu, da) in [
            (1300.0, 100.0),
            (1360.0, 30.0),
            (1380.0, 5.0),
            (0.0, 1500.0),
            (0.0, 3000.0),
            (1395.0, 2000.0),
        ] {
            let got = along_cap(mu, da, m);
            let want = fine(mu, da, m);
            assert!(
                (got - want).abs() < 1e-9 * m,
                "mu {mu} da {da}: {got} vs {want}"
            );
            assert!(got <= m);
        }
    }

    #[test]
    fn steps_compose() {
        // Moving by da1 then da2 is moving by da1 + da2 (the flow property).
        let m = 1400.0;
        let once = along_cap(1350.0, 80.0, m);
        let twice = along_cap(along_cap(1350.0, 30.0, m), 50.0, m);
        assert!((once - twice).abs() < 1e-9 * m, "{once} vs {twice}");
    }

    #[test]
    fn the_closed_form_cap_is_the_flow_from_zero() {
        let m = 1400.0;
        for a in [
            10.0, 1371.0, 1372.0, 1380.0, 1390.0, 1400.0, 1450.0, 3000.0, 4.0e4,
        ] {
            let (mu, g) = cap(a, m);
            let want = along_cap(0.0, a, m);
            assert!((mu - want).abs() < 1e-9 * m, "A {a}: {mu} vs {want}");
            // dμ/dA = 1 − S(μ).
            let gw = 1.0 - smooth_step(mu, 0.98 * m, m);
            assert!((g - gw).abs() < 1e-9, "A {a}: g {g} vs {gw}");
            assert!(mu <= m);
        }
        // Continuous and increasing across the start of the cap.
        let (below, _) = cap(0.98 * m, m);
        let (above, _) = cap(0.98 * m + 1e-9, m);
        assert!(above > below && above - below < 2e-9);
    }

    #[test]
    fn far_on_the_cap_mu_approaches_its_maximum_slowly() {
        // Near ξ = 1, dξ/ds ≈ 10 (1 − ξ)³, so 1 − ξ ≈ (20 s)^(−1/2).
        let m = 1400.0;
        let w = 0.02 * m;
        let s = 10_000.0;
        let got = along_cap(0.98 * m, s * w, m);
        let z = (m - got) / w;
        let asymptotic = (20.0 * s).powf(-0.5);
        assert!((z / asymptotic - 1.0).abs() < 0.05, "{z} vs {asymptotic}");
    }
}
