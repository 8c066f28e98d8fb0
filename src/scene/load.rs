//! Loading a case: its schema and rules ([`crate::case`]) and, one layer up, what the mesh
//! generator, the material laws and the physics validators would refuse
//! ([`terms::layer_checks`]), so that a case that loads is one the run accepts. Each
//! refusal is reported at the case field (or the `--set` argument) it comes from.

use std::path::Path;

use super::terms;
use crate::case::{Case, CaseError, Override, Violation};

impl Case {
    /// Reads, parses and validates the case file at `path`.
    pub fn load(path: impl AsRef<Path>) -> Result<Case, CaseError> {
        Case::parse_file(path, terms::layer_checks)
    }

    /// Parses and validates a case from the bytes of a file, which must be UTF-8 text (a
    /// byte that is not is reported at its line and column); `file_label` names the file in
    /// error messages.
    pub fn from_bytes(bytes: &[u8], file_label: &str) -> Result<Case, CaseError> {
        Case::parse_bytes(bytes, file_label, terms::layer_checks)
    }

    /// Parses and validates a case from `text`; `file_label` names it in error messages.
    /// A leading byte-order mark is ignored.
    pub fn from_str(text: &str, file_label: &str) -> Result<Case, CaseError> {
        Case::parse_str(text, file_label, terms::layer_checks)
    }

    /// Reads the case file at `path`, applies `overrides` and validates the result. Errors
    /// in the file's text are located in the file; errors in an override's value name the
    /// `--set` argument ([`CaseError::Override`], or a [`crate::case::Problem`] whose `set`
    /// is the argument).
    pub fn load_with_overrides(
        path: impl AsRef<Path>,
        overrides: &[Override],
    ) -> Result<Case, CaseError> {
        Case::parse_file_with_overrides(path, overrides, terms::layer_checks)
    }

    /// As [`Case::from_str`], with `overrides` applied to the text first (see
    /// [`Case::load_with_overrides`]).
    pub fn from_str_with_overrides(
        text: &str,
        file_label: &str,
        overrides: &[Override],
    ) -> Result<Case, CaseError> {
        Case::parse_str_with_overrides(text, file_label, overrides, terms::layer_checks)
    }

    /// Checks every range and consistency rule, and what the mesh generator, the material
    /// law and the physics validators would refuse; returns all violations.
    pub fn validate(&self) -> Result<(), Vec<Violation>> {
        self.validate_with(terms::layer_checks)
    }
}
