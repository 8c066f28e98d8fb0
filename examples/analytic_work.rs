//! Work against error on SUNDIALS' idaAnalytic_mels problem (x₁ = eᵗ, x₂ = eᵗ/(t − 2),
//! α = 10, t ∈ [0, 1]): IDA over an rtol ladder and the fixed-step BDF2 over a dt ladder,
//! each with its error at t = 1 (max over the two components, relative to the exact
//! value) and its work: steps, residual evaluations, Jacobian evaluations, wall time
//! (mean over repetitions of the whole integration). Then, for a few target errors, the
//! work of each integrator interpolated log–log on its ladder and the BDF2/IDA ratio.
//!
//! `cargo run --release --example analytic_work`

use std::time::Instant;

use cellsim::dae::bdf2::{Bdf2, Bdf2Options};
use cellsim::dae::problems::Analytic;
use cellsim::dae::{Atol, Integrator, Stats};
use cellsim::sundials::{Ida, IdaOptions};

/// Repeat each integration until this much wall time has passed (at least once).
const MIN_WALL: f64 = 0.2;

fn error(y: &[f64]) -> f64 {
    let (exact, _) = Analytic::exact(1.0);
    (0..2)
        .map(|i| ((y[i] - exact[i]) / exact[i]).abs())
        .fold(0.0, f64::max)
}

/// Error, statistics and mean wall seconds of one integration to t = 1.
fn measure(make: &dyn Fn() -> Box<dyn Integrator>) -> (f64, Stats, f64) {
    let mut out = None;
    let t0 = Instant::now();
    let mut reps = 0;
    while reps == 0 || t0.elapsed().as_secs_f64() < MIN_WALL {
        let mut integ = make();
        integ
            .advance_to(1.0, &mut |_, _| true)
            .expect("integration");
        out = Some((error(integ.y()), integ.stats()));
        reps += 1;
    }
    let wall = t0.elapsed().as_secs_f64() / reps as f64;
    let (e, s) = out.unwrap();
    (e, s, wall)
}

/// log–log interpolation of `work` at error `target` on a ladder of (error, work).
fn work_at(ladder: &[(f64, f64)], target: f64) -> Option<f64> {
    ladder.windows(2).find_map(|w| {
        let ((e0, w0), (e1, w1)) = (w[0], w[1]);
        let (lo, hi) = (e0.min(e1), e0.max(e1));
        (target >= lo && target <= hi && e0 != e1).then(|| {
            let s = (target.ln() - e0.ln()) / (e1.ln() - e0.ln());
            (w0.ln() + s * (w1.ln() - w0.ln())).exp()
        })
    })
}

fn main() {
    println!("integrator  setting   error(t=1)   steps  res.evals  jac.evals   wall[us]");
    let mut ida_ladder = Vec::new();
    for k in 3..=10 {
        let rtol = 10f64.powi(-k);
        let make = || -> Box<dyn Integrator> {
            let opts = IdaOptions {
                rtol,
                atol: Atol::Scalar(rtol * 1e-2),
                // x₂ is algebraic: kept in the error test, IDA needs ~17× more steps at
                // rtol 1e-4 and hundreds of error-test failures (as SUNDIALS' own
                // idaAnalytic_mels output shows); its error is still measured here.
                suppress_alg: true,
                ..Default::default()
            };
            Box::new(Ida::new(Analytic::new(10.0), opts).unwrap())
        };
        let (e, s, wall) = measure(&make);
        println!(
            "IDA         rtol 1e-{k:<2} {e:10.3e}  {:6}  {:9}  {:9}  {:9.1}",
            s.steps,
            s.residual_evals,
            s.jacobian_evals,
            wall * 1e6
        );
        ida_ladder.push((e, s.residual_evals as f64, wall));
    }
    let mut bdf_ladder = Vec::new();
    for k in 4..=13 {
        let dt = 2f64.powi(-k);
        let make = || -> Box<dyn Integrator> {
            let opts = Bdf2Options {
                dt,
                rtol: 1e-10,
                atol: Atol::Scalar(1e-12),
                ..Default::default()
            };
            Box::new(Bdf2::new(Analytic::new(10.0), opts).unwrap())
        };
        let (e, s, wall) = measure(&make);
        println!(
            "BDF2        dt 2^-{k:<2}  {e:10.3e}  {:6}  {:9}  {:9}  {:9.1}",
            s.steps,
            s.residual_evals,
            s.jacobian_evals,
            wall * 1e6
        );
        bdf_ladder.push((e, s.residual_evals as f64, wall));
    }
    println!("\nat equal error (log-log interpolation on each ladder):");
    println!(
        "  error    IDA res.evals  BDF2 res.evals  ratio   IDA wall[us]  BDF2 wall[us]  ratio"
    );
    for target in [1e-4, 1e-5, 1e-6, 1e-7] {
        let pick = |l: &[(f64, f64, f64)], wall: bool| {
            let pts: Vec<(f64, f64)> = l
                .iter()
                .map(|&(e, r, w)| (e, if wall { w * 1e6 } else { r }))
                .collect();
            work_at(&pts, target)
        };
        match (
            pick(&ida_ladder, false),
            pick(&bdf_ladder, false),
            pick(&ida_ladder, true),
            pick(&bdf_ladder, true),
        ) {
            (Some(ri), Some(rb), Some(wi), Some(wb)) => println!(
                "  {target:.0e}  {ri:13.0}  {rb:14.0}  {:5.1}  {wi:12.1}  {wb:13.1}  {:5.1}",
                rb / ri,
                wb / wi
            ),
            _ => println!("  {target:.0e}  (outside one of the ladders)"),
        }
    }
}
