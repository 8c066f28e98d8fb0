//! `cellsim table RUN_DIR...`: one markdown row per run directory, from its
//! `summary.json` alone — outcome, cost and final values, or the reason a run stopped.
//! Used for the README's hard-case table; works on finished, failed and interrupted runs.
//! `--phases` gives when the phases started, `--measures` what a map reports of each run
//! (and how far each is from the first).

use std::fmt::Write as _;

use crate::run_files::Summary;
use crate::run_files::read::RunData;

/// The table's header (markdown).
pub const HEADER: &str = "| run | outcome | unknowns | wall [s] | steps | Jacobians | t reached [s] | contact radius [µm] | uy_top [µm] | ‖E‖ nucleus | ‖E‖ cytoplasm |\n|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|";

/// One markdown row for a run: "finished", or "stopped: \<reason\>" (shortened to its
/// first sentence and the callback's report, if any).
pub fn row(s: &Summary) -> String {
    let mut r = format!(
        "| {} | {} | {} | {:.1} | {} | {} |",
        s.case,
        outcome(s),
        s.unknowns.total,
        s.wall_seconds,
        s.stats.steps,
        s.stats.jacobian_evals
    );
    match &s.final_values {
        Some(o) => {
            let _ = write!(
                r,
                " {} | {:.3} | {:.3} | {:.1} % | {:.1} % |",
                o.t,
                o.contact_radius,
                o.uy_top,
                100.0 * o.strain_nucleus,
                100.0 * o.strain_cytoplasm
            );
        }
        None => r.push_str(" – | – | – | – | – |"),
    }
    r
}

/// The phases' table's header (markdown): `cellsim table --phases`.
pub const PHASES_HEADER: &str = "| run | outcome | adhesion starts [s] | active starts [s] | end [s] | steps | wall [s] | u_y(p_t) [µm] | nucleus lowest [µm] | contact radius [µm] | ‖E‖ nucleus | ‖E‖ cytoplasm |\n|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|";

/// One markdown row of the phases' table: when adhesion and the active strain started —
/// on their conditions (MODEL.md §11, with the condition), else at the case's times (the
/// run's phase lines) — the end time, the cost and the final values.
pub fn phases_row(run: &RunData) -> String {
    let s = run.summary.as_ref();
    let outcome = s.map_or("no summary".into(), outcome);
    let [ta, tb, _, t_end] = run.mesh.phase_times;
    let start = |phase: &str, t: f64| {
        let event = s.and_then(|s| s.events.iter().find(|e| e.phase == phase));
        match event {
            Some(e) => match e.t {
                Some(t) => format!("{t:.0} ({})", e.condition),
                None => format!("– ({}, not met)", e.condition),
            },
            None => format!("{t:.0}"),
        }
    };
    let mut r = format!(
        "| {} | {outcome} | {} | {} | {t_end:.0} | {} | {} |",
        run.name,
        start("adhesion", ta),
        start("active", tb),
        s.map_or("–".into(), |s| s.stats.steps.to_string()),
        s.map_or("–".into(), |s| format!("{:.1}", s.wall_seconds)),
    );
    match s.and_then(|s| s.final_values) {
        Some(o) => {
            let _ = write!(
                r,
                " {:.3} | {:.3} | {:.3} | {:.1} % | {:.1} % |",
                o.uy_top,
                o.uy_nucleus_max,
                o.contact_radius,
                100.0 * o.strain_nucleus,
                100.0 * o.strain_cytoplasm
            );
        }
        None => r.push_str(" – | – | – | – | – |"),
    }
    r
}

/// The measures' table's header (markdown): `cellsim table --measures`.
pub const MEASURES_HEADER: &str = "| run | outcome | t reached [s] | penetration [µm] | u_y(p_t) [µm] | u_y(p_b) [µm] | contact area [µm²] | contact radius, deformed / reference [µm] | mean ‖E‖ nucleus | largest ‖E‖ nucleus |\n|---|---|---:|---:|---:|---:|---:|---:|---:|---:|";

