//! IDA's nonlinear solver, ours: a `SUNNonlinearSolver` of type ROOTFIND that does what
//! SUNDIALS' Newton module does (the same iterates to the bit, tested), records why each
//! attempt failed, and can take Broyden's quasi-Newton updates on the kept factorization.
//!
//! IDA solves one nonlinear system per step attempt, G(ycor) = F(t, y_pred + ycor,
//! ẏ_pred + cj ycor) = 0, by iterations ycor += δ with δ = −M⁻¹ G(ycor), M the iteration
//! matrix of the last set-up (IDA scales the solve by 2/(1 + cj/cj_M) when cj moved since).
//! IDA's own test ends the iteration: converged, or failed when the contraction rate
//! exceeds 0.9 ("rate"); the solver itself fails after the most iterations allowed
//! ("iterations"). A failure on a kept matrix is retried once on a fresh one (IDA's
//! `jbad`); a failure on a fresh matrix goes back to IDA, which cuts the step.
//!
//! With [`NonlinearMethod::Broyden`] the steps after the first of an attempt take
//! Broyden's updates of M ([`crate::dae::nonlinear`]), up to `max_updates` of them; past
//! that the updates start again from M. Each attempt starts from M, as its set-ups do. An
//! attempt that took updates and failed on a fresh matrix is made once more with plain
//! Newton steps on that matrix before IDA is told (and cuts the step): the updates never
//! fail a step that Newton would have taken.

use std::os::raw::{c_int, c_long, c_void};
use std::ptr;

use sundials_sys as sys;

use super::{Context, NVector, guard, view, view_mut};
use crate::dae::nonlinear::{
    FailureReason, NewtonCounts, NewtonFailure, NonlinearMethod, broyden_step, dot_w,
};

/// Most failures kept one by one ([`Nls::failures`]); the counts go on.
const MAX_RECORDS: usize = 100_000;

/// The Rust side of the solver: IDA's callbacks, the work vector, the counters.
struct NlsState {
    sys_fn: sys::SUNNonlinSolSysFn,
    lsetup: sys::SUNNonlinSolLSetupFn,
    lsolve: sys::SUNNonlinSolLSolveFn,
    ctest: sys::SUNNonlinSolConvTestFn,
    ctest_data: *mut c_void,
    max_iters: c_int,
    /// Iterations and convergence failures of the current solve (IDA reads them after
    /// each solve and adds them up), and the iteration within the current attempt.
    niters: c_long,
    nconvfails: c_long,
    curiter: c_int,
    /// Whether the matrix is current (set up during this solve).
    jcur: c_int,
    delta: NVector,
    method: NonlinearMethod,
    /// Broyden's steps of this attempt and their squared weighted norms.
    steps: Vec<Vec<f64>>,
    norms: Vec<f64>,
    /// cj of the last set-up, written by the Jacobian callback.
    cj_setup: *const f64,
    failures: Vec<NewtonFailure>,
    counts: NewtonCounts,
}

/// Our nonlinear solver, attached to one IDA memory.
pub(crate) struct Nls {
    pub(crate) raw: sys::SUNNonlinearSolver,
    state: Box<NlsState>,
}

impl Drop for Nls {
    fn drop(&mut self) {
        // SAFETY: created by SUNNonlinSolNewEmpty; IDA does not own it (attached with
        // IDASetNonlinearSolver), and the IDA memory using it is freed before this (Ida's
        // Drop). The content is Rust's: only the shell and its ops are freed.
        unsafe {
            if !self.raw.is_null() {
                (*self.raw).content = ptr::null_mut();
                sys::SUNNonlinSolFreeEmpty(self.raw);
            }
        }
    }
}

