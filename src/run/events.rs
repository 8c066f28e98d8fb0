//! The run's clock when the cell starts its phases itself (MODEL.md §11).
//!
//! A case's adhesion and active phases start at a time (`At`, the paper's T_g0 and
//! T_as0 by default) or when a condition on the state first holds ([`Condition`]). The
//! [`Schedule`] keeps what is known: which phases have started and when, which
//! conditions are armed. The model watches the conditions of the phases not started
//! (two root functions each, [`crate::model::events`]); at a root the driver asks the
//! schedule what it means (an arming, a start, or nothing) and, at a start, restarts the
//! integrator there with the phase's ramp from that time. The case's later times — the
//! end time, the output times, the gravity flip — are read as times after the phase they
//! fall in ([`crate::scene::terms::scheduled`]) and become known when it starts.

use crate::case::Case;
use crate::dae::Root;
use crate::model::ModelParams;
use crate::physics::Condition;
use crate::run_files::Event;
use crate::scene::terms::{phase_conditions, phase_starts, phases_from, scheduled};

/// The phases that can start on a condition.
pub(crate) const PHASES: [&str; 2] = ["adhesion", "active"];

/// How far past its end time a run waits for a condition to hold: `DEADLINE` × t_end.
pub(crate) const DEADLINE: f64 = 2.0;

/// What a root of the watched conditions meant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Meaning {
    /// Nothing to act on (a crossing of a condition not armed, or in the other sense).
    Nothing,
    /// A condition was armed; the phase did not start.
    Armed,
    /// Phase `k` (0 adhesion, 1 active) starts now.
    Starts(usize),
}

/// The phases' starts known so far, and the conditions watched for the others.
#[derive(Debug, Clone)]
pub(crate) struct Schedule {
    case: Case,
    /// The start of each phase, where known.
    pub starts: [Option<f64>; 2],
    conditions: [Option<Condition>; 2],
    armed: [Option<f64>; 2],
}

impl Schedule {
    /// The schedule of `case` before its run.
    pub fn new(case: &Case) -> Self {
        Self {
            case: case.clone(),
            starts: phase_starts(case),
            conditions: phase_conditions(case),
            armed: [None; 2],
        }
    }

    /// The case.
    pub fn case(&self) -> &Case {
        &self.case
    }

    /// Whether the case keeps the paper's clock: both phases start at T_g0 and T_as0
    /// (absent starts, or `At` those times).
    pub fn is_paper(&self) -> bool {
        let ph = &self.case.phases;
        !self.has_events() && self.starts == [Some(ph.t_g0), Some(ph.t_as0)]
    }

    /// Whether some phase starts on a condition.
    pub fn has_events(&self) -> bool {
        self.conditions.iter().any(Option::is_some)
    }

    /// The run time of the case's time `t` ([`scheduled`]), `None` while not known.
    pub fn at(&self, t: f64) -> Option<f64> {
        scheduled(&self.case, self.starts, t)
    }

    /// The run's end time, infinite while not known.
    pub fn t_end(&self) -> f64 {
        self.at(self.case.phases.t_end).unwrap_or(f64::INFINITY)
    }

    /// The time by which a pending condition must have held: [`DEADLINE`] × the case's
    /// end time.
    pub fn deadline(&self) -> f64 {
        DEADLINE * self.case.phases.t_end
    }

    /// The phases watched, in the order of the model's conditions: those that start on a
    /// condition and have not started.
    fn watched(&self) -> Vec<usize> {
        (0..2)
            .filter(|&k| self.conditions[k].is_some() && self.starts[k].is_none())
            .collect()
    }

    /// `params` (the case's, at its start) with the phases, the conditions watched and
    /// the end-time breakpoint known now.
    pub fn params(&self, mut params: ModelParams) -> ModelParams {
        params.phases = phases_from(&self.case, self.starts);
        params.events = self
            .watched()
            .into_iter()
            .filter_map(|k| self.conditions[k])
            .collect();
        params.extra_breakpoints = self.at(self.case.phases.t_end).into_iter().collect();
        params
    }

    /// The run times of `nominal` (the case's output times) known now, with the times the
    /// phases started on their conditions, up to the end time; sorted, without repeats.
    pub fn output_times(&self, nominal: &[f64]) -> Vec<f64> {
        let end = self.t_end();
        let mut t: Vec<f64> = nominal.iter().filter_map(|&t| self.at(t)).collect();
        for k in 0..2 {
            if let (Some(_), Some(s)) = (self.conditions[k], self.starts[k]) {
                t.push(s);
            }
        }
        t.retain(|&t| t <= end);
        t.sort_by(f64::total_cmp);
        let tol = 1e-9 * self.case.phases.t_end;
        t.dedup_by(|a, b| (*a - *b).abs() <= tol);
        t
    }

    /// What the root `root` of the model's conditions means. `fire_now(j)` evaluates the
    /// firing function of the j-th watched condition at the root (a `Settled` condition
    /// armed while the centre is already slower than its speed holds at once).
    pub fn on_root(&mut self, root: &Root, fire_now: impl Fn(usize) -> f64) -> Meaning {
        let mut meaning = Meaning::Nothing;
        for (j, k) in self.watched().into_iter().enumerate() {
            let (arm, fire) = (
                root.crossings.get(2 * j).copied().unwrap_or(0),
                root.crossings.get(2 * j + 1).copied().unwrap_or(0),
            );
            if arm > 0 && self.armed[k].is_none() {
                self.armed[k] = Some(root.t);
                meaning = Meaning::Armed;
                let settled = matches!(self.conditions[k], Some(Condition::Settled { .. }));
                if settled && fire_now(j) <= 0.0 {
                    return self.start(k, root.t);
                }
            } else if fire < 0 && self.armed[k].is_some() {
                return self.start(k, root.t);
            }
        }
        meaning
    }

