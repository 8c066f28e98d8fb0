//! Loading a run directory: what `cellsim run` wrote, complete or not.
//!
//! A run writes `mesh.json` first, then `timeseries.csv` row by row (flushed), a
//! `state_<phase>.json` at each phase end and `summary.json` after every row (see
//! [`crate::run_files`]). An interrupted or failed run therefore leaves a CSV with fewer rows,
//! fewer states, and a summary with `finished = false`; a run killed mid-write may leave
//! a last CSV line cut short. All of these load: what is missing is recorded in
//! [`RunData::notes`]. What cannot be loaded is an absent or malformed `mesh.json` or
//! `timeseries.csv` (without them there is nothing to draw), or a state or summary file
//! that exists but is not what a run writes; the error names the file.

use std::path::{Path, PathBuf};

use serde::de::DeserializeOwned;

use super::{MeshFile, QuarterMeshFile, QuarterObservables, QuarterStateFile, StateFile, Summary};
use crate::model::observables::{
    COLUMNS, N_COLUMNS, OLD_CSV_HEADER, Observables, RowError, interpolate, parse_fields,
};

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

/// The name of the state file a run that stopped before its end writes at its last
/// accepted step (`state_stopped.json`), read after the phases' ones.
pub const STOPPED: &str = "stopped";

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
    /// The state files present, in phase order (a stopped run's last state last).
    pub states: Vec<StateFile>,
    /// `summary.json`, if present.
    pub summary: Option<Summary>,
    /// What was missing or cut short (empty for a complete run).
    pub notes: Vec<String>,
    /// A 3-D run's own files (`mesh3.json` instead of `mesh.json`). Its [`Self::mesh`]
    /// then holds only what the time plots use (substrate section, active regions, phase
    /// times), no elements, and [`Self::states`] is empty.
    pub three_d: Option<QuarterRunData>,
}

/// What a 3-D run writes besides the 2-D columns.
#[derive(Debug, Clone)]
pub struct QuarterRunData {
    /// `mesh3.json`.
    pub mesh: QuarterMeshFile,
    /// The 3-D columns of `timeseries.csv`, one per row of [`RunData::series`].
    pub series: Vec<QuarterObservables>,
    /// The state files present, in phase order (a stopped run's last state last).
    pub states: Vec<QuarterStateFile>,
}

/// The time plots' view of a 3-D mesh file: no elements, the section's substrate.
fn section_of(m: &QuarterMeshFile) -> MeshFile {
    MeshFile {
        nodes: Vec::new(),
        elements: Vec::new(),
        domains: Vec::new(),
        outer_edges: Vec::new(),
        nucleus_edges: Vec::new(),
        membrane_inner_edges: Vec::new(),
        substrate: m.substrate.plane,
        active: m.active,
        contact_eps: m.contact_eps,
        layer_thickness: m.layer_thickness,
        center: [m.center[0], m.center[1]],
        phase_times: m.phase_times,
    }
}

/// Reads `mesh3.json` and checks its indices.
pub fn read_quarter_mesh(path: &Path) -> Result<QuarterMeshFile, ReadError> {
    let mesh: QuarterMeshFile = read_json(path)?;
    let n = mesh.nodes.len();
    let bad = |what: String| ReadError::malformed(path, what);
    if mesh.elements.is_empty() {
        return Err(bad("no elements".into()));
    }
    if mesh.domains.len() != mesh.elements.len() {
        return Err(bad(format!(
            "{} domains for {} elements",
            mesh.domains.len(),
            mesh.elements.len()
        )));
    }
    let out = |ids: &[usize]| ids.iter().any(|&i| i >= n);
    if let Some(k) = mesh.elements.iter().position(|e| out(e)) {
        return Err(bad(format!("element {k} refers to a node ≥ {n}")));
    }
    if let Some(k) = mesh.outer_faces.iter().position(|f| out(f)) {
        return Err(bad(format!("outer face {k} refers to a node ≥ {n}")));
    }
    Ok(mesh)
}

