//! Reference DAEs with published SUNDIALS outputs or closed-form solutions, shared by the
//! tests, the examples and the benchmarks.
//!
//! - [`Robertson`]: the stiff chemical kinetics index-1 DAE of SUNDIALS' `idaRoberts_dns`,
//!   with the forward sensitivities to its three rate constants of `idasRoberts_FSA_dns`.
//! - [`Heat2D`]: the 2-D heat equation with algebraic boundary rows of `idaHeat2D_bnd` /
//!   `idaHeat2D_klu`.
//! - [`Analytic`]: Ascher & Petzold's example 10.2 (`idaAnalytic_mels`), with solution
//!   x₁ = eᵗ, x₂ = eᵗ/(t − 2).

use super::{Dae, DaeError, Pattern, SensitivityDae, State};
use crate::fem::assembly::{pattern_from_entries, position};

/// Robertson kinetics: y₁' = −0.04 y₁ + 10⁴ y₂ y₃, y₂' = 0.04 y₁ − 10⁴ y₂ y₃ − 3·10⁷ y₂²,
/// 0 = y₁ + y₂ + y₃ − 1, y(0) = (1, 0, 0). The rate constants are its parameters
/// p = (0.04, 10⁴, 3·10⁷) ([`SensitivityDae`]).
pub struct Robertson {
    pattern: Pattern,
    /// The rate constants p₁, p₂, p₃.
    pub p: [f64; 3],
}

impl Default for Robertson {
    fn default() -> Self {
        Self::new()
    }
}

impl Robertson {
    /// The problem with its dense 3×3 pattern.
    pub fn new() -> Self {
        let entries: Vec<_> = (0..3).flat_map(|c| (0..3).map(move |r| (r, c))).collect();
        Self {
            pattern: pattern_from_entries(3, &entries),
            p: [0.04, 1.0e4, 3.0e7],
        }
    }
}

impl Dae for Robertson {
    fn size(&self) -> usize {
        3
    }

    fn residual(&mut self, State { y, yp, .. }: State, r: &mut [f64]) -> Result<(), DaeError> {
        let [p1, p2, p3] = self.p;
        let f1 = -p1 * y[0] + p2 * y[1] * y[2];
        r[0] = f1 - yp[0];
        r[1] = -f1 - p3 * y[1] * y[1] - yp[1];
        r[2] = y[0] + y[1] + y[2] - 1.0;
        Ok(())
    }

    fn pattern(&self) -> &Pattern {
        &self.pattern
    }

    fn jacobian(&mut self, State { y, .. }: State, cj: f64, v: &mut [f64]) -> Result<(), DaeError> {
        // Dense pattern, column-major: v[3c + r] = J[r][c].
        let [p1, p2, p3] = self.p;
        let j = [
            [-p1 - cj, p2 * y[2], p2 * y[1]],
            [p1, -p2 * y[2] - 2.0 * p3 * y[1] - cj, -p2 * y[1]],
            [1.0, 1.0, 1.0],
        ];
        for c in 0..3 {
            for (r, row) in j.iter().enumerate() {
                v[3 * c + r] = row[c];
            }
        }
        Ok(())
    }

    fn differential(&self) -> Vec<bool> {
        vec![true, true, false]
    }

    fn initial(&self) -> (f64, Vec<f64>, Vec<f64>) {
        let p1 = self.p[0];
        (0.0, vec![1.0, 0.0, 0.0], vec![-p1, p1, 0.0])
    }
}

impl SensitivityDae for Robertson {
    fn parameter_count(&self) -> usize {
        3
    }

    fn sensitivity_residuals(
        &mut self,
        State { y, .. }: State,
        _r: &[f64],
        s: &[&[f64]],
        sp: &[&[f64]],
        out: &mut [&mut [f64]],
    ) -> Result<(), DaeError> {
        let [p1, p2, p3] = self.p;
        for (i, o) in out.iter_mut().enumerate() {
            let (s, sp) = (s[i], sp[i]);
            // F_y s + F_ẏ ṡ, then + ∂F/∂pᵢ.
            let df1 = -p1 * s[0] + p2 * (y[2] * s[1] + y[1] * s[2]);
            o[0] = df1 - sp[0];
            o[1] = -df1 - 2.0 * p3 * y[1] * s[1] - sp[1];
            o[2] = s[0] + s[1] + s[2];
            let dp = match i {
                0 => [-y[0], y[0]],
                1 => [y[1] * y[2], -y[1] * y[2]],
                _ => [0.0, -y[1] * y[1]],
            };
            o[0] += dp[0];
            o[1] += dp[1];
        }
        Ok(())
    }

