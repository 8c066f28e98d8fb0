//! Several runs at once, computed together while their cases agree.
//!
//! Cases that differ only in what acts late — the active regions (from T_as0), the gravity
//! flip (from T_a0), the end time and the outputs — are the same computation up to the
//! time they part ([`shared_until`]). [`run_all`] integrates such a group once up to that
//! time (writing every member's outputs as it goes), and then each subgroup that still
//! agrees goes on by itself: every one of them restarts the integrator at the parting time
//! from the state there, with its own case's model ([`crate::model::CellModel::branched`]), so that
//! subgroups compared with each other (upside-down against its control) start alike. Their
//! results agree with their own runs' to the integrator's tolerance (measured in the
//! tests); a group from which members only end goes on with the same integrator. Every
//! member's directory is written as by [`super::run`] alone, and its summary records where
//! it parted from whom ([`crate::run_files::Parting`]).
//!
//! The groups and subgroups are tasks run `jobs` at a time.

use std::sync::{Condvar, Mutex};
use std::time::Instant;

use super::events::Schedule;
use super::{Advance, Driver, Progress, RunError, RunOptions, RunWriter, Solver, build_model};
use super::{Cell, Stop};
use crate::case::{Case, Output, Phases};
use crate::dae::Stats;
use crate::model::State;
use crate::run_files::{FailureKind, Parting, Summary};

/// The time up to which runs of `a` and `b` are the same computation: the earlier end
/// time when the cases differ only in their names, descriptions, end times and outputs; the
/// start of the gravity flip (T_a0) when they differ also in the flip; the start of the
/// active ramp (T_as0) when they differ also in the active regions; 0 when they differ in
/// anything else (or in the phase times).
pub fn shared_until(a: &Case, b: &Case) -> f64 {
    fn plain(c: &Case) -> Case {
        let mut c = c.clone();
        c.name.clear();
        c.description = None;
        c.output = Output::default();
        c.phases = Phases {
            t_end: 0.0,
            ..c.phases
        };
        c
    }
    if [a, b].iter().any(|c| !Schedule::new(c).is_paper()) {
        // Phases that start on conditions or at other times: its clock is its own.
        return 0.0;
    }
    let (mut x, mut y) = (plain(a), plain(b));
    let mut t = a.phases.t_end.min(b.phases.t_end);
    if x.gravity != y.gravity {
        // The flip acts from T_a0 (MODEL.md §5); g itself from the start.
        t = t.min(a.phases.t_a0);
        for g in [&mut x.gravity, &mut y.gravity] {
            g.upside_down = false;
            g.flip_duration = 0.0;
        }
    }
    if x.active != y.active {
        // The active strain ramps from T_as0: before, F_a = I whatever the regions.
        t = t.min(a.phases.t_as0);
        y.active = x.active.clone();
    }
    if x == y { t } else { 0.0 }
}

/// One case of [`run_all`].
pub struct Member<'a> {
    /// The case.
    pub case: &'a Case,
    /// Its file, for messages and the summary.
    pub file: &'a str,
    /// Its run options (output directory, settings, interrupt flag, snapshots; the progress
    /// display comes from [`run_all`]'s `progress`).
    pub opts: RunOptions,
}

/// Runs `members`, `jobs` tasks at a time, computing together what their cases share when
/// `share` (else each on its own). `progress(label, t_end)` makes the progress display of
/// a stretch (label: the case, or the first case and how many more); `done(k, result)` is
/// called as member `k` ends. Returns each member's result, in order.
pub fn run_all(
    members: &[Member],
    jobs: usize,
    share: bool,
    progress: &(dyn Fn(&str, f64) -> Progress + Sync),
    done: &(dyn Fn(usize, &Result<Summary, RunError>) + Sync),
) -> Vec<Result<Summary, RunError>> {
    let n = members.len();
    let ctx = Context {
        members,
        progress,
        done,
        results: Mutex::new((0..n).map(|_| None).collect()),
        queue: Mutex::new(Queue {
            tasks: Vec::new(),
            running: 0,
        }),
        wake: Condvar::new(),
    };
    // The groups that start together: connected by sharing something (all apart unless
    // `share`), the first group run first.
    let mut groups = partition(&(0..n).collect::<Vec<_>>(), |i, j| {
        share && shared_until(members[i].case, members[j].case) > 0.0
    });
    groups.reverse();
    if let Ok(mut q) = ctx.queue.lock() {
        q.tasks = groups
            .into_iter()
            .map(|g| Task {
                members: g.into_iter().map(Track::new).collect(),
                start: Start::Fresh,
            })
            .collect();
    }
    let jobs = jobs.clamp(1, n.max(1));
    std::thread::scope(|scope| {
        for _ in 0..jobs {
            scope.spawn(|| ctx.worker());
        }
    });
    ctx.results
        .into_inner()
        .unwrap_or_default()
        .into_iter()
        .enumerate()
        .map(|(k, r)| {
            r.unwrap_or_else(|| {
                Err(RunError::Model {
                    file: members[k].file.into(),
                    message: "not run".into(),
                })
            })
        })
        .collect()
}

