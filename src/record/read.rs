//! Loading a run directory: what `cellsim run` wrote, complete or not.
//!
//! A run writes `mesh.json` first, then `timeseries.csv` row by row (flushed), a
//! `state_<phase>.json` at each phase end and `summary.json` after every row (see
//! [`crate::record`]). An interrupted or failed run therefore leaves a CSV with fewer rows,
//! fewer states, and a summary with `finished = false`; a run killed mid-write may leave
//! a last CSV line cut short. All of these load: what is missing is recorded in
//! [`RunData::notes`]. What cannot be loaded is an absent or malformed `mesh.json` or
//! `timeseries.csv` (without them there is nothing to draw), or a state or summary file
//! that exists but is not what a run writes; the error names the file.

use std::path::{Path, PathBuf};

use serde::de::DeserializeOwned;

use super::observables::{COLUMNS, OLD_CSV_HEADER, Observables, interpolate};
use super::{MeshFile, StateFile, Summary};

/// Why a run directory's file could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    /// A file could not be read (missing, unreadable).
    #[error("cannot read {path}: {source}")]
    Read {
        /// The file.
        path: String,
        /// Cause.
        source: std::io::Error,
    },
    /// A file was read but its content is not what a run writes.
    #[error("{path}: {message}")]
    Malformed {
        /// The file.
        path: String,
        /// What is wrong, with the line or field where known.
        message: String,
    },
}

impl ReadError {
    /// A [`ReadError::Malformed`] for `path`.
    pub fn malformed(path: &Path, message: impl Into<String>) -> Self {
        ReadError::Malformed {
            path: path.display().to_string(),
            message: message.into(),
        }
    }
}

/// The phases whose end a state file records, in time order (`state_<phase>.json`).
pub const PHASES: [&str; 4] = ["gravity", "spreading", "active", "end"];

/// Everything a run directory holds, as read back from its files.
#[derive(Debug, Clone)]
pub struct RunData {
    /// The run directory.
    pub dir: PathBuf,
    /// Name of the run: the summary's case name, else the directory's name.
    pub name: String,
    /// `mesh.json`: reference mesh, substrate, active regions, phase times.
    pub mesh: MeshFile,
    /// `timeseries.csv`: one row per output time written, in time order.
    pub series: Vec<Observables>,
    /// The state files present, in phase order.
    pub states: Vec<StateFile>,
    /// `summary.json`, if present.
    pub summary: Option<Summary>,
    /// What was missing or cut short (empty for a complete run).
    pub notes: Vec<String>,
}

fn read_text(path: &Path) -> Result<String, ReadError> {
    std::fs::read_to_string(path).map_err(|source| ReadError::Read {
        path: path.display().to_string(),
        source,
    })
}

fn read_json<T: DeserializeOwned>(path: &Path) -> Result<T, ReadError> {
    let text = read_text(path)?;
    serde_json::from_str(&text).map_err(|e| ReadError::malformed(path, e.to_string()))
}

/// Reads `dir/summary.json`. One written by an older cellsim, whose final values lack the
/// paper's measures, is refused with a message saying so.
pub fn read_summary(dir: &Path) -> Result<Summary, ReadError> {
    let path = dir.join("summary.json");
    read_json(&path).map_err(|e| match e {
        ReadError::Malformed { path, message } if older_observables(&message) => {
            ReadError::Malformed {
                path,
                message: format!(
                    "{message}: written by an older cellsim (final values without {}); run \
                     the case again",
                    new_columns()
                ),
            }
        }
        e => e,
    })
}

/// Whether a JSON error says that a row of observables lacks one of the newer columns.
fn older_observables(message: &str) -> bool {
    let old = OLD_CSV_HEADER.split(',').count();
    COLUMNS[old..]
        .iter()
        .any(|c| message.contains(&format!("missing field `{c}`")))
}

/// Reads `mesh.json` and checks that every index it holds is in range.
pub fn read_mesh(path: &Path) -> Result<MeshFile, ReadError> {
    let mesh: MeshFile = read_json(path)?;
    let n = mesh.nodes.len();
    let bad = |what: &str| ReadError::malformed(path, what.to_string());
    if mesh.elements.is_empty() {
        return Err(bad("no elements"));
    }
    if mesh.domains.len() != mesh.elements.len() {
        return Err(bad(&format!(
            "{} domains for {} elements",
            mesh.domains.len(),
            mesh.elements.len()
        )));
    }
    let in_range = |ids: &[usize]| ids.iter().all(|&i| i < n);
    for (k, el) in mesh.elements.iter().enumerate() {
        if !in_range(el) {
            return Err(bad(&format!("element {k} refers to a node ≥ {n}")));
        }
    }
    for (name, edges) in [
        ("outer_edges", &mesh.outer_edges),
        ("nucleus_edges", &mesh.nucleus_edges),
        ("membrane_inner_edges", &mesh.membrane_inner_edges),
    ] {
        if edges.iter().any(|e| !in_range(e)) {
            return Err(bad(&format!("{name} refers to a node ≥ {n}")));
        }
    }
    if mesh.nodes.iter().flatten().any(|v| !v.is_finite()) {
        return Err(bad("non-finite node coordinate"));
    }
    Ok(mesh)
}

/// The columns a current `timeseries.csv` has after those of [`OLD_CSV_HEADER`].
fn new_columns() -> String {
    let old = OLD_CSV_HEADER.split(',').count();
    COLUMNS[old..].join(", ")
}

