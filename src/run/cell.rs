//! The model a run integrates, whatever its shape: the half cell ([`CellModel`]: plane
//! strain or axisymmetric) or the 3-D quarter cell ([`QuarterCell`]), both the one generic
//! [`CellOf`]. The driver, its changes of system and its outputs see it through
//! [`RunModel`]; only the output writers, which record each shape's mesh in its own files,
//! look at which it is ([`RunModel::view`]).

use crate::dae::{Dae, Inadmissible};
use crate::model::{
    CellModel, CellOf, ModelError, ModelParams, QuarterCell, Restart, Shape, State,
};
use crate::run_files::{Observables, QuarterObservables, StopPlace};

/// Which model a run integrates, for the writers of its mesh and states.
pub(crate) enum ModelView<'a> {
    /// The half-plane models.
    Plane(&'a CellModel),
    /// The 3-D quarter cell.
    Quarter(&'a QuarterCell),
}

/// What the driver asks of the model it integrates, besides the DAE itself.
pub(crate) trait RunModel: Dae + Send {
    /// Per-component absolute tolerances.
    fn atol_vector(&self, atol: f64) -> Vec<f64>;
    /// Whether the system has the velocity unknowns (inertia).
    fn inertia(&self) -> bool;
    /// Unknowns by block (u, v, μ_as), the μ_as integrated beside a deferring system
    /// counted.
    fn unknowns(&self) -> (usize, usize, usize);
    /// Elements and nodes of the mesh.
    fn mesh_size(&self) -> (usize, usize);
    /// Whether the μ_as unknowns are left out until T_g0.
    fn adhesion_deferred(&self) -> bool;
    /// The system with its μ_as unknowns added at the state `at`.
    fn with_adhesion_unknowns(&self, at: State<'_>) -> Result<Cell, ModelError>;
    /// Whether the contact carries the cell's current weight at `t`.
    fn contact_carries_weight(&self, t: f64, y: &[f64]) -> bool;
    /// The same cell without inertia, at rest in equilibrium at the time of `at`.
    fn without_inertia_at_rest(&self, at: State<'_>, restart: &Restart)
    -> Result<Cell, ModelError>;
    /// The same cell without inertia, restarting from (`y`, `yp`) in the new layout
    /// (nothing solved).
    fn without_inertia_from(&self, t: f64, y: Vec<f64>, yp: Vec<f64>) -> Result<Cell, ModelError>;
    /// A state of this system in the layout of the same system without inertia.
    fn drop_inertia(&self, y: &[f64], yp: &[f64]) -> (Vec<f64>, Vec<f64>);
    /// The same system with the parameters `params` of a case that agrees with this one's
    /// up to the time of `at`, restarting from the state `at`.
    fn branched(&self, params: ModelParams, at: State<'_>) -> Result<Cell, ModelError>;
    /// The time the integration starts from.
    fn initial_time(&self) -> f64;
    /// The watched conditions' root functions at `at` ([`crate::model::events`]).
    fn condition_values(&self, at: State<'_>, g: &mut [f64]);
    /// The scene's observables at `t`, and the 3-D ones for the 3-D model.
    fn observe(&self, t: f64, y: &[f64]) -> (Observables, Option<QuarterObservables>);
    /// The node that moved furthest in `y` and the length of its displacement \[µm\].
    fn largest_displacement(&self, y: &[f64]) -> (usize, f64);
    /// Which model this is, for the output writers.
    fn view(&self) -> ModelView<'_>;
    /// The element the last residual or Jacobian found inverted, as a stop's place.
    fn inadmissible_place(&self) -> Option<StopPlace>;
}

/// A run's model.
pub(crate) type Cell = Box<dyn RunModel>;

/// How each shape shows itself to the output writers.
pub(crate) trait Viewed {
    /// The view of this model.
    fn view_of(&self) -> ModelView<'_>;
}

impl Viewed for CellModel {
    fn view_of(&self) -> ModelView<'_> {
        ModelView::Plane(self)
    }
}

impl Viewed for QuarterCell {
    fn view_of(&self) -> ModelView<'_> {
        ModelView::Quarter(self)
    }
}

impl<S: Shape<D, N, E>, const D: usize, const N: usize, const E: usize> RunModel
    for CellOf<S, D, N, E>
where
    Self: Viewed + Send,
{
    fn atol_vector(&self, atol: f64) -> Vec<f64> {
        CellOf::atol_vector(self, atol)
    }

    fn inertia(&self) -> bool {
        self.dofs.inertia
    }

    fn unknowns(&self) -> (usize, usize, usize) {
        let (nu, nv, _) = self.block_sizes();
        (nu, nv, self.n_mu_as())
    }

    fn mesh_size(&self) -> (usize, usize) {
        use crate::fem::CellMesh;
        (self.mesh.elements().len(), self.mesh.nodes().len())
    }

    fn adhesion_deferred(&self) -> bool {
        CellOf::adhesion_deferred(self)
    }

    fn with_adhesion_unknowns(&self, at: State<'_>) -> Result<Cell, ModelError> {
        let State { t, y, yp } = at;
        Ok(Box::new(CellOf::with_adhesion_unknowns(self, t, y, yp)?))
    }

    fn contact_carries_weight(&self, t: f64, y: &[f64]) -> bool {
        CellOf::contact_carries_weight(self, t, y)
    }

    fn without_inertia_at_rest(
        &self,
        at: State<'_>,
        restart: &Restart,
    ) -> Result<Cell, ModelError> {
        let State { t, y, yp } = at;
        Ok(Box::new(CellOf::without_inertia_at_rest(
            self, t, y, yp, restart,
        )?))
    }

    fn without_inertia_from(&self, t: f64, y: Vec<f64>, yp: Vec<f64>) -> Result<Cell, ModelError> {
        Ok(Box::new(CellOf::without_inertia_from(self, t, y, yp)?))
    }

    fn drop_inertia(&self, y: &[f64], yp: &[f64]) -> (Vec<f64>, Vec<f64>) {
        CellOf::drop_inertia(self, y, yp)
    }

    fn branched(&self, params: ModelParams, at: State<'_>) -> Result<Cell, ModelError> {
        let State { t, y, yp } = at;
        Ok(Box::new(CellOf::branched(self, params, t, y, yp)?))
    }

    fn initial_time(&self) -> f64 {
        CellOf::initial_time(self)
    }

    fn condition_values(&self, at: State<'_>, g: &mut [f64]) {
        CellOf::condition_values(self, at, g)
    }

    fn observe(&self, t: f64, y: &[f64]) -> (Observables, Option<QuarterObservables>) {
        let obs3 = match self.view_of() {
            ModelView::Quarter(m) => Some(m.observe_quarter(y)),
            ModelView::Plane(_) => None,
        };
        (CellOf::observe(self, t, y), obs3)
    }

    fn largest_displacement(&self, y: &[f64]) -> (usize, f64) {
        self.dofs.largest_displacement(y)
    }

    fn view(&self) -> ModelView<'_> {
        self.view_of()
    }

    fn inadmissible_place(&self) -> Option<StopPlace> {
        let (why, domain, x) = self.last_inadmissible()?;
        let Inadmissible::Element {
            t,
            element,
            point,
            quantity,
            value,
        } = why
        else {
            return None;
        };
        Some(StopPlace {
            element: *element,
            domain: *domain,
            point: point.to_string(),
            quantity: quantity.to_string(),
            value: *value,
            t: *t,
            x: x.to_vec(),
        })
    }
}
