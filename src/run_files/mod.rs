//! The files a run writes, as types: the one place that says what is on disk.
//!
//! `cellsim run` writes, into its directory and as it goes: `mesh.json` ([`MeshFile`])
//! first, `timeseries.csv` row by row (one [`Observables`] per output time), a
//! `state_<phase>.json` ([`StateFile`]) at each phase end and `summary.json`
//! ([`Summary`], with [`SettingsUsed`], [`Unknowns`], the integrator statistics and, for a
//! run that stopped early, a typed [`Failure`]) after every row. The drivers (run, study,
//! paper) write these records and the figures read them back, so neither side imports the
//! other: this module sits below both. [`read`] loads a run directory back ([`RunData`]).

pub mod read;

pub use crate::model::observables::{
    Observables, QuarterMeshFile, QuarterObservables, QuarterSnapshot, Snapshot, SnapshotOf,
};
pub use read::{ReadError, RunData};

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::dae::Stats;
use crate::fem::Domain;
use crate::physics::{ActiveStrain, Substrate};
use crate::solver;

/// summary.json's `settings`: what the run integrated with, in one object: the solver
/// settings (the case's `solver` section, with the command line's flags applied to it)
/// and the run's own limits, both defined by [`crate::solver`]. Summaries of an older
/// cellsim read as well: their `dt` is `bdf2_dt`, their linear solver is named in kebab
/// case (`faer-condensed`, an alias of [`solver::LinearSolver`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(from = "SettingsOnDisk")]
pub struct SettingsUsed {
    /// The solver settings.
    #[serde(flatten)]
    pub solver: solver::Settings,
    /// The run's limits.
    #[serde(flatten)]
    pub limits: solver::Limits,
}

/// [`SettingsUsed`] as summaries of any cellsim write it.
#[derive(Deserialize)]
struct SettingsOnDisk {
    #[serde(flatten)]
    solver: solver::Settings,
    #[serde(flatten)]
    limits: solver::Limits,
    /// `bdf2_dt` as summaries before the settings had one type named it. (Not an alias
    /// of `bdf2_dt`: a case file's `solver` section has no `dt`.)
    #[serde(default)]
    dt: Option<f64>,
}

impl From<SettingsOnDisk> for SettingsUsed {
    fn from(d: SettingsOnDisk) -> Self {
        let mut solver = d.solver;
        if let Some(dt) = d.dt {
            solver.bdf2_dt = dt;
        }
        SettingsUsed {
            solver,
            limits: d.limits,
        }
    }
}

/// Unknown counts of the system.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Unknowns {
    /// All unknowns.
    pub total: usize,
    /// Displacements.
    pub u: usize,
    /// Velocities (0 without inertia).
    pub v: usize,
    /// Adhesion coefficients.
    pub mu_as: usize,
}

/// Why a run stopped early.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Failure {
    /// What kind of stop it was.
    #[serde(default)]
    pub kind: FailureKind,
    /// What happened.
    pub reason: String,
    /// Simulated time of the last output written \[s\].
    pub t_last_output: f64,
    /// Steps taken.
    pub step: u64,
    /// Simulated time the run reached: its last accepted step \[s\] (absent in summaries of
    /// an older cellsim).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub t_stop: Option<f64>,
    /// Where in the mesh, for a stop at an element ([`FailureKind::Inverted`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub place: Option<StopPlace>,
}

/// The element at which a run met a state it could not go past: the last evaluation of the
/// residual or the Jacobian before the integrator gave up found it not admissible there.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StopPlace {
    /// Index of the element in the mesh.
    pub element: usize,
    /// Its domain.
    pub domain: Domain,
    /// The point of the element ("quadrature point 3", "contact point 35").
    pub point: String,
    /// What was not positive there (`det F`, or the hoop stretch `1 + u_r/r`).
    pub quantity: String,
    /// Its value.
    pub value: f64,
    /// Time of that evaluation \[s\] (a trial state of the step that failed).
    pub t: f64,
    /// Centroid of the element's nodes in that state \[µm\].
    pub x: Vec<f64>,
}

