//! The model a run integrates: a half-plane cell ([`CellModel`]: plane strain or
//! axisymmetric) or the 3-D quarter cell ([`Cell3`]). The driver, its inertia switch and
//! its outputs see this one type; each call goes to the model the case asked for.

use crate::case::Case;
use crate::dae::{Dae, DaeError, FirstOrderBlocks, Pattern};
use crate::model::{CellModel, Restart};
use crate::model3d::Cell3;
use crate::record::{Observables, Observables3};
use crate::scene;

/// A run's model.
pub(crate) enum Cell {
    /// The half-plane models.
    Plane(Box<CellModel>),
    /// The 3-D quarter cell.
    Quarter(Box<Cell3>),
}

impl Cell {
    /// Per-component absolute tolerances.
    pub(crate) fn atol_vector(&self, atol: f64) -> Vec<f64> {
        match self {
            Cell::Plane(m) => m.atol_vector(atol),
            Cell::Quarter(m) => m.atol_vector(atol),
        }
    }

    /// Whether the system has the velocity unknowns (inertia).
    pub(crate) fn inertia(&self) -> bool {
        match self {
            Cell::Plane(m) => m.dofs.inertia,
            Cell::Quarter(m) => m.dofs.inertia,
        }
    }

    /// The node that moved furthest in `y` and the length of its displacement [µm].
    pub(crate) fn largest_displacement(&self, y: &[f64]) -> (usize, f64) {
        match self {
            Cell::Plane(m) => m.dofs.largest_displacement(y),
            Cell::Quarter(m) => m.dofs.largest_displacement(y),
        }
    }

    /// Number of unknowns.
    pub(crate) fn n(&self) -> usize {
        match self {
            Cell::Plane(m) => m.dofs.n,
            Cell::Quarter(m) => m.dofs.n,
        }
    }

    /// Unknowns by block (u, v, μ_as), the μ_as integrated beside a deferring system
    /// counted.
    pub(crate) fn unknowns(&self) -> (usize, usize, usize) {
        match self {
            Cell::Plane(m) => {
                let (nu, nv, _) = m.block_sizes();
                (nu, nv, m.n_mu_as())
            }
            Cell::Quarter(m) => {
                let nv = if m.dofs.inertia { m.dofs.n_u } else { 0 };
                (m.dofs.n_u, nv, m.n_mu_as())
            }
        }
    }

    /// Elements and nodes of the mesh.
    pub(crate) fn mesh_size(&self) -> (usize, usize) {
        match self {
            Cell::Plane(m) => (m.mesh.elements.len(), m.mesh.nodes.len()),
            Cell::Quarter(m) => (m.mesh.elements.len(), m.mesh.nodes.len()),
        }
    }

    /// Whether the μ_as unknowns are left out until T_g0.
    pub(crate) fn adhesion_deferred(&self) -> bool {
        match self {
            Cell::Plane(m) => m.adhesion_deferred(),
            Cell::Quarter(m) => m.adhesion_deferred(),
        }
    }

    /// The system with its μ_as unknowns added at `t` (see
    /// [`CellModel::with_adhesion_unknowns`]).
    pub(crate) fn with_adhesion_unknowns(
        &self,
        t: f64,
        y: &[f64],
        yp: &[f64],
    ) -> Result<Cell, String> {
        match self {
            Cell::Plane(m) => m
                .with_adhesion_unknowns(t, y, yp)
                .map(|m| Cell::Plane(Box::new(m)))
                .map_err(|e| e.to_string()),
            Cell::Quarter(m) => m
                .with_adhesion_unknowns(t, y, yp)
                .map(|m| Cell::Quarter(Box::new(m)))
                .map_err(|e| e.to_string()),
        }
    }

    /// Whether the contact carries the cell's current weight at `t`.
    pub(crate) fn contact_carries_weight(&self, t: f64, y: &[f64]) -> bool {
        match self {
            Cell::Plane(m) => m.contact_carries_weight(t, y),
            Cell::Quarter(m) => m.contact_carries_weight(t, y),
        }
    }

