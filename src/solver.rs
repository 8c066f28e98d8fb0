//! How a run integrates: the solver settings (the case's `solver` section, [`Settings`],
//! with its one set of defaults and its one range check), the sparse LU a user chooses
//! ([`LinearSolver`]) and its factory, the run's own limits ([`Limits`]) and the memory
//! estimate. Above the DAE layer (the [`crate::dae::linsolve::LinearSolver`] trait, faer's
//! LU, the condensed LU) and the FFI layer (KLU, UMFPACK), so that neither of those imports
//! the other's backends.

use serde::{Deserialize, Serialize};

use crate::dae::Dae;
use crate::dae::condensed::CondensedLu;
use crate::dae::linsolve::{
    self, ColumnOrdering, FaerLu, LinearSolverError, LinearSolverFactory, Permuted, SharedFactory,
};
use crate::dae::nonlinear::NonlinearMethod;

// ---------------------------------------------------------------------------------------
// The settings

/// Time integrator.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Integrator {
    /// SUNDIALS IDA: variable-order, variable-step BDF.
    #[serde(alias = "ida")]
    Ida,
    /// Fixed-step BDF2 (the paper's scheme), used to verify IDA.
    #[serde(alias = "bdf2")]
    Bdf2,
}

/// Loosest relative tolerance a run accepts (`solver.rtol`, `--rtol`, a study's rtols).
/// Looser, the error test controls no digit and lets nonsense pass: the fall of
/// `cases/fast/flat-gravity.ron` to 12 s ends 0.41 µm down at every rtol up to 0.2, and
/// 13 cm up at 0.5. The study's ladder starts at 1e-2.
pub const MAX_RTOL: f64 = 0.1;
/// Loosest absolute tolerance on displacements a run accepts \[µm\] (`solver.atol`,
/// `--atol`): a tenth of the contact band ε_ct = 0.1 µm. At atol 0.1 µm the fall above
/// stalled, at 1 µm it crossed into the substrate.
pub const MAX_ATOL: f64 = 0.01;

