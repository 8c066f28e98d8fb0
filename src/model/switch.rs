//! Changing the system during a run: the same cell rebuilt with fewer unknowns and
//! restarted, consistently, from the state of the old one.

use super::{CellOf, ModelError, ModelParams, Shape};
use crate::dae::{Atol, LinearSolverFactory, consistent_init};

/// How a restarted system is made consistent: the linear solver of its Newton solve
/// (a full-size one: the new system may have no (u, v) pairs to condense) and the
/// tolerances that weight its convergence test (those of the run).
pub struct Restart<'a> {
    /// Builds the linear solver of the Newton solve.
    pub linear_solver: &'a dyn LinearSolverFactory,
    /// Relative tolerance.
    pub rtol: f64,
    /// Absolute tolerance on displacements \[µm\] (scaled per block by
    /// [`CellOf::atol_vector`]).
    pub atol: f64,
}

/// The error of the restart `what` at `t`, refused with `message`.
fn refused(what: &'static str, t: f64, message: String) -> ModelError {
    ModelError::Restart {
        what,
        t,
        source: Box::new(crate::dae::IntegratorError::Problem { t, message }),
    }
}

impl<S: Shape<D, N, E>, const D: usize, const N: usize, const E: usize> CellOf<S, D, N, E> {
    /// This cell rebuilt with `params`, its μ_as unknowns deferred or not as here.
    fn rebuilt(&self, params: ModelParams) -> Result<Self, ModelError> {
        let deferred = self.history.is_some();
        let with_mu = !deferred && self.params.adhesion.is_some();
        let mut m = Self::build(params, self.mesh.clone(), self.constraints, with_mu)?;
        m.parallel = self.parallel;
        Ok(m)
    }

    /// This cell's deferred μ_as history, if any, restarted at `t` from the membrane
    /// motion of `m` in state (`y`, `yp`), given to `m`.
    fn carry_history(&self, m: &mut Self, t: f64, y: &[f64], yp: &[f64]) -> Result<(), String> {
        if let Some(h) = &self.history {
            let (x, xdot) = m.membrane_motion(y, yp);
            m.history = Some(h.restarted(t, x, xdot).map_err(|e| e.to_string())?);
        }
        Ok(())
    }

    /// Whether at time `t` the contact carries the cell's current weight (gravity ramped
    /// and signed as at `t`; false while there is no downward load).
    pub fn contact_carries_weight(&self, t: f64, y: &[f64]) -> bool {
        let ph = &self.params.phases;
        let load = self.weight() * ph.t_g(t) * ph.gravity_sign(t);
        load > 0.0 && self.contact_force_total(y)[1] >= load
    }

    /// The same cell without inertia, on (u, μ_as), set to restart at time `t` from the
    /// state (`y`, `yp`) of this model, placed at rest in equilibrium: u̇ = 0 and u solved
    /// from F(u, u̇ = 0, μ_as) = 0, while the μ_as ODEs keep μ_as and get a consistent
    /// μ̇_as. That is the consistent state up to the slow load ramp. Keeping u̇ = v
    /// instead carries the elastic ringing of the landing into a system whose rigid
    /// vertical mode is algebraic, and IDA then resolves an inconsistent transient: at
    /// rtol 1e-8 its step fell to 1e-13 s right after the switch and stayed there
    /// (measured on `cases/hard/rtol-tight.ron`). Without inertia that mode has no
    /// damping and only the contact's stiffness, so call this once the contact carries
    /// the cell ([`Self::contact_carries_weight`]).
    pub fn without_inertia_at_rest(
        &self,
        t: f64,
        y: &[f64],
        yp: &[f64],
        restart: &Restart,
    ) -> Result<Self, ModelError> {
        let (mut y2, mut yp2) = self.dofs.drop_inertia(y, yp);
        yp2[..self.dofs.n_u].iter_mut().for_each(|v| *v = 0.0);
        let mut params = self.params.clone();
        params.inertia = false;
        let mut m = self.rebuilt(params)?;
        let atol = Atol::Vector(m.atol_vector(restart.atol));
        let for_y: Vec<bool> = (0..m.dofs.n).map(|i| i < m.dofs.n_u).collect();
        consistent_init(
            &mut m,
            t,
            &mut y2,
            &mut yp2,
            &for_y,
            restart.linear_solver,
            restart.rtol,
            &atol,
        )
        .map_err(|source| ModelError::Restart {
            what: "switching inertia off",
            t,
            source: Box::new(source),
        })?;
        self.carry_history(&mut m, t, &y2, &yp2)
            .map_err(|e| refused("switching inertia off", t, e))?;
        m.set_initial(t, y2, yp2);
        Ok(m)
    }

