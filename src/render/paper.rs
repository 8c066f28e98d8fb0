//! The paper's scenes, what the paper reports about them, and the figures and comparison
//! table drawn from their runs (`cellsim paper`; the runs themselves are made by
//! [`crate::commands::paper`]).
//!
//! The scenes are the case files of `cases/`, compiled into the binary ([`super::scenes`],
//! re-exported here). Beside them runs a **control**: the push-pull scene continued to the
//! upside-down scene's end time with gravity unchanged, the "control" curve of the paper's
//! Fig. 9 — the paper's 0.006 µm is the difference between the two at the same time.
//!
//! Each reported value is compared with the cellsim measure that matches how the paper
//! measures it (MODEL.md §7, "How the paper measures"; [`Quantity::measures`]): the contact
//! radius along the reference contour, the cytoplasm with the membrane, the maximum
//! nucleus displacement over all nucleus points; our other measures of the same quantity
//! are shown beside it.
//!
//! The figures and `comparison.md` are drawn from the run directories' files only (see
//! [`crate::run_files::read`]), so they can be redrawn from runs that stopped early.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use super::OutputError;
use super::geometry::{Backdrop, Bounds};
use super::scenes::run_phases;
use super::shapes::{shape_figure_cached, shape_view};
use super::strain_bars::{StrainBars, strain_bars_figure};
use super::time_plots::{
    Compared, DisplacementMarks, contact_radius_figure, displacement_figure, strain_time_figure,
    upside_down_figure,
};
use crate::fem::Domain;
use crate::run_files::{MeshFile, Observables, RunData, StateFile};

pub use super::scenes::{CONTROL, SCENES, Scene};

/// When a reported value applies.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum When {
    /// At T_g0, the end of the gravity ramp.
    GravityEnd,
    /// At T_as0, the end of the adhesion ramp.
    SpreadingEnd,
    /// At the scene's end time.
    End,
}

/// A quantity the paper reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Quantity {
    /// Contact radius \[µm\].
    ContactRadius(When),
    /// Downward displacement of the nucleus, −u_y \[µm\]; at T_g0 and T_as0 the nucleus top
    /// p_t's; at the end the paper's "maximum displacement of the nucleus", the largest
    /// over the nucleus and the run (see [`Quantity::measures`]).
    NucleusDisplacement(When),
    /// Mean ‖E‖ over the nucleus at the end (fraction).
    StrainNucleus,
    /// Mean ‖E‖ over the paper's cytoplasm Ω_cp, which includes the membrane, at the end
    /// (fraction).
    StrainCytoplasm,
    /// |u_y(p_t)| difference between the upside-down run and the control at the end \[µm\]
    /// (p_t, the point the paper's Fig. 9 plots).
    UpsideDownDifference,
}

/// One value the paper reports, with where it says so.
#[derive(Debug, Clone, Copy)]
pub struct Reported {
    /// Scene.
    pub scene: &'static str,
    /// Quantity.
    pub quantity: Quantity,
    /// The paper's value (µm, or a fraction for strains).
    pub value: f64,
    /// Where in the paper (Mondésert-Deveraux, Aubry & Allena 2019).
    pub source: &'static str,
}