/// Time integration and linear algebra settings: the case's `solver` section
/// (`case::Solver`), which the command line's flags (`--rtol`, `--integrator`, ...)
/// override as `--set solver.<field>=<value>` does.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Settings {
    /// `Ida` or `Bdf2`. Default `Ida`.
    pub integrator: Integrator,
    /// Relative tolerance of the local error test (dimensionless). Default 1e-4.
    /// Valid: 0 < rtol ≤ 0.1 ([`MAX_RTOL`]).
    pub rtol: f64,
    /// Absolute tolerance on the displacement unknowns (µm). Default 1e-6 (a thousandth
    /// of the 3e-4 µm to which the paper's mesh converged, MODEL.md §9). Valid:
    /// 0 < atol ≤ 0.01 ([`MAX_ATOL`]).
    pub atol: f64,
    /// Time step of the fixed-step BDF2 integrator (s). Default 1. Valid: > 0. Unused by
    /// IDA.
    pub bdf2_dt: f64,
    /// Highest BDF order IDA may use. Default 5. Valid: 1 ≤ max_order ≤ 5.
    pub max_order: u32,
    /// Maximum number of internal steps between two output times (IDA's mxstep).
    /// Default 5000. Valid: ≥ 1.
    pub max_steps: u64,
    /// The sparse LU ([`LinearSolver`]): `Faer`, `Klu`, `FaerCondensed`, `KluMetis`,
    /// `Umfpack`, `UmfpackNd` or `UmfpackCondensed`. Default `FaerCondensed`: faer's LU with
    /// the velocities eliminated while inertia is on (0.75× the CPU time of `Faer` on the
    /// flat gravity phase), the same faer LU once inertia is off. faer is 1.3× faster than
    /// KLU on the fine mesh, 1.05× slower on the default one (whole runs,
    /// docs/benchmarks.md).
    pub linear_solver: LinearSolver,
    /// First step size tried by IDA (s). Default none (IDA's estimate). Valid: > 0.
    pub initial_step: Option<f64>,
    /// Leave the μ_as unknowns out of the system until adhesion can act (T_g0), and
    /// integrate μ_as beside it until then, along the accepted steps. Default true: before
    /// T_g0 the μ_as rows change nothing else but limit the steps (MODEL.md §8). `false`
    /// keeps them in the system from t = 0.
    pub defer_adhesion: bool,
    /// IDA re-forms and factorizes the Jacobian when its coefficient cj = α/h changed by
    /// more than this fraction since the last factorization (IDASetDeltaCjLSetup; the
    /// solution is rescaled by 2/(1 + cj/cj_old) in between). Default 0.25 (IDA's).
    /// Larger values keep a factorization across more step-size changes: worth it where a
    /// factorization costs many residuals (the 3-D cell). Valid: 0 < delta_cj < 1.
    pub delta_cj: f64,
    /// Most Newton iterations per IDA step (IDASetMaxNonlinIters). Default 4 (IDA's).
    /// Valid: 1 ≤ newton_iters ≤ 50.
    pub newton_iters: u32,
    /// Solve IDA's Newton systems by GMRES preconditioned by the last LU instead of by that
    /// LU alone: the factorization is kept across steps where plain Newton on it would fail
    /// (`Some(Krylov(max_dim: 5, eps_lin: 0.05))`). Default none. Unused by BDF2.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub krylov: Option<Krylov>,
    /// IDA's nonlinear iteration: none for SUNDIALS' Newton module (the default);
    /// `Some(Newton)` for ours, the same iterates, with every failed attempt counted by
    /// kind in summary.json (`newton_detail`); `Some(Broyden(max_updates: 10))` for ours
    /// with Broyden's updates of the kept matrix within each attempt. Valid:
    /// 1 ≤ max_updates ≤ 50. Unused by BDF2.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub nonlinear: Option<NonlinearMethod>,
    /// Compute the residual's and the Jacobian's element loops on rayon's thread pool
    /// (one thread per core; blocks of 64 elements, added in element order: the same bits
    /// either way). Default false: on the 2-D meshes the pool's synchronisation costs
    /// more than it saves (docs/benchmarks.md); the 3-D scenes turn it on.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub parallel_elements: bool,
}

/// GMRES (SUNDIALS' SPGMR) on IDA's Newton systems, `J v` by IDA's difference quotients of
/// the residual, preconditioned by the LU of the iteration matrix factorized at IDA's
/// preconditioner set-ups.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Krylov {
    /// Largest Krylov subspace (SPGMR's maxl). Default 5 (IDA's). Valid: 1 ≤ max_dim ≤ 100.
    pub max_dim: u32,
    /// Tolerance of the linear iterations as a fraction of the Newton tolerance
    /// (IDASetEpsLin). Default 0.05 (IDA's). Valid: 0 < eps_lin < 1.
    pub eps_lin: f64,
}

impl Default for Krylov {
    /// IDA's own defaults ([`crate::sundials::Krylov`]).
    fn default() -> Self {
        let ida = crate::sundials::Krylov::default();
        Krylov {
            max_dim: ida.max_dim.unsigned_abs(),
            eps_lin: ida.eps_lin,
        }
    }
}

impl Default for Settings {
    /// The one set of defaults: a case without a `solver` section, and every run that
    /// does not override a field, integrates with these.
    fn default() -> Self {
        Settings {
            integrator: Integrator::Ida,
            rtol: 1e-4,
            atol: 1e-6,
            bdf2_dt: 1.0,
            max_order: 5,
            max_steps: 5000,
            linear_solver: LinearSolver::FaerCondensed,
            initial_step: None,
            defer_adhesion: true,
            delta_cj: 0.25,
            newton_iters: 4,
            krylov: None,
            nonlinear: None,
            parallel_elements: false,
        }
    }
}