/// The kind of an early stop, so that readers of a summary need not parse its reason.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FailureKind {
    /// The integration method failed (Newton, error test, linear solver, inadmissible
    /// state, the inertia switch).
    #[default]
    Integration,
    /// A signal asked the run to stop.
    Interrupted,
    /// The wall-clock budget was spent.
    Budget,
    /// More than `solver.max_steps` steps between two output times.
    StepLimit,
    /// The step size collapsed (the stall rule of `StepGuard`).
    Stalled,
    /// The integrator gave up on a state in which an element is inverted or flattened
    /// (det F ≤ 0 at one of its points, [`Failure::place`]): the last state it tried was
    /// not admissible there.
    Inverted,
    /// The state left the scene: a node moved further than the cell's diameter plus its
    /// height above the substrate's lowest point (nothing written at that time).
    Unphysical,
    /// An output could not be written.
    Output,
    /// A phase that starts on a condition of the cell's state (MODEL.md §11) had not
    /// started by the run's deadline (twice the case's end time).
    NoEvent,
}

impl FailureKind {
    /// Its name in `summary.json` (and a sweep's `stop_class`): serde's, snake case.
    pub fn name(self) -> String {
        match serde_json::to_value(self) {
            Ok(serde_json::Value::String(s)) => s,
            _ => format!("{self:?}"),
        }
    }

    /// Whether the run was stopped from outside (signal or budget) rather than by the
    /// method or the model.
    pub fn is_external(self) -> bool {
        matches!(self, FailureKind::Interrupted | FailureKind::Budget)
    }
}

/// `summary.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    /// Case name.
    pub case: String,
    /// Case file.
    pub case_file: String,
    /// Integration settings used.
    pub settings: SettingsUsed,
    /// Inertia mode of the case.
    pub inertia: String,
    /// Unknown counts (u and v of the system at the start; μ_as counted even while its
    /// unknowns are deferred).
    pub unknowns: Unknowns,
    /// Elements and nodes of the mesh.
    pub mesh_elements: usize,
    /// Nodes of the mesh.
    pub mesh_nodes: usize,
    /// Wall-clock seconds of the integration (mesh and set-up excluded; a stretch computed
    /// together with other cases, [`Self::shared`], counts in full).
    pub wall_seconds: f64,
    /// Wall-clock seconds of mesh generation and model set-up.
    pub setup_seconds: f64,
    /// Integrator statistics (summed over both systems when inertia is switched off).
    pub stats: Stats,
    /// Whether the run reached its end time.
    pub finished: bool,
    /// Why not, if it did not.
    pub failure: Option<Failure>,
    /// The last output row.
    pub final_values: Option<Observables>,
    /// The 3-D columns of the last output row (3-D runs).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub final_values_3d: Option<QuarterObservables>,
    /// The largest ‖E‖_F at a quadrature point of the nucleus at the last output (the
    /// largest nucleus strain; `final_values` holds its mean).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub strain_nucleus_max: Option<f64>,
    /// At the last output: the elements folded inside (det F ≤ 0 at a point of the band
    /// rule while the solid rule's points stay positive; docs/MODEL.md §5) and the smallest
    /// det F at the band points of the elements a sufficient test did not show unfolded
    /// throughout (null when it showed every element; summaries before 2026-12-07 15:30
    /// give the smallest over every element).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub folded_elements: Option<(usize, Option<f64>)>,
    /// Output rows written (including t = 0).
    pub outputs: usize,
    /// Time at which inertia was switched off, if it was.
    pub inertia_switched_off_at: Option<f64>,
    /// Time at which the μ_as unknowns joined the system (T_g0), if they were deferred
    /// (before it μ_as is integrated beside the system).
    #[serde(default)]
    pub adhesion_unknowns_added_at: Option<f64>,
    /// The phases this run's cell started itself (MODEL.md §11), in order; empty when
    /// every phase starts at a time.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub events: Vec<Event>,
    /// The run's phase lines when the cell started phases itself: the adhesion ramp's
    /// start, the active ramp's start and end, and the end time \[s\] (what `mesh.json`'s
    /// `phase_times`, written before the run, holds for a run on the paper's clock); null
    /// where not reached.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub phase_times: Option<[Option<f64>; 4]>,
    /// Where this run was computed together with other cases up to some time and parted
    /// from them (`cellsim paper`, [`crate::run::run_all`]); empty for a run on its own.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub shared: Vec<Parting>,
    /// State files written (phase ends).
    pub states: Vec<String>,
    /// cellsim version.
    pub cellsim_version: String,
    /// SUNDIALS version linked.
    pub sundials_version: String,
    /// Where the integration's wall time went (built with the `timers` feature only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub timers: Option<TimeBreakdown>,
}