    fn initial_sensitivities(&self) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
        // y₀ does not depend on p; ẏ₀ = (−p₁, p₁, 0) does on p₁.
        let s0 = vec![vec![0.0; 3]; 3];
        let mut sp0 = vec![vec![0.0; 3]; 3];
        sp0[0] = vec![-1.0, 1.0, 0.0];
        (s0, sp0)
    }
}

/// The heat equation u_t = Δu on the unit square, 5-point differences on an m × m grid;
/// interior rows `u' − Δ_h u = 0`, boundary rows `u = 0` (algebraic). Initial profile
/// 16x(1−x)y(1−y), boundary values set to `boundary_value` (inconsistent unless 0, to be
/// corrected by IDACalcIC), as in SUNDIALS' idaHeat2D examples.
pub struct Heat2D {
    m: usize,
    coeff: f64,
    boundary_value: f64,
    pattern: Pattern,
    /// Positions of (diagonal, west, east, south, north) entries of each row, in `values`.
    pos: Vec<[usize; 5]>,
}

impl Heat2D {
    /// The m × m grid problem with the given initial boundary values.
    pub fn new(m: usize, boundary_value: f64) -> Self {
        let n = m * m;
        let dx = 1.0 / (m as f64 - 1.0);
        let mut entries = Vec::new();
        for k in 0..n {
            entries.push((k, k));
            if !Self::is_boundary(m, k) {
                for nb in [k - 1, k + 1, k - m, k + m] {
                    entries.push((k, nb));
                }
            }
        }
        let pattern = pattern_from_entries(n, &entries);
        let pos = (0..n)
            .map(|k| {
                let d = position(&pattern, k, k).expect("diagonal");
                if Self::is_boundary(m, k) {
                    [d; 5]
                } else {
                    let p = |c| position(&pattern, k, c).expect("stencil entry");
                    [d, p(k - 1), p(k + 1), p(k - m), p(k + m)]
                }
            })
            .collect();
        Self {
            m,
            coeff: 1.0 / (dx * dx),
            boundary_value,
            pattern,
            pos,
        }
    }

    fn is_boundary(m: usize, k: usize) -> bool {
        let (i, j) = (k % m, k / m);
        i == 0 || j == 0 || i == m - 1 || j == m - 1
    }

    /// Constraint vector u ≥ 0 for every component (IDASetConstraints), as in the examples.
    pub fn constraints(&self) -> Vec<f64> {
        vec![1.0; self.m * self.m]
    }

    fn laplacian(&self, u: &[f64], k: usize) -> f64 {
        let m = self.m;
        self.coeff * (u[k - 1] + u[k + 1] + u[k - m] + u[k + m] - 4.0 * u[k])
    }
}

impl Dae for Heat2D {
    fn size(&self) -> usize {
        self.m * self.m
    }

    fn residual(
        &mut self,
        State { y: u, yp: up, .. }: State,
        r: &mut [f64],
    ) -> Result<(), DaeError> {
        for k in 0..self.size() {
            r[k] = if Self::is_boundary(self.m, k) {
                u[k]
            } else {
                up[k] - self.laplacian(u, k)
            };
        }
        Ok(())
    }

    fn pattern(&self) -> &Pattern {
        &self.pattern
    }

    fn jacobian(&mut self, _: State, cj: f64, v: &mut [f64]) -> Result<(), DaeError> {
        v.fill(0.0);
        for k in 0..self.size() {
            let p = self.pos[k];
            if Self::is_boundary(self.m, k) {
                v[p[0]] = 1.0;
            } else {
                v[p[0]] = cj + 4.0 * self.coeff;
                for &q in &p[1..] {
                    v[q] = -self.coeff;
                }
            }
        }
        Ok(())
    }

    fn differential(&self) -> Vec<bool> {
        (0..self.size())
            .map(|k| !Self::is_boundary(self.m, k))
            .collect()
    }

    fn initial(&self) -> (f64, Vec<f64>, Vec<f64>) {
        let (m, n) = (self.m, self.size());
        let dx = 1.0 / (m as f64 - 1.0);
        let mut u: Vec<f64> = (0..n)
            .map(|k| {
                let (x, y) = ((k % m) as f64 * dx, (k / m) as f64 * dx);
                16.0 * x * (1.0 - x) * y * (1.0 - y)
            })
            .collect();
        let mut up = vec![0.0; n];
        for k in 0..n {
            if Self::is_boundary(m, k) {
                u[k] = self.boundary_value;
            } else {
                // The examples compute u' from the profile before the boundary values are
                // overwritten (those neighbours are 0 in the profile).
                let lap = {
                    let g = |kk: usize| if Self::is_boundary(m, kk) { 0.0 } else { u[kk] };
                    self.coeff * (g(k - 1) + g(k + 1) + g(k - m) + g(k + m) - 4.0 * u[k])
                };
                up[k] = lap;
            }
        }
        (0.0, u, up)
    }
}