impl Nls {
    /// A solver for systems of `n` unknowns; `cj_setup` points at the cj of the last
    /// set-up (owned by the caller, alive and unmoved as long as the solver is).
    pub(crate) fn new(
        n: usize,
        method: NonlinearMethod,
        cj_setup: *const f64,
        ctx: &Context,
    ) -> Result<Self, String> {
        let mut state = Box::new(NlsState {
            sys_fn: None,
            lsetup: None,
            lsolve: None,
            ctest: None,
            ctest_data: ptr::null_mut(),
            max_iters: 4,
            niters: 0,
            nconvfails: 0,
            curiter: 0,
            jcur: 0,
            delta: NVector::new(n, ctx)?,
            method,
            steps: Vec::new(),
            norms: Vec::new(),
            cj_setup,
            failures: Vec::new(),
            counts: NewtonCounts::default(),
        });
        // SAFETY: a fresh empty solver (NULL checked); its ops table is ours to fill, and
        // its content points at the boxed state, which never moves while the box lives.
        unsafe {
            let raw = sys::SUNNonlinSolNewEmpty(ctx.0);
            if raw.is_null() {
                return Err("SUNNonlinSolNewEmpty failed".into());
            }
            (*raw).content = (&mut *state as *mut NlsState).cast();
            let ops = &mut *(*raw).ops;
            ops.gettype = Some(nls_gettype);
            ops.initialize = Some(nls_initialize);
            ops.solve = Some(nls_solve);
            ops.free = Some(nls_free);
            ops.setsysfn = Some(nls_setsysfn);
            ops.setlsetupfn = Some(nls_setlsetupfn);
            ops.setlsolvefn = Some(nls_setlsolvefn);
            ops.setctestfn = Some(nls_setctestfn);
            ops.setmaxiters = Some(nls_setmaxiters);
            ops.getnumiters = Some(nls_getnumiters);
            ops.getcuriter = Some(nls_getcuriter);
            ops.getnumconvfails = Some(nls_getnumconvfails);
            Ok(Self { raw, state })
        }
    }

    /// The failed attempts so far (the first [`MAX_RECORDS`]).
    pub(crate) fn failures(&self) -> &[NewtonFailure] {
        &self.state.failures
    }

    /// The failed attempts counted by kind, and the Broyden updates.
    pub(crate) fn counts(&self) -> NewtonCounts {
        self.state.counts
    }
}

unsafe fn state<'a>(nls: sys::SUNNonlinearSolver) -> &'a mut NlsState {
    // SAFETY: the content was set to the boxed NlsState in `Nls::new`.
    unsafe { &mut *((*nls).content as *mut NlsState) }
}

unsafe extern "C" fn nls_gettype(_nls: sys::SUNNonlinearSolver) -> sys::SUNNonlinearSolver_Type {
    sys::SUNNonlinearSolver_Type_SUNNONLINEARSOLVER_ROOTFIND
}

unsafe extern "C" fn nls_initialize(nls: sys::SUNNonlinearSolver) -> c_int {
    // SAFETY: our solver.
    let s = unsafe { state(nls) };
    if s.sys_fn.is_none() || s.lsolve.is_none() || s.ctest.is_none() {
        return sys::SUN_NLS_MEM_NULL;
    }
    s.niters = 0;
    s.nconvfails = 0;
    s.jcur = 0;
    0
}

unsafe extern "C" fn nls_free(nls: sys::SUNNonlinearSolver) -> c_int {
    // IDA never frees a solver it does not own; the shell is freed by `Nls`'s Drop.
    let _ = nls;
    0
}

unsafe extern "C" fn nls_setsysfn(
    nls: sys::SUNNonlinearSolver,
    f: sys::SUNNonlinSolSysFn,
) -> c_int {
    // SAFETY: our solver.
    unsafe { state(nls).sys_fn = f };
    0
}

unsafe extern "C" fn nls_setlsetupfn(
    nls: sys::SUNNonlinearSolver,
    f: sys::SUNNonlinSolLSetupFn,
) -> c_int {
    // SAFETY: our solver.
    unsafe { state(nls).lsetup = f };
    0
}

unsafe extern "C" fn nls_setlsolvefn(
    nls: sys::SUNNonlinearSolver,
    f: sys::SUNNonlinSolLSolveFn,
) -> c_int {
    // SAFETY: our solver.
    unsafe { state(nls).lsolve = f };
    0
}