/// Reads a 3-D state file and checks its sizes against the mesh.
pub fn read_quarter_state(
    path: &Path,
    mesh: &QuarterMeshFile,
) -> Result<QuarterStateFile, ReadError> {
    let sizes = [mesh.nodes.len(), mesh.elements.len()];
    read_checked(path, sizes, |s: &QuarterStateFile| {
        let st = &s.state;
        (&st.u, [st.element_strain.len(), st.element_jacobian.len()])
    })
}

/// Reads a state file whose displacements and per-element array lengths `parts` gives,
/// and checks them against its mesh's `nn` nodes and `ne` elements and finite.
fn read_checked<T: DeserializeOwned, const D: usize>(
    path: &Path,
    [nn, ne]: [usize; 2],
    parts: impl Fn(&T) -> (&Vec<[f64; D]>, [usize; 2]),
) -> Result<T, ReadError> {
    let s: T = read_json(path)?;
    let (u, per_element) = parts(&s);
    if u.len() != nn {
        return Err(ReadError::malformed(
            path,
            format!("{} displacements for the mesh's {nn} nodes", u.len()),
        ));
    }
    if per_element != [ne, ne] {
        return Err(ReadError::malformed(
            path,
            format!("per-element arrays do not match the mesh's {ne} elements"),
        ));
    }
    if u.iter().flatten().any(|v| !v.is_finite()) {
        return Err(ReadError::malformed(path, "non-finite displacement"));
    }
    Ok(s)
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
/// [`Observables::CSV_HEADER`], or it followed by [`QuarterObservables::CSV_COLUMNS`] (a
/// 3-D run: those columns are read by [`parse_quarter_timeseries`]); a file with the header
/// of an older cellsim ([`OLD_CSV_HEADER`]) is refused with a message saying so. A last
/// line without its newline that does not parse is taken as cut short by an interruption
/// and dropped (reported in the second value); any other bad line is an error naming the
/// line.
pub fn parse_timeseries(
    path: &Path,
    text: &str,
) -> Result<(Vec<Observables>, Option<String>), ReadError> {
    parse_quarter_timeseries(path, text).map(|(rows, _, cut)| (rows, cut))
}

/// The rows of a time series, the 3-D columns of each row (empty for a 2-D run), and a
/// note if the last line was cut short.
pub type QuarterRows = (Vec<Observables>, Vec<QuarterObservables>, Option<String>);

/// [`parse_timeseries`] with the 3-D columns of each row.
pub fn parse_quarter_timeseries(path: &Path, text: &str) -> Result<QuarterRows, ReadError> {
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
    let three_d = format!(
        "{},{}",
        Observables::CSV_HEADER,
        QuarterObservables::CSV_COLUMNS
    );
    let extra = if header == three_d { 4 } else { 0 };
    if header != Observables::CSV_HEADER && extra == 0 {
        return Err(ReadError::malformed(
            path,
            format!(
                "line 1: header is `{header}`, expected `{}`",
                Observables::CSV_HEADER
            ),
        ));
    }
    let mut rows = Vec::new();
    let mut rows3 = Vec::new();
    let mut cut = None;
    for (k, raw) in lines {
        let complete = raw.ends_with('\n');
        let line = raw.trim_end();
        if line.is_empty() {
            continue;
        }
        let parsed = if extra == 0 {
            Observables::parse_csv_row(line).map(|o| (o, None))
        } else {
            split_3d_row(line).and_then(|(two, three)| {
                Ok((
                    Observables::parse_csv_row(two)?,
                    Some(parse_3d_columns(three)?),
                ))
            })
        };
        match parsed {
            Ok((o, o3)) => {
                rows.push(o);
                rows3.extend(o3);
            }
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
    Ok((rows, rows3, cut))
}

/// A 3-D row split after its 2-D columns.
fn split_3d_row(line: &str) -> Result<(&str, &str), RowError> {
    let at = line
        .match_indices(',')
        .nth(N_COLUMNS - 1)
        .map(|(i, _)| i)
        .ok_or(RowError::TooFew(N_COLUMNS + 4))?;
    Ok((&line[..at], &line[at + 1..]))
}

fn parse_3d_columns(text: &str) -> Result<QuarterObservables, RowError> {
    let v = parse_fields(text)?;
    match v[..] {
        [
            contact_area,
            contact_area_ref,
            contact_radius_equiv,
            penetration_depth,
        ] => Ok(QuarterObservables {
            contact_area,
            contact_area_ref,
            contact_radius_equiv,
            penetration_depth,
        }),
        _ => Err(RowError::Fields {
            found: N_COLUMNS + v.len(),
            expected: N_COLUMNS + 4,
        }),
    }
}

/// Reads a state file and checks its sizes against the mesh.
pub fn read_state(path: &Path, mesh: &MeshFile) -> Result<StateFile, ReadError> {
    let sizes = [mesh.nodes.len(), mesh.elements.len()];
    read_checked(path, sizes, |s: &StateFile| {
        (&s.u, [s.element_strain.len(), s.element_jacobian.len()])
    })
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
        let mesh3_path = dir.join("mesh3.json");
        let mesh3 = if !dir.join("mesh.json").exists() && mesh3_path.exists() {
            Some(read_quarter_mesh(&mesh3_path)?)
        } else {
            None
        };
        let mesh = match &mesh3 {
            Some(m) => section_of(m),
            None => read_mesh(&dir.join("mesh.json"))?,
        };
        let csv_path = dir.join("timeseries.csv");
        let (series, series3, cut) = parse_quarter_timeseries(&csv_path, &read_text(&csv_path)?)?;
        if mesh3.is_some() && series3.len() != series.len() {
            return Err(ReadError::malformed(
                &csv_path,
                "a 3-D run (mesh3.json) without the 3-D columns",
            ));
        }
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
        let mut states3 = Vec::new();
        for phase in PHASES.into_iter().chain([STOPPED]) {
            let p = dir.join(format!("state_{phase}.json"));
            if p.exists() {
                match &mesh3 {
                    Some(m) => states3.push(read_quarter_state(&p, m)?),
                    None => states.push(read_state(&p, &mesh)?),
                }
            }
        }
        let mut three_d = mesh3.map(|mesh| QuarterRunData {
            mesh,
            series: series3,
            states: states3,
        });
        // The phase lines of a run whose cell started its phases itself.
        let mut mesh = mesh;
        if let Some(times) = summary.as_ref().and_then(|s| s.phase_times) {
            let times = times.map(|t| t.unwrap_or(f64::NAN));
            mesh.phase_times = times;
            if let Some(t3) = three_d.as_mut() {
                t3.mesh.phase_times = times;
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
            three_d,
        })
    }

    /// Whether the summary says the run reached its end time.
    pub fn finished(&self) -> bool {
        self.summary.as_ref().is_some_and(|s| s.finished)
    }

    /// End time the run was meant to reach \[s\].
    pub fn t_end(&self) -> f64 {
        self.mesh.phase_times[3]
    }

    /// Last time written \[s\] (0 without rows).
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

#[cfg(test)]
mod round_trip {
    use super::*;

    /// Every number a run writes to JSON reads back as the same double: sweep.csv copies
    /// the final values from summary.json, and must hold the digits timeseries.csv holds.
    /// Without serde_json's `float_roundtrip`, -0.48454310266656725 (a sweep's uy_top)
    /// read back as its neighbour -0.4845431026665673.
    #[test]
    fn doubles_written_to_json_read_back_exactly() {
        let dir = std::env::temp_dir().join(format!("cellsim-json-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("values.json");
        let mut rng = oorandom::Rand64::new(7);
        let mut values = vec![-0.484_543_102_666_567_25_f64, 1e-300, -5e-324, f64::MAX];
        values.extend((0..20_000).map(|_| {
            let mantissa = rng.rand_float() * 2.0 - 1.0;
            mantissa * 10f64.powi(rng.rand_range(0..40) as i32 - 20)
        }));
        crate::run_files::write_json(&path, &values).unwrap();
        let back: Vec<f64> = read_json(&path).unwrap();
        let _ = std::fs::remove_dir_all(&dir);
        for (a, b) in values.iter().zip(&back) {
            assert_eq!(a.to_bits(), b.to_bits(), "{a} read back as {b}");
        }
        assert_eq!(back.len(), values.len());
    }
}
