//! A case in the lower layers' terms, one layer above [`crate::case`] (the schema),
//! [`crate::fem`], [`crate::physics`] and [`crate::model`]: the mesh parameters and the
//! physical parameters in solver units ([`terms`], and here the model's), the checks those
//! layers make of a case, which loading a case runs ([`Case::load`] and its kin, in
//! `load.rs`), and the run's cost estimate. Only what the scene needs is switched on (μ_as
//! unknowns with adhesion, active terms with active fibres, inertia per the case).

mod load;
pub mod terms;

use crate::case::{self, Case, InertiaMode};
use crate::model::ModelParams;
use crate::physics::{KinematicModel, Lattice, Yeoh};
use terms::{
    MEMORY_ESTIMATE, MESH_GENERATOR, active, adhesion, contact, fibres, phase_conditions,
    phase_starts, phases, scheduled, viscosity,
};
pub use terms::{layer_checks, mesh_params, substrate, tet_mesh_params};

/// A problem with a case that validation could not see (a material law rejecting its
/// parameters, say).
#[derive(Debug, Clone, thiserror::Error)]
#[error("{file}: {message}")]
pub struct SceneError {
    /// The case file.
    pub file: String,
    /// What is wrong.
    pub message: String,
}

/// Whether the scene starts with inertia.
pub fn starts_with_inertia(case: &Case) -> bool {
    !matches!(case.inertia.mode, InertiaMode::Off)
}

/// The model parameters of [`Case::reference`]: MODEL.md's defaults in solver units
/// (flat substrate, adhesion, no active strain, inertia on, no drag).
pub fn reference_params() -> ModelParams {
    model_params(&Case::reference(), "reference", true).expect("the reference case is valid")
}

/// Physical parameters of a case in solver units; `inertia` selects the (u, v, μ_as) or
/// (u, μ_as) system. Runs the physics checks of [`layer_checks`] first; a refusal names
/// the case field.
pub fn model_params(case: &Case, file: &str, inertia: bool) -> Result<ModelParams, SceneError> {
    let err = |message: String| SceneError {
        file: file.to_string(),
        message,
    };
    for check in layer_checks(case) {
        // The mesh's own checks run when it is generated.
        if check.layer == MESH_GENERATOR || check.layer == MEMORY_ESTIMATE {
            continue;
        }
        check.run().map_err(|r| {
            let at = r.fields.first().map(|(f, _)| f.as_str()).unwrap_or("");
            err(format!(
                "{at}: refused by the {}: {}",
                check.layer, r.message
            ))
        })?;
    }
    let m = &case.materials;
    let solid = |mat: &case::Material| {
        Yeoh::from_engineering(mat.e, mat.nu, m.gamma, m.beta_fraction)
            .map_err(|e| err(e.to_string()))
    };
    let solids = [
        solid(&m.nucleus)?,
        solid(&m.cytoplasm)?,
        solid(&m.membrane)?,
    ];
    Ok(ModelParams {
        kinematics: case.geometry.model,
        center: case.geometry.centre(),
        solids,
        densities: [m.nucleus.rho(), m.cytoplasm.rho(), m.membrane.rho()],
        viscosity: viscosity(case),
        gravity: case.gravity.g(),
        phases: phases(case),
        substrate: substrate(case),
        lattice: match &case.substrate {
            case::Substrate::Pillars(p) => p.lattice,
            case::Substrate::Flat(_) => Lattice::FourPillars,
        },
        contact: contact(case),
        adhesion: adhesion(case),
        active: active(case),
        fibres: fibres(case),
        inertia,
        drag: case.inertia.drag,
        contact_degree: case.mesh.contact_quadrature_degree as usize,
        contact_subdivisions: case.mesh.contact_subdivisions,
        extra_breakpoints: scheduled(case, phase_starts(case), case.phases.t_end)
            .into_iter()
            .collect(),
        events: phase_conditions(case).into_iter().flatten().collect(),
    })
}

/// Whether the case is the 3-D quarter cell (`geometry.model: ThreeD`).
pub fn is_3d(case: &Case) -> bool {
    case.geometry.model == KinematicModel::ThreeD
}
