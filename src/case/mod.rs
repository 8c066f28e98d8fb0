//! The case file: a RON description of one simulation (scene, parameters, numerics).
//!
//! A [`Case`] has one section per concern (deal.II step-44 style): [`Geometry`], [`Mesh`],
//! [`Materials`], [`Viscosity`], [`Gravity`], [`Substrate`], [`Contact`], [`Adhesion`],
//! [`Active`], [`Phases`], [`Inertia`], [`Solver`], [`Output`]. Every field has a default
//! equal to MODEL.md's value (the paper's), except the few a scene must state: `name`,
//! `substrate` and `phases.t_end`. Unknown fields are errors everywhere.
//!
//! Units are the solver's: lengths µm, times s, stresses Pa (= pN/µm²), viscosities Pa·s.
//! Where the paper gives a value in SI units that are not the solver's, the field name says
//! so (`rho_kg_m3`, `g_m_s2`, `mu_ct_n_m3`, `mu_as0_n_m3s`, `mu_as_max_n_m3`) and an
//! accessor returns the solver unit ([`Material::rho`], [`Gravity::g`], ...).
//!
//! A minimal file:
//!
//! ```ron
//! (
//!     name: "flat",
//!     substrate: Flat(y_s: -2.0),
//!     adhesion: (),            // on, with the defaults; leave out for no adhesion
//!     phases: (t_end: 40000.0),
//! )
//! ```
//!
//! Optional sections and fields (`adhesion`, `active.pac`, `substrate.y_top`, ...) may be
//! written bare (`adhesion: (e_f: 1.5)`), as `Some(...)`, or `None`.
//!
//! [`Case::load`] parses and validates; its errors ([`CaseError`]) name the file, the line
//! and column, and the field's dotted path.

mod error;
mod locate;
mod sections;
mod validate;

#[cfg(test)]
mod tests;

use std::path::Path;

use serde::{Deserialize, Serialize};

pub use error::{CaseError, Problem};
pub use locate::Position;
pub use sections::{
    Active, Adhesion, Bottom, Contact, Flat, Geometry, Gravity, Inertia, InertiaMode, Integrator,
    LinearSolver, Material, Materials, Mesh, Output, Pac, Phases, Pillars, Solver, Substrate,
    Viscosity, units,
};
pub use validate::{Rule, Violation};

use locate::FieldMap;

/// One simulation: the scene and every parameter of the model and of the numerics.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Case {
    /// Name of the case, used to label outputs. Required; must not be empty.
    pub name: String,
    /// Free text: what the case is for. Optional.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub description: Option<String>,
    /// Reference geometry of the half cell.
    #[serde(default)]
    pub geometry: Geometry,
    /// Mesh sizes and contact-layer quadrature.
    #[serde(default)]
    pub mesh: Mesh,
    /// Solid-phase materials of nucleus, cytoplasm and membrane.
    #[serde(default)]
    pub materials: Materials,
    /// Fluid-phase (Kelvin–Voigt) viscosity.
    #[serde(default)]
    pub viscosity: Viscosity,
    /// Gravity, and the upside-down flip.
    #[serde(default)]
    pub gravity: Gravity,
    /// Flat or micropillared substrate. Required.
    pub substrate: Substrate,
    /// Penalty contact with the substrate.
    #[serde(default)]
    pub contact: Contact,
    /// Fibronectin layer and adhesive spreading. Absent (the default): no adhesion, and no
    /// μ_as unknowns.
    #[serde(default)]
    pub adhesion: Option<Adhesion>,
    /// Active-strain regions. Default: none.
    #[serde(default)]
    pub active: Active,
    /// Phase times and end time. Required (at least `t_end`).
    pub phases: Phases,
    /// Inertia on/off and medium drag.
    #[serde(default)]
    pub inertia: Inertia,
    /// Integrator and linear solver.
    #[serde(default)]
    pub solver: Solver,
    /// Output times and snapshots.
    #[serde(default)]
    pub output: Output,
}

/// The RON options of case files: `implicit_some` lets optional sections be written bare.
fn ron_options() -> ron::Options {
    ron::Options::default().with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
}

impl Case {
    /// A case with every default, the given name, substrate and end time, no adhesion and
    /// no active strain.
    pub fn new(name: impl Into<String>, substrate: Substrate, t_end: f64) -> Self {
        Case {
            name: name.into(),
            description: None,
            geometry: Geometry::default(),
            mesh: Mesh::default(),
            materials: Materials::default(),
            viscosity: Viscosity::default(),
            gravity: Gravity::default(),
            substrate,
            contact: Contact::default(),
            adhesion: None,
            active: Active::default(),
            phases: Phases::paper(t_end),
            inertia: Inertia::default(),
            solver: Solver::default(),
            output: Output::default(),
        }
    }

