//! The paper's five scenes as compiled in (their case files, `cases/<name>.ron`) and the
//! name of the control run, and the loading phases of a run recovered from its case file or
//! from the scene of its name ([`run_phases`]): what both the paper's figures
//! ([`super::paper`]) and the time plots of any run need. It imports nothing of
//! [`super`]: the figure modules import it, not the other way round.

use crate::physics::Phases;
use crate::run_files::RunData;

/// One of the paper's scenes: its name and case file.
#[derive(Debug, Clone, Copy)]
pub struct Scene {
    /// Scene name (= the case's `name` and its run directory).
    pub name: &'static str,
    /// Case file, relative to the repository root.
    pub file: &'static str,
    /// The case file's text as compiled in.
    pub text: &'static str,
}

/// The [`Scene`] named `name`: its case file `cases/<name>.ron`, compiled in.
macro_rules! scene {
    ($name:literal) => {
        Scene {
            name: $name,
            file: concat!("cases/", $name, ".ron"),
            text: include_str!(concat!("../../cases/", $name, ".ron")),
        }
    };
}

/// The five scenes of MODEL.md §7, in the paper's order.
pub const SCENES: [Scene; 5] = [
    scene!("flat"),
    scene!("pillars-push"),
    scene!("pillars-pull"),
    scene!("pillars-push-pull"),
    scene!("upside-down"),
];

/// Name of the control run of the upside-down comparison.
pub const CONTROL: &str = "push-pull-control";

/// The loading phases of a run, with the gravity flip, which the run's files do not
/// record: from the case file its summary names (if it loads, has the run's name and its
/// phase times), else from the compiled-in paper scene of that name (the control:
/// push-pull's, without a flip). `None` if neither applies.
pub fn run_phases(run: &RunData) -> Option<Phases> {
    let fits = |case: &crate::case::Case| {
        let scheduled = crate::scene::terms::phase_starts(case);
        let starts = (run.summary.as_ref()).map_or(scheduled, |sm| sm.phase_starts(scheduled));
        let ph = crate::scene::terms::phases_from(case, starts);
        let [tg, tas, ta, _] = run.mesh.phase_times;
        (case.name == run.name && ph.times() == [tg, tas, ta]).then_some(ph)
    };
    if let Some(sm) = &run.summary {
        if let Some(ph) = crate::case::Case::load(&sm.case_file)
            .ok()
            .as_ref()
            .and_then(fits)
        {
            return Some(ph);
        }
    }
    let (scene, name) = if run.name == CONTROL {
        ("pillars-push-pull", CONTROL)
    } else {
        (run.name.as_str(), run.name.as_str())
    };
    let s = SCENES.iter().find(|s| s.name == scene)?;
    let mut case = crate::case::Case::from_str(s.text, s.file).ok()?;
    case.name = name.to_string();
    fits(&case)
}