/// Everything the paper reports that a run can be compared with (MODEL.md §7, which
/// quotes the paper's Sect. 3): the single table the figures and `comparison.md` use.
pub const REPORTED: [Reported; 18] = {
    use Quantity::*;
    use When::*;
    const S32: &str = "Sect. 3.2";
    [
        Reported {
            scene: "flat",
            quantity: ContactRadius(GravityEnd),
            value: 1.0,
            source: "Sect. 3.1, Fig. 6b (\"up to 1 µm\")",
        },
        Reported {
            scene: "flat",
            quantity: ContactRadius(End),
            value: 8.8,
            source: "Sect. 3.1, Fig. 6b",
        },
        Reported {
            scene: "pillars-push",
            quantity: NucleusDisplacement(GravityEnd),
            value: 0.1,
            source: S32,
        },
        Reported {
            scene: "pillars-push",
            quantity: NucleusDisplacement(SpreadingEnd),
            value: 5.0,
            source: S32,
        },
        Reported {
            scene: "pillars-push",
            quantity: NucleusDisplacement(End),
            value: 5.4,
            source: "Sect. 3.2, Fig. 8a-c",
        },
        Reported {
            scene: "pillars-push",
            quantity: StrainNucleus,
            value: 0.13,
            source: "Sect. 3.2, Fig. 7a",
        },
        Reported {
            scene: "pillars-push",
            quantity: StrainCytoplasm,
            value: 0.56,
            source: "Sect. 3.2, Fig. 7d",
        },
        Reported {
            scene: "pillars-pull",
            quantity: NucleusDisplacement(GravityEnd),
            value: 0.1,
            source: S32,
        },
        Reported {
            scene: "pillars-pull",
            quantity: NucleusDisplacement(SpreadingEnd),
            value: 5.0,
            source: S32,
        },
        Reported {
            scene: "pillars-pull",
            quantity: NucleusDisplacement(End),
            value: 9.63,
            source: "Sect. 3.2, Fig. 8d-f",
        },
        Reported {
            scene: "pillars-pull",
            quantity: StrainNucleus,
            value: 0.37,
            source: "Sect. 3.2, Fig. 7b",
        },
        Reported {
            scene: "pillars-pull",
            quantity: StrainCytoplasm,
            value: 0.59,
            source: "Sect. 3.2, Fig. 7e",
        },
        Reported {
            scene: "pillars-push-pull",
            quantity: NucleusDisplacement(GravityEnd),
            value: 0.1,
            source: S32,
        },
        Reported {
            scene: "pillars-push-pull",
            quantity: NucleusDisplacement(SpreadingEnd),
            value: 5.0,
            source: S32,
        },
        Reported {
            scene: "pillars-push-pull",
            quantity: NucleusDisplacement(End),
            value: 9.65,
            source: "Sect. 3.2, Fig. 8g-i",
        },
        Reported {
            scene: "pillars-push-pull",
            quantity: StrainNucleus,
            value: 0.37,
            source: "Sect. 3.2, Fig. 7c",
        },
        Reported {
            scene: "pillars-push-pull",
            quantity: StrainCytoplasm,
            value: 0.69,
            source: "Sect. 3.2, Fig. 7f",
        },
        Reported {
            scene: "upside-down",
            quantity: UpsideDownDifference,
            value: 0.006,
            source: "Sect. 3.3, Fig. 9",
        },
    ]
};

/// The reported values of one scene.
pub fn reported_for(scene: &str) -> impl Iterator<Item = &'static Reported> + '_ {
    REPORTED.iter().filter(move |r| r.scene == scene)
}

impl Quantity {
    /// Description with units, for the table.
    pub fn describe(&self) -> String {
        let when = |w: &When| match w {
            When::GravityEnd => "at T_g0 = end of gravity ramp",
            When::SpreadingEnd => "at T_as0 = end of adhesion ramp",
            When::End => "at the end",
        };
        match self {
            Quantity::ContactRadius(w) => format!("contact radius {} (µm)", when(w)),
            Quantity::NucleusDisplacement(When::End) => {
                "maximum downward displacement of the nucleus (µm)".into()
            }
            Quantity::NucleusDisplacement(w) => {
                format!("downward displacement of the nucleus {} (µm)", when(w))
            }
            Quantity::StrainNucleus => "mean ‖E‖ of the nucleus at the end (%)".into(),
            Quantity::StrainCytoplasm => "mean ‖E‖ of the cytoplasm at the end (%)".into(),
            Quantity::UpsideDownDifference => {
                "difference of the nucleus displacement, upside down − control, at the end, \
                 absolute (µm)"
                    .into()
            }
        }
    }

    /// Whether values are fractions shown as %.
    fn percent(&self) -> bool {
        matches!(self, Quantity::StrainNucleus | Quantity::StrainCytoplasm)
    }

    /// The cellsim measure compared with the paper's value (the one matching the paper's
    /// definition, MODEL.md §7 "How the paper measures"), and the other measures of the
    /// same quantity shown beside it.
    pub fn measures(&self) -> (Measure, &'static [Measure]) {
        use Measure::*;
        match self {
            Quantity::ContactRadius(_) => (ContactReference, &[ContactDeformed]),
            // "Maximum displacement of the nucleus" (Sect. 3.2) names no point: the largest
            // over the nucleus; p_t (the point Fig. 9 plots) beside it.
            Quantity::NucleusDisplacement(When::End) => (NucleusLowest, &[NucleusTop]),
            // Values at a time read off a displacement curve: Fig. 9's curve is p_t's.
            Quantity::NucleusDisplacement(_) => (NucleusTop, &[NucleusLowest]),
            Quantity::StrainNucleus => (StrainNucleus, &[]),
            // The paper's cytoplasm Ω_cp includes the membrane (Sect. 2.1).
            Quantity::StrainCytoplasm => (
                StrainCytoplasmWithMembrane,
                &[StrainCytoplasmAlone, StrainMembrane],
            ),
            // Fig. 9 plots p_t.
            Quantity::UpsideDownDifference => (NucleusTop, &[NucleusLowest]),
        }
    }
}