/// Ascher & Petzold example 10.2 (SUNDIALS' idaAnalytic_mels), stiffness parameter α:
/// x₁' = (1−α)/(t−2) x₁ − x₁ + (α−1) x₂ + 2eᵗ, 0 = (t+2) x₁ − (t+2) eᵗ;
/// solution x₁ = eᵗ, x₂ = eᵗ/(t−2).
pub struct Analytic {
    alpha: f64,
    pattern: Pattern,
}

impl Analytic {
    /// The problem with stiffness parameter α (SUNDIALS uses 10).
    pub fn new(alpha: f64) -> Self {
        Self {
            alpha,
            pattern: pattern_from_entries(2, &[(0, 0), (1, 0), (0, 1)]),
        }
    }

    /// Exact solution (x₁, x₂) and its derivative at t.
    pub fn exact(t: f64) -> ([f64; 2], [f64; 2]) {
        let e = t.exp();
        let x2 = e / (t - 2.0);
        ([e, x2], [e, x2 - e / ((t - 2.0) * (t - 2.0))])
    }
}

impl Dae for Analytic {
    fn size(&self) -> usize {
        2
    }

    fn residual(&mut self, State { t, y, yp }: State, r: &mut [f64]) -> Result<(), DaeError> {
        let a = self.alpha;
        r[0] = (1.0 - a) / (t - 2.0) * y[0] - y[0] + (a - 1.0) * y[1] + 2.0 * t.exp() - yp[0];
        r[1] = (t + 2.0) * y[0] - (t + 2.0) * t.exp();
        Ok(())
    }

    fn pattern(&self) -> &Pattern {
        &self.pattern
    }

    fn jacobian(&mut self, State { t, .. }: State, cj: f64, v: &mut [f64]) -> Result<(), DaeError> {
        let a = self.alpha;
        // Column 0: rows 0, 1; column 1: row 0.
        v[0] = (1.0 - a) / (t - 2.0) - 1.0 - cj;
        v[1] = t + 2.0;
        v[2] = a - 1.0;
        Ok(())
    }

    fn differential(&self) -> Vec<bool> {
        vec![true, false]
    }

    fn initial(&self) -> (f64, Vec<f64>, Vec<f64>) {
        let (y, yp) = Self::exact(0.0);
        (0.0, y.to_vec(), yp.to_vec())
    }
}

/// A problem with root functions added ([`Dae::root_directions`]): `g(at, out)` fills the
/// values of the functions, `directions` the crossing each counts (+1, −1, 0).
pub struct WithRoots<P> {
    /// The problem.
    pub inner: P,
    /// One per function: +1 rising, −1 falling, 0 either.
    pub directions: Vec<i32>,
    /// The functions' values at a state.
    pub g: fn(&State, &mut [f64]),
}

impl<P: Dae> Dae for WithRoots<P> {
    fn size(&self) -> usize {
        self.inner.size()
    }
    fn residual(&mut self, at: State, r: &mut [f64]) -> Result<(), DaeError> {
        self.inner.residual(at, r)
    }
    fn pattern(&self) -> &Pattern {
        self.inner.pattern()
    }
    fn jacobian(&mut self, at: State, cj: f64, v: &mut [f64]) -> Result<(), DaeError> {
        self.inner.jacobian(at, cj, v)
    }
    fn differential(&self) -> Vec<bool> {
        self.inner.differential()
    }
    fn initial(&self) -> (f64, Vec<f64>, Vec<f64>) {
        self.inner.initial()
    }
    fn breakpoints(&self) -> Vec<f64> {
        self.inner.breakpoints()
    }
    fn root_directions(&self) -> Vec<i32> {
        self.directions.clone()
    }
    fn root_functions(&mut self, at: State, g: &mut [f64]) -> Result<(), DaeError> {
        (self.g)(&at, g);
        Ok(())
    }
}

impl WithRoots<Robertson> {
    /// SUNDIALS' idaRoberts_dns with its root functions `grob`: y₁ − 1e-4 and y₃ − 0.01,
    /// either direction.
    pub fn robertson() -> Self {
        WithRoots {
            inner: Robertson::new(),
            directions: vec![0, 0],
            g: |at, g| {
                g[0] = at.y[0] - 1e-4;
                g[1] = at.y[2] - 0.01;
            },
        }
    }
}
