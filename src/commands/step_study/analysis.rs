//! The study's pure functions: log–log fits and interpolation, errors of a run against
//! the reference, and the analysis of a finished ladder (orders, speed-up, reference check).

use serde::{Deserialize, Serialize};

use super::report::{
    OrderFit, Quantity, ReferenceCheck, ReferenceInfo, Role, Speedup, SpeedupAt, StudyReport,
    StudyRow,
};
use super::{ORDER_QUANTITY, StudyOptions, TARGET_ERROR};
use crate::case::Case;
use crate::run_files::Observables;

/// A least-squares line through (ln x, ln y).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LogLogFit {
    /// Slope (the order).
    pub slope: f64,
    /// ln y at ln x = 0.
    pub intercept: f64,
    /// Points used.
    pub n: usize,
}

impl LogLogFit {
    /// y on the fitted line at x.
    pub fn eval(&self, x: f64) -> f64 {
        (self.intercept + self.slope * x.ln()).exp()
    }
}

/// Least-squares fit of ln y = a + p ln x over the points with x, y > 0 and finite;
/// None with fewer than two such points or all x equal.
pub fn fit_loglog(points: &[(f64, f64)]) -> Option<LogLogFit> {
    let pts: Vec<(f64, f64)> = points
        .iter()
        .filter(|(x, y)| x.is_finite() && y.is_finite() && *x > 0.0 && *y > 0.0)
        .map(|(x, y)| (x.ln(), y.ln()))
        .collect();
    let n = pts.len();
    if n < 2 {
        return None;
    }
    let mx = pts.iter().map(|p| p.0).sum::<f64>() / n as f64;
    let my = pts.iter().map(|p| p.1).sum::<f64>() / n as f64;
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    if !(sxx > 0.0) {
        return None;
    }
    let slope = sxy / sxx;
    Some(LogLogFit {
        slope,
        intercept: my - slope * mx,
        n,
    })
}

/// y at `x` on the piecewise log-log line through `points` (taken in order of x; points
/// with non-positive or non-finite coordinates dropped), interpolated between the two
/// points that bracket x. Outside the points' span, extrapolated along the least-squares
/// log-log line through all of them (steadier than the two end points when the data are
/// noisy, as wall times are). Returns (y, extrapolated); None with fewer than two usable
/// points.
pub fn interp_loglog(points: &[(f64, f64)], x: f64) -> Option<(f64, bool)> {
    let mut pts: Vec<(f64, f64)> = points
        .iter()
        .copied()
        .filter(|(a, b)| a.is_finite() && b.is_finite() && *a > 0.0 && *b > 0.0)
        .collect();
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    pts.dedup_by(|a, b| a.0 == b.0);
    if pts.len() < 2 || !(x > 0.0) {
        return None;
    }
    match pts.windows(2).find(|w| w[0].0 <= x && x <= w[1].0) {
        Some(w) => {
            let (x0, y0) = (w[0].0.ln(), w[0].1.ln());
            let (x1, y1) = (w[1].0.ln(), w[1].1.ln());
            let s = (x.ln() - x0) / (x1 - x0);
            Some(((y0 + s * (y1 - y0)).exp(), false))
        }
        None => fit_loglog(&pts).map(|f| (f.eval(x), true)),
    }
}

/// The errors of the displacement curve at which [`speedup_curve`] compares the ladders.
pub const CURVE_ERRORS: [f64; 5] = [1e-3, 1e-4, 1e-5, 1e-6, 1e-7];

/// BDF2's wall over IDA's at each of `errors` of the uy_top curve, each ladder's wall
/// from [`wall_at`] (None where either ladder does not reach).
pub fn speedup_curve(rows: &[StudyRow], errors: &[f64]) -> Vec<SpeedupAt> {
    let q = Quantity::UyTopCurve;
    let (b, i) = (
        work_points(rows, Role::Bdf2, q),
        work_points(rows, Role::Ida, q),
    );
    errors
        .iter()
        .map(|&error| {
            let (bdf2_wall, ida_wall) = (wall_at(&b, error), wall_at(&i, error));
            let ratio = match (bdf2_wall, ida_wall) {
                (Some((bw, _)), Some((iw, _))) if iw > 0.0 => Some(bw / iw),
                _ => None,
            };
            SpeedupAt {
                error,
                bdf2_wall,
                ida_wall,
                ratio,
            }
        })
        .collect()
}

/// Relative errors of `run` (its output rows) against the reference's rows.
pub fn errors_against(
    quantities: &[Quantity],
    run: &[Observables],
    reference: &[Observables],
    finished: bool,
) -> Vec<(Quantity, Option<f64>)> {
    let rel = |a: f64, b: f64| {
        if b != 0.0 {
            (a - b).abs() / b.abs()
        } else {
            (a - b).abs()
        }
    };
    quantities
        .iter()
        .map(|&q| {
            if !finished || run.is_empty() || reference.is_empty() {
                return (q, None);
            }
            let e = match q {
                Quantity::UyTopCurve => curve_error(run, reference),
                _ => {
                    let (a, b) = (run[run.len() - 1], reference[reference.len() - 1]);
                    let same_t = (a.t - b.t).abs() <= 1e-9 * b.t.abs().max(1.0);
                    same_t.then(|| rel(q.final_value(&a), q.final_value(&b)))
                }
            };
            (q, e)
        })
        .collect()
}