/// A cellsim measure of a quantity the paper reports: which column of `timeseries.csv`
/// (or value derived from the columns) is set against the paper's value.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Measure {
    /// `contact_radius_ref`: the length of the cell contour in contact measured along the
    /// reference contour, as the paper's COMSOL integrates it (Sect. 3.1's definition).
    ContactReference,
    /// `contact_radius`: the same contact measured along the deformed contour.
    ContactDeformed,
    /// `uy_top`: the nucleus top p_t, the point the paper's Fig. 9 plots.
    NucleusTop,
    /// `uy_nucleus_max`: the lowest u_y over every node of the nucleus.
    NucleusLowest,
    /// `strain_nucleus`: mean ‖E‖ over the nucleus.
    StrainNucleus,
    /// `strain_cytoplasm`: mean ‖E‖ over the cytoplasm and the membrane together, the
    /// paper's Ω_cp (Sect. 2.1).
    StrainCytoplasmWithMembrane,
    /// Mean ‖E‖ over the cytoplasm without the membrane (cellsim's measure before the
    /// paper's), from `strain_cytoplasm`, `strain_membrane` and the domains' reference
    /// areas.
    StrainCytoplasmAlone,
    /// `strain_membrane`: mean ‖E‖ over the membrane alone.
    StrainMembrane,
}

impl Measure {
    /// What the measure is, named for a row about `q`, with its column.
    pub fn describe(&self, q: Quantity) -> String {
        let over_run = q == Quantity::NucleusDisplacement(When::End);
        match self {
            Measure::ContactReference => {
                "reference-frame contour length in contact (`contact_radius_ref`), the \
                 paper's definition"
                    .into()
            }
            Measure::ContactDeformed => "deformed contour length (`contact_radius`)".into(),
            Measure::NucleusTop if over_run => {
                "nucleus top p_t at its lowest over the run (`uy_top`), the point Fig. 9 plots"
                    .into()
            }
            Measure::NucleusTop => "nucleus top p_t (`uy_top`), the point Fig. 9 plots".into(),
            Measure::NucleusLowest if over_run => {
                "largest over all nucleus nodes and over the run (`uy_nucleus_max`)".into()
            }
            Measure::NucleusLowest => "largest over all nucleus nodes (`uy_nucleus_max`)".into(),
            Measure::StrainNucleus => {
                "reference-area mean over the nucleus (`strain_nucleus`)".into()
            }
            Measure::StrainCytoplasmWithMembrane => {
                "cytoplasm incl. membrane, the paper's Ω_cp (`strain_cytoplasm`)".into()
            }
            Measure::StrainCytoplasmAlone => "cytoplasm without the membrane".into(),
            Measure::StrainMembrane => "membrane alone (`strain_membrane`)".into(),
        }
    }

    /// The downward displacement's column (`uy_top` or `uy_nucleus_max`), for the
    /// displacement measures.
    fn uy(&self) -> Option<fn(&Observables) -> f64> {
        match self {
            Measure::NucleusTop => Some(|o| o.uy_top),
            Measure::NucleusLowest => Some(|o| o.uy_nucleus_max),
            _ => None,
        }
    }

    /// The value of this measure in one row (fractions for strains; u_y as signed for the
    /// displacements). `mesh` gives the areas [`Measure::StrainCytoplasmAlone`] needs.
    pub fn in_row(&self, o: &Observables, mesh: &MeshFile) -> f64 {
        match self {
            Measure::ContactReference => o.contact_radius_ref,
            Measure::ContactDeformed => o.contact_radius,
            Measure::NucleusTop => o.uy_top,
            Measure::NucleusLowest => o.uy_nucleus_max,
            Measure::StrainNucleus => o.strain_nucleus,
            Measure::StrainCytoplasmWithMembrane => o.strain_cytoplasm,
            Measure::StrainCytoplasmAlone => {
                cytoplasm_alone(o, mesh.area(Domain::Cytoplasm), mesh.area(Domain::Membrane))
            }
            Measure::StrainMembrane => o.strain_membrane,
        }
    }
}

/// The mean ‖E‖ over the cytoplasm without the membrane, from the mean over both
/// (`strain_cytoplasm`), the membrane's (`strain_membrane`) and the reference areas
/// `a_cp` (cytoplasm alone) and `a_m` (membrane).
pub fn cytoplasm_alone(o: &Observables, a_cp: f64, a_m: f64) -> f64 {
    (o.strain_cytoplasm * (a_cp + a_m) - o.strain_membrane * a_m) / a_cp
}

/// Why a run's files give no value of a reported quantity.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum NoValue {
    /// The run stopped before the time the value is taken at.
    #[error("the run stopped at t = {} s, before t = {} s", fmt_num(*.stopped, 0), fmt_num(*.needed, 0))]
    Stopped {
        /// The run's last time \[s\].
        stopped: f64,
        /// The time the value is taken at \[s\].
        needed: f64,
    },
    /// The measure asked for a largest displacement is not a displacement.
    #[error("not a displacement measure")]
    NotADisplacement,
    /// The run has no finite row.
    #[error("no rows")]
    NoRows,
    /// No control run (for the upside-down difference).
    #[error("no control run")]
    NoControl,
    /// The control run stopped before the time the value is taken at.
    #[error("control did not reach t = {} s", fmt_num(*.0, 0))]
    ControlStopped(f64),
    /// The scene was not run.
    #[error("no run")]
    NoRun,
}

