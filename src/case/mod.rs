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
//! and column, and the field's dotted path. This module is the schema, its rules and the
//! locating of errors; the checks of the layers below (mesh generator, material laws,
//! physics validators) come from one layer up ([`crate::scene::terms::layer_checks`]),
//! which also defines `Case::load` and its kin over this module's `Case::parse_*`.

mod error;
mod locate;
pub mod overrides;
mod sections;
mod validate;

#[cfg(test)]
mod tests;

use std::path::Path;

use serde::{Deserialize, Serialize};

pub use error::{CaseError, Problem};
pub use locate::Position;
pub use overrides::Override;
pub use sections::{
    Active, Adhesion, AdhesionDirection, Bottom, Contact, Fibres, Flat, Geometry, Gravity, Inertia,
    InertiaMode, Integrator, KinematicModel, Krylov, LinearSolver, MAX_ATOL, MAX_RTOL, Material,
    Materials, Mesh, Output, Pac, Phases, Pillars, Solver, Start, Substrate, Viscosity,
    WedgeChoice, units,
};
pub use validate::{LayerCheck, LayerChecks, Refusal, Rule, Violation, layer_check};
pub(crate) use validate::{axes, num};

use locate::FieldMap;

/// One simulation: the scene and every parameter of the model and of the numerics.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Case {
    /// Name of the case, used to label outputs and to name their directory. Required.
    /// Valid: a single path component: not empty, no `/` or `\`, not `.` or `..`, no
    /// control characters.
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

    /// MODEL.md's scene with every default: the flat substrate, adhesion, no active
    /// region, the paper's phases to T_a0 = 50 000 s. The one source of the model's default
    /// numbers: the layers below the case (physics, mesh, model) hold none, and their
    /// tests take them from here through [`crate::scene::terms`] (e.g.
    /// `terms::contact(&Case::reference())`).
    pub fn reference() -> Self {
        let mut c = Case::new("reference", Substrate::flat(), 50_000.0);
        c.adhesion = Some(Adhesion::default());
        c
    }

    /// [`Case::reference`] with both active regions at their defaults.
    pub fn reference_active() -> Self {
        let mut c = Case::reference();
        c.active.pac = Some(Pac::default());
        c.active.bottom = Some(Bottom::default());
        c
    }

    /// Reads, parses and validates the case file at `path`, with the lower layers' checks
    /// `layers` ([`Case::load`] gives them).
    pub fn parse_file(path: impl AsRef<Path>, layers: LayerChecks) -> Result<Case, CaseError> {
        let (label, bytes) = Case::read_file(path.as_ref())?;
        Case::parse_bytes(&bytes, &label, layers)
    }

    /// The bytes of the case file at `path`, with the label its messages use.
    pub(crate) fn read_file(path: &Path) -> Result<(String, Vec<u8>), CaseError> {
        let label = path.display().to_string();
        let bytes = std::fs::read(path).map_err(|source| CaseError::Read {
            file: label.clone(),
            source,
        })?;
        Ok((label, bytes))
    }

    /// Parses and validates a case from the bytes of a file, which must be UTF-8 text (a
    /// byte that is not is reported at its line and column); `file_label` names the file in
    /// error messages; `layers` are the lower layers' checks ([`Case::from_bytes`]).
    pub fn parse_bytes(
        bytes: &[u8],
        file_label: &str,
        layers: LayerChecks,
    ) -> Result<Case, CaseError> {
        // Columns count from after a byte-order mark, as in `from_str`.
        let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
        match std::str::from_utf8(bytes) {
            Ok(text) => Case::parse_str(text, file_label, layers),
            Err(e) => {
                let valid = bytes.get(..e.valid_up_to()).unwrap_or_default();
                let position = end_of(&String::from_utf8_lossy(valid));
                let byte = bytes.get(e.valid_up_to()).copied().unwrap_or_default();
                let fields = FieldMap::scan(&String::from_utf8_lossy(bytes));
                Err(CaseError::Parse {
                    file: file_label.to_string(),
                    position,
                    field: fields.path_at(position).map(str::to_string),
                    message: format!(
                        "not valid UTF-8: byte 0x{byte:02X} here does not belong to a UTF-8 \
                         character (a case file must be UTF-8 text)"
                    ),
                })
            }
        }
    }

    /// Parses and validates a case from `text`; `file_label` names it in error messages,
    /// `layers` are the lower layers' checks ([`Case::from_str`]). A leading byte-order
    /// mark is ignored.
    pub fn parse_str(text: &str, file_label: &str, layers: LayerChecks) -> Result<Case, CaseError> {
        let text = text.strip_prefix('\u{FEFF}').unwrap_or(text);
        let case: Case = match ron_options().from_str(text) {
            Ok(case) => case,
            Err(e) => return Err(parse_error(e, text, file_label)),
        };
        let fields = FieldMap::scan(text);
        let violations = case.violations(&|path| fields.contains(path), layers);
        if violations.is_empty() {
            Ok(case)
        } else {
            let problems = violations
                .into_iter()
                .map(|violation| Problem {
                    position: fields.locate(&violation.field),
                    violation,
                    set: None,
                })
                .collect();
            Err(CaseError::Invalid {
                file: file_label.to_string(),
                problems,
            })
        }
    }

    /// Checks every range and consistency rule, and what the lower layers' checks `layers`
    /// refuse ([`Case::validate`] gives the mesh generator's, the material law's and the
    /// physics validators'); returns all violations.
    pub fn validate_with(&self, layers: LayerChecks) -> Result<(), Vec<Violation>> {
        let violations = self.violations(&|_| false, layers);
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
    // Each name once: an alias that differs from a name before it only in case and dashes
    // (the command line's `faer-condensed` after `FaerCondensed`) is left out.
    let one_of = |names: &[&str]| {
        let key = |n: &str| n.replace('-', "").to_ascii_lowercase();
        let names: Vec<String> = names
            .iter()
            .enumerate()
            .filter(|&(k, n)| !names[..k].iter().any(|m| key(m) == key(n)))
            .map(|(_, n)| format!("`{n}`"))
            .collect();
        names.join(", ")
    };
    if let Some((position, number)) = decimal_for_integer(&e.code, text, start)
        .or_else(|| decimal_for_integer(&e.code, text, end))
    {
        return CaseError::Parse {
            file: file.to_string(),
            position,
            field: fields.path_at(position).map(str::to_string),
            message: format!("expected an integer, found the decimal number `{number}`"),
        };
    }
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
            Position { line: 1, col: 1 },
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

/// The position just after the end of `text`.
fn end_of(text: &str) -> Position {
    let line = text.matches('\n').count() + 1;
    let col = text.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    Position { line, col }
}

/// If ron stopped inside (or, for an integer error, at the start of) a decimal number such
/// as `400.5` or `4e2`, the number's position and text: an integer field was given a
/// decimal number. Told from the text at the error position, whatever the field.
fn decimal_for_integer(
    code: &ron::error::Error,
    text: &str,
    at: Position,
) -> Option<(Position, String)> {
    use ron::error::Error as E;
    // Errors of an integer parse, reported at the number's start.
    let integer_error = matches!(
        code,
        E::ExpectedInteger | E::InvalidIntegerDigit { .. } | E::IntegerOutOfBounds
    );
    // Errors after a value that ended early: an integer parse stopped at `.` or `e`.
    let stopped_early = matches!(
        code,
        E::ExpectedComma
            | E::ExpectedStructLikeEnd
            | E::ExpectedOptionEnd
            | E::ExpectedArrayEnd
            | E::ExpectedMapEnd
            | E::TrailingCharacters
    );
    if !(integer_error || stopped_early) {
        return None;
    }
    let line: Vec<char> = text.lines().nth(at.line.checked_sub(1)?)?.chars().collect();
    let i = at.col.checked_sub(1)?;
    let in_number = |c: char| c.is_ascii_digit() || matches!(c, '.' | '_' | 'e' | 'E' | '+' | '-');
    let mut start = i.min(line.len());
    while start > 0 && in_number(line[start - 1]) {
        start -= 1;
    }
    let mut end = start;
    while end < line.len() && in_number(line[end]) {
        end += 1;
    }
    let inside = start < i && i < end;
    let at_start = start == i && i < end && integer_error;
    if !(inside || at_start) {
        return None;
    }
    // Not the tail of an identifier.
    if start > 0 && (line[start - 1].is_alphanumeric() || line[start - 1] == '_') {
        return None;
    }
    let number: String = line[start..end].iter().collect();
    let unsigned = number.trim_start_matches(['+', '-']);
    let decimal = unsigned.starts_with(|c: char| c.is_ascii_digit())
        && number.contains(['.', 'e', 'E'])
        && number.replace('_', "").parse::<f64>().is_ok();
    decimal.then_some((
        Position {
            line: at.line,
            col: start + 1,
        },
        number,
    ))
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
