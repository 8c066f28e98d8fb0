//! A case in the lower layers' terms: the mesh parameters, the substrate, the phase
//! switches and the physics laws in solver units, and the checks those layers make of
//! them ([`layer_checks`]), so that validating a case runs the very rules the mesh
//! generator and the physics apply, and reports a refusal at the case field it comes from.
//! (The model's full parameters are built one layer up, by [`crate::scene`].)

use crate::case::{self, Case, LayerCheck, Refusal, layer_check};
use crate::fem::{MeshError, MeshParams, TetMeshParams, Wedge};
use crate::physics::{self, ActiveStrain, Condition, Flip, Phases, Substrate, Viscosity, Yeoh};

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
        h_surface: case.mesh.h_surface,
        min_angle_deg: crate::fem::mesh::MIN_ANGLE_DEG,
    }
}

/// The 3-D mesh parameters of a case: the 2-D ones (radii, sizes, refinement) about the
/// centre (0, c_y, 0), so that the section z = 0 follows the 2-D grading law. For
/// [`Case::reference`]: c = (0, 8.5, 0), r_n 5, r_cp 9.75, r_c 10 µm, h_bottom 0.3 µm,
/// h_nucleus 1 µm, ≈ 10 000 tetrahedra and ≈ 44 000 displacement unknowns.
pub fn tet_mesh_params(case: &Case) -> TetMeshParams {
    let wedge = match case.geometry.wedge {
        case::WedgeChoice::Quarter => Wedge::Quarter,
        case::WedgeChoice::Eighth => Wedge::Eighth,
        case::WedgeChoice::Auto if case.substrate.mirrors_diagonal() => Wedge::Eighth,
        case::WedgeChoice::Auto => Wedge::Quarter,
    };
    TetMeshParams {
        wedge,
        ..TetMeshParams::from_section(&mesh_params(case), 0.0)
    }
}

/// The mesh a case's model is built on: the half-plane mesh of six-node triangles (plane
/// strain, axisymmetric) or the 3-D quarter cell's ten-node tetrahedra. A run generates
/// it from these very parameters, and validating a case runs their generator's checks.
#[derive(Debug, Clone, PartialEq)]
pub enum MeshSpec {
    /// The half-plane models' mesh.
    Plane(MeshParams),
    /// The 3-D quarter cell's mesh.
    Quarter(TetMeshParams),
}

impl MeshSpec {
    /// The mesh of `case`'s model.
    pub fn of(case: &Case) -> Self {
        match case.geometry.model {
            crate::physics::KinematicModel::ThreeD => MeshSpec::Quarter(tet_mesh_params(case)),
            _ => MeshSpec::Plane(mesh_params(case)),
        }
    }

    /// The generator's own checks of the parameters (with its element-count limit).
    pub fn validate(&self) -> Result<(), MeshError> {
        match self {
            MeshSpec::Plane(p) => p.validate(),
            MeshSpec::Quarter(p) => p.validate(),
        }
    }

    /// Elements expected before meshing (for parameters that pass [`Self::validate`]).
    pub fn expected_elements(&self) -> f64 {
        match self {
            MeshSpec::Plane(p) => p.expected_elements(),
            MeshSpec::Quarter(p) => p.estimated_tets(),
        }
    }

    /// 2 or 3.
    pub fn dimension(&self) -> usize {
        match self {
            MeshSpec::Plane(_) => 2,
            MeshSpec::Quarter(_) => 3,
        }
    }