/// Our value of `q` from a run's files with the measure the comparison uses
/// ([`Quantity::measures`]), or why there is none. `control` is needed for
/// [`Quantity::UpsideDownDifference`].
pub fn our_value(q: Quantity, run: &RunData, control: Option<&RunData>) -> Result<f64, NoValue> {
    measure_value(q, q.measures().0, run, control)
}

/// Our value of `q` measured by `m` (one of [`Quantity::measures`]), or why there is none:
/// a downward displacement is −u_y, at the end its largest over the run.
pub fn measure_value(
    q: Quantity,
    m: Measure,
    run: &RunData,
    control: Option<&RunData>,
) -> Result<f64, NoValue> {
    let [tg, tas, _, t_end] = run.mesh.phase_times;
    let at = |t: f64| {
        run.at(t).ok_or_else(|| NoValue::Stopped {
            stopped: run.t_last(),
            needed: t,
        })
    };
    let time = |w: When| match w {
        When::GravityEnd => tg,
        When::SpreadingEnd => tas,
        When::End => t_end,
    };
    let value = |o: &Observables| m.in_row(o, &run.mesh);
    match q {
        Quantity::ContactRadius(w) => Ok(value(&at(time(w))?)),
        Quantity::NucleusDisplacement(When::End) => {
            at(t_end)?;
            let uy = m.uy().ok_or(NoValue::NotADisplacement)?;
            lowest(run, uy).map(|(_, v)| -v).ok_or(NoValue::NoRows)
        }
        Quantity::NucleusDisplacement(w) => Ok(-value(&at(time(w))?)),
        Quantity::StrainNucleus | Quantity::StrainCytoplasm => Ok(value(&at(t_end)?)),
        Quantity::UpsideDownDifference => {
            let c = control.ok_or(NoValue::NoControl)?;
            let mine = at(t_end)?;
            let theirs = c.at(t_end).ok_or(NoValue::ControlStopped(t_end))?;
            Ok((value(&mine) - m.in_row(&theirs, &c.mesh)).abs())
        }
    }
}

/// When and where `uy` (a column of the rows) is lowest over the run: (t, value) of the
/// row with the smallest value (the first of equal ones).
pub fn lowest(run: &RunData, uy: impl Fn(&Observables) -> f64) -> Option<(f64, f64)> {
    run.series
        .iter()
        .map(|o| (o.t, uy(o)))
        .filter(|(_, v)| v.is_finite())
        .fold(None, |best: Option<(f64, f64)>, (t, v)| match best {
            Some((_, b)) if b <= v => best,
            _ => Some((t, v)),
        })
}

/// When and where the nucleus top p_t is lowest over the run: (t, u_y(p_t)) of the row
/// with the smallest u_y (the first of equal ones); the alternative measure of the
/// paper's "maximum displacement of the nucleus".
pub fn lowest_top(run: &RunData) -> Option<(f64, f64)> {
    lowest(run, |o| o.uy_top)
}

/// When and where the nucleus is lowest over the run: (t, `uy_nucleus_max`) of the row
/// with the smallest value; the paper's "maximum displacement of the nucleus" is compared
/// with its negative.
pub fn lowest_nucleus(run: &RunData) -> Option<(f64, f64)> {
    lowest(run, |o| o.uy_nucleus_max)
}

/// The paper's contact radii on the flat substrate (Fig. 6b) against ours in the paper's
/// measure, `contact_radius_ref`, at T_g0 and at the end: the marks of
/// `contact-radius.png`, on the reference-frame curve.
pub fn contact_radius_compared(flat: &RunData) -> Vec<Compared> {
    let [tg, _, _, t_end] = flat.mesh.phase_times;
    [
        (Quantity::ContactRadius(When::GravityEnd), tg),
        (Quantity::ContactRadius(When::End), t_end),
    ]
    .into_iter()
    .filter_map(|(q, t)| {
        let paper = reported_for("flat").find(|r| r.quantity == q)?.value;
        let ours = our_value(q, flat, None).ok()?;
        Some(Compared { t, paper, ours })
    })
    .collect()
}