/// The measures a map reports of a run, in [`MEASURES_HEADER`]'s order: penetration depth
/// (3-D), u_y of p_t and p_b, contact area (3-D), contact radius deformed and reference,
/// the mean and the largest nucleus strain. `None` where the run has no such value.
pub fn measures(s: &Summary) -> Option<[Option<f64>; 8]> {
    let o = s.final_values?;
    let f3 = s.final_values_3d;
    Some([
        f3.map(|f| f.penetration_depth),
        Some(o.uy_top),
        Some(o.uy_bottom),
        f3.map(|f| f.contact_area),
        Some(o.contact_radius),
        Some(o.contact_radius_ref),
        Some(o.strain_nucleus),
        s.strain_nucleus_max,
    ])
}

/// One markdown row of the measures' table for `s`; with `against` (the first run's
/// measures) a second row of the relative differences from it, in percent.
pub fn measures_rows(s: &Summary, against: Option<&[Option<f64>; 8]>) -> String {
    let outcome = outcome(s);
    let t = s.final_values.map_or("–".into(), |o| format!("{}", o.t));
    let Some(m) = measures(s) else {
        return format!(
            "| {} | {outcome} | {t} | – | – | – | – | – | – | – |",
            s.case
        );
    };
    let v = |x: Option<f64>, f: &dyn Fn(f64) -> String| x.map_or("–".into(), f);
    let d3 = |x: f64| format!("{x:.3}");
    let d1 = |x: f64| format!("{x:.1}");
    let pc = |x: f64| format!("{:.1} %", 100.0 * x);
    let mut r = format!(
        "| {} | {outcome} | {t} | {} | {} | {} | {} | {} / {} | {} | {} |",
        s.case,
        v(m[0], &d3),
        v(m[1], &d3),
        v(m[2], &d3),
        v(m[3], &d1),
        v(m[4], &d3),
        v(m[5], &d3),
        v(m[6], &pc),
        v(m[7], &pc),
    );
    if let Some(a) = against {
        let rel = |k: usize| match (m[k], a[k]) {
            (Some(x), Some(y)) if y != 0.0 => format!("{:+.2} %", 100.0 * (x - y) / y.abs()),
            _ => "–".into(),
        };
        let _ = write!(
            r,
            "\n| difference from the first run | | | {} | {} | {} | {} | {} / {} | {} | {} |",
            rel(0),
            rel(1),
            rel(2),
            rel(3),
            rel(4),
            rel(5),
            rel(6),
            rel(7)
        );
    }
    r
}

/// A run's outcome in a table cell: "finished", "stopped: \<reason\>" (shortened to its
/// first sentence and the callback's report, if any) or "interrupted or running".
fn outcome(s: &Summary) -> String {
    match (&s.failure, s.finished) {
        (_, true) => "finished".to_string(),
        (Some(f), false) => format!("stopped: {}", short_reason(&f.reason)).replace('|', "/"),
        (None, false) => "interrupted or running".to_string(),
    }
}

/// IDA's messages repeat the flag name and the time; keep the readable part.
fn short_reason(reason: &str) -> String {
    // "IDASolve failed at t = … with flag -4 (IDA_CONV_FAIL): [IDA IDASolve -4] At t = …,
    // the corrector … [residual: inadmissible state: …]"
    let mut out = reason.to_string();
    if let Some(i) = reason.find("): [IDA ") {
        let head = &reason[..i + 1];
        let tail = &reason[i + 3..];
        let msg = tail.find("] ").map(|j| &tail[j + 2..]).unwrap_or(tail);
        out = format!("{head}: {msg}");
    }
    out
}

#[cfg(test)]
mod tests {
    use super::short_reason;

    #[test]
    fn ida_reasons_keep_flag_message_and_callback_report() {
        let r = "IDASolve failed at t = 4.711900e4 with flag -9 (IDA_REP_RES_ERR): [IDA IDASolve -9] At t = 47119, repeated recoverable residual errors. [residual: inadmissible state: element 16]";
        assert_eq!(
            short_reason(r),
            "IDASolve failed at t = 4.711900e4 with flag -9 (IDA_REP_RES_ERR): At t = 47119, repeated recoverable residual errors. [residual: inadmissible state: element 16]"
        );
        assert_eq!(short_reason("cannot switch"), "cannot switch");
    }
}