    /// What its elements are called in messages.
    fn elements_name(&self) -> &'static str {
        match self {
            MeshSpec::Plane(_) => "triangles",
            MeshSpec::Quarter(_) => "tetrahedra",
        }
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

/// The fluid-phase viscosity of a case.
pub fn viscosity(case: &Case) -> Viscosity {
    Viscosity {
        lambda_f: case.viscosity.lambda_f,
        mu_f: case.viscosity.mu_f,
    }
}

/// The fibre law of a case (MODEL.md §11), if it has fibres.
pub fn fibres(case: &Case) -> Option<physics::Fibres> {
    case.materials.fibres.as_ref().map(|f| physics::Fibres {
        k1: f.k1_pa,
        k2: f.k2,
        delta: f.delta,
    })
}

/// The phase switches of a case at its start (with the gravity flip if the case turns
/// upside down): the phases that start at a time have their ramps, those that start on a
/// condition have none yet ([`phases_from`]).
pub fn phases(case: &Case) -> Phases {
    phases_from(case, phase_starts(case))
}

/// The starts of the adhesion and active phases known before the run: `At(t)` (`None`
/// in the case: the paper's T_g0 and T_as0) gives its time, a condition `None`.
pub fn phase_starts(case: &Case) -> [Option<f64>; 2] {
    let ph = &case.phases;
    let known = |start: Option<case::Start>, paper: f64| match start {
        None => Some(paper),
        Some(case::Start::At(t)) => Some(t),
        Some(_) => None,
    };
    [
        known(ph.adhesion_start, ph.t_g0),
        known(ph.active_start, ph.t_as0),
    ]
}

/// The conditions that start the adhesion and active phases (MODEL.md §11), `None` for a
/// phase that starts at a time.
pub fn phase_conditions(case: &Case) -> [Option<Condition>; 2] {
    let ph = &case.phases;
    let condition = |start: Option<case::Start>| match start {
        Some(case::Start::Settled(speed)) => Some(Condition::Settled { speed }),
        Some(case::Start::SpreadingSlows(rate)) => Some(Condition::SpreadingSlows { rate }),
        _ => None,
    };
    [condition(ph.adhesion_start), condition(ph.active_start)]
}

/// The run time of a time `t` of the case's schedule, given the phases' starts (`None`:
/// not yet known): a time after a phase's paper start (T_g0 for adhesion, T_as0 for the
/// active strain; strictly after, so that T_as0 itself, the end of the paper's spreading,
/// belongs to the adhesion phase) is read as a time after that phase's start and moves
/// with it. `None` when it falls in a phase whose start is not known yet. With the paper's
/// starts, every time is itself.
pub fn scheduled(case: &Case, starts: [Option<f64>; 2], t: f64) -> Option<f64> {
    let ph = &case.phases;
    let paper = [ph.t_g0, ph.t_as0];
    match (0..2).rev().find(|&k| t > paper[k]) {
        None => Some(t),
        Some(k) => starts[k].map(|s| if s == paper[k] { t } else { t - paper[k] + s }),
    }
}

/// The phase switches of a case once the adhesion and active phases started at `starts`
/// (`None`: not yet): each ramp runs from its start over its paper duration (T_as0 − T_g0,
/// T_a0 − T_as0; with the paper's starts exactly [T_g0, T_as0] and [T_as0, T_a0]), the
/// gravity flip from the scheduled T_a0 ([`scheduled`]).
pub fn phases_from(case: &Case, starts: [Option<f64>; 2]) -> Phases {
    let ph = &case.phases;
    let ramp = |start: Option<f64>, paper: [f64; 2]| {
        start.map(|s| {
            if s == paper[0] {
                paper
            } else {
                [s, s + (paper[1] - paper[0])]
            }
        })
    };
    Phases {
        t_g0: ph.t_g0,
        adhesion: ramp(starts[0], [ph.t_g0, ph.t_as0]),
        active: ramp(starts[1], [ph.t_as0, ph.t_a0]),
        flip: if case.gravity.upside_down {
            scheduled(case, starts, ph.t_a0).map(|start| Flip {
                start,
                duration: case.gravity.flip_duration,
            })
        } else {
            None
        },
    }
}

/// The active-strain regions of a case; `None` if it has neither region.
pub fn active(case: &Case) -> Option<ActiveStrain> {
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
    (active.pac.is_some() || active.bottom.is_some()).then_some(active)
}

/// The contact law of a case in solver units.
pub fn contact(case: &Case) -> physics::Contact {
    physics::Contact {
        mu_ct: case.contact.mu_ct(),
        eps: case.contact.eps_ct,
        stiffening: case.contact.stiffening,
        self_contact: case.contact.self_contact,
    }
}

/// The adhesion law of a case in solver units, if it has adhesion.
pub fn adhesion(case: &Case) -> Option<physics::Adhesion> {
    case.adhesion.as_ref().map(|a| physics::Adhesion {
        e_f: a.e_f,
        eps: a.eps,
        mu_as0: a.mu_as0(),
        mu_as_max: a.mu_as_max(),
        direction: a.direction,
        jacobian_factor: a.jacobian_factor,
        exclude_substrate: a.layer_excludes_substrate.then_some(case.contact.eps_ct),
        fold_release: a.fold_release,
    })
}

/// The name of the mesh generator's layer in [`LayerCheck::layer`].
pub const MESH_GENERATOR: &str = "mesh generator";
/// The name of the memory estimate's layer in [`LayerCheck::layer`].
pub const MEMORY_ESTIMATE: &str = "memory estimate";

/// A case field and its value, formatted as in case messages.
fn field(path: impl Into<String>, value: f64) -> Option<(String, String)> {
    Some((path.into(), case::num(value)))
}

/// A physics validator's verdict `checked`, its error turned into a [`Refusal`]: `to_case`
/// maps the validator's parameter name to the case field, else the refusal names `section`.
fn physics_refusal<T>(
    checked: Result<T, physics::PhysicsError>,
    section: &str,
    to_case: impl Fn(&str) -> Option<(String, String)>,
) -> Result<(), Refusal> {
    let e = match checked {
        Ok(_) => return Ok(()),
        Err(e) => e,
    };
    let physics::PhysicsError::InvalidParameter { name, value, .. } = &e;
    let fields = vec![to_case(name).unwrap_or_else(|| (section.to_string(), case::num(*value)))];
    Err(Refusal {
        fields,
        message: e.to_string(),
    })
}

/// The case fields the mesh is made from.
const MESH_READS: [&str; 5] = [
    "geometry",
    "mesh.h_bottom",
    "mesh.h_nucleus",
    "mesh.refine",
    "mesh.h_surface",
];

/// Every check the lower layers make of a case's parameters before a run integrates:
/// the mesh generator's of the model's mesh ([`MeshSpec::validate`], with its
/// element-count limit), the run's memory against the limit ([`memory_refusal`]), the
/// material law [`Yeoh::from_engineering`] of each domain, and the validators of the
/// phases, the substrate, the active strain, contact, adhesion, viscosity and fibres. `cellsim
/// check` and every command that runs a case load it through these.
pub fn layer_checks(case: &Case) -> Vec<LayerCheck<'_>> {
    let mut checks = vec![
        layer_check(MESH_GENERATOR, &MESH_READS, move || mesh_refusal(case)),
        layer_check(MEMORY_ESTIMATE, &MESH_READS, move || memory_refusal(case)),
    ];
    let m = &case.materials;
    for (domain, mat) in [
        ("nucleus", &m.nucleus),
        ("cytoplasm", &m.cytoplasm),
        ("membrane", &m.membrane),
    ] {
        let e_path = format!("materials.{domain}.e");
        let nu_path = format!("materials.{domain}.nu");
        let reads = [
            e_path.as_str(),
            nu_path.as_str(),
            "materials.gamma",
            "materials.beta_fraction",
        ];
        checks.push(layer_check("material law", &reads, move || {
            material_refusal(m, domain, mat)
        }));
    }
    checks.extend([
        layer_check(
            "phase switches",
            &["phases", "gravity.flip_duration"],
            move || phases_refusal(case),
        ),
        layer_check("substrate model", &["substrate", "geometry"], move || {
            substrate_refusal(case)
        }),
        layer_check(
            "active-strain model",
            &["active", "geometry.centre_y"],
            move || active_refusal(case),
        ),
        layer_check("contact model", &["contact"], move || contact_refusal(case)),
        layer_check(
            "adhesion model",
            &["adhesion", "contact.eps_ct"],
            move || adhesion_refusal(case),
        ),
        layer_check("viscosity model", &["viscosity"], move || {
            viscosity_refusal(case)
        }),
        layer_check("fibre law", &["materials.fibres"], move || {
            fibres_refusal(case)
        }),
    ]);
    checks
}