    /// The same cell without inertia, at rest in equilibrium at `t`.
    pub(crate) fn without_inertia_at_rest(
        &self,
        t: f64,
        y: &[f64],
        yp: &[f64],
        restart: &Restart,
    ) -> Result<Cell, String> {
        match self {
            Cell::Plane(m) => m
                .without_inertia_at_rest(t, y, yp, restart)
                .map(|m| Cell::Plane(Box::new(m)))
                .map_err(|e| e.to_string()),
            Cell::Quarter(m) => m
                .without_inertia_at_rest(t, y, yp, restart)
                .map(|m| Cell::Quarter(Box::new(m)))
                .map_err(|e| e.to_string()),
        }
    }

    /// The same system with the parameters of `case` (which agrees with this one's up
    /// to `t`), restarting at `t` from (`y`, `yp`).
    pub(crate) fn branched(
        &self,
        case: &Case,
        file: &str,
        t: f64,
        y: &[f64],
        yp: &[f64],
    ) -> Result<Cell, String> {
        let inertia = self.inertia();
        match self {
            Cell::Plane(m) => scene::model_params(case, file, inertia)
                .map_err(|e| e.to_string())
                .and_then(|p| m.branched(p, t, y, yp).map_err(|e| e.to_string()))
                .map(|m| Cell::Plane(Box::new(m))),
            Cell::Quarter(m) => scene::params3(case, file, inertia)
                .map_err(|e| e.to_string())
                .and_then(|p| m.branched(p, t, y, yp).map_err(|e| e.to_string()))
                .map(|m| Cell::Quarter(Box::new(m))),
        }
    }

    /// The time the integration starts from.
    pub(crate) fn initial_time(&self) -> f64 {
        match self {
            Cell::Plane(m) => m.initial_time(),
            Cell::Quarter(m) => m.initial_time(),
        }
    }

    /// The scene's observables at `t`, and the 3-D ones for the 3-D model.
    pub(crate) fn observe(&self, t: f64, y: &[f64]) -> (Observables, Option<Observables3>) {
        match self {
            Cell::Plane(m) => (m.observe(t, y), None),
            Cell::Quarter(m) => (m.observe(t, y), Some(m.observe3(y))),
        }
    }
}

impl Dae for Cell {
    fn size(&self) -> usize {
        match self {
            Cell::Plane(m) => m.size(),
            Cell::Quarter(m) => m.size(),
        }
    }

    fn residual(&mut self, t: f64, y: &[f64], yp: &[f64], r: &mut [f64]) -> Result<(), DaeError> {
        match self {
            Cell::Plane(m) => m.residual(t, y, yp, r),
            Cell::Quarter(m) => m.residual(t, y, yp, r),
        }
    }

    fn pattern(&self) -> &Pattern {
        match self {
            Cell::Plane(m) => m.pattern(),
            Cell::Quarter(m) => m.pattern(),
        }
    }

    fn jacobian(
        &mut self,
        t: f64,
        y: &[f64],
        yp: &[f64],
        cj: f64,
        v: &mut [f64],
    ) -> Result<(), DaeError> {
        match self {
            Cell::Plane(m) => m.jacobian(t, y, yp, cj, v),
            Cell::Quarter(m) => m.jacobian(t, y, yp, cj, v),
        }
    }

    fn differential(&self) -> Vec<bool> {
        match self {
            Cell::Plane(m) => m.differential(),
            Cell::Quarter(m) => m.differential(),
        }
    }

    fn initial(&self) -> (f64, Vec<f64>, Vec<f64>) {
        match self {
            Cell::Plane(m) => m.initial(),
            Cell::Quarter(m) => m.initial(),
        }
    }

    fn first_order_blocks(&self) -> Option<FirstOrderBlocks> {
        match self {
            Cell::Plane(m) => m.first_order_blocks(),
            Cell::Quarter(m) => m.first_order_blocks(),
        }
    }

    fn accepted_step(&mut self, t: f64, y: &[f64], yp: &[f64]) {
        match self {
            Cell::Plane(m) => m.accepted_step(t, y, yp),
            Cell::Quarter(m) => m.accepted_step(t, y, yp),
        }
    }

    fn breakpoints(&self) -> Vec<f64> {
        match self {
            Cell::Plane(m) => m.breakpoints(),
            Cell::Quarter(m) => m.breakpoints(),
        }
    }
}