unsafe extern "C" fn nls_setctestfn(
    nls: sys::SUNNonlinearSolver,
    f: sys::SUNNonlinSolConvTestFn,
    data: *mut c_void,
) -> c_int {
    // SAFETY: our solver.
    let s = unsafe { state(nls) };
    s.ctest = f;
    s.ctest_data = data;
    0
}

unsafe extern "C" fn nls_setmaxiters(nls: sys::SUNNonlinearSolver, m: c_int) -> c_int {
    if m < 1 {
        return sys::SUN_NLS_ILL_INPUT;
    }
    // SAFETY: our solver.
    unsafe { state(nls).max_iters = m };
    0
}

unsafe extern "C" fn nls_getnumiters(nls: sys::SUNNonlinearSolver, n: *mut c_long) -> c_int {
    // SAFETY: our solver, and IDA's out-pointer.
    unsafe { *n = state(nls).niters };
    0
}

unsafe extern "C" fn nls_getcuriter(nls: sys::SUNNonlinearSolver, n: *mut c_int) -> c_int {
    // SAFETY: our solver, and IDA's out-pointer.
    unsafe { *n = state(nls).curiter };
    0
}

unsafe extern "C" fn nls_getnumconvfails(nls: sys::SUNNonlinearSolver, n: *mut c_long) -> c_int {
    // SAFETY: our solver, and IDA's out-pointer.
    unsafe { *n = state(nls).nconvfails };
    0
}

/// The nonlinear solve IDA calls once per step attempt: SUNDIALS' Newton loop (the same
/// calls in the same order), with Broyden's updates where asked, and every failed attempt
/// recorded.
unsafe extern "C" fn nls_solve(
    nls: sys::SUNNonlinearSolver,
    _y0: sys::N_Vector,
    ycor: sys::N_Vector,
    w: sys::N_Vector,
    tol: f64,
    call_lsetup: c_int,
    mem: *mut c_void,
) -> c_int {
    // SAFETY: our solver; IDA passes valid serial vectors and its memory. The callbacks
    // are IDA's own (C), called as SUNDIALS' Newton calls them. No Rust code in here can
    // panic but slice arithmetic on equal lengths, under `guard` nonetheless.
    let out = guard(|| unsafe { solve_inner(nls, ycor, w, tol, call_lsetup, mem) });
    out.unwrap_or(-1)
}