/// The material law's check of the domain `domain`'s material `mat`
/// ([`Yeoh::from_engineering`]), its error traced back to the case fields.
fn material_refusal(
    m: &case::Materials,
    domain: &str,
    mat: &case::Material,
) -> Result<(), Refusal> {
    let law = Yeoh::from_engineering(mat.e, mat.nu, m.gamma, m.beta_fraction);
    physics_refusal(law, &format!("materials.{domain}"), |name| match name {
        "E" => field(format!("materials.{domain}.e"), mat.e),
        "nu" => field(format!("materials.{domain}.nu"), mat.nu),
        "gamma" => field("materials.gamma", m.gamma),
        "beta_fraction" => field("materials.beta_fraction", m.beta_fraction),
        _ => None,
    })
}

/// The phase switches' check ([`Phases::validate`]), its error traced back to the case
/// fields.
fn phases_refusal(case: &Case) -> Result<(), Refusal> {
    let ph = &case.phases;
    physics_refusal(phases(case).validate(), "phases", |name| match name {
        "t_g0" => field("phases.t_g0", ph.t_g0),
        "t_as0" => field("phases.t_as0", ph.t_as0),
        "t_a0" | "flip.start" => field("phases.t_a0", ph.t_a0),
        "flip.duration" => field("gravity.flip_duration", case.gravity.flip_duration),
        _ => None,
    })
}

