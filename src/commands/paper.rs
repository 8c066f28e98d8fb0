//! `cellsim paper`: the five scenes of MODEL.md §7 (and the upside-down control), run in
//! parallel into `DIR/runs/<scene>/`, then the paper's figures and the comparison with
//! what the paper reports, drawn from those files ([`crate::render::paper`]).
//!
//! The scenes are the case files of `cases/`, compiled into the binary (so the command
//! works from any directory; `--cases DIR` reads them from a directory instead).

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Instant;

use indicatif::MultiProgress;

use crate::case::Case;
use crate::render::paper::{CONTROL, PaperReport, SCENES, SceneOutcome, draw_paper};
use crate::render::{OutputError, RunData, SnapshotOptions};
use crate::run::{self, Member, Progress, RunError, RunOptions};
use crate::run_files::Summary;
use crate::solver::Limits;
use crate::stop::StopFlag;

/// Options of [`run_paper`].
#[derive(Debug, Clone)]
pub struct PaperOptions {
    /// Output directory (figures, `comparison.md`, `runs/`).
    pub out: PathBuf,
    /// Runs at once.
    pub jobs: usize,
    /// Read the case files from this directory instead of the compiled-in copies.
    pub cases: Option<PathBuf>,
    /// Do not rerun a scene whose run directory holds a finished run.
    pub reuse: bool,
    /// Per-output-time files of each run (`--vtu`, `--gif`).
    pub snapshots: SnapshotOptions,
    /// Show progress lines.
    pub progress: bool,
    /// Set to stop every run cleanly.
    pub interrupt: StopFlag,
}

