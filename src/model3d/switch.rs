//! Changing the 3-D system during a run, as the half-plane models do
//! (`crate::model::switch`): inertia switched off once the contact carries the cell, the
//! cell placed at rest in equilibrium; and a case that agrees with another up to a time
//! branched from its state.

use super::{Cell3, Model3Error, Params3};
use crate::dae::{Atol, consistent_init};
use crate::model::Restart;
use crate::model::history;

impl Cell3 {
    /// Whether at time `t` the contact carries the cell's current weight (gravity ramped
    /// and signed as at `t`; false while there is no downward load).
    pub fn contact_carries_weight(&self, t: f64, y: &[f64]) -> bool {
        let ph = &self.params.plane.phases;
        let load = self.weight() * ph.t_g(t) * ph.gravity_sign(t);
        load > 0.0 && self.contact_force_total(y).y >= load
    }

    /// The time the integration starts from: 0, or that of [`Cell3::set_initial`].
    pub fn initial_time(&self) -> f64 {
        self.initial_state.as_ref().map_or(0.0, |s| s.0)
    }

    /// The same cell without inertia, set to restart at time `t` from (`y`, `yp`), placed
    /// at rest in equilibrium: u̇ = 0 and u solved from F(u, u̇ = 0, A) = 0, the exposures
    /// kept with a consistent Ȧ (see `CellModel::without_inertia_at_rest` for why).
    pub fn without_inertia_at_rest(
        &self,
        t: f64,
        y: &[f64],
        yp: &[f64],
        restart: &Restart,
    ) -> Result<Cell3, Model3Error> {
        let (mut y2, mut yp2) = self.dofs.drop_inertia(y, yp);
        yp2[..self.dofs.n_u].iter_mut().for_each(|v| *v = 0.0);
        let mut params = self.params.clone();
        params.plane.inertia = false;
        let deferred = self.history.is_some();
        let mut m = Cell3::build(
            params,
            self.mesh.clone(),
            self.constraints,
            !deferred && self.params.plane.adhesion.is_some(),
        )?;
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
        .map_err(|source| Model3Error::Restart {
            what: "switching inertia off",
            t,
            source: Box::new(source),
        })?;
        if let Some(h) = &self.history {
            let (x, xdot) = m.membrane_motion(&y2, &yp2);
            m.history = Some(h.restarted(t, x, xdot).map_err(|e| Model3Error::Restart {
                what: "switching inertia off",
                t,
                source: Box::new(crate::dae::IntegratorError::Problem { t, message: e }),
            })?);
        }
        m.set_initial(t, y2, yp2);
        Ok(m)
    }

    /// The same cell with its exposure unknowns, set to restart at `t` (T_g0) from the
    /// state of this model, which defers them (see
    /// `crate::model::CellModel::with_adhesion_unknowns`).
    pub fn with_adhesion_unknowns(
        &self,
        t: f64,
        y: &[f64],
        yp: &[f64],
    ) -> Result<Cell3, Model3Error> {
        let restart_err = |e: String| Model3Error::Restart {
            what: "adding the adhesion unknowns",
            t,
            source: Box::new(crate::dae::IntegratorError::Problem { t, message: e }),
        };
        let h = self
            .history
            .as_ref()
            .ok_or_else(|| restart_err("the adhesion unknowns are already there".into()))?;
        let exposure = h.at(t).map_err(restart_err)?;
        let mut m =
            Cell3::with_constraints(self.params.clone(), self.mesh.clone(), self.constraints)?;
        let (mut y2, mut yp2) = (y.to_vec(), yp.to_vec());
        y2.extend_from_slice(&exposure);
        let ad = self
            .params
            .plane
            .adhesion
            .as_ref()
            .expect("deferred adhesion");
        for &i in &m.dofs.mu_nodes {
            let x = m.position(y, i);
            yp2.push(crate::physics::adhesion_rate3(&m.substrate, ad, &x, 0.0));
        }
        m.set_initial(t, y2, yp2);
        Ok(m)
    }

    /// The same system as this one now with the parameters `params` of another case that
    /// agrees with this one's up to `t`, set to restart at `t` from (`y`, `yp`).
    pub fn branched(
        &self,
        mut params: Params3,
        t: f64,
        y: &[f64],
        yp: &[f64],
    ) -> Result<Cell3, Model3Error> {
        params.plane.inertia = self.dofs.inertia;
        let refuse = |message: String| Model3Error::Restart {
            what: "branching",
            t,
            source: Box::new(crate::dae::IntegratorError::Problem { t, message }),
        };
        if params.plane.adhesion.is_some() != self.params.plane.adhesion.is_some() {
            return Err(refuse("one case has adhesion and the other not".into()));
        }
        let deferred = self.history.is_some();
        let mut m = Cell3::build(
            params,
            self.mesh.clone(),
            self.constraints,
            !deferred && self.params.plane.adhesion.is_some(),
        )?;
        if m.dofs.n != self.dofs.n || y.len() != m.dofs.n || yp.len() != m.dofs.n {
            return Err(refuse(format!(
                "the systems differ: {} unknowns against {}",
                m.dofs.n, self.dofs.n
            )));
        }
        if let Some(h) = &self.history {
            let (x, xdot) = m.membrane_motion(y, yp);
            m.history = Some(h.restarted(t, x, xdot).map_err(refuse)?);
        }
        m.set_initial(t, y.to_vec(), yp.to_vec());
        Ok(m)
    }

    /// μ_as = Φ(A) per mesh node at time `t` in state `y` (`None` off the membrane or
    /// without adhesion): the unknowns, or while deferred the history's values (`t`
    /// within the integrator's last step).
    pub fn nodal_mu_as(&self, t: f64, y: &[f64]) -> Result<Vec<Option<f64>>, String> {
        let n = self.mesh.nodes.len();
        let Some(ad) = &self.params.plane.adhesion else {
            return Ok(vec![None; n]);
        };
        let mu = |a: f64| history::cap(a, ad.mu_as_max).0;
        match &self.history {
            None => Ok((0..n)
                .map(|i| {
                    let d = self.dofs.mu[i];
                    (d != crate::fem::assembly::NONE).then(|| mu(y[d]))
                })
                .collect()),
            Some(h) => {
                let a = h.at(t)?;
                let mut out = vec![None; n];
                for (k, i) in self.membrane_nodes().into_iter().enumerate() {
                    out[i] = Some(mu(a[k]));
                }
                Ok(out)
            }
        }
    }
}
