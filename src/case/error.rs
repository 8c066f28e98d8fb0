//! Errors of loading a case file. Each names the file, the position (line:column) and the
//! field (dotted path), in the form compilers use:
//!
//! ```text
//! cases/flat.ron:14:9: materials.nucleus.nu = 0.5 is out of range (must satisfy -1 < nu < 0.5)
//! ```

use std::fmt;

use super::locate::Position;
use super::validate::Violation;

/// Why a case file could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum CaseError {
    /// The file could not be read.
    #[error("{file}: cannot read the case file: {source}")]
    Read {
        /// The file, as given.
        file: String,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// The text is not a case: RON syntax, a missing required field, a value of the wrong
    /// type, an unknown field or enum variant.
    #[error("{file}:{position}: {}{message}", field_prefix(field))]
    Parse {
        /// The file, as given.
        file: String,
        /// Where ron stopped.
        position: Position,
        /// Dotted path of the field concerned, when it can be told.
        field: Option<String>,
        /// What is wrong.
        message: String,
    },
    /// A `--set PATH=VALUE` override does not apply or gives a value of the wrong type.
    #[error("{arg}: {}{message}", field_prefix(field))]
    Override {
        /// The file the override was applied to.
        file: String,
        /// The override as the message names it ([`super::Override::label`]):
        /// `--set PATH=VALUE`, or the sweep file entry it comes from.
        arg: String,
        /// Dotted path of the field concerned, when it can be told.
        field: Option<String>,
        /// What is wrong.
        message: String,
    },
    /// The case parses, but values are out of range or inconsistent. Lists every problem
    /// found, one per line.
    #[error("{}", render(file, problems))]
    Invalid {
        /// The file, as given.
        file: String,
        /// The problems, in schema order (at least one).
        problems: Vec<Problem>,
    },
}

/// A [`Violation`] with the place the file writes the field, if it does.
#[derive(Debug, Clone, PartialEq)]
pub struct Problem {
    /// The broken rule.
    pub violation: Violation,
    /// Position of the field's name in the file; `None` if the file does not write the
    /// field (the value is a default).
    pub position: Option<Position>,
    /// The override that wrote the field's value, as the message names it
    /// (`--set PATH=VALUE`, or a sweep file's axis), if an override did (then `position`
    /// is `None`).
    pub set: Option<String>,
}

impl Problem {
    /// Formats the problem as one line prefixed by the file and position.
    pub fn render(&self, file: &str) -> String {
        match (&self.set, self.position) {
            (Some(arg), _) => format!("{arg}: {}", self.violation.describe(false)),
            (None, Some(p)) => format!("{file}:{p}: {}", self.violation.describe(false)),
            (None, None) => format!("{file}: {}", self.violation.describe(true)),
        }
    }
}

fn field_prefix(field: &Option<String>) -> String {
    match field {
        Some(f) if !f.is_empty() => format!("{f}: "),
        _ => String::new(),
    }
}

fn render(file: &str, problems: &[Problem]) -> String {
    let lines: Vec<String> = problems.iter().map(|p| p.render(file)).collect();
    lines.join("\n")
}

impl CaseError {
    /// The file the error is about.
    pub fn file(&self) -> &str {
        match self {
            CaseError::Read { file, .. }
            | CaseError::Parse { file, .. }
            | CaseError::Override { file, .. }
            | CaseError::Invalid { file, .. } => file,
        }
    }

    /// Dotted path of the (first) field concerned, if any.
    pub fn field(&self) -> Option<&str> {
        match self {
            CaseError::Read { .. } => None,
            CaseError::Parse { field, .. } | CaseError::Override { field, .. } => field.as_deref(),
            CaseError::Invalid { problems, .. } => {
                problems.first().map(|p| p.violation.field.as_str())
            }
        }
    }

    /// Position of the (first) error in the file, if it has one.
    pub fn position(&self) -> Option<Position> {
        match self {
            CaseError::Read { .. } | CaseError::Override { .. } => None,
            CaseError::Parse { position, .. } => Some(*position),
            CaseError::Invalid { problems, .. } => problems.first().and_then(|p| p.position),
        }
    }
}

/// The violation without the file name, noting when the value is a default.
impl fmt::Display for Problem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let default = self.position.is_none() && self.set.is_none();
        f.write_str(&self.violation.describe(default))
    }
}