/// Why the paper's cases could not be had.
#[derive(Debug, thiserror::Error)]
pub enum PaperCasesError {
    /// A case file could not be read or is not a case.
    #[error(transparent)]
    Case(#[from] crate::case::CaseError),
    /// A case file holds another scene than the one expected.
    #[error("{label}: case name `{found}`, expected `{expected}`")]
    Name {
        /// The file (or compiled-in copy).
        label: String,
        /// The case's name.
        found: String,
        /// The scene's name.
        expected: &'static str,
    },
}

/// The cases to run: the five scenes and the control, each with its label for messages.
pub fn paper_cases(cases_dir: Option<&Path>) -> Result<Vec<(Case, String)>, PaperCasesError> {
    let mut out = Vec::new();
    for s in SCENES {
        let (case, label) = match cases_dir {
            Some(d) => {
                let p = d.join(Path::new(s.file).file_name().unwrap_or_default());
                (Case::load(&p)?, p.display().to_string())
            }
            None => (Case::from_str(s.text, s.file)?, s.file.to_string()),
        };
        if case.name != s.name {
            return Err(PaperCasesError::Name {
                label,
                found: case.name,
                expected: s.name,
            });
        }
        out.push((case, label));
    }
    let push_pull = out.iter().find(|(c, _)| c.name == "pillars-push-pull");
    let upside = out.iter().find(|(c, _)| c.name == "upside-down");
    if let (Some((pp, label)), Some((ud, _))) = (push_pull, upside) {
        let mut control = pp.clone();
        control.name = CONTROL.to_string();
        control.description = Some(
            "Control of the upside-down scene: push-pull continued to its end time, gravity unchanged"
                .into(),
        );
        control.phases.t_end = ud.phases.t_end;
        control.output = ud.output.clone();
        let label = format!("{label} (continued to t = {} s)", ud.phases.t_end);
        out.push((control, label));
    }
    Ok(out)
}

/// Runs `cases` into `out/runs/<name>/`, `jobs` tasks at a time, computing together what
/// their cases share ([`run::run_all`]: the pillar scenes are one run up to T_as0), one
/// progress line per stretch.
pub fn run_cases(cases: &[(Case, String)], opts: &PaperOptions) -> Vec<SceneOutcome> {
    let runs_dir = opts.out.join("runs");
    let visible = opts.progress && std::io::stderr().is_terminal();
    let mp = MultiProgress::new();
    if !visible {
        mp.set_draw_target(indicatif::ProgressDrawTarget::hidden());
    }
    let say = |msg: String| {
        if visible {
            let _ = mp.println(&msg);
        } else if opts.progress {
            let _ =
                std::io::Write::write_all(&mut std::io::stderr(), format!("{msg}\n").as_bytes());
        }
    };
    let mut outcomes: Vec<Option<SceneOutcome>> = vec![None; cases.len()];
    // The scenes to run (the others reused or not started), by index into `cases`.
    let mut to_run = Vec::new();
    for (k, (case, _)) in cases.iter().enumerate() {
        let name = case.name.clone();
        let dir = runs_dir.join(&name);
        if opts.reuse && RunData::load(&dir).is_ok_and(|r| r.finished()) {
            say(format!(
                "{name}: reusing the finished run in {}",
                dir.display()
            ));
            outcomes[k] = Some(SceneOutcome {
                name,
                dir,
                result: Ok(false),
            });
        } else if opts.interrupt.is_set() {
            outcomes[k] = Some(SceneOutcome {
                result: Err(format!("{name}: interrupted before it started")),
                name,
                dir,
            });
        } else {
            to_run.push(k);
        }
    }
    let members: Vec<Member> = to_run
        .iter()
        .map(|&k| {
            let (case, label) = &cases[k];
            Member {
                case,
                file: label,
                opts: RunOptions {
                    out: runs_dir.join(&case.name),
                    settings: case.solver.clone(),
                    limits: Limits::default(),
                    progress: Progress::Hidden,
                    interrupt: opts.interrupt.clone(),
                    snapshots: opts.snapshots,
                },
            }
        })
        .collect();
    let progress = |label: &str, t_end: f64| {
        if visible {
            Progress::Bar(run::progress_bar_labelled(label, t_end, true, Some(&mp)))
        } else if opts.progress {
            Progress::Lines {
                label: label.to_string(),
                every: run::PROGRESS_LINE_INTERVAL,
            }
        } else {
            Progress::Hidden
        }
    };
    let start = Instant::now();
    let done = |i: usize, result: &Result<Summary, RunError>| {
        let name = &members[i].case.name;
        match result {
            Ok(s) => say(format!(
                "{name}: finished t = {} s in {:.1} s wall ({} steps{})",
                s.final_values.map(|o| o.t).unwrap_or(0.0),
                s.wall_seconds,
                s.stats.steps,
                shared_note(s)
            )),
            Err(e) => say(format!(
                "{name}: stopped after {:.1} s: {e}",
                start.elapsed().as_secs_f64()
            )),
        }
    };
    let results = run::run_all(&members, opts.jobs, true, &progress, &done);
    for (&k, result) in to_run.iter().zip(results) {
        let name = cases[k].0.name.clone();
        outcomes[k] = Some(SceneOutcome {
            dir: runs_dir.join(&name),
            result: result.map(|_| true).map_err(|e| e.to_string()),
            name,
        });
    }
    outcomes
        .into_iter()
        .zip(cases)
        .map(|(r, (c, _))| {
            r.unwrap_or_else(|| SceneOutcome {
                name: c.name.clone(),
                dir: runs_dir.join(&c.name),
                result: Err(format!("{}: not run", c.name)),
            })
        })
        .collect()
}

/// "; parted from A, B at t = … s" for a run computed together with others at its start.
fn shared_note(s: &Summary) -> String {
    s.shared
        .iter()
        .map(|p| format!("; parted from {} at t = {} s", p.from.join(", "), p.t))
        .collect()
}

/// `cellsim paper`: runs the scenes (unless reused), then writes the figures and
/// `comparison.md` into `opts.out`.
pub fn run_paper(opts: &PaperOptions) -> Result<PaperReport, OutputError> {
    crate::render::create_dir(&opts.out)?;
    let cases =
        paper_cases(opts.cases.as_deref()).map_err(|m| crate::run_files::ReadError::Malformed {
            path: opts
                .cases
                .as_ref()
                .map(|p| p.display().to_string())
                .unwrap_or_else(|| "cases (compiled in)".into()),
            message: m.to_string(),
        })?;
    let start = Instant::now();
    let runs = run_cases(&cases, opts);
    let runs_seconds = start.elapsed().as_secs_f64();
    let mut report = draw_paper(&opts.out, &runs);
    report.runs = runs;
    report.runs_seconds = runs_seconds;
    Ok(report)
}