/// A setting outside its valid range.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{field} = {value} is out of range (must satisfy {range})")]
pub struct OutOfRange {
    /// The field's path in [`Settings`], e.g. `rtol`, `krylov.max_dim` (in a case it is
    /// under `solver.`).
    pub field: &'static str,
    /// Its value, formatted as the case's messages write numbers.
    pub value: String,
    /// The rule it breaks, e.g. `0 < rtol <= 0.1`.
    pub range: String,
}

impl Settings {
    /// The one range check of every field: each field outside its valid range (its
    /// documentation states it), in the order of the fields. Every source of a setting
    /// goes through it: the case file, `--set solver.<field>=`, the command line's flags
    /// (which are `--set` overrides), a sweep's axes.
    pub fn validate(&self) -> Result<(), Vec<OutOfRange>> {
        let mut c = Checks(Vec::new());
        c.real(
            "rtol",
            self.rtol,
            self.rtol > 0.0 && self.rtol <= MAX_RTOL,
            format!("0 < rtol <= {MAX_RTOL}"),
        );
        c.real(
            "atol",
            self.atol,
            self.atol > 0.0 && self.atol <= MAX_ATOL,
            format!("0 < atol <= {MAX_ATOL} µm"),
        );
        c.positive("bdf2_dt", self.bdf2_dt);
        c.integer("max_order", self.max_order.into(), 1, Some(5));
        c.integer("max_steps", self.max_steps, 1, None);
        c.real(
            "delta_cj",
            self.delta_cj,
            self.delta_cj > 0.0 && self.delta_cj < 1.0,
            "0 < delta_cj < 1",
        );
        c.integer("newton_iters", self.newton_iters.into(), 1, Some(50));
        if let Some(k) = &self.krylov {
            c.integer("krylov.max_dim", k.max_dim.into(), 1, Some(100));
            c.real(
                "krylov.eps_lin",
                k.eps_lin,
                k.eps_lin > 0.0 && k.eps_lin < 1.0,
                "0 < eps_lin < 1",
            );
        }
        if let Some(NonlinearMethod::Broyden { max_updates }) = self.nonlinear {
            c.integer("nonlinear.max_updates", max_updates as u64, 1, Some(50));
        }
        if let Some(h0) = self.initial_step {
            c.positive("initial_step", h0);
        }
        if c.0.is_empty() { Ok(()) } else { Err(c.0) }
    }
}

/// The fields found out of range, in order.
struct Checks(Vec<OutOfRange>);

impl Checks {
    /// Requires `ok` and a finite value; `range` states the rule.
    fn real(&mut self, field: &'static str, v: f64, ok: bool, range: impl Into<String>) {
        let range = range.into();
        let range = if !v.is_finite() {
            format!("{range}, and be finite")
        } else if !ok {
            range
        } else {
            return;
        };
        self.0.push(OutOfRange {
            field,
            value: num(v),
            range,
        });
    }

    fn positive(&mut self, field: &'static str, v: f64) {
        self.real(field, v, v > 0.0, format!("{} > 0", short(field)));
    }

    /// Requires lo ≤ v (≤ hi).
    fn integer(&mut self, field: &'static str, v: u64, lo: u64, hi: Option<u64>) {
        if v >= lo && hi.is_none_or(|hi| v <= hi) {
            return;
        }
        let range = match hi {
            Some(hi) => format!("{lo} <= {} <= {hi}", short(field)),
            None => format!("{} >= {lo}", short(field)),
        };
        self.0.push(OutOfRange {
            field,
            value: v.to_string(),
            range,
        });
    }
}

/// Last component of a dotted path, as a rule names it.
fn short(field: &str) -> &str {
    field.rsplit('.').next().unwrap_or(field)
}