/// The paper's nucleus displacements for `scene` against ours from its `run`, signed as
/// u_y: at T_g0 and T_as0 on the p_t curve; the maximum against the lowest
/// `uy_nucleus_max` (when it is reached), with p_t's lowest beside it.
pub fn displacement_marks(scene: &str, run: &RunData) -> DisplacementMarks {
    let [tg, tas, _, _] = run.mesh.phase_times;
    let paper = |q: Quantity| {
        reported_for(scene)
            .find(|r| r.quantity == q)
            .map(|r| r.value)
    };
    let q = Quantity::NucleusDisplacement;
    let at_times = [(tg, When::GravityEnd), (tas, When::SpreadingEnd)]
        .into_iter()
        .filter_map(|(t, w)| {
            let p = paper(q(w))?;
            let ours = our_value(q(w), run, None).ok()?;
            Some(Compared {
                t,
                paper: -p,
                ours: -ours,
            })
        })
        .collect();
    let finished = our_value(q(When::End), run, None).is_ok();
    let maximum = paper(q(When::End)).filter(|_| finished).and_then(|p| {
        lowest_nucleus(run).map(|(t, v)| Compared {
            t,
            paper: -p,
            ours: v,
        })
    });
    DisplacementMarks {
        at_times,
        maximum,
        maximum_top: maximum.and(lowest_top(run)),
    }
}

fn fmt_num(v: f64, digits: usize) -> String {
    format!("{v:.digits$}")
}

/// Significant-looking formatting of a table value.
fn fmt_value(v: f64, percent: bool) -> String {
    if percent {
        return format!("{:.1}", 100.0 * v);
    }
    let a = v.abs();
    if a >= 100.0 {
        format!("{v:.1}")
    } else if a >= 1.0 {
        format!("{v:.3}")
    } else {
        format!("{v:.4}")
    }
}

/// How one scene's run went.
#[derive(Debug, Clone)]
pub struct SceneOutcome {
    /// Scene name.
    pub name: String,
    /// Run directory.
    pub dir: PathBuf,
    /// `Ok(true)` ran and finished, `Ok(false)` reused, `Err` why it did not finish.
    pub result: Result<bool, String>,
}

/// What `cellsim paper` produced.
#[derive(Debug, Clone, Default)]
pub struct PaperReport {
    /// How each run went.
    pub runs: Vec<SceneOutcome>,
    /// Files written.
    pub written: Vec<PathBuf>,
    /// Problems met while drawing (each names its file).
    pub problems: Vec<String>,
    /// Wall-clock seconds of running the scenes (all of them, mesh and set-up included).
    pub runs_seconds: f64,
}

impl PaperReport {
    /// Whether every run finished and every file was written.
    pub fn ok(&self) -> bool {
        self.problems.is_empty() && self.runs.iter().all(|r| r.result.is_ok())
    }

    /// Notes a file written, or the problem met writing it.
    fn record(&mut self, res: Result<PathBuf, OutputError>) {
        match res {
            Ok(p) => self.written.push(p),
            Err(e) => self.problems.push(e.to_string()),
        }
    }
}

/// Draws the paper's figures and `comparison.md` into `out` from the run directories of
/// `runs` (as written by [`crate::commands::paper::run_cases`]; any of them may be partial or
/// missing).
pub fn draw_paper(out: &Path, runs: &[SceneOutcome]) -> PaperReport {
    let mut report = PaperReport::default();
    let data = load_runs(runs, &mut report);
    // The substrate drawing, computed once per view (the pillar scenes share theirs).
    let backdrops = Backdrops::default();
    // The figures, drawn on the thread pool once all are listed (each writes its own file),
    // and recorded in the order listed.
    let mut figures = comparison_figures(out, &data);
    figures.extend(shape_figures(out, &data, &backdrops));
    {
        use rayon::prelude::*;
        let drawn: Vec<Result<PathBuf, OutputError>> = figures.par_iter().map(|f| f()).collect();
        for res in drawn {
            report.record(res);
        }
    }
    for (name, text) in [
        (COMPARISON_FILE, comparison_markdown(runs, &data)),
        (TIMINGS_FILE, timings_markdown(runs, &data)),
    ] {
        let p = out.join(name);
        report.record(
            std::fs::write(&p, text)
                .map(|_| p.clone())
                .map_err(|e| OutputError::write(&p, e)),
        );
    }
    report
}

/// The files of each of `runs` that started, by scene name; runs that cannot be read
/// are noted in `report`.
fn load_runs(runs: &[SceneOutcome], report: &mut PaperReport) -> Vec<(String, RunData)> {
    let mut data = Vec::new();
    for r in runs {
        if r.result.is_err() && !r.dir.exists() {
            continue; // never started: its error is reported with the runs
        }
        match RunData::load(&r.dir) {
            Ok(d) => data.push((r.name.clone(), d)),
            Err(e) => report.problems.push(e.to_string()),
        }
    }
    data
}

/// The run of scene `name` in `data`, if it was loaded.
fn run_named<'a>(data: &'a [(String, RunData)], name: &str) -> Option<&'a RunData> {
    data.iter().find(|(n, _)| n == name).map(|(_, d)| d)
}

/// The value the paper reports for `scene`'s quantity `q`, if it reports one.
fn reported_value(scene: &str, q: Quantity) -> Option<f64> {
    reported_for(scene)
        .find(|r| r.quantity == q)
        .map(|r| r.value)
}