/// The substrate model's check ([`Substrate::validate`]), its error traced back to the
/// case fields.
fn substrate_refusal(case: &Case) -> Result<(), Refusal> {
    physics_refusal(substrate(case).validate(), "substrate", |name| {
        match (&case.substrate, name) {
            (case::Substrate::Flat(f), "y_s") => field("substrate.y_s", f.y_s),
            (case::Substrate::Pillars(p), name) => match name {
                "pillars.width" => field("substrate.width", p.width),
                "pillars.spacing" => field("substrate.spacing", p.spacing),
                "pillars.height" => field("substrate.height", p.height),
                "pillars.q" => field("substrate.q", p.q),
                "pillars.first_center" => field("substrate.first_center", p.first_center),
                // Without an explicit y_top, the tops are placed from the gap.
                "pillars.y_top" => match p.y_top {
                    Some(y) => field("substrate.y_top", y),
                    None => field("substrate.gap", p.gap),
                },
                _ => None,
            },
            _ => None,
        }
    })
}

/// The active-strain model's check ([`ActiveStrain::validate`]; none without active
/// strain), its error traced back to the case fields.
fn active_refusal(case: &Case) -> Result<(), Refusal> {
    let Some(a) = active(case) else {
        return Ok(());
    };
    let (pac, bottom) = (case.active.pac.as_ref(), case.active.bottom.as_ref());
    physics_refusal(a.validate(), "active", |name| match name {
        "active.eps" => field("active.eps_a", case.active.eps_a),
        "active.center" => field("geometry.centre_y", case.geometry.centre_y),
        "pac.e" => pac.and_then(|p| field("active.pac.e", p.e)),
        "pac.theta_deg" => pac.and_then(|p| field("active.pac.theta_deg", p.theta_deg)),
        "pac.inner_axes" => pac.map(|p| {
            let v = case::axes(p.inner_semi_axes);
            ("active.pac.inner_semi_axes".to_string(), v)
        }),
        "pac.outer_axes" => pac.map(|p| {
            let v = case::axes(p.outer_semi_axes);
            ("active.pac.outer_semi_axes".to_string(), v)
        }),
        "bottom.e" => bottom.and_then(|b| field("active.bottom.e", b.e)),
        "bottom.theta_deg" => bottom.and_then(|b| field("active.bottom.theta_deg", b.theta_deg)),
        _ => None,
    })
}

/// The contact model's check ([`physics::Contact::validate`]), its error traced back to
/// the case fields.
fn contact_refusal(case: &Case) -> Result<(), Refusal> {
    physics_refusal(contact(case).validate(), "contact", |name| match name {
        "contact.mu_ct" => field("contact.mu_ct_n_m3", case.contact.mu_ct_n_m3),
        "contact.eps" => field("contact.eps_ct", case.contact.eps_ct),
        "contact.stiffening" => field("contact.stiffening", case.contact.stiffening),
        _ => None,
    })
}

/// The adhesion model's check ([`physics::Adhesion::validate`]; none without adhesion),
/// its error traced back to the case fields.
fn adhesion_refusal(case: &Case) -> Result<(), Refusal> {
    let (Some(a), Some(written)) = (adhesion(case), case.adhesion.as_ref()) else {
        return Ok(());
    };
    physics_refusal(a.validate(), "adhesion", |name| match name {
        "adhesion.e_f" => field("adhesion.e_f", written.e_f),
        "adhesion.eps" => field("adhesion.eps", written.eps),
        "adhesion.mu_as0" => field("adhesion.mu_as0_n_m3s", written.mu_as0_n_m3s),
        "adhesion.mu_as_max" => field("adhesion.mu_as_max_n_m3", written.mu_as_max_n_m3),
        "adhesion.exclude_substrate" => field("contact.eps_ct", case.contact.eps_ct),
        _ => None,
    })
}

/// The viscosity model's check ([`Viscosity::validate`]), its error traced back to the
/// case fields.
fn viscosity_refusal(case: &Case) -> Result<(), Refusal> {
    physics_refusal(viscosity(case).validate(), "viscosity", |name| match name {
        "lambda_f" => field("viscosity.lambda_f", case.viscosity.lambda_f),
        "mu_f" => field("viscosity.mu_f", case.viscosity.mu_f),
        _ => None,
    })
}

