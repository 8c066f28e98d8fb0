//! How IDA's nonlinear systems are solved (the method, and the record of its failures), and
//! the arithmetic of Broyden's updates; the solver itself is FFI
//! (`crate::sundials`'s nonlinear solver).
//!
//! **Broyden** ([`NonlinearMethod::Broyden`]): the updates of "good" Broyden on the kept
//! iteration matrix M, B_{k+1} = B_k + G(x_{k+1}) s_kᵀ W / (s_kᵀ W s_k) with full steps s_k
//! and W the error weights squared (the update's inner product in IDA's norm), applied
//! through the recurrence of Kelley's `brsol` (Iterative Methods for Linear and Nonlinear
//! Equations, SIAM 1995, §7.3): z = −M⁻¹G(x_{n+1}); z += s_{j+1} ⟨s_j, z⟩/⟨s_j, s_j⟩ for
//! j < n; s_{n+1} = z / (1 − ⟨s_n, z⟩/⟨s_n, s_n⟩). Only the steps are stored.

use serde::{Deserialize, Serialize};

/// The iteration IDA's nonlinear systems are solved by.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub enum NonlinearMethod {
    /// Newton on the kept iteration matrix (SUNDIALS' own iteration).
    #[default]
    Newton,
    /// Broyden's updates of the kept matrix, up to `max_updates` per attempt; an attempt
    /// that took updates and failed on a fresh matrix is made again with Newton steps alone
    /// before the step is cut.
    Broyden {
        /// Most updates per attempt (≥ 1).
        max_updates: usize,
    },
}

/// Why one attempt at a step's nonlinear system failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FailureReason {
    /// IDA's test: the iterates contract by more than 0.9 per iteration.
    Rate,
    /// The most iterations allowed (IDA's default 4) without convergence.
    Iterations,
    /// The residual refused an iterate (an inadmissible state).
    Residual,
    /// The linear solver's set-up or solve failed recoverably.
    Linear,
}

/// One failed attempt: when, on which matrix, why.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NewtonFailure {
    /// IDA's current time (the end of the step attempted) and step size.
    pub t: f64,
    pub h: f64,
    /// cj of the step over cj of the matrix it iterated on.
    pub cj_ratio: f64,
    /// Iterations taken in the attempt.
    pub iterations: u32,
    /// Whether the matrix had been set up for this attempt (then IDA cuts the step);
    /// otherwise it was a kept one, and the attempt is retried on a fresh matrix.
    pub fresh: bool,
    pub reason: FailureReason,
}

/// The counters of [`NewtonFailure`]s over a run.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct NewtonCounts {
    /// Failed attempts on a kept matrix (each costs a new Jacobian and factorization).
    pub stale: u64,
    /// Failed attempts on a fresh matrix (each makes IDA cut the step).
    pub fresh: u64,
    /// Failed attempts by reason: rate, iterations, residual, linear.
    pub rate: u64,
    pub iterations: u64,
    pub residual: u64,
    pub linear: u64,
    /// Broyden updates applied.
    pub updates: u64,
}

impl NewtonCounts {
    /// Nothing counted (SUNDIALS' own Newton, or BDF2).
    pub fn is_empty(&self) -> bool {
        *self == Self::default()
    }
}

impl std::ops::AddAssign<&NewtonCounts> for NewtonCounts {
    fn add_assign(&mut self, b: &NewtonCounts) {
        self.stale += b.stale;
        self.fresh += b.fresh;
        self.rate += b.rate;
        self.iterations += b.iterations;
        self.residual += b.residual;
        self.linear += b.linear;
        self.updates += b.updates;
    }
}

/// Weighted inner product Σ aᵢ bᵢ wᵢ².
pub fn dot_w(a: &[f64], b: &[f64], w: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .zip(w)
        .map(|((a, b), w)| a * b * w * w)
        .sum()
}

/// Broyden's step from the plain one `z` = −M⁻¹G(x_{n+1}) and the attempt's earlier
/// steps s_0 … s_n (with their squared norms): Kelley's recurrence, in place. Returns
/// false (z untouched beyond repair) when the denominator vanishes.
pub fn broyden_step(z: &mut [f64], steps: &[Vec<f64>], norms: &[f64], w: &[f64]) -> bool {
    let n = steps.len();
    for j in 0..n.saturating_sub(1) {
        let c = dot_w(&steps[j], z, w) / norms[j];
        for (zi, si) in z.iter_mut().zip(&steps[j + 1]) {
            *zi += c * si;
        }
    }
    if let Some(last) = steps.last() {
        let d = 1.0 - dot_w(last, z, w) / norms[n - 1];
        if d.abs() < 1e-12 || !d.is_finite() {
            return false;
        }
        for zi in z.iter_mut() {
            *zi /= d;
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Kelley's recurrence gives −B_n⁻¹ G with B_n built by Broyden's updates explicitly
    /// (dense, weighted inner product), on random data.
    #[test]
    fn the_broyden_recurrence_applies_the_updated_inverse() {
        let n = 5;
        let mut seed = 12345u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        };
        let w: Vec<f64> = (0..n).map(|_| 1.0 + rnd().abs()).collect();
        // M: diagonally dominant.
        let m = nalgebra::DMatrix::from_fn(n, n, |i, j| if i == j { 3.0 } else { rnd() });
        let minv = m.clone().try_inverse().unwrap();
        let wm = nalgebra::DMatrix::from_diagonal(&nalgebra::DVector::from_iterator(
            n,
            w.iter().map(|x| x * x),
        ));
        // A sequence of residuals G_k; steps s_k = −B_k⁻¹ G_k, B_{k+1} = B_k + G_{k+1} s_kᵀW/(s_kᵀWs_k).
        let mut b = m.clone();
        let mut steps: Vec<Vec<f64>> = Vec::new();
        let mut norms: Vec<f64> = Vec::new();
        for k in 0..4 {
            let g = nalgebra::DVector::from_fn(n, |_, _| rnd());
            if k > 0 {
                let s = nalgebra::DVector::from_column_slice(steps.last().unwrap());
                let denom = (s.transpose() * &wm * &s)[(0, 0)];
                b += &g * (s.transpose() * &wm) / denom;
            }
            let exact = -(b.clone().try_inverse().unwrap() * &g);
            let mut z: Vec<f64> = (-(&minv * &g)).iter().copied().collect();
            assert!(broyden_step(&mut z, &steps, &norms, &w));
            for i in 0..n {
                assert!(
                    (z[i] - exact[i]).abs() < 1e-12 * (1.0 + exact[i].abs()),
                    "k {k}"
                );
            }
            norms.push(dot_w(&z, &z, &w));
            steps.push(z);
        }
    }
}
