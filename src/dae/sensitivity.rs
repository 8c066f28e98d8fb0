//! Forward sensitivities of any [`Dae`] to parameters it was built from: [`Perturbed`]
//! carries the problem and, per parameter pᵢ, the same problem built at pᵢ + δᵢ, and is a
//! [`SensitivityDae`]:
//!
//! - `F_y sᵢ + F_ẏ ṡᵢ` from the problem's own Jacobian, `F_y = J(cj = 0)` and
//!   `F_ẏ = J(1) − J(0)` (exact, as the Jacobian is; assembled once per state, however many
//!   times the integrator asks at it);
//! - `F_{pᵢ}` by the difference of the perturbed problem's residual at the same state,
//!   `(F(pᵢ + δᵢ) − F(pᵢ)) / δᵢ`, once per state: exact where the residual is linear in pᵢ
//!   (a modulus, the gravity), `O(δᵢ)` otherwise (δᵢ = 1e-7 |pᵢ| leaves ~1e-7 relative).
//!
//! Nothing here knows what the problem is: the cell model of every dimension gets its
//! sensitivities from its residual and Jacobian alone.

use super::{Dae, DaeError, FirstOrderBlocks, Pattern, SensitivityDae, State};

/// Sensitivities and their time derivatives, one vector each per parameter.
pub type SensitivityVectors = (Vec<Vec<f64>>, Vec<Vec<f64>>);

/// One parameter's perturbed problem and its step.
pub struct PerturbedModel<M> {
    /// The problem built at pᵢ + δᵢ.
    pub model: M,
    /// δᵢ (≠ 0), in the parameter's units.
    pub delta: f64,
}

/// The Jacobian's two parts at one state.
struct Parts {
    t: f64,
    y: Vec<f64>,
    yp: Vec<f64>,
    /// F_y and F_ẏ in the pattern's order.
    fy: Vec<f64>,
    fyp: Vec<f64>,
    /// F_{pᵢ} per parameter.
    fp: Vec<Vec<f64>>,
}

/// A problem with its perturbed copies: a [`Dae`] as the problem is, and a
/// [`SensitivityDae`] on the parameters of the pairs (see the module's text).
pub struct Perturbed<M> {
    /// The problem integrated.
    pub model: M,
    /// Per parameter, the problem at pᵢ + δᵢ.
    pub perturbed: Vec<PerturbedModel<M>>,
    parts: Option<Parts>,
    /// Initial sensitivities given (a restart), instead of the perturbed problems' own.
    initial: Option<SensitivityVectors>,
}

impl<M: Dae> Perturbed<M> {
    /// `model` and its perturbed copies (each of the same size as `model`).
    pub fn new(model: M, perturbed: Vec<PerturbedModel<M>>) -> Result<Self, DaeError> {
        let n = model.size();
        for (i, p) in perturbed.iter().enumerate() {
            if p.model.size() != n || p.delta == 0.0 || !p.delta.is_finite() {
                return Err(DaeError::Fatal(format!(
                    "parameter {i}: a perturbed problem of {} unknowns for {n}, δ = {}",
                    p.model.size(),
                    p.delta
                )));
            }
        }
        Ok(Self {
            model,
            perturbed,
            parts: None,
            initial: None,
        })
    }