/// Formats a number for a message: plain for ordinary magnitudes, scientific otherwise.
/// (Every range message of the case uses it.)
pub(crate) fn num(v: f64) -> String {
    let a = v.abs();
    if v == 0.0 || (1e-4..1e7).contains(&a) || !v.is_finite() {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// A run's own limits, which are not case fields: the command line (`--dt-inertia`,
/// `--max-wall`), a study or a sweep sets them. With [`Settings`], what a run integrates
/// with.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Limits {
    /// BDF2's step while the system has inertia (the fall, before inertia is switched
    /// off), when smaller than `bdf2_dt` \[s\]. A fixed step much longer than the fall cannot
    /// land the cell on the penalty contact (Newton diverges at contact onset), so a dt
    /// ladder over a whole scene caps the step of the fall. `None`: `bdf2_dt` throughout.
    #[serde(default)]
    pub dt_inertia: Option<f64>,
    /// Wall-clock budget of the integration \[s\]: past it the run stops cleanly, with
    /// its outputs so far and the reason in the summary. `None`: no limit.
    #[serde(default)]
    pub max_wall_seconds: Option<f64>,
}

// ---------------------------------------------------------------------------------------
// The sparse LU

/// METIS's nested dissection of A + Aᵀ as a column ordering of faer's LU.
pub const METIS_ORDERING: ColumnOrdering = ColumnOrdering::External {
    name: "faer-metis",
    order: crate::sundials::nested_dissection,
};

/// UMFPACK as the 3-D cell uses it: METIS's nested dissection of A + Aᵀ, the symmetric
/// strategy (diagonal pivots preferred), no iterative refinement.
fn nested_dissection_umfpack() -> crate::sundials::UmfpackLu {
    crate::sundials::UmfpackLu::new(crate::sundials::UmfpackOrdering::Metis)
        .with_symmetric_strategy(true)
        .without_refinement()
}

/// The sparse LU of the Newton systems. Case files (and summary.json) name it as the
/// variants are written (`FaerCondensed`); the command line's `--linear-solver` and the
/// summaries of an older cellsim in kebab case (`faer-condensed`), the aliases.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum LinearSolver {
    /// faer's sequential supernodal LU (pure Rust).
    #[serde(alias = "faer")]
    Faer,
    /// SUNDIALS' KLU (SuiteSparse) with AMD ordering.
    #[serde(alias = "klu")]
    Klu,
    /// faer's LU on the half-size system left after eliminating the velocities of a
    /// first-order (u, v) system ([`CondensedLu`]) while inertia is on; the full-size faer
    /// LU once inertia is off. Needs a problem with [`Dae::first_order_blocks`] (the cell
    /// model with inertia).
    #[serde(alias = "faer-condensed")]
    FaerCondensed,
    /// KLU (natural ordering) on the matrix permuted by METIS's nested dissection of
    /// A + Aᵀ: the least fill of the measured orderings (docs/benchmarks.md).
    #[serde(alias = "klu-metis")]
    KluMetis,
    /// SuiteSparse's UMFPACK (multifrontal; symmetric strategy, AMD ordering).
    #[serde(alias = "umfpack")]
    Umfpack,
    /// UMFPACK on METIS's nested dissection of A + Aᵀ with its symmetric strategy
    /// (diagonal pivots preferred), without iterative refinement (a solve is one pair of
    /// substitutions; the Newton iteration corrects what it leaves): the LU of the 3-D
    /// cell, where it has half the fill of UMFPACK's default and factorizes 1.9× faster
    /// (docs/benchmarks.md).
    #[serde(alias = "umfpack-nd")]
    UmfpackNd,
    /// [`Self::UmfpackNd`] on the condensed system while inertia is on (as
    /// `FaerCondensed`), on the full system after: the faster LU on the 3-D cell's
    /// Jacobians (docs/benchmarks.md).
    #[serde(alias = "umfpack-condensed")]
    UmfpackCondensed,
}