/// One figure to draw: writes its file and returns its path.
type Figure<'a> = Box<dyn Fn() -> Result<PathBuf, OutputError> + Send + Sync + 'a>;

/// The pillar scenes whose nucleus displacement and strain are compared.
const PILLAR_SCENES: [&str; 3] = ["pillars-push", "pillars-pull", "pillars-push-pull"];

/// The figures comparing the runs of `data` with the paper, to be drawn into `out`: the
/// contact radius, the nucleus displacement, the strain over time and at the end, and
/// upside down against the control (for the runs there are).
fn comparison_figures<'a>(out: &Path, data: &'a [(String, RunData)]) -> Vec<Figure<'a>> {
    let get = |name: &str| run_named(data, name);
    let mut figures: Vec<Figure> = Vec::new();
    // Contact radius on the flat substrate (Fig. 6b): both frames, the paper's marks on
    // the reference-frame curve (its measure).
    if let Some(flat) = get("flat") {
        let pts = contact_radius_compared(flat);
        let p = out.join("contact-radius.png");
        figures.push(Box::new(move || {
            contact_radius_figure(&p, &[flat], &pts, "paper (Sect. 3.1, Fig. 6b)")
                .map(|_| p.clone())
        }));
    }

    // Nucleus displacement for push, pull, push-pull (Fig. 9's kind of curve): the values
    // at T_g0 and T_as0 on the p_t curve; the paper's maximum against the lowest point of
    // the nucleus, p_t's lowest beside it.
    let pillar_runs: Vec<(&str, &RunData)> = PILLAR_SCENES
        .iter()
        .filter_map(|n| get(n).map(|r| (*n, r)))
        .collect();
    let pillars: Vec<&RunData> = pillar_runs.iter().map(|(_, r)| *r).collect();
    if !pillars.is_empty() {
        let marks: Vec<DisplacementMarks> = pillar_runs
            .iter()
            .map(|(n, r)| displacement_marks(n, r))
            .collect();
        let p = out.join("nucleus-displacement.png");
        let pillars2 = pillars.clone();
        figures.push(Box::new(move || {
            displacement_figure(&p, &pillars2, &marks, "paper (Sect. 3.2)").map(|_| p.clone())
        }));
        let p = out.join("strain-time.png");
        figures.push(Box::new(move || {
            strain_time_figure(&p, &pillars).map(|_| p.clone())
        }));
    }

    // Strain norms (Fig. 7).
    let bars = strain_bars(data);
    let p = out.join("strain-norms.png");
    figures.push(Box::new(move || {
        strain_bars_figure(&p, &bars, "cellsim", "paper (Sect. 3.2, Fig. 7)").map(|_| p.clone())
    }));

    // Upside down against the control (Fig. 9).
    if let (Some(c), Some(u)) = (get(CONTROL), get("upside-down")) {
        let p = out.join("upside-down.png");
        let d = reported_value("upside-down", Quantity::UpsideDownDifference);
        figures.push(Box::new(move || {
            upside_down_figure(&p, c, u, d).map(|_| p.clone())
        }));
    }
    figures
}

/// The strain norms of the nucleus and the cytoplasm of each of [`PILLAR_SCENES`], the
/// paper's and ours from `data`.
fn strain_bars(data: &[(String, RunData)]) -> Vec<StrainBars> {
    PILLAR_SCENES
        .iter()
        .map(|n| {
            let ours = |q| run_named(data, n).and_then(|r| our_value(q, r, None).ok());
            StrainBars {
                scene: n.trim_start_matches("pillars-").to_string(),
                paper_nucleus: reported_value(n, Quantity::StrainNucleus),
                ours_nucleus: ours(Quantity::StrainNucleus),
                paper_cytoplasm: reported_value(n, Quantity::StrainCytoplasm),
                ours_cytoplasm: ours(Quantity::StrainCytoplasm),
            }
        })
        .collect()
}

/// The scenes on pillars, drawn in one frame and sharing a substrate drawing.
const SHARED_FRAME_SCENES: [&str; 4] = [
    "pillars-push",
    "pillars-pull",
    "pillars-push-pull",
    "upside-down",
];

/// The substrate drawings the shape figures share (see [`shape_figures`]).
#[derive(Default)]
struct Backdrops {
    /// That of [`SHARED_FRAME_SCENES`], which share one view.
    shared: Mutex<Option<Backdrop>>,
    /// That of the other scenes.
    others: Mutex<Option<Backdrop>>,
}