    /// Sensitivities consistent with the problem at `at` (a restart, as
    /// [`super::consistent_init`] makes the state consistent): where `solve_for_y[i]`, sᵢ
    /// is solved for and ṡᵢ kept as given; elsewhere ṡᵢ is solved for and sᵢ kept. The
    /// linearisation of the consistent state, F_y s + F_ẏ ṡ + F_p = 0, one linear solve
    /// per parameter on one factorization. Returns them, and keeps them as the initial
    /// sensitivities ([`SensitivityDae::initial_sensitivities`]).
    pub fn consistent_sensitivities(
        &mut self,
        at: State,
        solve_for_y: &[bool],
        mut s: Vec<Vec<f64>>,
        mut sp: Vec<Vec<f64>>,
        factory: &dyn super::LinearSolverFactory,
    ) -> Result<SensitivityVectors, super::IntegratorError> {
        use super::IntegratorError;
        let n = self.model.size();
        let problem = |e: DaeError| IntegratorError::Problem {
            t: at.t,
            message: format!("consistent sensitivities: {e}"),
        };
        let linear = |e: super::linsolve::LinearSolverError| IntegratorError::Linear {
            context: "consistent sensitivities",
            source: e,
        };
        if solve_for_y.len() != n
            || s.len() != self.perturbed.len()
            || sp.len() != s.len()
            || s.iter().chain(&sp).any(|v| v.len() != n)
        {
            return Err(IntegratorError::Input(format!(
                "consistent sensitivities: {} unknowns, {} parameters; given a mask of {} and \
                 {} / {} vectors",
                n,
                self.perturbed.len(),
                solve_for_y.len(),
                s.len(),
                sp.len()
            )));
        }
        let mut r = vec![0.0; n];
        self.model.residual(at, &mut r).map_err(problem)?;
        self.parts_at(at, &r).map_err(problem)?;
        let parts = self.parts.as_ref().expect("assembled by parts_at");
        let pattern = self.model.pattern().clone();
        let mut m = parts.fy.clone();
        for (c, &for_y) in solve_for_y.iter().enumerate() {
            if !for_y {
                let range = pattern.col_ptr()[c]..pattern.col_ptr()[c + 1];
                m[range.clone()].copy_from_slice(&parts.fyp[range]);
            }
        }
        let mut solver = factory.build_for(&self.model).map_err(linear)?;
        solver.analyse(&pattern).map_err(linear)?;
        solver.factorize(&m).map_err(linear)?;
        for (i, (si, spi)) in s.iter_mut().zip(sp.iter_mut()).enumerate() {
            // The known parts: F_y s on the kept s, F_ẏ ṡ on the kept ṡ.
            let known_s: Vec<f64> = (0..n)
                .map(|c| if solve_for_y[c] { 0.0 } else { si[c] })
                .collect();
            let known_sp: Vec<f64> = (0..n)
                .map(|c| if solve_for_y[c] { spi[c] } else { 0.0 })
                .collect();
            let mut b = parts.fp[i].clone();
            add_product(&pattern, &parts.fy, &known_s, &mut b);
            add_product(&pattern, &parts.fyp, &known_sp, &mut b);
            b.iter_mut().for_each(|v| *v = -*v);
            solver.solve_in_place(&mut b).map_err(linear)?;
            for c in 0..n {
                if solve_for_y[c] {
                    si[c] = b[c];
                } else {
                    spi[c] = b[c];
                }
            }
        }
        self.initial = Some((s.clone(), sp.clone()));
        Ok((s, sp))
    }

    /// F_y, F_ẏ and F_p at `at` (where F = `r`), assembled unless they are those of the
    /// last call's state.
    fn parts_at(&mut self, at: State, r: &[f64]) -> Result<&Parts, DaeError> {
        let current = self
            .parts
            .as_ref()
            .is_some_and(|p| p.t == at.t && p.y == at.y && p.yp == at.yp);
        if !current {
            let nnz = self.model.pattern().row_idx().len();
            let mut parts = self.parts.take().unwrap_or(Parts {
                t: f64::NAN,
                y: Vec::new(),
                yp: Vec::new(),
                fy: vec![0.0; nnz],
                fyp: vec![0.0; nnz],
                fp: vec![vec![0.0; r.len()]; self.perturbed.len()],
            });
            // Invalid until all are assembled.
            parts.t = f64::NAN;
            self.model.jacobian(at, 0.0, &mut parts.fy)?;
            self.model.jacobian(at, 1.0, &mut parts.fyp)?;
            for (d, j0) in parts.fyp.iter_mut().zip(&parts.fy) {
                *d -= j0;
            }
            for (p, fp) in self.perturbed.iter_mut().zip(&mut parts.fp) {
                p.model.residual(at, fp)?;
                for (f, r) in fp.iter_mut().zip(r) {
                    *f = (*f - r) / p.delta;
                }
            }
            parts.t = at.t;
            parts.y.clear();
            parts.y.extend_from_slice(at.y);
            parts.yp.clear();
            parts.yp.extend_from_slice(at.yp);
            self.parts = Some(parts);
        }
        Ok(self.parts.as_ref().expect("assembled above"))
    }
}

/// `out += A x` for the values `a` of the pattern `p` (column-major).
fn add_product(p: &Pattern, a: &[f64], x: &[f64], out: &mut [f64]) {
    let (cp, ri) = (p.col_ptr(), p.row_idx());
    for (c, &xc) in x.iter().enumerate() {
        if xc != 0.0 {
            for k in cp[c]..cp[c + 1] {
                out[ri[k]] += a[k] * xc;
            }
        }
    }
}

impl<M: Dae> Dae for Perturbed<M> {
    fn size(&self) -> usize {
        self.model.size()
    }
    fn residual(&mut self, at: State, r: &mut [f64]) -> Result<(), DaeError> {
        self.model.residual(at, r)
    }
    fn pattern(&self) -> &Pattern {
        self.model.pattern()
    }
    fn jacobian(&mut self, at: State, cj: f64, v: &mut [f64]) -> Result<(), DaeError> {
        self.model.jacobian(at, cj, v)
    }
    fn differential(&self) -> Vec<bool> {
        self.model.differential()
    }
    fn initial(&self) -> (f64, Vec<f64>, Vec<f64>) {
        self.model.initial()
    }
    fn accepted_step(&mut self, t: f64, y: &[f64], yp: &[f64]) {
        self.model.accepted_step(t, y, yp);
        for p in &mut self.perturbed {
            p.model.accepted_step(t, y, yp);
        }
    }
    fn breakpoints(&self) -> Vec<f64> {
        self.model.breakpoints()
    }
    fn first_order_blocks(&self) -> Option<FirstOrderBlocks> {
        self.model.first_order_blocks()
    }
    fn root_directions(&self) -> Vec<i32> {
        self.model.root_directions()
    }
    fn root_functions(&mut self, at: State, g: &mut [f64]) -> Result<(), DaeError> {
        self.model.root_functions(at, g)
    }
}