/// Splits `items` into the classes of the smallest equivalence containing `related`, each
/// in the order of `items`, the classes in the order of their first items.
fn partition(items: &[usize], related: impl Fn(usize, usize) -> bool) -> Vec<Vec<usize>> {
    let mut class: Vec<usize> = (0..items.len()).collect();
    fn root(class: &mut [usize], mut i: usize) -> usize {
        while class[i] != i {
            class[i] = class[class[i]];
            i = class[i];
        }
        i
    }
    for a in 0..items.len() {
        for b in a + 1..items.len() {
            if related(items[a], items[b]) {
                let (ra, rb) = (root(&mut class, a), root(&mut class, b));
                class[ra.max(rb)] = ra.min(rb);
            }
        }
    }
    let mut out: Vec<(usize, Vec<usize>)> = Vec::new();
    for (a, &item) in items.iter().enumerate() {
        let r = root(&mut class, a);
        match out.iter_mut().find(|(k, _)| *k == r) {
            Some((_, v)) => v.push(item),
            None => out.push((r, vec![item])),
        }
    }
    out.into_iter().map(|(_, v)| v).collect()
}

/// The shared state of the workers.
struct Context<'a, 'm> {
    members: &'a [Member<'m>],
    progress: &'a (dyn Fn(&str, f64) -> Progress + Sync),
    done: &'a (dyn Fn(usize, &Result<Summary, RunError>) + Sync),
    results: Mutex<Vec<Option<Result<Summary, RunError>>>>,
    queue: Mutex<Queue>,
    wake: Condvar,
}

struct Queue {
    tasks: Vec<Task>,
    /// Tasks being run (each may still add tasks).
    running: usize,
}

/// A group of members to run from a common state.
struct Task {
    /// The members (sorted when the task starts: the leader first).
    members: Vec<Track>,
    start: Start,
}

/// How a task starts.
enum Start {
    /// From t = 0: every member's files created, the system built from the leader's case.
    Fresh,
    /// From a parting: the system of the parent at its time, with the leader's parameters.
    Branch(Box<Branch>),
}

/// What a restarted subgroup takes from the stretch before it.
struct Branch {
    model: Cell,
    stats: Stats,
    switch_after: Option<f64>,
    switched_at: Option<f64>,
    adhesion_at: Option<f64>,
    adhesion_added_at: Option<f64>,
    last_step: f64,
}

/// One member within a task: its files and the wall time spent on its path before.
struct Track {
    k: usize,
    files: Option<RunWriter>,
    wall_before: f64,
}

impl Track {
    fn new(k: usize) -> Self {
        Track {
            k,
            files: None,
            wall_before: 0.0,
        }
    }
}

impl Context<'_, '_> {
    fn worker(&self) {
        loop {
            let task = {
                let Ok(mut q) = self.queue.lock() else { return };
                loop {
                    if let Some(t) = q.tasks.pop() {
                        q.running += 1;
                        break Some(t);
                    }
                    if q.running == 0 {
                        break None;
                    }
                    match self.wake.wait(q) {
                        Ok(g) => q = g,
                        Err(_) => return,
                    }
                }
            };
            let Some(task) = task else {
                self.wake.notify_all();
                return;
            };
            self.run_task(task);
            if let Ok(mut q) = self.queue.lock() {
                q.running -= 1;
            }
            self.wake.notify_all();
        }
    }

    fn push(&self, task: Task) {
        if let Ok(mut q) = self.queue.lock() {
            q.tasks.push(task);
        }
        self.wake.notify_all();
    }

    fn finish(&self, k: usize, result: Result<Summary, RunError>) {
        (self.done)(k, &result);
        if let Ok(mut r) = self.results.lock() {
            r[k] = Some(result);
        }
    }

    fn case(&self, track: &Track) -> &Case {
        self.members[track.k].case
    }

    /// The members' label: the leader's name, and how many more.
    fn label(&self, tracks: &[Track]) -> String {
        match tracks {
            [] => String::new(),
            [one] => self.case(one).name.clone(),
            [first, rest @ ..] => format!("{} +{}", self.case(first).name, rest.len()),
        }
    }

