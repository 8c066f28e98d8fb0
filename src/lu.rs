//! The sparse LUs a user can choose, and how each is built: above the DAE layer (the
//! [`LinearSolver`] trait, faer's LU, the condensed LU) and the FFI layer (KLU), so that
//! neither of those imports the other's backends.

use serde::{Deserialize, Serialize};

use crate::dae::Dae;
use crate::dae::condensed::CondensedLu;
use crate::dae::linsolve::{
    ColumnOrdering, FaerLu, LinearSolver, LinearSolverError, LinearSolverFactory, Permuted,
    SharedFactory,
};

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

/// Which sparse LU to use.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LinearSolverKind {
    /// faer's sequential supernodal LU (default).
    #[default]
    Faer,
    /// SUNDIALS' KLU (SuiteSparse) with AMD ordering.
    Klu,
    /// faer's LU on the condensed system: the velocities of a first-order (u, v) system
    /// eliminated ([`CondensedLu`]). Needs a problem with [`Dae::first_order_blocks`]
    /// (the cell model with inertia).
    #[serde(rename = "faer-condensed")]
    FaerCondensed,
    /// KLU (natural ordering) on the matrix permuted by METIS's nested dissection of
    /// A + Aᵀ: the least fill of the measured orderings (docs/benchmarks.md).
    #[serde(rename = "klu-metis")]
    KluMetis,
    /// SuiteSparse's UMFPACK (multifrontal; symmetric strategy, AMD ordering).
    Umfpack,
    /// UMFPACK on METIS's nested dissection of A + Aᵀ with its symmetric strategy
    /// (diagonal pivots preferred), without iterative refinement (a solve is one pair of
    /// substitutions; the Newton iteration corrects what it leaves): the LU of the 3-D
    /// cell, where it has half the fill of UMFPACK's default and factorizes 1.9× faster
    /// (docs/benchmarks.md).
    #[serde(rename = "umfpack-nd")]
    UmfpackNd,
    /// [`Self::UmfpackNd`] on the condensed system while inertia is on (as
    /// `faer-condensed`), on the full system after.
    #[serde(rename = "umfpack-condensed")]
    UmfpackCondensed,
}

impl LinearSolverKind {
    /// A fresh solver of this kind for a problem described by its pattern alone. The
    /// condensed kind needs the problem's block layout ([`Self::build_for`]); built here it
    /// reports [`LinearSolverError::Unsupported`] from `analyse`.
    pub fn build(self) -> Box<dyn LinearSolver> {
        match self {
            LinearSolverKind::Faer => Box::new(FaerLu::new()),
            LinearSolverKind::Klu => Box::new(crate::sundials::KluLu::new()),
            LinearSolverKind::KluMetis => Box::new(Permuted::new(
                "klu-metis",
                crate::sundials::nested_dissection,
                Box::new(crate::sundials::KluLu::natural()),
            )),
            LinearSolverKind::Umfpack => Box::new(crate::sundials::UmfpackLu::new(
                crate::sundials::UmfpackOrdering::Amd,
            )),
            LinearSolverKind::UmfpackNd => Box::new(nested_dissection_umfpack()),
            LinearSolverKind::FaerCondensed | LinearSolverKind::UmfpackCondensed => {
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
    ) -> Result<Box<dyn LinearSolver>, LinearSolverError> {
        match self {
            LinearSolverKind::FaerCondensed | LinearSolverKind::UmfpackCondensed => {
                match dae.first_order_blocks() {
                    Some(blocks) if self == LinearSolverKind::FaerCondensed => {
                        Ok(Box::new(CondensedLu::new(blocks)))
                    }
                    Some(blocks) => Ok(Box::new(CondensedLu::with_inner(
                        blocks,
                        Box::new(nested_dissection_umfpack()),
                    ))),
                    None => {
                        let (name, instead) = if self == LinearSolverKind::FaerCondensed {
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
            LinearSolverKind::FaerCondensed => LinearSolverKind::Faer,
            LinearSolverKind::UmfpackCondensed => LinearSolverKind::UmfpackNd,
            other => other,
        }
    }
}

impl LinearSolverFactory for LinearSolverKind {
    fn build_for(&self, dae: &dyn Dae) -> Result<Box<dyn LinearSolver>, LinearSolverError> {
        LinearSolverKind::build_for(*self, dae)
    }
}

impl From<LinearSolverKind> for SharedFactory {
    fn from(kind: LinearSolverKind) -> Self {
        std::sync::Arc::new(kind)
    }
}

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

/// Peak memory [bytes] of a run of the cell on a mesh of `elements` elements in `dim`
/// dimensions (2: six-node triangles, plane strain or axisymmetric; 3: ten-node
/// tetrahedra) with the scenes' LUs (faer-condensed in 2-D, umfpack-condensed in 3-D):
/// the model, its Jacobian and the LU's factors, with inertia and the μ_as unknowns.
///
/// Fitted to the peak resident set of runs on this project's kind of machine
/// (2026-12-02): in 2-D `cellsim run cases/pillars-push-pull.ron --set phases.t_end=0.5
/// --set solver.defer_adhesion=false --set mesh.refine=R` at R = 4 and 8 (9 099 and
/// 36 263 triangles: 0.53 and 2.41 GB, growing as elements^1.1); in 3-D the 3-D runs' LU
/// on the Jacobian at rest (`cargo run --release --example cell3d -- --case
/// cases/3d/pillars-push-pull.ron --t-end 1 --drag 1e-6 --lu-memory` at refine 1, 1.5, 2:
/// 9 660, 26 927 and 57 626 tetrahedra, 1.38, 4.57 and 12.1 GB, growing as
/// tetrahedra^1.25, the nested-dissection fill), times 1.2 for the velocities and the
/// condensation while inertia is on (a run at refine 1.5 peaked at 5.41 GB). The
/// estimate is within 10 % of those runs and 30 % above a mesh graded more steeply
/// (h_bottom 0.02 µm: 51 374 tetrahedra, 9.7 GB for the LU alone).
pub fn estimated_run_memory(dim: usize, elements: f64) -> f64 {
    if dim == 3 {
        16_200.0 * elements.powf(1.25)
    } else {
        23_300.0 * elements.powf(1.1)
    }
}