impl LinearSolver {
    /// A fresh solver of this kind for a problem described by its pattern alone. The
    /// condensed kind needs the problem's block layout ([`Self::build_for`]); built here it
    /// reports [`LinearSolverError::Unsupported`] from `analyse`.
    pub fn build(self) -> Box<dyn linsolve::LinearSolver> {
        match self {
            LinearSolver::Faer => Box::new(FaerLu::new()),
            LinearSolver::Klu => Box::new(crate::sundials::KluLu::new()),
            LinearSolver::KluMetis => Box::new(Permuted::new(
                "klu-metis",
                crate::sundials::nested_dissection,
                Box::new(crate::sundials::KluLu::natural()),
            )),
            LinearSolver::Umfpack => Box::new(crate::sundials::UmfpackLu::new(
                crate::sundials::UmfpackOrdering::Amd,
            )),
            LinearSolver::UmfpackNd => Box::new(nested_dissection_umfpack()),
            LinearSolver::FaerCondensed | LinearSolver::UmfpackCondensed => {
                Box::new(CondensedLu::unconfigured())
            }
        }
    }

    /// A fresh solver of this kind for `dae`. Fails with
    /// [`LinearSolverError::Unsupported`] when the condensed kind is asked for a problem
    /// without first-order (u, v) pairs (e.g. the cell model without inertia; see
    /// [`Self::uncondensed`]).
    pub fn build_for<D: Dae + ?Sized>(
        self,
        dae: &D,
    ) -> Result<Box<dyn linsolve::LinearSolver>, LinearSolverError> {
        match self {
            LinearSolver::FaerCondensed | LinearSolver::UmfpackCondensed => {
                match dae.first_order_blocks() {
                    Some(blocks) if self == LinearSolver::FaerCondensed => {
                        Ok(Box::new(CondensedLu::new(blocks)))
                    }
                    Some(blocks) => Ok(Box::new(CondensedLu::with_inner(
                        blocks,
                        Box::new(nested_dissection_umfpack()),
                    ))),
                    None => {
                        let (name, instead) = if self == LinearSolver::FaerCondensed {
                            ("faer-condensed", "faer or klu")
                        } else {
                            ("umfpack-condensed", "umfpack-nd")
                        };
                        Err(LinearSolverError::Unsupported(format!(
                            "the condensed solver ({name}) needs a first-order (u, v) system, \
                             and this problem has no velocity unknowns (inertia off?): use \
                             {instead}"
                        )))
                    }
                }
            }
            other => Ok(other.build()),
        }
    }

    /// The kind to use on a problem without (u, v) pairs: `Faer` for the condensed
    /// kind (its LU on the full system), the kind itself otherwise.
    pub fn uncondensed(self) -> Self {
        match self {
            LinearSolver::FaerCondensed => LinearSolver::Faer,
            LinearSolver::UmfpackCondensed => LinearSolver::UmfpackNd,
            other => other,
        }
    }
}

impl LinearSolverFactory for LinearSolver {
    fn build_for(
        &self,
        dae: &dyn Dae,
    ) -> Result<Box<dyn linsolve::LinearSolver>, LinearSolverError> {
        LinearSolver::build_for(*self, dae)
    }
}

impl From<LinearSolver> for SharedFactory {
    fn from(kind: LinearSolver) -> Self {
        std::sync::Arc::new(kind)
    }
}

// ---------------------------------------------------------------------------------------
// The memory estimate

/// The memory a run is allowed: `CELLSIM_MEMORY_GB` if set, else 90 % of the smaller of
/// the machine's memory (`MemTotal` of /proc/meminfo) and the process's control group
/// limit (a Slurm job's `--mem`, cgroup v2's memory.max); `None` where neither can be read.
#[derive(Debug, Clone, PartialEq)]
pub struct MemoryLimit {
    /// Bytes.
    pub bytes: f64,
    /// Where the limit comes from, for messages.
    pub source: String,
}

/// A `CELLSIM_MEMORY_GB` that is not a positive number.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{MEMORY_ENV} = {value:?} is not a positive number of GB (1e9 bytes)")]
pub struct BadMemoryLimit {
    /// The variable's value.
    pub value: String,
}

