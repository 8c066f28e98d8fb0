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