    /// Reads, parses and validates the case file at `path`.
    pub fn load(path: impl AsRef<Path>) -> Result<Case, CaseError> {
        let path = path.as_ref();
        let label = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|source| CaseError::Read {
            file: label.clone(),
            source,
        })?;
        Case::from_str(&text, &label)
    }

    /// Parses and validates a case from `text`; `file_label` names it in error messages.
    pub fn from_str(text: &str, file_label: &str) -> Result<Case, CaseError> {
        let case: Case = match ron_options().from_str(text) {
            Ok(case) => case,
            Err(e) => return Err(parse_error(e, text, file_label)),
        };
        let fields = FieldMap::scan(text);
        let violations = case.violations(&|path| fields.contains(path));
        if violations.is_empty() {
            Ok(case)
        } else {
            let problems = violations
                .into_iter()
                .map(|violation| Problem {
                    position: fields.locate(&violation.field),
                    violation,
                })
                .collect();
            Err(CaseError::Invalid {
                file: file_label.to_string(),
                problems,
            })
        }
    }

    /// Checks every range and consistency rule; returns all violations.
    pub fn validate(&self) -> Result<(), Vec<Violation>> {
        let violations = self.violations(&|_| false);
        if violations.is_empty() {
            Ok(())
        } else {
            Err(violations)
        }
    }

    /// The case as RON text, every field written out; [`Case::from_str`] reads it back.
    pub fn to_ron(&self) -> Result<String, ron::Error> {
        ron_options().to_string_pretty(self, ron::ser::PrettyConfig::default())
    }
}

/// Turns ron's error into a [`CaseError::Parse`] naming the field at the error's position.
fn parse_error(e: ron::error::SpannedError, text: &str, file: &str) -> CaseError {
    use ron::error::Error as E;

    let fields = FieldMap::scan(text);
    let end = Position::from(e.span.end);
    // ron's span may start on the whitespace before the offending token: point at the token.
    let start = skip_whitespace(text, Position::from(e.span.start), end);
    let one_of = |names: &[&str]| {
        let names: Vec<String> = names.iter().map(|n| format!("`{n}`")).collect();
        names.join(", ")
    };
    let (position, field, message) = match &e.code {
        E::MissingStructField { field, .. } => {
            // ron points at (or spans to) the closing bracket of the struct that lacks it.
            let parent = fields.path_at(end).unwrap_or("");
            (
                end,
                Some(join(parent, field)),
                "required field is missing (it has no default)".to_string(),
            )
        }
        E::NoSuchStructField {
            expected, found, ..
        } => (
            start,
            fields.path_at(start).map(str::to_string),
            format!(
                "unknown field `{found}`; expected one of {}",
                one_of(expected)
            ),
        ),
        E::NoSuchEnumVariant {
            expected, found, ..
        } => (
            start,
            fields.path_at(start).map(str::to_string),
            format!(
                "unknown variant `{found}`; expected one of {}",
                one_of(expected)
            ),
        ),
        E::DuplicateStructField { .. } => (
            start,
            fields.path_at(start).map(str::to_string),
            "field written twice".to_string(),
        ),
        _ if fields.is_blank() => (
            start,
            None,
            "the file is empty: a case needs at least `name`, `substrate` and `phases`".to_string(),
        ),
        E::Eof => (end, None, "unexpected end of file".to_string()),
        code => (
            start,
            fields.path_at_or_before(start).map(str::to_string),
            code.to_string(),
        ),
    };
    CaseError::Parse {
        file: file.to_string(),
        position,
        field,
        message,
    }
}

/// The first non-whitespace position at or after `from` on the same line, but not past
/// `limit`.
fn skip_whitespace(text: &str, from: Position, limit: Position) -> Position {
    let Some(line) = text.lines().nth(from.line.saturating_sub(1)) else {
        return from;
    };
    let mut pos = from;
    for c in line.chars().skip(from.col.saturating_sub(1)) {
        if !c.is_whitespace() || pos >= limit {
            break;
        }
        pos.col += 1;
    }
    pos
}

fn join(base: &str, name: &str) -> String {
    if base.is_empty() {
        name.to_string()
    } else {
        format!("{base}.{name}")
    }
}