/// The fibre law's check ([`physics::Fibres::validate`]), traced back to the case fields
/// (that the fibres have regions to lie in is the case validation's rule).
fn fibres_refusal(case: &Case) -> Result<(), Refusal> {
    let (Some(law), Some(written)) = (fibres(case), case.materials.fibres.as_ref()) else {
        return Ok(());
    };
    physics_refusal(law.validate(), "materials.fibres", |name| match name {
        "k1" => field("materials.fibres.k1_pa", written.k1_pa),
        "k2" => field("materials.fibres.k2", written.k2),
        "delta" => field("materials.fibres.delta", written.delta),
        _ => None,
    })
}

/// The mesh fields that refine the mesh, the one that refines most (relative to its
/// default) first: they share the blame for too many elements.
fn refining_fields(case: &Case) -> Vec<(String, String)> {
    let m = &case.mesh;
    let d = case::Mesh::default();
    let mut fields = vec![
        (m.refine / d.refine, field("mesh.refine", m.refine)),
        (d.h_bottom / m.h_bottom, field("mesh.h_bottom", m.h_bottom)),
        (
            d.h_nucleus / m.h_nucleus,
            field("mesh.h_nucleus", m.h_nucleus),
        ),
    ];
    fields.sort_by(|a, b| b.0.total_cmp(&a.0));
    fields.into_iter().filter_map(|(_, f)| f).collect()
}

/// A run's estimated peak memory ([`crate::solver::estimated_run_memory`], from the elements
/// estimated before meshing) against the memory it may use
/// ([`crate::solver::MemoryLimit`]): a mesh the machine cannot factor is refused before
/// meshing, with the estimate. Passes a mesh the generator refuses (its own check says
/// why) and where no limit can be read.
pub fn memory_refusal(case: &Case) -> Result<(), Refusal> {
    let spec = MeshSpec::of(case);
    if spec.validate().is_err() {
        return Ok(());
    }
    let limit = crate::solver::MemoryLimit::of_this_process().map_err(|e| Refusal {
        fields: refining_fields(case),
        message: e.to_string(),
    })?;
    let Some(limit) = limit else {
        return Ok(());
    };
    let elements = spec.expected_elements();
    let need = crate::solver::estimated_run_memory(spec.dimension(), elements);
    if need <= limit.bytes {
        return Ok(());
    }
    Err(Refusal {
        fields: refining_fields(case),
        message: format!(
            "mesh too large for the memory: about {elements:.0} {} estimated, a run would \
             need about {:.1} GB (the sparse LU's factors and the model), more than the \
             {:.1} GB allowed ({}); coarsen the mesh (a smaller mesh.refine, a larger \
             mesh.h_bottom or mesh.h_nucleus)",
            spec.elements_name(),
            need / 1e9,
            limit.bytes / 1e9,
            limit.source
        ),
    })
}

/// What a run of a case is expected to cost, estimated before it is meshed (for the batch
/// scripts of a sweep, [`crate::commands::sweep::slurm`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunCost {
    /// 2 (plane strain, axisymmetric) or 3 (the 3-D cell).
    pub dimension: usize,
    /// Elements expected ([`MeshSpec::expected_elements`]).
    pub elements: f64,
    /// Wall time on one core of this project's machines \[s\] ([`estimated_run_seconds`]).
    pub seconds: f64,
    /// Peak memory \[bytes\] ([`crate::solver::estimated_run_memory`]).
    pub bytes: f64,
}

/// The expected cost of a run of `case`; `None` for a mesh the generator refuses.
pub fn run_cost(case: &Case) -> Option<RunCost> {
    let spec = MeshSpec::of(case);
    spec.validate().ok()?;
    let (dimension, elements) = (spec.dimension(), spec.expected_elements());
    Some(RunCost {
        dimension,
        elements,
        seconds: estimated_run_seconds(dimension, elements, &case.phases),
        bytes: crate::solver::estimated_run_memory(dimension, elements),
    })
}