/// A phase started by a condition on the cell's state (MODEL.md §11).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Event {
    /// The phase: `adhesion` or `active`.
    pub phase: String,
    /// The condition, as in the case (`Settled(1e-5)`, `SpreadingSlows(0.0001)`).
    pub condition: String,
    /// When it was armed \[s\], if it was.
    pub armed_at: Option<f64>,
    /// When it held and the phase started \[s\], if it did.
    pub t: Option<f64>,
    /// The phase's time in the paper's schedule (T_g0, T_as0) \[s\].
    pub paper_t: f64,
}

impl Summary {
    /// The starts of the adhesion and active phases: those the run's events record,
    /// `scheduled` (the case's times, `At`) for the others.
    pub fn phase_starts(&self, scheduled: [Option<f64>; 2]) -> [Option<f64>; 2] {
        let mut starts = scheduled;
        for e in &self.events {
            match e.phase.as_str() {
                "adhesion" => starts[0] = e.t,
                "active" => starts[1] = e.t,
                _ => {}
            }
        }
        starts
    }
}

/// A time where a run computed together with other cases parted from some of them: their
/// cases agree up to that time ([`crate::run::shared_until`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Parting {
    /// The time \[s\].
    pub t: f64,
    /// The cases it had been computed with and parted from there.
    pub from: Vec<String>,
    /// Whether its integrator restarted at `t` from the state there, with its own case's
    /// model (its results then agree with its own run's to the integrator's tolerance), or
    /// went on with the integrator it had (or the run ended at `t`). Up to its first
    /// restart a run is the same computation as its own run, bit for bit.
    pub restarted: bool,
}

/// Wall time of the integration split by what IDA (or BDF2) was doing: the callbacks it
/// made, its own work, and the rest of the run loop (outputs, inertia switch). Measured
/// by [`crate::dae::timing`] (cargo feature `timers`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TimeBreakdown {
    /// Integration wall time \[s\] (= `Summary::wall_seconds`).
    pub wall: f64,
    /// Residual evaluations called by IDA \[s\] and their number.
    pub residual: f64,
    pub residual_calls: u64,
    /// Jacobian assemblies \[s\] and their number.
    pub jacobian: f64,
    pub jacobian_calls: u64,
    /// Numeric LU factorizations \[s\] and their number.
    pub factorize: f64,
    pub factorize_calls: u64,
    /// Triangular solves \[s\] and their number.
    pub solve: f64,
    pub solve_calls: u64,
    /// IDA's own work: time inside IDASolve/IDACalcIC minus the callbacks above \[s\].
    pub ida_internal: f64,
    /// Outside IDA: outputs, observables, the inertia switch (with its consistent
    /// initialization) \[s\].
    pub outside: f64,
}

impl TimeBreakdown {
    /// From the timers' totals and the integration wall time.
    pub fn from_totals(t: &crate::dae::timing::Totals, wall: f64) -> Self {
        use crate::dae::timing::Phase;
        Self {
            wall,
            residual: t.get(Phase::Residual),
            residual_calls: t.count(Phase::Residual),
            jacobian: t.get(Phase::Jacobian),
            jacobian_calls: t.count(Phase::Jacobian),
            factorize: t.get(Phase::Factorize),
            factorize_calls: t.count(Phase::Factorize),
            solve: t.get(Phase::Solve),
            solve_calls: t.count(Phase::Solve),
            ida_internal: t.ida_internal(),
            outside: wall - t.get(Phase::Ida),
        }
    }

    /// A table of seconds and shares of the wall time.
    pub fn table(&self) -> String {
        let row = |name: &str, s: f64, calls: Option<u64>| {
            let c = calls
                .map(|c| format!("{c:>8}"))
                .unwrap_or_else(|| " ".repeat(8));
            format!(
                "  {name:<22} {s:>9.3} s {:>6.1} %  {c}\n",
                100.0 * s / self.wall
            )
        };
        let mut out = String::from("time breakdown (feature `timers`):\n");
        out += &row("residual", self.residual, Some(self.residual_calls));
        out += &row(
            "Jacobian assembly",
            self.jacobian,
            Some(self.jacobian_calls),
        );
        out += &row(
            "LU factorization",
            self.factorize,
            Some(self.factorize_calls),
        );
        out += &row("LU solve", self.solve, Some(self.solve_calls));
        out += &row("IDA internals", self.ida_internal, None);
        out += &row("outside IDA", self.outside, None);
        out += &row("total (wall)", self.wall, None);
        out
    }
}