/// The shape figures at each phase end of every scene in `data` (Figs. 5, 6a, 8), to be
/// drawn into `out`: [`SHARED_FRAME_SCENES`] in one frame, the others each in its own, the
/// substrate drawing computed once and kept in `backdrops`.
fn shape_figures<'a>(
    out: &Path,
    data: &'a [(String, RunData)],
    backdrops: &'a Backdrops,
) -> Vec<Figure<'a>> {
    let shared = shared_view(data);
    let mut figures: Vec<Figure> = Vec::new();
    for s in SCENES {
        let Some(r) = run_named(data, s.name) else {
            continue;
        };
        let in_shared = SHARED_FRAME_SCENES.contains(&s.name);
        let view = if in_shared { shared } else { None }
            .unwrap_or_else(|| shape_view(&r.mesh, &r.states.iter().collect::<Vec<_>>()));
        let phases = run_phases(r);
        for st in &r.states {
            let p = out.join(format!("shape-{}-{}.png", s.name, st.phase));
            let cache = if in_shared {
                &backdrops.shared
            } else {
                &backdrops.others
            };
            figures.push(Box::new(move || {
                shape_figure_cached(&p, s.name, &r.mesh, st, view, phases.as_ref(), cache)
                    .map(|_| p.clone())
            }));
        }
    }
    figures
}

/// The frame the shapes of [`SHARED_FRAME_SCENES`] share: the union of their runs' views
/// in `data`; `None` if none ran.
fn shared_view(data: &[(String, RunData)]) -> Option<Bounds> {
    let mut shared = None;
    for n in SHARED_FRAME_SCENES {
        if let Some(r) = run_named(data, n) {
            let states: Vec<&StateFile> = r.states.iter().collect();
            let v = shape_view(&r.mesh, &states);
            shared = Some(match shared {
                None => v,
                Some(s) => v.union(s),
            });
        }
    }
    shared
}

/// The comparison with the paper: physics only, so it changes only when the results do.
pub const COMPARISON_FILE: &str = "comparison.md";
/// What each run cost (wall time, steps, Jacobians), apart from the comparison because it
/// changes from run to run (`plots/timings.md` is not under version control).
pub const TIMINGS_FILE: &str = "timings.md";

/// Status of a run for the tables: "finished" whether it ran now or was reused.
fn run_status(o: &SceneOutcome) -> String {
    match &o.result {
        Ok(_) => "finished".to_string(),
        Err(e) => format!("did not finish ({})", e.replace('|', "/")),
    }
}

/// The text of `comparison.md`: every reported value against ours, then how far each run
/// got. Nothing in it depends on the machine or the load (wall times are in
/// [`timings_markdown`]), so rerunning unchanged code leaves it unchanged.
pub fn comparison_markdown(runs: &[SceneOutcome], data: &[(String, RunData)]) -> String {
    let get = |name: &str| data.iter().find(|(n, _)| n == name).map(|(_, d)| d);
    let mut s = String::new();
    let _ = writeln!(s, "# cellsim against the paper\n");
    let _ = writeln!(
        s,
        "Written by `cellsim paper` (cellsim {}). Paper: Mondésert-Deveraux, Aubry & Allena, \
         *Biomech Model Mechanobiol* 18:1281–1295 (2019); its values are those MODEL.md §7 \
         quotes. Difference = (cellsim − paper) / paper.\n",
        env!("CARGO_PKG_VERSION")
    );
    let _ = writeln!(
        s,
        "Each row sets the paper's value against one cellsim measure, the one matching how the \
         paper measures (MODEL.md §7, \"How the paper measures\"), named in *measure compared*; \
         the same quantity in our other measures is in the last columns, with its difference \
         to the paper.\n"
    );
    let _ = writeln!(
        s,
        "| scene | quantity | measure compared | paper | cellsim | difference | other cellsim \
         measures | paper's source |\n|---|---|---|---:|---:|---:|---|---|"
    );
    for r in REPORTED.iter() {
        let pct = r.quantity.percent();
        let (primary, others) = r.quantity.measures();
        let value = |m: Measure| match get(r.scene) {
            Some(run) => measure_value(r.quantity, m, run, get(CONTROL)),
            None => Err(NoValue::NoRun),
        };
        let diff = |v: f64| format!("{:+.1} %", 100.0 * (v - r.value) / r.value);
        let (ours_s, diff_s) = match value(primary) {
            Ok(v) => (fmt_value(v, pct), diff(v)),
            Err(why) => (format!("n/a: {why}"), "–".into()),
        };
        let other_s = others
            .iter()
            .filter_map(|&m| {
                value(m).ok().map(|v| {
                    format!(
                        "{}: {} ({})",
                        m.describe(r.quantity),
                        fmt_value(v, pct),
                        diff(v)
                    )
                })
            })
            .collect::<Vec<_>>()
            .join("; ");
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {} |",
            r.scene,
            r.quantity.describe(),
            primary.describe(r.quantity),
            fmt_value(r.value, pct),
            ours_s,
            diff_s,
            if other_s.is_empty() {
                "–".into()
            } else {
                other_s
            },
            r.source
        );
    }
    let _ = writeln!(
        s,
        "\n## Runs\n\nRun directories: `runs/<run>/` beside this file. What each run cost \
         (wall time, steps, Jacobians) is in `{TIMINGS_FILE}` beside it, kept apart because \
         it changes from run to run.\n\n| run | status | t reached (s) | unknowns |\n|---|---|---:|---:|"
    );
    for o in runs {
        let d = get(&o.name);
        let sm = d.and_then(|d| d.summary.as_ref());
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} |",
            o.name,
            run_status(o),
            d.map(|d| fmt_num(d.t_last(), 0)).unwrap_or("–".into()),
            sm.map(|x| x.unknowns.total.to_string())
                .unwrap_or("–".into()),
        );
    }
    let _ = writeln!(
        s,
        "\nDefinitions. *Contact radius*: length of the half cell's boundary within ε_ct of \
         the substrate; the paper defines it as \"the length of the cell contour in contact \
         with the substrate\" (Sect. 3.1) and its COMSOL integrates boundary lengths on the \
         fixed mesh, i.e. along the reference contour (`contact_radius_ref`); along the \
         deformed contour (`contact_radius`) the stretched membrane makes it longer. \
         *Downward displacement of the nucleus*: −u_y; the paper's \"maximum displacement of \
         the nucleus\" (Sect. 3.2) names no point, so it is compared with the largest over \
         every nucleus node and over the run (`uy_nucleus_max`), the nucleus top p_t beside \
         it (`uy_top`, the point the paper's Fig. 9 plots); the values at T_g0 and T_as0 \
         and the upside-down difference are p_t's, as on Fig. 9's curves. Displacements \
         count from the suspended start, so they include the fall onto the pillars (the \
         cell starts 0.5 µm above them, MODEL.md §5). *Mean ‖E‖*: reference-area mean of the \
         Frobenius norm of the Green-Lagrange strain over the domain; the paper's cytoplasm \
         Ω_cp includes the membrane (Sect. 2.1), as `strain_cytoplasm` does; the cytoplasm \
         without the membrane is \
         (`strain_cytoplasm`·(A_cp + A_m) − `strain_membrane`·A_m)/A_cp with the reference \
         areas A_cp (cytoplasm) and A_m (membrane). *Upside down − control*: the control \
         (`{CONTROL}`) is the push-pull scene continued to the upside-down scene's end time \
         with gravity unchanged, the paper's Fig. 9 control; both are compared at that \
         time."
    );
    s
}