/// Wall time \[s\] of a run of the scene phases `phases` (to its `t_end`) on a mesh of
/// `elements` elements (as estimated before meshing) in `dim` dimensions, at the scenes'
/// tolerances, on one core of this project's kind of machine.
///
/// Calibrated on the push-pull scene (to 50 000 s, the scenes' hardest), whose cost grows
/// with the mesh as the cost per step (the step count hardly changes with the mesh).
/// In 2-D 7.3 s on the default mesh (590 triangles; 5 388 unknowns) and n^1.21 with the
/// mesh from refine 1 to 4 (`cargo run --release --example scaling`). In 3-D, the quarter
/// cell, through measured runs ([`crate::solver::through_anchors`]): the 3-D maps'
/// configuration (`cases/sweeps/pillar-geometry-3d.ron` at w = s = 8 µm, about 3 100
/// tetrahedra estimated: 722 s, two runs side by side on two cores, 2026-12-08),
/// the default mesh (about 9 900: 1 551 s) and refined ×1.5 (about 29 500: 5 544 s; the
/// README's measurements of 2026-12-02), beyond as tetrahedra^1.24. The coarse mesh costs
/// more per tetrahedron than a uniform coarsening would (its graded bottom layer); the law
/// of the finer two alone gave it 379 s. A run that ends earlier, or whose phases are
/// shorter, costs the fraction [`work_fraction`] of that. What the estimate leaves out
/// (the geometry: up to 2× on the map, the `Gap` lattice and the narrow gaps; another tolerance or
/// integrator; a slower node; the mesh generator's first run) is the margin's job.
pub fn estimated_run_seconds(dim: usize, elements: f64, phases: &case::Phases) -> f64 {
    let seconds = if dim == 3 {
        crate::solver::through_anchors(
            &[(3_102.0, 722.0), (9_884.0, 1_551.0), (29_538.0, 5_544.0)],
            1.24,
            elements,
        )
    } else {
        7.3 * (elements / 590.0).powf(1.21)
    };
    seconds * work_fraction(phases)
}

/// The fraction of the push-pull scene's work a run of `phases` does, by phase: the
/// gravity phase (to t_g0, the landing) 0.1, the spreading (to t_as0) 0.6, the active
/// phase (to t_a0) 0.3, and 0.02 for each 10 000 s after it; within a phase the square
/// root of the fraction of its time (the work comes early in a phase: the landing, the
/// first spreading, the onset of contraction). Measured on `cellsim run
/// cases/pillars-push-pull.ron --set phases.t_end=T` (2026-12-04): wall fractions 0.10,
/// 0.63, 0.72 and 0.75 of the whole at T = 10 000, 25 000, 40 000 and 45 000 s (this
/// gives 0.10, 0.52, 0.70 and 0.91: ahead by the active phase, behind by a fifth in the
/// middle of the spreading). A phase that never starts (t_end before it) costs nothing;
/// the fraction does not depend on the phases' lengths (a compressed scene does the
/// same work faster).
pub fn work_fraction(phases: &case::Phases) -> f64 {
    let t = phases.t_end;
    let part = |from: f64, to: f64| {
        if to <= from {
            f64::from(u8::from(t >= to))
        } else {
            ((t - from) / (to - from)).clamp(0.0, 1.0).sqrt()
        }
    };
    0.1 * part(0.0, phases.t_g0)
        + 0.6 * part(phases.t_g0, phases.t_as0)
        + 0.3 * part(phases.t_as0, phases.t_a0)
        + 0.02 * ((t - phases.t_a0).max(0.0) / 10_000.0)
}

/// The mesh generator's checks of a case's mesh ([`MeshSpec::validate`]), its error
/// traced back to the case fields.
fn mesh_refusal(case: &Case) -> Result<(), Refusal> {
    let g = &case.geometry;
    let m = &case.mesh;
    let e = match MeshSpec::of(case).validate() {
        Ok(()) => return Ok(()),
        Err(e) => e,
    };
    let fields = match &e {
        MeshError::InvalidParam {
            field: name, value, ..
        } => {
            let f = match *name {
                "center[0]" | "center[1]" | "center[2]" | "center" => {
                    field("geometry.centre_y", g.centre_y)
                }
                "r_n" => field("geometry.r_n", g.r_n),
                "r_cp" => field("geometry.r_cp", g.r_cp),
                "r_c" => field("geometry.r_c", g.r_c),
                "h_bottom" => field("mesh.h_bottom", m.h_bottom),
                "h_nucleus" => field("mesh.h_nucleus", m.h_nucleus),
                "refine" => field("mesh.refine", m.refine),
                _ => None,
            };
            vec![f.unwrap_or_else(|| ("mesh".to_string(), case::num(*value)))]
        }
        // Too many elements: the sizes and the refinement share the blame.
        _ => refining_fields(case),
    };
    Err(Refusal {
        fields,
        message: e.to_string(),
    })
}