/// max_t |uy − uy_ref| / max_t |uy_ref| over the common output times (None if the rows do
/// not share their times).
fn curve_error(run: &[Observables], reference: &[Observables]) -> Option<f64> {
    if run.len() != reference.len() {
        return None;
    }
    let mut diff: f64 = 0.0;
    let mut scale: f64 = 0.0;
    for (a, b) in run.iter().zip(reference) {
        if (a.t - b.t).abs() > 1e-9 * b.t.abs().max(1.0) {
            return None;
        }
        diff = diff.max((a.uy_top - b.uy_top).abs());
        scale = scale.max(b.uy_top.abs());
    }
    Some(if scale > 0.0 { diff / scale } else { diff })
}

/// The ladder points (knob, error of q) of the finished runs of one role.
pub fn ladder_points(rows: &[StudyRow], role: Role, q: Quantity) -> Vec<(f64, f64)> {
    rows.iter()
        .filter(|r| r.role == role && r.finished)
        .filter_map(|r| r.error(q).map(|e| (r.knob(), e)))
        .collect()
}

/// The work-precision points (error of q, wall seconds) of the finished runs of one role.
pub fn work_points(rows: &[StudyRow], role: Role, q: Quantity) -> Vec<(f64, f64)> {
    rows.iter()
        .filter(|r| r.role == role && r.finished)
        .filter_map(|r| r.error(q).map(|e| (e, r.wall_seconds)))
        .collect()
}

/// Wall time at relative error `target` on a ladder's (error, wall) points, see
/// [`interp_loglog`]; an extrapolation is refused (None) when the ladder's fit does not
/// have cost rising as error falls (the error is not converging along the ladder), or
/// when the target lies more than a decade of error beyond the ladder.
pub fn wall_at(points: &[(f64, f64)], target: f64) -> Option<(f64, bool)> {
    let w = interp_loglog(points, target)?;
    if w.1 && !fit_loglog(points).is_some_and(|f| f.slope < 0.0) {
        return None;
    }
    // Nor more than a decade of error beyond the ladder's ends: a ladder whose loosest run
    // is already 1000× within the target says nothing about the cost at the target.
    let (lo, hi) = points
        .iter()
        .map(|p| p.0)
        .filter(|e| *e > 0.0 && e.is_finite())
        .fold((f64::INFINITY, 0.0_f64), |(lo, hi), e| {
            (lo.min(e), hi.max(e))
        });
    if w.1 && (target > 10.0 * hi || target < lo / 10.0) {
        return None;
    }
    Some(w)
}

/// The study's report from its runs: BDF2's order, IDA's slopes, the speed-ups and the
/// check of the reference (`series[0]`, the reference's output rows, as `rows[0]`).
#[allow(clippy::too_many_arguments)]
pub(super) fn analyse(
    case: &Case,
    file: &str,
    opts: &StudyOptions,
    reference: ReferenceInfo,
    rows: &[StudyRow],
    series: &[Vec<Observables>],
    interrupted: bool,
) -> StudyReport {
    let (bdf2_order, bdf2_order_fit) = order_fit(rows);
    let (ida_speedup, ida_speedup_detail) = speedup_at_target(rows);
    let reference_check = check_reference(&reference, rows, series);
    StudyReport {
        case: case.name.clone(),
        case_file: file.to_string(),
        output_times: series.first().map_or(0, |s| s.len()),
        reference,
        reference_check,
        bdf2_order,
        bdf2_order_fit,
        ida_rtol_slopes: slopes(rows, Role::Ida),
        ida_speedup,
        ida_speedup_detail,
        speedup_curve: speedup_curve(rows, &CURVE_ERRORS),
        interrupted,
        settings: opts.settings.clone(),
        runs: rows.to_vec(),
    }
}

/// BDF2's (dt, error of `q`) points, largest dt first, and the orders between successive
/// rungs.
fn bdf2_local_orders(rows: &[StudyRow], q: Quantity) -> (Vec<(f64, f64)>, Vec<f64>) {
    let mut pts = ladder_points(rows, Role::Bdf2, q);
    pts.sort_by(|a, b| b.0.total_cmp(&a.0));
    let orders = pts
        .windows(2)
        .map(|w| (w[0].1 / w[1].1).ln() / (w[0].0 / w[1].0).ln())
        .collect::<Vec<f64>>();
    (pts, orders)
}

/// The slope of each quantity's error against the knob on the ladder of `role`.
fn slopes(rows: &[StudyRow], role: Role) -> Vec<(Quantity, Option<f64>)> {
    Quantity::ALL
        .iter()
        .map(|&q| {
            (
                q,
                fit_loglog(&ladder_points(rows, role, q)).map(|f| f.slope),
            )
        })
        .collect()
}

