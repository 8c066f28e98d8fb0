//! `cellsim table RUN_DIR...`: one markdown row per run directory, from its
//! `summary.json` alone — outcome, cost and final values, or the reason a run stopped.
//! Used for the README's hard-case table; works on finished, failed and interrupted runs.

use std::fmt::Write as _;

use crate::run_files::Summary;
use crate::run_files::read::RunData;

/// The table's header (markdown).
pub const HEADER: &str = "| run | outcome | unknowns | wall [s] | steps | Jacobians | t reached [s] | contact radius [µm] | uy_top [µm] | ‖E‖ nucleus | ‖E‖ cytoplasm |\n|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|";

/// One markdown row for a run: "finished", or "stopped: \<reason\>" (shortened to its
/// first sentence and the callback's report, if any).
pub fn row(s: &Summary) -> String {
    let outcome = match (&s.failure, s.finished) {
        (_, true) => "finished".to_string(),
        (Some(f), false) => format!("stopped: {}", short_reason(&f.reason)),
        (None, false) => "interrupted or running".to_string(),
    };
    let mut r = format!(
        "| {} | {} | {} | {:.1} | {} | {} |",
        s.case,
        outcome.replace('|', "/"),
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
    let outcome = match s {
        Some(s) if s.finished => "finished".to_string(),
        Some(s) => match &s.failure {
            Some(f) => format!("stopped: {}", short_reason(&f.reason)).replace('|', "/"),
            None => "interrupted or running".into(),
        },
        None => "no summary".into(),
    };
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