impl<M: Dae> SensitivityDae for Perturbed<M> {
    fn parameter_count(&self) -> usize {
        self.perturbed.len()
    }

    fn sensitivity_residuals(
        &mut self,
        at: State,
        r: &[f64],
        s: &[&[f64]],
        sp: &[&[f64]],
        out: &mut [&mut [f64]],
    ) -> Result<(), DaeError> {
        self.parts_at(at, r)?;
        let parts = self.parts.as_ref().expect("assembled by parts_at");
        let pattern = self.model.pattern();
        for (i, o) in out.iter_mut().enumerate() {
            o.copy_from_slice(&parts.fp[i]);
            add_product(pattern, &parts.fy, s[i], o);
            add_product(pattern, &parts.fyp, sp[i], o);
        }
        Ok(())
    }

    /// Those given by [`Perturbed::consistent_sensitivities`], else the differences of the
    /// perturbed problems' initial values.
    fn initial_sensitivities(&self) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
        if let Some(given) = &self.initial {
            return given.clone();
        }
        let (_, y0, yp0) = self.model.initial();
        let diff = |a: &[f64], b: &[f64], h: f64| -> Vec<f64> {
            a.iter().zip(b).map(|(a, b)| (a - b) / h).collect()
        };
        self.perturbed
            .iter()
            .map(|p| {
                let (_, y1, yp1) = p.model.initial();
                (diff(&y1, &y0, p.delta), diff(&yp1, &yp0, p.delta))
            })
            .unzip()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dae::problems::Robertson;

    fn robertson_at(p: [f64; 3]) -> Robertson {
        let mut r = Robertson::new();
        r.p = p;
        r
    }

    #[test]
    fn perturbed_robertson_has_robertsons_own_sensitivity_residuals() {
        // Robertson's analytic sensitivity residuals against the generic ones made of its
        // Jacobian and perturbed copies, at a state off the solution with arbitrary s, ṡ.
        let p = Robertson::new().p;
        let perturbed = (0..3)
            .map(|i| {
                let delta = 1e-3 * p[i];
                let mut up = p;
                up[i] += delta;
                PerturbedModel {
                    model: robertson_at(up),
                    delta,
                }
            })
            .collect();
        let mut generic = Perturbed::new(Robertson::new(), perturbed).unwrap();
        let mut exact = Robertson::new();
        let (y, yp) = ([0.7, 2e-5, 0.3], [-0.3, 1e-3, 0.3]);
        let at = State::new(3.0, &y, &yp);
        let s: Vec<Vec<f64>> = (0..3)
            .map(|i| vec![0.1 * i as f64 - 0.2, 1e-6, 0.05])
            .collect();
        let sp: Vec<Vec<f64>> = (0..3).map(|i| vec![0.3, -0.1 * i as f64, 0.0]).collect();
        let (s_ref, sp_ref): (Vec<&[f64]>, Vec<&[f64]>) = (
            s.iter().map(|v| &v[..]).collect(),
            sp.iter().map(|v| &v[..]).collect(),
        );
        let mut r = [0.0; 3];
        exact.residual(at, &mut r).unwrap();
        let mut a = vec![vec![0.0; 3]; 3];
        let mut b = vec![vec![0.0; 3]; 3];
        {
            let mut out: Vec<&mut [f64]> = a.iter_mut().map(|v| &mut v[..]).collect();
            generic
                .sensitivity_residuals(at, &r, &s_ref, &sp_ref, &mut out)
                .unwrap();
        }
        {
            let mut out: Vec<&mut [f64]> = b.iter_mut().map(|v| &mut v[..]).collect();
            exact
                .sensitivity_residuals(at, &r, &s_ref, &sp_ref, &mut out)
                .unwrap();
        }
        for i in 0..3 {
            for k in 0..3 {
                // The residual is linear in each pᵢ: the differences are exact to round-off.
                let scale = b[i].iter().fold(1e-300_f64, |m, v| m.max(v.abs()));
                assert!(
                    (a[i][k] - b[i][k]).abs() <= 1e-9 * scale,
                    "parameter {i}, row {k}: {} against {}",
                    a[i][k],
                    b[i][k]
                );
            }
        }
        let (s0, sp0) = generic.initial_sensitivities();
        assert_eq!(s0, vec![vec![0.0; 3]; 3]);
        assert!((sp0[0][0] + 1.0).abs() < 1e-12 && (sp0[0][1] - 1.0).abs() < 1e-12);
    }
}