unsafe fn solve_inner(
    nls: sys::SUNNonlinearSolver,
    ycor: sys::N_Vector,
    w: sys::N_Vector,
    tol: f64,
    mut call_lsetup: c_int,
    mem: *mut c_void,
) -> c_int {
    // SAFETY: see `nls_solve`.
    unsafe {
        let s = state(nls);
        let (Some(sys_fn), Some(lsolve), Some(ctest)) = (s.sys_fn, s.lsolve, s.ctest) else {
            return sys::SUN_NLS_MEM_NULL;
        };
        let delta = s.delta.0;
        let mut jbad: c_int = 0;
        // Newton steps only: the repeat of an attempt whose updates failed on a fresh matrix.
        let mut plain = false;
        s.niters = 0;
        s.nconvfails = 0;
        let mut retval;
        loop {
            retval = sys_fn(ycor, delta, mem);
            let residual_refused = retval != 0;
            if retval == 0 && call_lsetup != 0 {
                retval = match s.lsetup {
                    Some(lsetup) => lsetup(jbad, &mut s.jcur, mem),
                    None => sys::SUN_NLS_MEM_NULL,
                };
            }
            if retval != 0 {
                // As SUNDIALS' Newton: a residual refused at the predictor, or a failed
                // set-up, goes back to IDA (which cuts the step) without another attempt:
                // the same attempt would fail the same way.
                if retval > 0 {
                    record(s, retval, !residual_refused, mem);
                }
                break;
            }
            let mut linear = false;
            let updates_before = s.counts.updates;
            s.curiter = 0;
            s.steps.clear();
            s.norms.clear();
            loop {
                s.niters += 1;
                for d in view_mut(delta).iter_mut() {
                    *d = -*d;
                }
                retval = lsolve(delta, mem);
                if retval != 0 {
                    linear = true;
                    break;
                }
                if let (NonlinearMethod::Broyden { max_updates }, false) = (s.method, plain) {
                    let (z, wv) = (view_mut(delta), view(w));
                    if s.curiter > 0
                        && s.steps.len() <= max_updates
                        && broyden_step(z, &s.steps, &s.norms, wv)
                    {
                        s.counts.updates += 1;
                    } else {
                        // The first step, past the updates allowed, or a vanishing
                        // denominator: a plain step on M, the updates started again.
                        s.steps.clear();
                        s.norms.clear();
                    }
                    if s.steps.len() <= max_updates {
                        let n = dot_w(z, z, wv);
                        if n > 0.0 && n.is_finite() {
                            s.steps.push(z.to_vec());
                            s.norms.push(n);
                        }
                    }
                }
                for (y, d) in view_mut(ycor).iter_mut().zip(view(delta)) {
                    *y += d;
                }
                retval = ctest(nls, ycor, delta, tol, w, s.ctest_data);
                if retval == 0 {
                    s.jcur = 0;
                    return 0;
                }
                if retval != sys::SUN_NLS_CONTINUE {
                    break;
                }
                s.curiter += 1;
                if s.curiter >= s.max_iters {
                    retval = sys::SUN_NLS_CONV_RECVR;
                    break;
                }
                retval = sys_fn(ycor, delta, mem);
                if retval != 0 {
                    break;
                }
            }
            if retval > 0 {
                record(s, retval, linear, mem);
            }
            if retval > 0 && s.jcur == 0 && s.lsetup.is_some() {
                s.nconvfails += 1;
                call_lsetup = 1;
                jbad = 1;
                view_mut(ycor).fill(0.0);
                continue;
            }
            if retval > 0 && !plain && s.counts.updates > updates_before {
                s.nconvfails += 1;
                plain = true;
                call_lsetup = 0;
                view_mut(ycor).fill(0.0);
                continue;
            }
            break;
        }
        s.nconvfails += 1;
        retval
    }
}

/// Records a failed attempt (recoverable `retval`) of the solver `s`.
///
/// # Safety
/// `mem` is the IDA memory calling the solver.
unsafe fn record(s: &mut NlsState, retval: c_int, linear: bool, mem: *mut c_void) {
    let reason = if linear {
        FailureReason::Linear
    } else if retval == sys::SUN_NLS_CONV_RECVR {
        if s.curiter >= s.max_iters {
            FailureReason::Iterations
        } else {
            FailureReason::Rate
        }
    } else {
        FailureReason::Residual
    };
    let fresh = s.jcur != 0;
    let c = &mut s.counts;
    match reason {
        FailureReason::Rate => c.rate += 1,
        FailureReason::Iterations => c.iterations += 1,
        FailureReason::Residual => c.residual += 1,
        FailureReason::Linear => c.linear += 1,
    }
    match fresh {
        true => c.fresh += 1,
        false => c.stale += 1,
    }
    if s.failures.len() < MAX_RECORDS {
        let (mut t, mut h, mut cj) = (f64::NAN, f64::NAN, f64::NAN);
        // SAFETY: the IDA memory, out-pointers to locals.
        unsafe {
            sys::IDAGetCurrentTime(mem, &mut t);
            sys::IDAGetCurrentStep(mem, &mut h);
            sys::IDAGetCurrentCj(mem, &mut cj);
        }
        // SAFETY: the caller's cj, alive as long as the solver (`Nls::new`).
        let cj_m = unsafe { *s.cj_setup };
        s.failures.push(NewtonFailure {
            t,
            h,
            cj_ratio: cj / cj_m,
            iterations: s.curiter as u32 + u32::from(reason == FailureReason::Rate),
            fresh,
            reason,
        });
    }
}