    /// The same system as this one now (inertia on or off, μ_as unknowns there or
    /// deferred) with the parameters `params` of another case that agrees with this one's
    /// up to `t` ([`crate::run::shared_until`]), set to restart at `t` from (`y`, `yp`).
    /// Nothing is solved: the state is consistent for both, as their residuals agree at `t`.
    pub fn branched(
        &self,
        mut params: ModelParams,
        t: f64,
        y: &[f64],
        yp: &[f64],
    ) -> Result<Self, ModelError> {
        let refuse = |message: String| refused("branching", t, message);
        if params.adhesion.is_some() != self.params.adhesion.is_some() {
            return Err(refuse("one case has adhesion and the other not".into()));
        }
        params.inertia = self.dofs.inertia;
        let mut m = self.rebuilt(params)?;
        if m.dofs.n != self.dofs.n || y.len() != m.dofs.n || yp.len() != m.dofs.n {
            return Err(refuse(format!(
                "the systems differ: {} unknowns against {}",
                m.dofs.n, self.dofs.n
            )));
        }
        self.carry_history(&mut m, t, y, yp).map_err(refuse)?;
        m.set_initial(t, y.to_vec(), yp.to_vec());
        Ok(m)
    }

    /// The same cell without inertia (with its own parameters), set to restart at `t` from
    /// the state (`y`, `yp`), given in the new system's layout ([`Self::drop_inertia`]):
    /// nothing is solved. The perturbed copies of a sensitivity run follow the solution's
    /// switch so ([`crate::run::sensitivity`]).
    pub fn without_inertia_from(
        &self,
        t: f64,
        y: Vec<f64>,
        yp: Vec<f64>,
    ) -> Result<Self, ModelError> {
        let mut params = self.params.clone();
        params.inertia = false;
        let mut m = self.rebuilt(params)?;
        if y.len() != m.dofs.n || yp.len() != m.dofs.n {
            return Err(refused(
                "switching inertia off",
                t,
                format!(
                    "a state of {} and {} values for {} unknowns",
                    y.len(),
                    yp.len(),
                    m.dofs.n
                ),
            ));
        }
        self.carry_history(&mut m, t, &y, &yp)
            .map_err(|e| refused("switching inertia off", t, e))?;
        m.set_initial(t, y, yp);
        Ok(m)
    }

    /// A state (or its sensitivities) of this system in the layout of the same system
    /// without inertia: (u, μ_as), with u̇ = v.
    pub fn drop_inertia(&self, y: &[f64], yp: &[f64]) -> (Vec<f64>, Vec<f64>) {
        self.dofs.drop_inertia(y, yp)
    }

    /// The same cell with its μ_as unknowns, set to restart at time `t` (T_g0, where
    /// adhesion starts to act) from the state (`y`, `yp`) of this model, which defers them:
    /// u (and v) and their derivatives carried over, the exposure A from the history
    /// integrated beside the system, Ȧ = a(x). Every row is then consistent: the old rows
    /// do not see μ_as while `t_as(t) = 0`, and the new ones hold by construction.
    pub fn with_adhesion_unknowns(
        &self,
        t: f64,
        y: &[f64],
        yp: &[f64],
    ) -> Result<Self, ModelError> {
        let restart_err = |e: String| refused("adding the adhesion unknowns", t, e);
        let h = self
            .history
            .as_ref()
            .ok_or_else(|| restart_err("the adhesion unknowns are already there".into()))?;
        let exposure = h.at(t).map_err(|e| restart_err(e.to_string()))?;
        let mut m =
            Self::with_constraints(self.params.clone(), self.mesh.clone(), self.constraints)?;
        m.parallel = self.parallel;
        debug_assert_eq!(m.dofs.n, self.dofs.n + exposure.len());
        let mut y2 = y.to_vec();
        let mut yp2 = yp.to_vec();
        y2.extend_from_slice(&exposure);
        let ad = self.params.adhesion.as_ref().expect("deferred adhesion");
        for &i in &m.dofs.mu_nodes {
            let x = m.position(y, i);
            yp2.push(crate::physics::adhesion_rate(&m.substrate, ad, &x, 0.0));
        }
        m.set_initial(t, y2, yp2);
        Ok(m)
    }
}