/// The environment variable that sets [`MemoryLimit`] [GB, 1e9 bytes].
pub const MEMORY_ENV: &str = "CELLSIM_MEMORY_GB";

impl MemoryLimit {
    /// The limit of this process (see the type's documentation); an unreadable
    /// `CELLSIM_MEMORY_GB` is an error naming it.
    pub fn of_this_process() -> Result<Option<Self>, BadMemoryLimit> {
        if let Ok(v) = std::env::var(MEMORY_ENV) {
            return match v.trim().parse::<f64>() {
                Ok(gb) if gb.is_finite() && gb > 0.0 => Ok(Some(MemoryLimit {
                    bytes: gb * 1e9,
                    source: format!("{MEMORY_ENV} = {}", v.trim()),
                })),
                _ => Err(BadMemoryLimit { value: v }),
            };
        }
        let machine = std::fs::read_to_string("/proc/meminfo").ok().and_then(|s| {
            s.lines()
                .find_map(|l| l.strip_prefix("MemTotal:"))
                .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<f64>().ok())
                .map(|kb| kb * 1024.0)
        });
        let group = std::fs::read_to_string("/sys/fs/cgroup/memory.max")
            .ok()
            .and_then(|s| s.trim().parse::<f64>().ok());
        let (bytes, what) = match (machine, group) {
            (Some(m), Some(g)) if g < m => (g, "its control group's memory.max"),
            (Some(m), _) => (m, "this machine's memory"),
            (None, Some(g)) => (g, "its control group's memory.max"),
            (None, None) => return Ok(None),
        };
        Ok(Some(MemoryLimit {
            bytes: 0.9 * bytes,
            source: format!(
                "90 % of {what}, {:.1} GB; {MEMORY_ENV} sets another limit",
                bytes / 1e9
            ),
        }))
    }
}

/// Peak memory \[bytes\] of a run of the cell on a mesh of `elements` elements (as
/// estimated before meshing) in `dim` dimensions (2: six-node triangles, plane strain or
/// axisymmetric; 3: ten-node tetrahedra) with the scenes' LUs (faer-condensed in 2-D,
/// umfpack-condensed in 3-D): the model, its Jacobian and the LU's factors, with inertia and
/// the μ_as unknowns.
///
/// In 2-D fitted to the peak resident set of `cellsim run cases/pillars-push-pull.ron --set
/// phases.t_end=0.5 --set solver.defer_adhesion=false --set mesh.refine=R` at R = 4 and 8
/// (9 099 and 36 263 triangles: 0.53 and 2.41 GB, growing as elements^1.1; 2026-12-02).
/// In 3-D through the peaks of whole push-pull runs, the quarter cell
/// ([`through_anchors`]): the 3-D maps' configuration (`cases/sweeps/pillar-geometry-3d.ron`,
/// about 3 100 tetrahedra estimated: 0.80–0.86 GB, 2026-12-07/08), the default mesh
/// (about 9 900: 2.63 GB) and refined ×1.5 (about 29 500: 5.41 GB); beyond, as the LU's
/// factors alone grow (`cargo run --release --example cell3d -- --case
/// cases/3d/pillars-push-pull.ron --t-end 1 --drag 1e-6 --lu-memory` at refine 1, 1.5, 2:
/// 1.38, 4.57 and 12.1 GB, as tetrahedra^1.25, the nested-dissection fill). Until
/// 2026-12-08 the 3-D estimate was that LU law alone, times 1.2: about half the peak of the
/// maps' points and of the default mesh (0.41 and 1.6 GB), and a Slurm task's request
/// (× 1.5 + 200 MB) below the maps' points' peak.
pub fn estimated_run_memory(dim: usize, elements: f64) -> f64 {
    if dim == 3 {
        through_anchors(
            &[(3_102.0, 0.86e9), (9_884.0, 2.63e9), (29_538.0, 5.41e9)],
            1.25,
            elements,
        )
    } else {
        23_300.0 * elements.powf(1.1)
    }
}