    /// Where a stretch of `tracks` from `t0` ends: where they part, or the only member's
    /// end (infinite while it waits for a phase the cell starts itself).
    fn stretch_end(&self, driver: &Driver, tracks: &[Track]) -> f64 {
        let mut end = f64::INFINITY;
        for (a, ta) in tracks.iter().enumerate() {
            end = end.min(driver.t_end(self.case(ta)));
            for tb in &tracks[a + 1..] {
                end = end.min(shared_until(self.case(ta), self.case(tb)));
            }
        }
        end
    }

    fn run_task(&self, task: Task) {
        let Task { members, start } = task;
        let mut tracks = members;
        // The leader (first) is the member that runs longest: the system is built from
        // its case, and its end time sets the progress display and the stall rule.
        tracks.sort_by(|a, b| {
            self.case(b)
                .phases
                .t_end
                .total_cmp(&self.case(a).phases.t_end)
                .then(a.k.cmp(&b.k))
        });
        let leader = &self.members[tracks[0].k];
        let progress = (self.progress)(&self.label(&tracks), leader.case.phases.t_end);
        let ropts = RunOptions {
            progress,
            ..leader.opts.clone()
        };
        let driver: Result<Option<Driver>, String> = match start {
            Start::Fresh => self.fresh(&mut tracks, &ropts),
            Start::Branch(b) => {
                let b = *b;
                let mut settings = ropts.settings.clone();
                if b.last_step > 0.0 {
                    // As after adding the μ_as unknowns: IDA's own first step starts far
                    // below the step the solution allows.
                    settings.initial_step = Some(0.1 * b.last_step);
                }
                let t = b.model.initial_time();
                Solver::new(b.model, &settings, &ropts.limits)
                    .map(|solver| {
                        Some(Driver {
                            stats_before: b.stats,
                            switch_after: b.switch_after,
                            switched_at: b.switched_at,
                            adhesion_at: b.adhesion_at,
                            adhesion_added_at: b.adhesion_added_at,
                            ..Driver::with_solver(leader.case, &ropts, solver)
                        })
                    })
                    .map_err(|e| format!("restart at the parting t = {t} s: {e}"))
            }
        };
        let mut driver = match driver {
            Ok(Some(d)) => d,
            // No member could start (each already ended with its error).
            Ok(None) => return,
            Err(reason) => {
                let stop = Stop::new(FailureKind::Integration, reason);
                for tr in tracks {
                    self.end(tr, Stats::default(), Some(stop.clone()));
                }
                return;
            }
        };
        self.go_on(&mut driver, tracks);
        driver.finish();
    }

    /// Creates the files of every member (failures end that member) and the driver on the
    /// leader's system. `None` when no member could start.
    fn fresh(&self, tracks: &mut Vec<Track>, ropts: &RunOptions) -> Result<Option<Driver>, String> {
        let mut trunk: Option<Cell> = None;
        let mut kept = Vec::new();
        for mut tr in std::mem::take(tracks) {
            let m = &self.members[tr.k];
            let setup = Instant::now();
            let started = build_model(m.case, m.file, &m.opts.settings).and_then(|model| {
                let mut files = RunWriter::create(m.case, m.file, &m.opts, &model)?;
                let y0 = vec![0.0; model.size()];
                if let Err(stop) = files.output(&model, 0.0, &y0, &y0) {
                    let message = stop.into_stop()?.reason;
                    return Err(RunError::Model {
                        file: m.file.into(),
                        message,
                    });
                }
                files.summary.setup_seconds = setup.elapsed().as_secs_f64();
                Ok((model, files))
            });
            match started {
                Ok((model, files)) => {
                    tr.files = Some(files);
                    if trunk.is_none() {
                        trunk = Some(model);
                    }
                    kept.push(tr);
                }
                Err(e) => self.finish(tr.k, Err(e)),
            }
        }
        *tracks = kept;
        let Some(model) = trunk else { return Ok(None) };
        let leader = &self.members[tracks[0].k];
        Driver::new(leader.case, ropts, model)
            .map(Some)
            .map_err(|e| e.to_string())
    }