/// The text of `timings.md`: what each run cost. Wall times change from run to run (and
/// steps from machine to machine), so this is apart from `comparison.md`.
pub fn timings_markdown(runs: &[SceneOutcome], data: &[(String, RunData)]) -> String {
    let get = |name: &str| data.iter().find(|(n, _)| n == name).map(|(_, d)| d);
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# What each run of `cellsim paper` cost\n\nWritten by `cellsim paper` (cellsim {}); \
         the physics is in `{COMPARISON_FILE}`. Wall time is the integration only (mesh and \
         set-up excluded); a reused run shows the time of the run that wrote it. Runs whose \
         cases agree up to some time are computed together up to it (the pillar scenes up to \
         T_as0, the upside-down scene and its control up to T_a0) and then each restarted from \
         the state there: their wall time, steps and Jacobians count that shared stretch in \
         full, and `shared until` says to when.\n\n| run | status \
         | t reached (s) | wall (s) | steps | Jacobians | error-test failures | unknowns | shared until (s) | run directory |\n\
         |---|---|---:|---:|---:|---:|---:|---:|---:|---|",
        env!("CARGO_PKG_VERSION")
    );
    for o in runs {
        let d = get(&o.name);
        let status = match &o.result {
            Ok(true) => "finished".to_string(),
            Ok(false) => "finished (reused)".to_string(),
            Err(_) => run_status(o),
        };
        let sm = d.and_then(|d| d.summary.as_ref());
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | `{}` |",
            o.name,
            status,
            d.map(|d| fmt_num(d.t_last(), 0)).unwrap_or("–".into()),
            sm.map(|x| format!("{:.1}", x.wall_seconds))
                .unwrap_or("–".into()),
            sm.map(|x| x.stats.steps.to_string()).unwrap_or("–".into()),
            sm.map(|x| x.stats.jacobian_evals.to_string())
                .unwrap_or("–".into()),
            sm.map(|x| x.stats.error_test_failures.to_string())
                .unwrap_or("–".into()),
            sm.map(|x| x.unknowns.total.to_string())
                .unwrap_or("–".into()),
            sm.and_then(|x| x.shared.iter().map(|p| p.t).reduce(f64::max))
                .map(|t| fmt_num(t, 0))
                .unwrap_or("–".into()),
            o.dir.display()
        );
    }
    s
}