/// BDF2's fitted order on [`ORDER_QUANTITY`] and the details of the fit.
fn order_fit(rows: &[StudyRow]) -> (Option<f64>, OrderFit) {
    let (sorted, local_orders) = bdf2_local_orders(rows, ORDER_QUANTITY);
    let order = fit_loglog(&sorted).map(|f| f.slope);
    let fit = OrderFit {
        quantity: ORDER_QUANTITY,
        dt: sorted.iter().map(|p| p.0).collect(),
        error: sorted.iter().map(|p| p.1).collect(),
        local_orders,
        final_uy_top_local_orders: bdf2_local_orders(rows, Quantity::UyTop).1,
        per_quantity: slopes(rows, Role::Bdf2),
    };
    (order, fit)
}

/// The cheapest finished run of `role` whose error of the final uy_top is within
/// [`TARGET_ERROR`]: (label, wall \[s\]).
fn cheapest_meeting_target(rows: &[StudyRow], role: Role) -> Option<(String, f64)> {
    rows.iter()
        .filter(|r| r.role == role && r.finished)
        .filter(|r| r.error(Quantity::UyTop).is_some_and(|e| e <= TARGET_ERROR))
        .min_by(|a, b| a.wall_seconds.total_cmp(&b.wall_seconds))
        .map(|r| (r.label.clone(), r.wall_seconds))
}

/// The speed-up at [`TARGET_ERROR`] of the final uy_top, and how it was obtained.
fn speedup_at_target(rows: &[StudyRow]) -> (Option<f64>, Speedup) {
    let q0 = Quantity::UyTop;
    let bdf2_w = wall_at(&work_points(rows, Role::Bdf2, q0), TARGET_ERROR);
    let ida_w = wall_at(&work_points(rows, Role::Ida, q0), TARGET_ERROR);
    let speedup = match (bdf2_w, ida_w) {
        (Some((b, _)), Some((i, _))) if i > 0.0 => Some(b / i),
        _ => None,
    };
    let ida_meeting_target = cheapest_meeting_target(rows, Role::Ida);
    let bdf2_meeting_target = cheapest_meeting_target(rows, Role::Bdf2);
    // A lower bound only from BDF2's wall interpolated at the target: extrapolated beyond
    // its ladder, it bounds nothing.
    let speedup_at_least = match (bdf2_w, &ida_meeting_target) {
        (Some((b, false)), Some((_, i))) if *i > 0.0 => Some(b / i),
        _ => None,
    };
    let cheapest_ratio = match (&bdf2_meeting_target, &ida_meeting_target) {
        (Some((_, b)), Some((_, i))) if *i > 0.0 => Some(b / i),
        _ => None,
    };
    let detail = Speedup {
        target_error: TARGET_ERROR,
        bdf2_wall: bdf2_w.map(|w| w.0),
        bdf2_extrapolated: bdf2_w.is_some_and(|w| w.1),
        ida_wall: ida_w.map(|w| w.0),
        ida_extrapolated: ida_w.is_some_and(|w| w.1),
        ida_meeting_target,
        ida_speedup_at_least: speedup_at_least,
        bdf2_meeting_target,
        cheapest_runs_ratio: cheapest_ratio,
    };
    (speedup, detail)
}

/// The reference against BDF2's two smallest finished rungs (None without one): their
/// difference on the uy_top curve beside BDF2's own error by Richardson extrapolation.
fn check_reference(
    reference: &ReferenceInfo,
    rows: &[StudyRow],
    series: &[Vec<Observables>],
) -> Option<ReferenceCheck> {
    let bdf2_runs: Vec<(usize, &StudyRow)> = {
        let mut v: Vec<(usize, &StudyRow)> = rows
            .iter()
            .enumerate()
            .filter(|(_, r)| r.role == Role::Bdf2 && r.finished)
            .collect();
        v.sort_by(|a, b| a.1.knob().total_cmp(&b.1.knob()));
        v
    };
    bdf2_runs.first().map(|&(k, r)| {
        let uy = |r: &StudyRow| r.final_values.map(|o| o.uy_top).unwrap_or(f64::NAN);
        let uy_ref = reference.final_values.map(|o| o.uy_top).unwrap_or(f64::NAN);
        let scale = series[0].iter().fold(0.0_f64, |m, o| m.max(o.uy_top.abs()));
        let richardson = bdf2_runs.get(1).and_then(|&(k2, r2)| {
            let halved = (r2.knob() / r.knob() - 2.0).abs() < 1e-9;
            let d = series[k]
                .iter()
                .zip(&series[k2])
                .fold(0.0_f64, |m, (a, b)| m.max((a.uy_top - b.uy_top).abs()));
            (halved && series[k].len() == series[k2].len() && scale > 0.0).then(|| d / 3.0 / scale)
        });
        let rel_curve = curve_error(&series[k], &series[0]);
        ReferenceCheck {
            bdf2_label: r.label.clone(),
            dt: r.knob(),
            rel_diff_curve: rel_curve,
            richardson_curve: richardson,
            ratio: match (rel_curve, richardson) {
                (Some(a), Some(b)) if b > 0.0 => Some(a / b),
                _ => None,
            },
            rel_diff_uy_top: (uy(r) - uy_ref).abs() / uy_ref.abs(),
        }
    })
}