/// Parses `timeseries.csv`. The header must be exactly
/// [`Observables::CSV_HEADER`]; a file with the header of an older cellsim
/// ([`OLD_CSV_HEADER`]) is refused with a message saying so. A last line without its newline that does not parse is
/// taken as cut short by an interruption and dropped (reported in the second value);
/// any other bad line is an error naming the line.
pub fn parse_timeseries(
    path: &Path,
    text: &str,
) -> Result<(Vec<Observables>, Option<String>), ReadError> {
    let mut lines = text.split_inclusive('\n').enumerate();
    let header = match lines.next() {
        Some((_, h)) => h.trim_end(),
        None => return Err(ReadError::malformed(path, "empty file (no header)")),
    };
    if header == OLD_CSV_HEADER {
        return Err(ReadError::malformed(
            path,
            format!(
                "line 1: written by an older cellsim (header `{header}`): it lacks the \
                 columns {} and its strain_cytoplasm excludes the membrane, so it cannot be \
                 read as a current run; run the case again",
                new_columns()
            ),
        ));
    }
    if header != Observables::CSV_HEADER {
        return Err(ReadError::malformed(
            path,
            format!(
                "line 1: header is `{header}`, expected `{}`",
                Observables::CSV_HEADER
            ),
        ));
    }
    let mut rows = Vec::new();
    let mut cut = None;
    for (k, raw) in lines {
        let complete = raw.ends_with('\n');
        let line = raw.trim_end();
        if line.is_empty() {
            continue;
        }
        match Observables::parse_csv_row(line) {
            Ok(o) => rows.push(o),
            Err(msg) if !complete => {
                cut = Some(format!(
                    "{}: last line {} cut short ({msg}); dropped",
                    path.display(),
                    k + 1
                ));
            }
            Err(msg) => {
                return Err(ReadError::malformed(path, format!("line {}: {msg}", k + 1)));
            }
        }
    }
    if rows.windows(2).any(|w| !(w[1].t >= w[0].t)) {
        return Err(ReadError::malformed(path, "times are not increasing"));
    }
    Ok((rows, cut))
}

/// Reads a state file and checks its sizes against the mesh.
pub fn read_state(path: &Path, mesh: &MeshFile) -> Result<StateFile, ReadError> {
    let s: StateFile = read_json(path)?;
    let (nn, ne) = (mesh.nodes.len(), mesh.elements.len());
    if s.u.len() != nn {
        return Err(ReadError::malformed(
            path,
            format!("{} displacements for the mesh's {nn} nodes", s.u.len()),
        ));
    }
    if s.element_strain.len() != ne || s.element_jacobian.len() != ne {
        return Err(ReadError::malformed(
            path,
            format!("per-element arrays do not match the mesh's {ne} elements"),
        ));
    }
    if s.u.iter().flatten().any(|v| !v.is_finite()) {
        return Err(ReadError::malformed(path, "non-finite displacement"));
    }
    Ok(s)
}

impl RunData {
    /// Loads the run in `dir`; see the module documentation for what may be missing.
    pub fn load(dir: impl AsRef<Path>) -> Result<RunData, ReadError> {
        let dir = dir.as_ref().to_path_buf();
        if !dir.is_dir() {
            return Err(ReadError::Read {
                path: dir.display().to_string(),
                source: std::io::Error::new(
                    std::io::ErrorKind::NotFound,
                    "not a run directory (no such directory)",
                ),
            });
        }
        let mesh = read_mesh(&dir.join("mesh.json"))?;
        let csv_path = dir.join("timeseries.csv");
        let (series, cut) = parse_timeseries(&csv_path, &read_text(&csv_path)?)?;
        let mut notes: Vec<String> = cut.into_iter().collect();
        if series.is_empty() {
            notes.push(format!("{}: no data rows", csv_path.display()));
        }
        let summary_path = dir.join("summary.json");
        let summary: Option<Summary> = if summary_path.exists() {
            Some(read_summary(&dir)?)
        } else {
            notes.push(format!("{}: missing", summary_path.display()));
            None
        };
        let mut states = Vec::new();
        for phase in PHASES {
            let p = dir.join(format!("state_{phase}.json"));
            if p.exists() {
                states.push(read_state(&p, &mesh)?);
            }
        }
        if let Some(s) = &summary {
            if !s.finished {
                let why = s
                    .failure
                    .as_ref()
                    .map(|f| f.reason.clone())
                    .unwrap_or_else(|| "interrupted or still running".into());
                let t = series.last().map(|o| o.t).unwrap_or(0.0);
                notes.push(format!(
                    "{}: run did not finish (last output t = {t} s of {} s): {why}",
                    dir.display(),
                    mesh.phase_times[3]
                ));
            }
        }
        let name = summary
            .as_ref()
            .map(|s| s.case.clone())
            .or_else(|| dir.file_name().map(|n| n.to_string_lossy().into_owned()))
            .unwrap_or_else(|| "run".into());
        Ok(RunData {
            dir,
            name,
            mesh,
            series,
            states,
            summary,
            notes,
        })
    }

    /// Whether the summary says the run reached its end time.
    pub fn finished(&self) -> bool {
        self.summary.as_ref().is_some_and(|s| s.finished)
    }

    /// End time the run was meant to reach [s].
    pub fn t_end(&self) -> f64 {
        self.mesh.phase_times[3]
    }

    /// Last time written [s] (0 without rows).
    pub fn t_last(&self) -> f64 {
        self.series.last().map(|o| o.t).unwrap_or(0.0)
    }

    /// The row at time `t` (linear interpolation between rows), if `t` lies within the
    /// rows written.
    pub fn at(&self, t: f64) -> Option<Observables> {
        interpolate(&self.series, t)
    }

    /// The state file of `phase`, if written.
    pub fn state(&self, phase: &str) -> Option<&StateFile> {
        self.states.iter().find(|s| s.phase == phase)
    }
}