    /// Runs `tracks` on `driver` stretch by stretch: at each parting the members that end
    /// there are finished; the others go on here when they still all agree, else each
    /// subgroup that agrees is queued as a restart.
    fn go_on(&self, driver: &mut Driver, mut tracks: Vec<Track>) {
        loop {
            let t0 = driver.solver.integ_ref().t();
            let t_max = tracks
                .iter()
                .map(|tr| self.case(tr).phases.t_end)
                .fold(0.0, f64::max);
            let tol = 1e-9 * t_max.max(1.0);
            let mut end = self.stretch_end(driver, &tracks);
            if end <= t0 + tol && tracks.len() > 1 {
                // Parted already (only if sharing is not transitive): each on its own.
                end = t0;
            }
            let start = Instant::now();
            let stop = if end > t0 + tol {
                self.stretch(driver, &mut tracks, end, start)
            } else {
                None
            };
            if end.is_infinite() {
                // A run that waited for its phases: it ended where its end became known.
                end = driver.solver.integ_ref().t();
            }
            let wall = start.elapsed().as_secs_f64();
            for tr in &mut tracks {
                tr.wall_before += wall;
            }
            if let Some(stop) = stop {
                for mut tr in tracks {
                    let mut stop = stop.clone();
                    if let Some(files) = tr.files.as_mut() {
                        let (t, y, yp) = driver.solver.integ_ref().last_step();
                        if let Err(e) = files.stopped_state(driver.solver.model(), t, y, yp) {
                            let why = match e.into_stop() {
                                Ok(s) => s.reason,
                                Err(e) => e.to_string(),
                            };
                            stop.reason =
                                format!("{} (its last state not written: {why})", stop.reason);
                        }
                    }
                    self.end(tr, driver.stats(), Some(stop));
                }
                return;
            }
            // Members that end here; the others in subgroups that still agree. One
            // subgroup goes on here; several each restart from the state here.
            let names: Vec<String> = tracks.iter().map(|tr| self.case(tr).name.clone()).collect();
            let (ending, going): (Vec<Track>, Vec<Track>) = tracks
                .into_iter()
                .partition(|tr| driver.t_end(self.case(tr)) <= end + tol);
            for mut tr in ending {
                // Computed with the others to its end.
                let others: Vec<String> = going.iter().map(|g| self.case(g).name.clone()).collect();
                if let (Some(f), false) = (tr.files.as_mut(), others.is_empty()) {
                    f.summary.shared.push(Parting {
                        t: end,
                        from: others,
                        restarted: false,
                    });
                }
                self.end(tr, driver.stats(), None);
            }
            if going.is_empty() {
                return;
            }
            let indices: Vec<usize> = (0..going.len()).collect();
            let classes = if end > t0 + tol {
                partition(&indices, |a, b| {
                    shared_until(self.case(&going[a]), self.case(&going[b])) > end + tol
                })
            } else {
                indices.iter().map(|&i| vec![i]).collect()
            };
            let mut slots: Vec<Option<Track>> = going.into_iter().map(Some).collect();
            let mut continuing = None;
            let alone = classes.len() == 1 && end > t0 + tol;
            for class in classes {
                let mut sub: Vec<Track> = class.iter().filter_map(|&i| slots[i].take()).collect();
                let goes_on = alone;
                if sub.len() < names.len() {
                    let from: Vec<String> = names
                        .iter()
                        .filter(|n| !sub.iter().any(|tr| &&self.case(tr).name == n))
                        .cloned()
                        .collect();
                    for tr in &mut sub {
                        if let Some(f) = tr.files.as_mut() {
                            f.summary.shared.push(Parting {
                                t: end,
                                from: from.clone(),
                                restarted: !goes_on,
                            });
                        }
                    }
                }
                if goes_on {
                    continuing = Some(sub);
                } else {
                    self.branch(driver, sub);
                }
            }
            match continuing {
                Some(sub) => {
                    let parted = sub.len() < names.len();
                    tracks = sub;
                    if parted {
                        let label = self.label(&tracks);
                        let t_end = self.case(&tracks[0]).phases.t_end;
                        driver.relabel((self.progress)(&label, t_end), t_end);
                    }
                }
                None => return,
            }
        }
    }