/// A cost measured at a few mesh sizes (`anchors`: elements estimated before meshing, and
/// the cost; increasing in both), interpolated linearly in log-log between them; below the
/// first, the first segment's growth, beyond the last as elements^`beyond`.
pub fn through_anchors(anchors: &[(f64, f64)], beyond: f64, elements: f64) -> f64 {
    let slope = |(n0, c0): (f64, f64), (n1, c1): (f64, f64)| (c1 / c0).ln() / (n1 / n0).ln();
    let last = anchors[anchors.len() - 1];
    // The segment that holds `elements` (the first one below it, which extends it).
    match anchors.windows(2).find(|w| elements < w[1].0) {
        Some(w) => w[0].1 * (elements / w[0].0).powf(slope(w[0], w[1])),
        None => last.1 * (elements / last.0).powf(beyond),
    }
}

/// Shares the cores among `jobs` runs side by side: OpenBLAS (UMFPACK's BLAS, the 3-D
/// runs') gets [`blas_threads`] threads. Returns the threads OpenBLAS reports, if it is the
/// BLAS loaded and the user did not choose its threads.
///
/// Two 3-D runs side by side on two cores with OpenBLAS's default two threads each took
/// 1.4× the wall time of one thread each (docs/benchmarks.md, 2026-12-08: the idle threads
/// spin, 82–94 s of system time a run against 19 s).
pub fn share_cores_among(jobs: usize) -> Option<usize> {
    let chosen = std::env::var_os("OPENBLAS_NUM_THREADS").is_some()
        || std::env::var_os("OMP_NUM_THREADS").is_some();
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    crate::sundials::set_openblas_threads(blas_threads(jobs, cores, chosen)?)
}

