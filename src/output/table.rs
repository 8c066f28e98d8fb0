//! `cellsim table RUN_DIR...`: one markdown row per run directory, from its
//! `summary.json` alone — outcome, cost and final values, or the reason a run stopped.
//! Used for the README's hard-case table; works on finished, failed and interrupted runs.

use std::fmt::Write as _;

use crate::record::Summary;

/// The table's header (markdown).
pub const HEADER: &str = "| run | outcome | unknowns | wall [s] | steps | Jacobians | t reached [s] | contact radius [µm] | uy_top [µm] | ‖E‖ nucleus | ‖E‖ cytoplasm |\n|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|";

/// One markdown row for a run: "finished", or "stopped: <reason>" (shortened to its
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
