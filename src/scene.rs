//! From a validated [`Case`] to what the solver needs: the mesh parameters and the
//! physical parameters in solver units. Only what the scene needs is switched on (μ_as
//! unknowns with adhesion, active terms with active fibres, inertia per the case).

use crate::case::{self, Case, InertiaMode};
use crate::fem::MeshParams;
use crate::model::ModelParams;
use crate::physics::{self, ActiveStrain, Flip, Phases, Substrate, Viscosity, Yeoh};

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

/// Mesh parameters of a case.
pub fn mesh_params(case: &Case) -> MeshParams {
    MeshParams {
        center: case.geometry.centre(),
        r_n: case.geometry.r_n,
        r_cp: case.geometry.r_cp,
        r_c: case.geometry.r_c,
        h_bottom: case.mesh.h_bottom,
        h_nucleus: case.mesh.h_nucleus,
        refine: case.mesh.refine,
        ..MeshParams::default()
    }
}

/// The substrate of a case in solver terms (pillar tops placed from the gap rule).
pub fn substrate(case: &Case) -> Substrate {
    match &case.substrate {
        case::Substrate::Flat(f) => Substrate::Flat { y_s: f.y_s },
        case::Substrate::Pillars(p) => {
            Substrate::Pillars(p.at_height(p.resolved_y_top(&case.geometry)))
        }
    }
}

/// Whether the scene starts with inertia.
pub fn starts_with_inertia(case: &Case) -> bool {
    !matches!(case.inertia.mode, InertiaMode::Off)
}

/// Physical parameters of a case in solver units; `inertia` selects the (u, v, μ_as) or
/// (u, μ_as) system.
pub fn model_params(case: &Case, file: &str, inertia: bool) -> Result<ModelParams, SceneError> {
    let err = |e: physics::PhysicsError| SceneError {
        file: file.to_string(),
        message: e.to_string(),
    };
    let m = &case.materials;
    let solid =
        |mat: &case::Material| Yeoh::from_engineering(mat.e, mat.nu, m.gamma, m.beta_fraction);
    let solids = [
        solid(&m.nucleus).map_err(err)?,
        solid(&m.cytoplasm).map_err(err)?,
        solid(&m.membrane).map_err(err)?,
    ];
    let ph = &case.phases;
    let phases = Phases {
        t_g0: ph.t_g0,
        t_as0: ph.t_as0,
        t_a0: ph.t_a0,
        flip: case.gravity.upside_down.then_some(Flip {
            start: ph.t_a0,
            duration: case.gravity.flip_duration,
        }),
    };
    let active = ActiveStrain {
        pac: case.active.pac.as_ref().map(|p| physics::Pac {
            e: p.e,
            theta_deg: p.theta_deg,
            inner_axes: [p.inner_semi_axes.0, p.inner_semi_axes.1],
            outer_axes: [p.outer_semi_axes.0, p.outer_semi_axes.1],
        }),
        bottom: case.active.bottom.as_ref().map(|b| physics::Bottom {
            e: b.e,
            theta_deg: b.theta_deg,
        }),
        eps: case.active.eps_a,
        center: case.geometry.centre(),
    };
    let has_active = active.pac.is_some() || active.bottom.is_some();
    let adhesion = case.adhesion.as_ref().map(|a| physics::Adhesion {
        e_f: a.e_f,
        eps: a.eps,
        mu_as0: a.mu_as0(),
        mu_as_max: a.mu_as_max(),
    });
    let params = ModelParams {
        center: case.geometry.centre(),
        solids,
        densities: [m.nucleus.rho(), m.cytoplasm.rho(), m.membrane.rho()],
        viscosity: Viscosity {
            lambda_f: case.viscosity.lambda_f,
            mu_f: case.viscosity.mu_f,
        },
        gravity: case.gravity.g(),
        phases,
        substrate: substrate(case),
        contact: physics::Contact {
            mu_ct: case.contact.mu_ct(),
            eps: case.contact.eps_ct,
        },
        adhesion,
        active: has_active.then_some(active),
        inertia,
        drag: case.inertia.drag,
        contact_degree: case.mesh.contact_quadrature_degree as usize,
        contact_subdivisions: case.mesh.contact_subdivisions,
        extra_breakpoints: vec![ph.t_end],
    };
    params.phases.validate().map_err(err)?;
    params.substrate.validate().map_err(err)?;
    if let Some(a) = &params.active {
        a.validate().map_err(err)?;
    }
    Ok(params)
}