    /// Integrates `tracks` from the driver's time to `end`, writing each member's outputs
    /// at its own output times. Returns the stop that ends them all, if any; a member whose
    /// files cannot be written ends alone.
    fn stretch(
        &self,
        driver: &mut Driver,
        tracks: &mut Vec<Track>,
        end: f64,
        start: Instant,
    ) -> Option<Stop> {
        let tol = 1e-9 * self.case(&tracks[0]).phases.t_end.max(1.0);
        // The output times, those of the phases the cell starts itself as they become
        // known: recomputed after each start.
        let member_times = |driver: &Driver, tracks: &[Track]| -> Vec<Vec<f64>> {
            tracks
                .iter()
                .map(|tr| driver.output_times(self.case(tr)))
                .collect()
        };
        let mut per_member = member_times(driver, tracks);
        loop {
            let t_now = driver.solver.integ_ref().t();
            let next = per_member
                .iter()
                .flatten()
                .copied()
                .filter(|&t| t > t_now + tol && t <= end + tol)
                .min_by(f64::total_cmp);
            let (tout, deadline) = match next {
                Some(t) => (t, false),
                None if driver.schedule.t_end().is_infinite() => (driver.schedule.deadline(), true),
                None => return None,
            };
            let tout = match driver.advance_to(tout) {
                Advance::Stopped(stop) => return Some(stop),
                Advance::Started => {
                    per_member = member_times(driver, tracks);
                    let t = driver.solver.integ_ref().t();
                    for tr in tracks.iter_mut() {
                        if let Some(f) = tr.files.as_mut() {
                            f.set_schedule(&driver.schedule);
                        }
                    }
                    t
                }
                Advance::Reached if deadline => {
                    let waiting: Vec<String> = driver
                        .schedule
                        .events()
                        .into_iter()
                        .filter(|e| e.t.is_none())
                        .map(|e| format!("the {} phase's {}", e.phase, e.condition))
                        .collect();
                    let reason = format!(
                        "{} did not hold by t = {tout} s ({} × the case's t_end)",
                        waiting.join(" and "),
                        super::events::DEADLINE
                    );
                    return Some(Stop {
                        t: Some(tout),
                        ..Stop::new(FailureKind::NoEvent, reason)
                    });
                }
                Advance::Reached => tout,
            };
            let mut failed = Vec::new();
            for (i, tr) in tracks.iter_mut().enumerate() {
                if !per_member[i].iter().any(|t| (t - tout).abs() <= tol) {
                    continue;
                }
                let Some(files) = tr.files.as_mut() else {
                    continue;
                };
                let (model, y, yp) = driver.state();
                if let Err(stop) = files.output(model, tout, y, yp) {
                    match stop.into_stop() {
                        Ok(stop) => return Some(stop),
                        Err(e) => {
                            failed.push((i, e));
                            continue;
                        }
                    }
                }
                files.summary.stats = driver.stats();
                files.summary.inertia_switched_off_at = driver.switched_at;
                files.summary.adhesion_unknowns_added_at = driver.adhesion_added_at;
                files.summary.wall_seconds = tr.wall_before + start.elapsed().as_secs_f64();
                if let Err(e) = files.write_summary_if_due() {
                    failed.push((i, e));
                }
            }
            for (i, e) in failed.into_iter().rev() {
                let tr = tracks.remove(i);
                self.finish(tr.k, Err(e));
            }
            if tracks.is_empty() {
                return None;
            }
            if let Some(reason) = driver.switch_overdue() {
                return Some(Stop::new(FailureKind::Integration, reason));
            }
        }
    }

    /// Queues `sub` to restart from the driver's state with its leader's model.
    fn branch(&self, driver: &Driver, sub: Vec<Track>) {
        let (model, y, yp) = driver.state();
        let t = driver.solver.integ_ref().t();
        let lead = &self.members[sub[0].k];
        let built = crate::scene::model_params(lead.case, lead.file, model.inertia())
            .map_err(|e| e.to_string())
            .and_then(|params| {
                model
                    .branched(params, State { t, y, yp })
                    .map_err(|e| e.to_string())
            });
        match built {
            Ok(model) => self.push(Task {
                members: sub,
                start: Start::Branch(Box::new(Branch {
                    model,
                    stats: driver.stats(),
                    switch_after: driver.switch_after,
                    switched_at: driver.switched_at,
                    adhesion_at: driver.adhesion_at,
                    adhesion_added_at: driver.adhesion_added_at,
                    last_step: driver.solver.integ_ref().stats().last_step,
                })),
            }),
            Err(reason) => {
                for tr in sub {
                    self.end(
                        tr,
                        driver.stats(),
                        Some(Stop::new(FailureKind::Integration, reason.clone())),
                    );
                }
            }
        }
    }

    /// Writes a member's final summary (finished, or stopped) and reports it.
    fn end(&self, tr: Track, stats: Stats, stop: Option<Stop>) {
        let m = &self.members[tr.k];
        let Some(files) = tr.files else {
            let message = stop
                .map(|s| s.reason)
                .unwrap_or_else(|| "not started".into());
            self.finish(
                tr.k,
                Err(RunError::Model {
                    file: m.file.into(),
                    message,
                }),
            );
            return;
        };
        let result = files.finish(m.case, stats, tr.wall_before, stop);
        self.finish(tr.k, result);
    }
}
