//! Optional wall-clock timers around what IDA calls: the residual, the Jacobian, the
//! factorization and the solve, and IDA's own calls (IDASolve, IDACalcIC) that contain
//! them. "Where the time goes": IDA's internals are its own time minus the callbacks'.
//!
//! Compiled in only with the cargo feature `timers`; without it [`time`] is the bare call
//! (no clock read, no counter) and [`totals`] returns zeros. With it, the totals are
//! process-wide (relaxed atomics), so one run at a time should be measured:
//! `cargo run --release --features timers -- run CASE.ron --quiet` prints the breakdown
//! at the end of the run and writes it into summary.json (`timers`).

/// What is being timed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Phase {
    /// `Dae::residual` called by IDA.
    Residual = 0,
    /// `Dae::jacobian` called by IDA.
    Jacobian = 1,
    /// `LinearSolver::factorize` (IDA's linear-solver setup).
    Factorize = 2,
    /// `LinearSolver::solve_in_place` (IDA's linear-solver solve).
    Solve = 3,
    /// Inside IDASolve or IDACalcIC (contains all of the above).
    Ida = 4,
}

/// Whether the timers are compiled in (cargo feature `timers`).
pub const ENABLED: bool = cfg!(feature = "timers");

/// Accumulated time and number of calls per [`Phase`], indexed by `Phase as usize`.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Totals {
    /// Seconds spent.
    pub seconds: [f64; 5],
    /// Number of calls.
    pub calls: [u64; 5],
}

impl Totals {
    /// Seconds in `phase`.
    pub fn get(&self, phase: Phase) -> f64 {
        self.seconds[phase as usize]
    }

    /// Calls of `phase`.
    pub fn count(&self, phase: Phase) -> u64 {
        self.calls[phase as usize]
    }

    /// IDA's own work: time inside IDA minus the callbacks it made.
    pub fn ida_internal(&self) -> f64 {
        self.get(Phase::Ida)
            - self.get(Phase::Residual)
            - self.get(Phase::Jacobian)
            - self.get(Phase::Factorize)
            - self.get(Phase::Solve)
    }
}

#[cfg(feature = "timers")]
mod imp {
    use std::sync::atomic::{AtomicU64, Ordering};

    pub static NANOS: [AtomicU64; 5] = [const { AtomicU64::new(0) }; 5];
    pub static CALLS: [AtomicU64; 5] = [const { AtomicU64::new(0) }; 5];

    pub fn record(i: usize, nanos: u64) {
        NANOS[i].fetch_add(nanos, Ordering::Relaxed);
        CALLS[i].fetch_add(1, Ordering::Relaxed);
    }

    pub fn load(i: usize) -> (u64, u64) {
        (
            NANOS[i].load(Ordering::Relaxed),
            CALLS[i].load(Ordering::Relaxed),
        )
    }

    pub fn reset() {
        for i in 0..5 {
            NANOS[i].store(0, Ordering::Relaxed);
            CALLS[i].store(0, Ordering::Relaxed);
        }
    }
}

/// Runs `f`, adding its wall time to `phase` when the timers are compiled in.
#[inline(always)]
pub fn time<R>(phase: Phase, f: impl FnOnce() -> R) -> R {
    #[cfg(feature = "timers")]
    {
        let start = std::time::Instant::now();
        let r = f();
        imp::record(phase as usize, start.elapsed().as_nanos() as u64);
        r
    }
    #[cfg(not(feature = "timers"))]
    {
        let _ = phase;
        f()
    }
}

/// The totals so far (zeros without the `timers` feature).
pub fn totals() -> Totals {
    #[allow(unused_mut)]
    let mut t = Totals::default();
    #[cfg(feature = "timers")]
    for i in 0..5 {
        let (ns, calls) = imp::load(i);
        t.seconds[i] = ns as f64 * 1e-9;
        t.calls[i] = calls;
    }
    t
}

/// Sets every total back to zero.
pub fn reset() {
    #[cfg(feature = "timers")]
    imp::reset();
}