/// What the mesh file records: enough to redraw the deformed cell from a state file.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct MeshFile {
    /// Reference node coordinates \[µm\].
    pub nodes: Vec<[f64; 2]>,
    /// Six-node elements.
    pub elements: Vec<[usize; 6]>,
    /// Domain of each element.
    pub domains: Vec<Domain>,
    /// Outer boundary edges (vertex, mid, vertex), bottom to top.
    pub outer_edges: Vec<[usize; 3]>,
    /// Nucleus interface edges.
    pub nucleus_edges: Vec<[usize; 3]>,
    /// Membrane inner interface edges.
    pub membrane_inner_edges: Vec<[usize; 3]>,
    /// The substrate.
    pub substrate: Substrate,
    /// Active strain regions, if any.
    pub active: Option<ActiveStrain>,
    /// Contact band half-width ε_ct \[µm\].
    pub contact_eps: f64,
    /// Fibronectin layer thickness e_f \[µm\], with adhesion.
    pub layer_thickness: Option<f64>,
    /// Cell centre \[µm\].
    pub center: [f64; 2],
    /// Phase end times T_g0, T_as0, T_a0 and the end time \[s\].
    pub phase_times: [f64; 4],
}

impl MeshFile {
    /// Reference area of the elements of domain `d` \[µm²\] (half cell): det J of each
    /// isoparametric P2 map integrated exactly (it is quadratic; a degree-2 rule is exact),
    /// the areas the run's reference-area means are weighted with.
    pub fn area(&self, d: Domain) -> f64 {
        use crate::fem::{P2Tabulation, TriangleRule, tri6 as p2};
        let tab = P2Tabulation::new(&TriangleRule::degree(2));
        self.elements
            .iter()
            .zip(&self.domains)
            .filter(|(_, dom)| **dom == d)
            .map(|(el, _)| {
                let x = el.map(|n| self.nodes[n]);
                (0..tab.weights.len())
                    .map(|q| p2::jacobian(&x, &tab.grads[q]).1 * tab.weights[q])
                    .sum::<f64>()
            })
            .sum()
    }
}

/// A state written at a phase end.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct StateFile {
    /// Phase name: "gravity", "spreading", "active" or "end".
    pub phase: String,
    /// Time \[s\].
    pub t: f64,
    /// Displacement of every node \[µm\].
    pub u: Vec<[f64; 2]>,
    /// μ_as per node [pN/µm³] (None off the membrane or without adhesion).
    pub mu_as: Vec<Option<f64>>,
    /// Per element: mean ‖E‖_F and mean det F.
    pub element_strain: Vec<f64>,
    /// Per element: mean det F.
    pub element_jacobian: Vec<f64>,
    /// The observables at this time.
    pub observables: Observables,
}

/// The state of one output time of either model ([`Snapshot`], [`QuarterSnapshot`]), as the
/// per-output-time writers see it.
pub trait Timed: Clone {
    /// Time \[s\].
    fn time(&self) -> f64;
}

impl<const D: usize> Timed for SnapshotOf<D> {
    fn time(&self) -> f64 {
        self.t
    }
}

/// A 3-D run's state file: the phase, its snapshot and the observables then.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct QuarterStateFile {
    /// Phase name: "gravity", "spreading", "active" or "end".
    pub phase: String,
    /// The state.
    pub state: QuarterSnapshot,
    /// The 2-D scene's observables (section z = 0).
    pub observables: Observables,
    /// The 3-D ones.
    pub observables3: QuarterObservables,
}

/// Writes `value` as pretty JSON to `path` through a temporary file and a rename, so that
/// a reader never sees half a file.
pub fn write_json<T: Serialize>(path: &Path, value: &T) -> std::io::Result<()> {
    let text = serde_json::to_string_pretty(value).map_err(std::io::Error::other)?;
    let tmp = path.with_extension("json.tmp");
    std::fs::write(&tmp, text)?;
    std::fs::rename(&tmp, path)
}

#[cfg(test)]
mod tests {
    use super::FailureKind;

    #[test]
    fn a_failure_kind_is_named_as_in_the_summary() {
        assert_eq!(FailureKind::StepLimit.name(), "step_limit");
        assert_eq!(FailureKind::Inverted.name(), "inverted");
    }
}