    fn start(&mut self, k: usize, t: f64) -> Meaning {
        self.starts[k] = Some(t);
        Meaning::Starts(k)
    }

    /// The events for the summary: each phase that starts on a condition.
    pub fn events(&self) -> Vec<Event> {
        let ph = &self.case.phases;
        let paper = [ph.t_g0, ph.t_as0];
        (0..2)
            .filter_map(|k| {
                self.conditions[k].map(|c| Event {
                    phase: PHASES[k].to_string(),
                    condition: c.to_string(),
                    armed_at: self.armed[k],
                    t: self.starts[k],
                    paper_t: paper[k],
                })
            })
            .collect()
    }

    /// The figures' phase lines: adhesion start, active start and end, end time (NaN
    /// where not known).
    pub fn phase_times(&self) -> [f64; 4] {
        let [a, b, c] = phases_from(&self.case, self.starts).times();
        let end = self.at(self.case.phases.t_end).unwrap_or(f64::NAN);
        [a, b, c, end]
    }

    /// The state files' phase ends: the end, the gravity ramp's, the paper's spreading
    /// end (T_as0) and active end (T_a0) as scheduled (NaN where not known).
    pub fn phase_ends(&self) -> [f64; 4] {
        let ph = &self.case.phases;
        let at = |t: f64| self.at(t).unwrap_or(f64::NAN);
        [at(ph.t_end), ph.t_g0, at(ph.t_as0), at(ph.t_a0)]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::case::Start;

    fn case(adhesion: Option<Start>, active: Option<Start>) -> Case {
        let mut c = Case::reference();
        c.phases.t_end = 50_000.0;
        c.phases.adhesion_start = adhesion;
        c.phases.active_start = active;
        c
    }

    #[test]
    fn the_paper_clock_is_unchanged() {
        let s = Schedule::new(&case(None, None));
        assert!(!s.has_events());
        for t in [0.0, 5e3, 1e4, 2e4, 4e4, 4.5e4, 5e4] {
            assert_eq!(s.at(t), Some(t));
        }
        assert_eq!(s.phase_times(), [1e4, 4e4, 5e4, 5e4]);
    }

    #[test]
    fn times_after_a_phase_start_move_with_it() {
        let mut s = Schedule::new(&case(
            Some(Start::Settled(1e-5)),
            Some(Start::SpreadingSlows(1e-4)),
        ));
        assert!(s.has_events());
        // Gravity's times are the clock's; the others wait for their phase.
        assert_eq!(s.at(1e4), Some(1e4));
        assert_eq!(s.at(1.2e4), None);
        assert_eq!(s.t_end(), f64::INFINITY);
        assert_eq!(s.watched(), vec![0, 1]);
        // Adhesion starts at 12 000 s: its times move by +2 000 s, T_as0 (its end) too.
        let root = Root::new(1.1e4, vec![1, 0, 0, 0]);
        assert_eq!(s.on_root(&root, |_| 1.0), Meaning::Armed);
        let root = Root::new(1.2e4, vec![0, -1, 0, 0]);
        assert_eq!(s.on_root(&root, |_| 1.0), Meaning::Starts(0));
        assert_eq!(s.at(2e4), Some(2.2e4));
        assert_eq!(s.at(4e4), Some(4.2e4));
        assert_eq!(s.at(4.5e4), None);
        assert_eq!(s.watched(), vec![1]);
        // A falling crossing before the arming means nothing.
        let root = Root::new(3e4, vec![0, -1]);
        assert_eq!(s.on_root(&root, |_| -1.0), Meaning::Nothing);
        let root = Root::new(3.1e4, vec![1, 0]);
        assert_eq!(s.on_root(&root, |_| -1.0), Meaning::Armed);
        let root = Root::new(3.5e4, vec![0, -1]);
        assert_eq!(s.on_root(&root, |_| -1.0), Meaning::Starts(1));
        // The active phase from 35 000 s: T_a0 and the end at 45 000 s.
        assert_eq!(s.t_end(), 4.5e4);
        assert_eq!(s.phase_times(), [1.2e4, 3.5e4, 4.5e4, 4.5e4]);
        let p = s.params(crate::scene::model_params(&s.case, "test", true).unwrap());
        assert_eq!(p.phases.adhesion, Some([1.2e4, 4.2e4]));
        assert_eq!(p.phases.active, Some([3.5e4, 4.5e4]));
        assert!(p.events.is_empty());
        assert_eq!(p.extra_breakpoints, vec![4.5e4]);
        let times = s.output_times(&[1e4, 2e4, 4e4, 4.5e4, 5e4]);
        assert_eq!(times, vec![1e4, 1.2e4, 2.2e4, 3.5e4, 4e4, 4.2e4, 4.5e4]);
        let ev = s.events();
        assert_eq!(ev[0].t, Some(1.2e4));
        assert_eq!(ev[0].armed_at, Some(1.1e4));
        assert_eq!(ev[1].condition, "SpreadingSlows(1e-4)");
    }

    #[test]
    fn settled_armed_while_already_slow_starts_at_once() {
        let mut s = Schedule::new(&case(Some(Start::Settled(1e-5)), None));
        assert_eq!(s.watched(), vec![0]);
        let root = Root::new(9.0, vec![1, 0]);
        assert_eq!(s.on_root(&root, |_| -0.5), Meaning::Starts(0));
        assert_eq!(s.starts[0], Some(9.0));
    }
}