/// OpenBLAS's threads for `jobs` runs side by side on `cores` cores: cores / jobs, at least
/// one; none set where the user chose them (`chosen`).
fn blas_threads(jobs: usize, cores: usize, chosen: bool) -> Option<usize> {
    (!chosen).then(|| (cores / jobs.max(1)).max(1))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The anchored cost law passes through its anchors, is continuous and increasing
    /// between and around them, and grows beyond the last as asked.
    #[test]
    fn the_anchored_cost_law_passes_through_its_anchors() {
        let a = [(100.0, 1.0), (400.0, 2.0), (1_600.0, 16.0)];
        for &(n, c) in &a {
            assert!((through_anchors(&a, 1.5, n) / c - 1.0).abs() < 1e-12, "{n}");
        }
        // Below the first: the first segment's growth (a factor 2 per factor 4).
        assert!((through_anchors(&a, 1.5, 25.0) - 0.5).abs() < 1e-12);
        // Between: log-log linear (the geometric mean of the ends at the middle).
        assert!((through_anchors(&a, 1.5, 800.0) - (2.0f64 * 16.0).sqrt()).abs() < 1e-12);
        // Beyond: elements^1.5.
        assert!((through_anchors(&a, 1.5, 6_400.0) - 16.0 * 8.0).abs() < 1e-9);
        let mut last = 0.0;
        for k in 1..400 {
            let c = through_anchors(&a, 1.5, 10.0 * f64::from(k));
            assert!(c > last);
            last = c;
        }
    }

    /// OpenBLAS (the BLAS the Makefile installs behind UMFPACK) is found in the process and
    /// takes the threads it is given: two where there are two cores, then one again (what
    /// `make test` runs with).
    #[test]
    fn openblas_is_loaded_and_takes_the_threads_it_is_given() {
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        let two = crate::sundials::set_openblas_threads(2);
        let one = crate::sundials::set_openblas_threads(1);
        assert_eq!(
            one,
            Some(1),
            "OpenBLAS not loaded (libblas.so.3 should be libopenblas0-pthread's)"
        );
        // Two, or the cores where OpenBLAS keeps to them (a one-core machine).
        assert!(
            matches!(two, Some(n) if n == 2 || n == cores),
            "{two:?} on {cores} cores"
        );
    }

    /// The cores shared among runs side by side: one thread each where the runs fill the
    /// cores, the rest divided, all of them to a single run, none where the user chose.
    #[test]
    fn blas_threads_share_the_cores_among_the_runs() {
        assert_eq!(blas_threads(2, 2, false), Some(1));
        assert_eq!(blas_threads(3, 2, false), Some(1));
        assert_eq!(blas_threads(2, 8, false), Some(4));
        assert_eq!(blas_threads(1, 2, false), Some(2));
        assert_eq!(blas_threads(2, 2, true), None);
    }

    const ALL: [LinearSolver; 7] = [
        LinearSolver::Faer,
        LinearSolver::Klu,
        LinearSolver::FaerCondensed,
        LinearSolver::KluMetis,
        LinearSolver::Umfpack,
        LinearSolver::UmfpackNd,
        LinearSolver::UmfpackCondensed,
    ];

    /// Each LU reads from the name a case file writes and from its kebab-case alias (the
    /// command line's, and older summaries'), and writes the case file's name.
    #[test]
    fn every_linear_solver_reads_its_case_name_and_its_kebab_alias() {
        let kebab = [
            "faer",
            "klu",
            "faer-condensed",
            "klu-metis",
            "umfpack",
            "umfpack-nd",
            "umfpack-condensed",
        ];
        for (kind, alias) in ALL.into_iter().zip(kebab) {
            let name = format!("{kind:?}");
            assert_eq!(serde_json::to_string(&kind).unwrap(), format!("\"{name}\""));
            for text in [name.as_str(), alias] {
                let read: LinearSolver = serde_json::from_value(text.into()).unwrap();
                assert_eq!(read, kind, "{text}");
            }
            let ron: LinearSolver = ron::from_str(&name).unwrap();
            assert_eq!(ron, kind);
        }
    }

    /// The defaults pass the check; each field out of range is named with its value and
    /// its range, in the order of the fields.
    #[test]
    fn validate_names_each_field_its_value_and_its_range() {
        assert_eq!(Settings::default().validate(), Ok(()));
        let s = Settings {
            rtol: 0.5,
            atol: f64::NAN,
            bdf2_dt: 0.0,
            max_order: 6,
            max_steps: 0,
            delta_cj: 1.0,
            newton_iters: 0,
            krylov: Some(Krylov {
                max_dim: 0,
                eps_lin: 2.0,
            }),
            nonlinear: Some(NonlinearMethod::Broyden { max_updates: 51 }),
            initial_step: Some(-1e-9),
            ..Settings::default()
        };
        let found: Vec<String> = s
            .validate()
            .unwrap_err()
            .iter()
            .map(ToString::to_string)
            .collect();
        assert_eq!(
            found,
            [
                "rtol = 0.5 is out of range (must satisfy 0 < rtol <= 0.1)",
                "atol = NaN is out of range (must satisfy 0 < atol <= 0.01 µm, and be finite)",
                "bdf2_dt = 0 is out of range (must satisfy bdf2_dt > 0)",
                "max_order = 6 is out of range (must satisfy 1 <= max_order <= 5)",
                "max_steps = 0 is out of range (must satisfy max_steps >= 1)",
                "delta_cj = 1 is out of range (must satisfy 0 < delta_cj < 1)",
                "newton_iters = 0 is out of range (must satisfy 1 <= newton_iters <= 50)",
                "krylov.max_dim = 0 is out of range (must satisfy 1 <= max_dim <= 100)",
                "krylov.eps_lin = 2 is out of range (must satisfy 0 < eps_lin < 1)",
                "nonlinear.max_updates = 51 is out of range (must satisfy 1 <= max_updates <= 50)",
                "initial_step = -1e-9 is out of range (must satisfy initial_step > 0)",
            ]
        );
    }
}
