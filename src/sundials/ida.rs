//! A safe driver for SUNDIALS IDA (variable-order, variable-step BDF for `F(t, y, ẏ) = 0`).
//!
//! The linear solver is a custom `SUNLinearSolver` of type DIRECT written in Rust around a
//! [`LinearSolver`] (faer's LU or KLU), paired with a thin custom `SUNMatrix` whose values
//! live on the Rust side. IDA calls our Jacobian callback ([`Dae::jacobian`] fills
//! `J = ∂F/∂y + cj ∂F/∂ẏ` into the fixed pattern), then the solver's `setup`
//! (numerical factorization) and `solve` (back-substitution). Because the solver is
//! DIRECT, IDA keeps its own bookkeeping: the `cj`-ratio correction of stale Jacobians and
//! the same counters as with SUNDIALS' own matrix-based solvers. (A MATRIX_EMBEDDED
//! solver, measured on SUNDIALS 6.4.1, never gets `setup` called, loses the cj-ratio
//! correction and crashes inside IDACalcIC; DIRECT with a NULL matrix is refused.)

use std::os::raw::{c_char, c_int, c_long, c_void};
use std::ptr;

use sundials_sys as sys;

mod sens;

pub use sens::{SensitivityMethod, SensitivityOptions};

use super::nls::Nls;
use super::{Context, NVector, guard, ida_flag_name, view, view_mut};
use crate::dae::linsolve::{FaerFactory, LinearSolver, LinearSolverError, SharedFactory};
use crate::dae::nonlinear::{NewtonFailure, NonlinearMethod};
use crate::dae::timing::{self, Phase};
use crate::dae::{
    Atol, Dae, DaeError, Integrator, IntegratorError, Root, Setup, State, Stats, wrms_norm,
};

/// Initial-condition calculation (IDACalcIC) before the first step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CalcIc {
    /// `IDA_YA_YDP_INIT`: given the differential components of y, compute the algebraic
    /// components of y and ẏ of the differential ones. `tout1` is the first output time.
    AlgebraicAndDerivatives {
        /// First output time (sets the scale of the IC calculation).
        tout1: f64,
    },
    /// `IDA_Y_INIT`: given ẏ, compute all of y.
    AllOfY {
        /// First output time.
        tout1: f64,
    },
}

/// IDA settings. Defaults are IDA's own except `max_steps` (1e6 instead of 500: a step
/// limit per output interval is a nuisance on the long scenes).
#[derive(Debug, Clone)]
pub struct IdaOptions {
    /// Relative tolerance.
    pub rtol: f64,
    /// Absolute tolerance(s).
    pub atol: Atol,
    /// Maximum BDF order (1–5).
    pub max_order: u32,
    /// Initial step size (IDA estimates one when `None`).
    pub init_step: Option<f64>,
    /// Largest step allowed.
    pub max_step: Option<f64>,
    /// Most internal steps per output interval.
    pub max_steps: i64,
    /// Exclude the algebraic components from the local error test.
    pub suppress_alg: bool,
    /// Compute consistent initial conditions first.
    pub calc_ic: Option<CalcIc>,
    /// Which sparse LU factorizes the iteration matrix.
    pub linear_solver: SharedFactory,
    /// IDASetConstraints: per component 0 (none), 1 (≥ 0), −1 (≤ 0), 2 (> 0), −2 (< 0).
    pub constraints: Option<Vec<f64>>,
    /// Most Newton iterations per step (IDA's default 4).
    pub max_newton_iters: Option<i32>,
    /// Most Newton convergence failures per step (IDA's default 10).
    pub max_conv_fails: Option<i32>,
    /// Most error-test failures per step (IDA's default 10).
    pub max_err_test_fails: Option<i32>,
    /// Relative change of cj that triggers a new Jacobian (IDA's default 0.25).
    pub delta_cj: Option<f64>,
    /// Solve each Newton system by GMRES preconditioned by the last LU of the iteration
    /// matrix instead of by that LU alone (`None`: the LU alone).
    pub krylov: Option<Krylov>,
    /// Solve the nonlinear systems by our own iteration ([`NonlinearMethod`]: Newton as
    /// SUNDIALS' own, or with Broyden's updates), which records every failed attempt
    /// (`None`: SUNDIALS' Newton module).
    pub nonlinear: Option<NonlinearMethod>,
}

/// GMRES (SUNDIALS' SPGMR, left preconditioning) on the Newton systems, with the
/// products `J v` by IDA's difference quotients of the residual (exact to round-off at the
/// current iterate) and the preconditioner the LU of the iteration matrix factorized at
/// IDA's preconditioner set-ups: a factorization kept across steps where the plain
/// Newton iteration on it would fail to converge.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Krylov {
    /// Largest Krylov subspace (SPGMR's `maxl`; IDA's default 5).
    pub max_dim: i32,
    /// The linear iterations' tolerance as a fraction of the Newton tolerance
    /// (IDASetEpsLin; IDA's default 0.05).
    pub eps_lin: f64,
}

impl Default for Krylov {
    fn default() -> Self {
        Self {
            max_dim: 5,
            eps_lin: 0.05,
        }
    }
}

impl Default for IdaOptions {
    fn default() -> Self {
        Self {
            rtol: 1e-4,
            atol: Atol::Scalar(1e-6),
            max_order: 5,
            init_step: None,
            max_step: None,
            max_steps: 1_000_000,
            suppress_alg: false,
            calc_ic: None,
            linear_solver: std::sync::Arc::new(FaerFactory),
            constraints: None,
            max_newton_iters: None,
            max_conv_fails: None,
            max_err_test_fails: None,
            delta_cj: None,
            krylov: None,
            nonlinear: None,
        }
    }
}

/// The Rust side of the linear solver: the iteration matrix values in the fixed pattern
/// and the factorization. The custom SUNMatrix and SUNLinearSolver point here.
struct LsState {
    solver: Box<dyn LinearSolver>,
    values: Vec<f64>,
    factorizations: u64,
    last_error: Option<String>,
    /// cj of the last Jacobian (the iteration matrix being factorized).
    cj: f64,
}

/// What C keeps a pointer to (boxed, never moved): the problem, the linear solver state
/// and the last messages from callbacks and from IDA's error handler.
struct UserData<D> {
    dae: D,
    ls: LsState,
    callback_error: Option<String>,
    ida_message: String,
    /// The number of root functions ([`Dae::root_directions`]).
    nroots: usize,
}

/// SUNDIALS IDA integrating a [`Dae`].
pub struct Ida<D: Dae> {
    mem: *mut c_void,
    ls: sys::SUNLinearSolver,
    mat: sys::SUNMatrix,
    yy: NVector,
    yp: NVector,
    out_y: NVector,
    out_yp: NVector,
    user: Box<UserData<D>>,
    breakpoints: Vec<f64>,
    tstop: Option<f64>,
    t_internal: f64,
    t_out: f64,
    /// GMRES preconditioned by the LU ([`Krylov`]) rather than the LU alone.
    krylov: bool,
    /// IDA's error weights after the last step, and y before it ([`Stats::path`]).
    weights: NVector,
    before: Vec<f64>,
    /// [`Stats::path`] so far.
    path: f64,
    /// The root the last advance stopped at; one found past its output time, reported by
    /// the next; and whether `before` still holds y before the step that found it.
    root: Option<Root>,
    pending_root: Option<Root>,
    /// The end of the last step the problem was told of ([`Dae::accepted_step`]).
    accepted_to: f64,
    keep_before: bool,
    /// Our nonlinear solver, when `IdaOptions::nonlinear` asks for it (freed after IDA's
    /// memory).
    nls: Option<Nls>,
    /// The forward sensitivities' vectors, when [`Ida::with_sensitivities`] asked for them
    /// (freed after IDA's memory).
    sens: Option<sens::Sensitivities>,
    // Dropped last: everything above was created in this context.
    ctx: Context,
}

impl<D: Dae> Drop for Ida<D> {
    fn drop(&mut self) {
        // SAFETY: each handle is either NULL or was created by us and is freed once, IDA
        // memory first (it references the solver and matrix), then the solver and matrix.
        unsafe {
            if !self.mem.is_null() {
                sys::IDAFree(&mut self.mem);
            }
            if !self.ls.is_null() {
                sys::SUNLinSolFree(self.ls);
            }
            if !self.mat.is_null() {
                sys::SUNMatDestroy(self.mat);
            }
        }
    }
}

/// The error of `function` having returned NULL (`p`) at time `t`.
fn non_null<T>(p: *mut T, function: &'static str, t: f64) -> Result<(), IntegratorError> {
    match p.is_null() {
        true => Err(sundials_err(function, -1, "NULL returned".into(), t)),
        false => Ok(()),
    }
}

fn sundials_err(function: &'static str, flag: c_int, message: String, t: f64) -> IntegratorError {
    IntegratorError::Sundials {
        function,
        flag,
        name: ida_flag_name(flag),
        message,
        t,
    }
}

impl<D: Dae> Ida<D> {
    /// Sets IDA up on `dae` from its consistent initial values; with `opts.calc_ic` the
    /// initial conditions are corrected by IDACalcIC first.
    pub fn new(dae: D, opts: IdaOptions) -> Result<Self, IntegratorError> {
        Self::build(dae, opts, None)
    }

    /// [`Ida::new`], with the forward sensitivities of `sens` initialized before the
    /// initial conditions are corrected (IDACalcIC then corrects theirs too).
    fn build(
        dae: D,
        opts: IdaOptions,
        sens: Option<sens::SensitivityInit>,
    ) -> Result<Self, IntegratorError> {
        let setup = Setup::new(&dae, opts.linear_solver.as_ref(), &opts.atol)?;
        let (t0, y0, yp0) = (setup.t0, setup.y0, setup.yp0);
        if !(opts.rtol >= 0.0) || !(1..=5).contains(&opts.max_order) {
            return Err(IntegratorError::Input(format!(
                "rtol = {} must be ≥ 0 and max_order = {} in 1..=5",
                opts.rtol, opts.max_order
            )));
        }
        let ctx = Context::new().map_err(IntegratorError::Input)?;
        let vector = |v: &[f64]| NVector::from_slice(v, &ctx).map_err(IntegratorError::Input);
        let (yy, yp, out_y, out_yp) = (vector(&y0)?, vector(&yp0)?, vector(&y0)?, vector(&yp0)?);
        let weights = vector(&y0)?;

        let user = Box::new(UserData {
            dae,
            ls: LsState {
                solver: setup.solver,
                values: vec![0.0; setup.nnz],
                factorizations: 0,
                last_error: None,
                cj: f64::NAN,
            },
            callback_error: None,
            ida_message: String::new(),
            nroots: 0,
        });
        let mut ida = Ida {
            mem: ptr::null_mut(),
            ls: ptr::null_mut(),
            mat: ptr::null_mut(),
            yy,
            yp,
            out_y,
            out_yp,
            user,
            breakpoints: setup.breakpoints,
            tstop: None,
            t_internal: t0,
            t_out: t0,
            krylov: opts.krylov.is_some(),
            weights,
            before: y0.clone(),
            path: 0.0,
            root: None,
            pending_root: None,
            accepted_to: f64::NEG_INFINITY,
            keep_before: false,
            nls: None,
            sens: None,
            ctx,
        };
        ida.setup(&opts, t0, sens)?;
        Ok(ida)
    }

    fn check(&self, function: &'static str, flag: c_int) -> Result<(), IntegratorError> {
        if flag < 0 {
            let mut message = self.user.ida_message.clone();
            if let Some(e) = &self.user.callback_error {
                message = format!("{message} [{e}]");
            }
            if let Some(e) = &self.user.ls.last_error {
                message = format!("{message} [linear solver: {e}]");
            }
            Err(sundials_err(function, flag, message, self.t_internal))
        } else {
            Ok(())
        }
    }

    /// Creates IDA's memory on the initial values and configures it from `opts`: the
    /// tolerances, our linear solver, the step limits, the differential components and
    /// constraints, and (with `opts.calc_ic`) the corrected initial conditions.
    fn setup(
        &mut self,
        opts: &IdaOptions,
        t0: f64,
        sens: Option<sens::SensitivityInit>,
    ) -> Result<(), IntegratorError> {
        self.create_memory(opts, t0)?;
        if let Some(method) = opts.nonlinear {
            self.attach_nonlinear_solver(method)?;
        }
        match opts.krylov {
            None => self.attach_linear_solver(t0)?,
            Some(k) => self.attach_krylov(k, t0)?,
        }
        self.set_step_limits(opts)?;
        self.set_components(opts)?;
        self.init_roots()?;
        if let Some(init) = sens {
            self.init_sensitivities(init)?;
        }
        if let Some(ic) = opts.calc_ic {
            self.correct_initial_conditions(ic)?;
        }
        Ok(())
    }

    /// Creates IDA's memory at `t0` on `yy`, `yp` with our residual, error handler, user
    /// data and the tolerances of `opts`.
    fn create_memory(&mut self, opts: &IdaOptions, t0: f64) -> Result<(), IntegratorError> {
        // SAFETY: all pointers passed are valid for the calls; the user data box never
        // moves while IDA holds a pointer to it; the tolerance vector is copied by IDA.
        unsafe {
            self.mem = sys::IDACreate(self.ctx.0);
            non_null(self.mem, "IDACreate", t0)?;
            let mem = self.mem;
            let user_ptr: *mut UserData<D> = &mut *self.user;
            self.check(
                "IDASetErrHandlerFn",
                sys::IDASetErrHandlerFn(mem, Some(err_handler::<D>), user_ptr.cast()),
            )?;
            self.check(
                "IDAInit",
                sys::IDAInit(
                    mem,
                    Some(residual_trampoline::<D>),
                    t0,
                    self.yy.0,
                    self.yp.0,
                ),
            )?;
            self.check("IDASetUserData", sys::IDASetUserData(mem, user_ptr.cast()))?;
            match &opts.atol {
                Atol::Scalar(a) => {
                    self.check("IDASStolerances", sys::IDASStolerances(mem, opts.rtol, *a))?
                }
                Atol::Vector(v) => {
                    // Its length was checked by Setup::new.
                    let av = NVector::from_slice(v, &self.ctx).map_err(IntegratorError::Input)?;
                    self.check(
                        "IDASVtolerances",
                        sys::IDASVtolerances(mem, opts.rtol, av.0),
                    )?;
                }
            }
        }
        Ok(())
    }

    /// Hands the DAE's root functions to IDA's root finding (IDARootInit, with their
    /// directions), if it has any.
    fn init_roots(&mut self) -> Result<(), IntegratorError> {
        let mut dirs: Vec<c_int> = self.user.dae.root_directions();
        if dirs.is_empty() {
            return Ok(());
        }
        self.user.nroots = dirs.len();
        let n = dirs.len() as c_int;
        // SAFETY: valid IDA memory; IDA copies the directions.
        unsafe {
            self.check(
                "IDARootInit",
                sys::IDARootInit(self.mem, n, Some(root_trampoline::<D>)),
            )?;
            self.check(
                "IDASetRootDirection",
                sys::IDASetRootDirection(self.mem, dirs.as_mut_ptr()),
            )?;
        }
        Ok(())
    }

    /// y and ẏ at `t` (within IDA's last step) into the output vectors, and `t` as the
    /// output time.
    fn interpolate_output(&mut self, t: f64) -> Result<(), IntegratorError> {
        // SAFETY: t lies in [tn - hu, tn], where IDAGetDky interpolates.
        unsafe {
            let f0 = sys::IDAGetDky(self.mem, t, 0, self.out_y.0);
            self.check("IDAGetDky", f0)?;
            let f1 = sys::IDAGetDky(self.mem, t, 1, self.out_yp.0);
            self.check("IDAGetDky", f1)?;
        }
        self.t_out = t;
        Ok(())
    }

    /// What IDASolve returned in `yy`, `yp` as the output at `t`.
    fn output_returned(&mut self, t: f64) {
        self.out_y
            .as_mut_slice()
            .copy_from_slice(self.yy.as_slice());
        self.out_yp
            .as_mut_slice()
            .copy_from_slice(self.yp.as_slice());
        self.t_out = t;
    }

    /// IDA's `rootsfound` at its last root return: per function +1 rising, −1 falling, 0.
    fn root_info(&self) -> Result<Vec<i32>, IntegratorError> {
        let mut found: Vec<c_int> = vec![0; self.user.nroots];
        // SAFETY: valid IDA memory, an array of nroots entries.
        let flag = unsafe { sys::IDAGetRootInfo(self.mem, found.as_mut_ptr()) };
        self.check("IDAGetRootInfo", flag)?;
        Ok(found)
    }

    /// Attaches our nonlinear solver ([`Nls`]) in place of SUNDIALS' Newton module.
    fn attach_nonlinear_solver(&mut self, method: NonlinearMethod) -> Result<(), IntegratorError> {
        let cj: *const f64 = &self.user.ls.cj;
        let nls = Nls::new(self.user.dae.size(), method, cj, &self.ctx)
            .map_err(IntegratorError::Input)?;
        // SAFETY: valid IDA memory (made by `create_memory`); the solver outlives it (the
        // field is dropped after `Drop::drop` frees the memory) and the cj it reads lives
        // in the boxed user data.
        let flag = unsafe { sys::IDASetNonlinearSolver(self.mem, nls.raw) };
        self.nls = Some(nls);
        self.check("IDASetNonlinearSolver", flag)
    }

    /// Every failed attempt of our nonlinear solver so far (empty with SUNDIALS' own).
    pub fn newton_failures(&self) -> &[NewtonFailure] {
        self.nls.as_ref().map_or(&[], |n| n.failures())
    }

    /// Attaches the thin matrix and the linear solver, both pointing at the LsState (the
    /// matrix's values are LsState::values), and our Jacobian.
    fn attach_linear_solver(&mut self, t0: f64) -> Result<(), IntegratorError> {
        // SAFETY: all pointers passed are valid for the calls (the IDA memory is the one
        // `create_memory` made, before this in `setup`); the LsState inside the user data
        // box never moves while IDA holds pointers to it; the ops tables are those
        // SUNMatNewEmpty and SUNLinSolNewEmpty allocated.
        unsafe {
            let ls_ptr: *mut LsState = &mut self.user.ls;
            self.mat = sys::SUNMatNewEmpty(self.ctx.0);
            non_null(self.mat, "SUNMatNewEmpty", t0)?;
            (*self.mat).content = ls_ptr.cast();
            let mops = &mut *(*self.mat).ops;
            mops.getid = Some(mat_getid);
            mops.zero = Some(mat_zero);
            mops.destroy = Some(mat_destroy);

            self.ls = sys::SUNLinSolNewEmpty(self.ctx.0);
            non_null(self.ls, "SUNLinSolNewEmpty", t0)?;
            (*self.ls).content = ls_ptr.cast();
            let lops = &mut *(*self.ls).ops;
            lops.gettype = Some(ls_gettype);
            lops.getid = Some(ls_getid);
            lops.setup = Some(ls_setup);
            lops.solve = Some(ls_solve);
            lops.free = Some(ls_free);

            let mem = self.mem;
            self.check(
                "IDASetLinearSolver",
                sys::IDASetLinearSolver(mem, self.ls, self.mat),
            )?;
            self.check(
                "IDASetJacFn",
                sys::IDASetJacFn(mem, Some(jacobian_trampoline::<D>)),
            )?;
        }
        Ok(())
    }

    /// Attaches SPGMR with our preconditioner: set-up = Jacobian and LU factorization,
    /// solve = the LU's triangular solves ([`Krylov`]).
    fn attach_krylov(&mut self, k: Krylov, t0: f64) -> Result<(), IntegratorError> {
        // SAFETY: valid IDA memory (made by `create_memory`, before this in `setup`) and
        // template vector; the preconditioner callbacks receive the boxed UserData set by
        // `create_memory`.
        unsafe {
            let pretype = sys::SUN_PREC_LEFT as c_int;
            self.ls = sys::SUNLinSol_SPGMR(self.yy.0, pretype, k.max_dim, self.ctx.0);
            non_null(self.ls, "SUNLinSol_SPGMR", t0)?;
            let mem = self.mem;
            self.check(
                "IDASetLinearSolver",
                sys::IDASetLinearSolver(mem, self.ls, ptr::null_mut()),
            )?;
            self.check(
                "IDASetPreconditioner",
                sys::IDASetPreconditioner(mem, Some(prec_setup::<D>), Some(prec_solve::<D>)),
            )?;
            self.check("IDASetEpsLin", sys::IDASetEpsLin(mem, k.eps_lin))?;
        }
        Ok(())
    }

    /// Sets the BDF order, step and iteration limits of `opts` (IDA's defaults where
    /// `opts` has none).
    fn set_step_limits(&self, opts: &IdaOptions) -> Result<(), IntegratorError> {
        let mem = self.mem;
        // SAFETY: valid IDA memory (made by `create_memory`, before this in `setup`); the
        // calls take values only.
        unsafe {
            self.check(
                "IDASetMaxOrd",
                sys::IDASetMaxOrd(mem, opts.max_order as c_int),
            )?;
            self.check(
                "IDASetMaxNumSteps",
                sys::IDASetMaxNumSteps(mem, opts.max_steps as c_long),
            )?;
        }
        self.set_if_given("IDASetInitStep", opts.init_step, sys::IDASetInitStep)?;
        self.set_if_given("IDASetMaxStep", opts.max_step, sys::IDASetMaxStep)?;
        self.set_if_given(
            "IDASetMaxNonlinIters",
            opts.max_newton_iters,
            sys::IDASetMaxNonlinIters,
        )?;
        self.set_if_given(
            "IDASetMaxConvFails",
            opts.max_conv_fails,
            sys::IDASetMaxConvFails,
        )?;
        self.set_if_given(
            "IDASetDeltaCjLSetup",
            opts.delta_cj,
            sys::IDASetDeltaCjLSetup,
        )?;
        self.set_if_given(
            "IDASetMaxErrTestFails",
            opts.max_err_test_fails,
            sys::IDASetMaxErrTestFails,
        )
    }

    /// Makes the IDASet* call `set` with `value`, and checks its flag, when there is one.
    fn set_if_given<T>(
        &self,
        function: &'static str,
        value: Option<T>,
        set: unsafe extern "C" fn(*mut c_void, T) -> c_int,
    ) -> Result<(), IntegratorError> {
        match value {
            // SAFETY: valid IDA memory (made by `create_memory`); the call takes a value only.
            Some(v) => self.check(function, unsafe { set(self.mem, v) }),
            None => Ok(()),
        }
    }

    /// Tells IDA which components are differential (needed to suppress the algebraic
    /// ones from the error test and by IDACalcIC) and the constraints of `opts`.
    fn set_components(&self, opts: &IdaOptions) -> Result<(), IntegratorError> {
        let n = self.user.dae.size();
        let mem = self.mem;
        // SAFETY: valid IDA memory (made by `create_memory`, before this in `setup`); the
        // vectors passed to IDASet* functions are copied by IDA.
        unsafe {
            if opts.suppress_alg || opts.calc_ic.is_some() {
                let id: Vec<f64> = self
                    .user
                    .dae
                    .differential()
                    .iter()
                    .map(|&d| if d { 1.0 } else { 0.0 })
                    .collect();
                if id.len() != n {
                    return Err(IntegratorError::Input(format!(
                        "differential() has {} entries for {n} unknowns",
                        id.len()
                    )));
                }
                let idv = NVector::from_slice(&id, &self.ctx).map_err(IntegratorError::Input)?;
                self.check("IDASetId", sys::IDASetId(mem, idv.0))?;
                self.check(
                    "IDASetSuppressAlg",
                    sys::IDASetSuppressAlg(mem, opts.suppress_alg as c_int),
                )?;
            }
            if let Some(c) = &opts.constraints {
                if c.len() != n {
                    return Err(IntegratorError::Input(format!(
                        "{} constraints for {n} unknowns",
                        c.len()
                    )));
                }
                let cv = NVector::from_slice(c, &self.ctx).map_err(IntegratorError::Input)?;
                self.check("IDASetConstraints", sys::IDASetConstraints(mem, cv.0))?;
            }
        }
        Ok(())
    }

    /// Corrects the initial conditions by IDACalcIC as `ic` asks, and takes IDA's
    /// consistent values as the current y and ẏ.
    fn correct_initial_conditions(&mut self, ic: CalcIc) -> Result<(), IntegratorError> {
        let mem = self.mem;
        let (icopt, tout1) = match ic {
            CalcIc::AlgebraicAndDerivatives { tout1 } => (sys::IDA_YA_YDP_INIT, tout1),
            CalcIc::AllOfY { tout1 } => (sys::IDA_Y_INIT, tout1),
        };
        // SAFETY: valid IDA memory, set up for IDACalcIC (by `setup`, before this); the
        // output vectors are serial vectors of the problem's length, owned here.
        unsafe {
            let flag = timing::time(Phase::Ida, || sys::IDACalcIC(mem, icopt, tout1));
            self.check("IDACalcIC", flag)?;
            self.check(
                "IDAGetConsistentIC",
                sys::IDAGetConsistentIC(mem, self.out_y.0, self.out_yp.0),
            )?;
        }
        self.yy
            .as_mut_slice()
            .copy_from_slice(self.out_y.as_slice());
        self.yp
            .as_mut_slice()
            .copy_from_slice(self.out_yp.as_slice());
        Ok(())
    }

    /// The problem being integrated.
    pub fn dae(&self) -> &D {
        &self.user.dae
    }

    /// Mutable access to the problem (e.g. to change a parameter between outputs).
    pub fn dae_mut(&mut self) -> &mut D {
        &mut self.user.dae
    }

    /// Internal time reached by IDA (≥ the output time).
    pub fn t_internal(&self) -> f64 {
        self.t_internal
    }

    /// The last step's estimated local error of each component times its error weight
    /// (IDAGetEstLocalErrors, IDAGetErrWeights): the components whose |value| is near 1
    /// are those limiting the step. Zeros before the first step (IDA has no estimate yet).
    pub fn weighted_local_errors(&self) -> Result<Vec<f64>, IntegratorError> {
        let n = self.user.dae.size();
        // Before the first step IDA's error vector holds whatever its allocation held (not
        // zeros), so it is not read.
        if self.getter("IDAGetNumSteps", sys::IDAGetNumSteps) == 0 {
            return Ok(vec![0.0; n]);
        }
        let ctx = IntegratorError::Input;
        let ele = NVector::new(n, &self.ctx).map_err(ctx)?;
        let ewt = NVector::new(n, &self.ctx).map_err(ctx)?;
        // SAFETY: valid IDA memory; two serial vectors of the problem's length, owned here.
        let flags = unsafe {
            (
                sys::IDAGetEstLocalErrors(self.mem, ele.0),
                sys::IDAGetErrWeights(self.mem, ewt.0),
            )
        };
        if flags != (0, 0) {
            return Err(ctx(format!(
                "IDAGetEstLocalErrors/IDAGetErrWeights returned {flags:?}"
            )));
        }
        Ok(ele
            .as_slice()
            .iter()
            .zip(ewt.as_slice())
            .map(|(e, w)| e * w)
            .collect())
    }

    /// ‖y − y_before‖ in IDA's weighted RMS norm, with its weights after the step just
    /// taken ([`Stats::path`]); leaves the difference in `before`.
    fn step_length(&mut self) -> Result<f64, IntegratorError> {
        // SAFETY: valid IDA memory and a vector of the system's length.
        let flag = unsafe { sys::IDAGetErrWeights(self.mem, self.weights.0) };
        self.check("IDAGetErrWeights", flag)?;
        for (d, y) in self.before.iter_mut().zip(self.yy.as_slice()) {
            *d = y - *d;
        }
        Ok(wrms_norm(&self.before, self.weights.as_slice()))
    }

    fn getter(
        &self,
        function: &'static str,
        f: unsafe extern "C" fn(*mut c_void, *mut c_long) -> c_int,
    ) -> u64 {
        let mut v: c_long = 0;
        // SAFETY: valid IDA memory and an out-pointer to a local.
        let flag = unsafe { f(self.mem, &mut v) };
        debug_assert!(flag == 0, "{function} returned {flag}");
        v.max(0) as u64
    }
}

impl<D: Dae> Integrator for Ida<D> {
    fn t(&self) -> f64 {
        self.t_out
    }

    fn advance(
        &mut self,
        tout: f64,
        on_step: &mut dyn FnMut(f64, &Stats) -> bool,
    ) -> Result<(), IntegratorError> {
        let mut tret = self.t_internal;
        // Within round-off of IDA's own time, tout is reached: IDA refuses an output time
        // that close to its initial time (IDA_ILL_INPUT "tout too close to t0"), which is
        // what a restart at an output time (the inertia switch) asks otherwise.
        let eps = 8.0 * f64::EPSILON * tout.abs().max(1.0);
        self.root = None;
        if let Some(r) = self.pending_root.take() {
            // A root found past the last output time: IDA has not stepped since.
            if r.t <= tout + eps {
                self.interpolate_output(r.t)?;
                self.t_internal = r.t;
                self.root = Some(r);
                return Ok(());
            }
            self.pending_root = Some(r);
            return self.interpolate_output(tout);
        }
        while self.t_internal < tout - eps {
            let next = self
                .breakpoints
                .iter()
                .copied()
                .find(|&b| b > self.t_internal + eps);
            if next != self.tstop {
                if let Some(b) = next {
                    // SAFETY: valid IDA memory.
                    let flag = unsafe { sys::IDASetStopTime(self.mem, b) };
                    self.check("IDASetStopTime", flag)?;
                }
                self.tstop = next;
            }
            self.user.callback_error = None;
            if !std::mem::take(&mut self.keep_before) {
                self.before.copy_from_slice(self.yy.as_slice());
            }
            // One step towards the next breakpoint rather than `tout`: IDA's first step is
            // a fraction of the distance it is given, and the steps must not depend on the
            // output times (runs with other outputs take the same steps, `run::run_all`).
            let towards = self.tstop.unwrap_or(tout);
            // SAFETY: valid IDA memory and vectors of the right length.
            let flag = timing::time(Phase::Ida, || unsafe {
                sys::IDASolve(
                    self.mem,
                    towards,
                    &mut tret,
                    self.yy.0,
                    self.yp.0,
                    sys::IDA_ONE_STEP,
                )
            });
            self.check("IDASolve", flag)?;
            if flag == sys::IDA_ROOT_RETURN {
                // IDA's step went past the root; yy, yp hold the solution at it (tret). The
                // next IDASolve returns the step itself, so its path is measured then, from
                // y before it.
                let root = Root::new(tret, self.root_info()?);
                // The step that holds the root is accepted: the problem is told now, at
                // its end t_n (a restart at the root needs what it integrates beside the
                // system up to there), and not again when IDA returns the step itself.
                let mut tn = tret;
                // SAFETY: valid IDA memory.
                let flag = unsafe { sys::IDAGetCurrentTime(self.mem, &mut tn) };
                self.check("IDAGetCurrentTime", flag)?;
                if tn > self.accepted_to {
                    self.interpolate_output(tn)?;
                    self.user
                        .dae
                        .accepted_step(tn, self.out_y.as_slice(), self.out_yp.as_slice());
                    self.accepted_to = tn;
                }
                self.keep_before = true;
                self.t_internal = tret;
                if tret <= tout + eps {
                    self.output_returned(tret);
                    self.root = Some(root);
                    return Ok(());
                }
                self.pending_root = Some(root);
                return self.interpolate_output(tout);
            }
            self.t_internal = tret;
            if tret > self.accepted_to {
                self.user
                    .dae
                    .accepted_step(tret, self.yy.as_slice(), self.yp.as_slice());
                self.accepted_to = tret;
            }
            if flag == sys::IDA_TSTOP_RETURN {
                // IDA clears its stop time once reached.
                self.tstop = None;
            }
            self.path += self.step_length()?;
            let stats = self.stats();
            if !on_step(tret, &stats) {
                return Err(IntegratorError::Interrupted { t: tret });
            }
        }
        if (tout - self.t_internal).abs() <= eps {
            // At IDA's own time y and ẏ are what it returned (or, before its first step,
            // the initial values: IDAGetDky has no derivative of order 1 to give then).
            self.output_returned(tout);
            return Ok(());
        }
        self.interpolate_output(tout)
    }

    fn y(&self) -> &[f64] {
        self.out_y.as_slice()
    }

    fn yp(&self) -> &[f64] {
        self.out_yp.as_slice()
    }

    fn last_step(&self) -> (f64, &[f64], &[f64]) {
        // IDASolve in one-step mode returns the solution at its internal time in these
        // vectors (the initial values before the first step); a failed step leaves them
        // at the last accepted one.
        (self.t_internal, self.yy.as_slice(), self.yp.as_slice())
    }

    fn stats(&self) -> Stats {
        let mut order: c_int = 0;
        let mut h = 0.0;
        // SAFETY: valid IDA memory, out-pointers to locals.
        unsafe {
            sys::IDAGetLastOrder(self.mem, &mut order);
            sys::IDAGetLastStep(self.mem, &mut h);
        }
        let residual_evals = self.getter("IDAGetNumResEvals", sys::IDAGetNumResEvals);
        // With GMRES the Jacobians are the preconditioner's set-ups, and the products J v
        // cost a residual each.
        let (residual_evals, jacobian_evals) = match self.krylov {
            false => (
                residual_evals,
                self.getter("IDAGetNumJacEvals", sys::IDAGetNumJacEvals),
            ),
            true => (
                residual_evals + self.getter("IDAGetNumLinResEvals", sys::IDAGetNumLinResEvals),
                self.getter("IDAGetNumPrecEvals", sys::IDAGetNumPrecEvals),
            ),
        };
        Stats {
            steps: self.getter("IDAGetNumSteps", sys::IDAGetNumSteps),
            residual_evals,
            jacobian_evals,
            lu_factorizations: self.user.ls.factorizations,
            newton_iters: self.getter("IDAGetNumNonlinSolvIters", sys::IDAGetNumNonlinSolvIters),
            newton_failures: self.getter(
                "IDAGetNumNonlinSolvConvFails",
                sys::IDAGetNumNonlinSolvConvFails,
            ),
            error_test_failures: self.getter("IDAGetNumErrTestFails", sys::IDAGetNumErrTestFails),
            linear_iters: match self.krylov {
                true => self.getter("IDAGetNumLinIters", sys::IDAGetNumLinIters),
                false => 0,
            },
            linear_failures: match self.krylov {
                true => self.getter("IDAGetNumLinConvFails", sys::IDAGetNumLinConvFails),
                false => 0,
            },
            root_evals: match self.user.nroots {
                0 => 0,
                _ => self.getter("IDAGetNumGEvals", sys::IDAGetNumGEvals),
            },
            newton_detail: self.nls.as_ref().map(|n| n.counts()).unwrap_or_default(),
            path: self.path,
            last_order: order.max(0) as u32,
            last_step: h,
        }
    }

    fn root(&self) -> Option<&Root> {
        self.root.as_ref()
    }
}

// ---------------------------------------------------------------------------------------
// Callbacks. None may unwind into C: each runs its Rust body under `guard` (catch_unwind).

fn dae_code<D>(
    user: &mut UserData<D>,
    r: Result<Result<(), DaeError>, String>,
    what: &str,
) -> c_int {
    match r {
        Ok(Ok(())) => 0,
        Ok(Err(DaeError::Inadmissible(why))) => {
            user.callback_error = Some(format!("{what}: inadmissible state: {why}"));
            1
        }
        Ok(Err(DaeError::Fatal(m))) => {
            user.callback_error = Some(format!("{what}: {m}"));
            -1
        }
        Err(p) => {
            user.callback_error = Some(format!("{what}: panic: {p}"));
            -1
        }
    }
}

unsafe extern "C" fn residual_trampoline<D: Dae>(
    t: f64,
    yy: sys::N_Vector,
    yp: sys::N_Vector,
    rr: sys::N_Vector,
    user_data: *mut c_void,
) -> c_int {
    // SAFETY: user_data is the boxed UserData<D> set in `create_memory`; IDA passes
    // distinct, valid vectors of length n.
    unsafe {
        let user = &mut *(user_data as *mut UserData<D>);
        let (y, ypv, r) = (view(yy), view(yp), view_mut(rr));
        let out = guard(|| {
            timing::time(Phase::Residual, || {
                user.dae.residual(State::new(t, y, ypv), r)
            })
        });
        dae_code(user, out, "residual")
    }
}

unsafe extern "C" fn root_trampoline<D: Dae>(
    t: f64,
    yy: sys::N_Vector,
    yp: sys::N_Vector,
    gout: *mut f64,
    user_data: *mut c_void,
) -> c_int {
    // SAFETY: user_data is the boxed UserData<D>; IDA passes valid vectors of length n and
    // gout with room for the nroots functions given to IDARootInit.
    unsafe {
        let user = &mut *(user_data as *mut UserData<D>);
        let g = std::slice::from_raw_parts_mut(gout, user.nroots);
        let (y, ypv) = (view(yy), view(yp));
        let out = guard(|| user.dae.root_functions(State::new(t, y, ypv), g));
        // IDA has no recoverable failure for root functions: any error ends the solve.
        match dae_code(user, out, "root functions") {
            0 => 0,
            _ => -1,
        }
    }
}

#[allow(clippy::too_many_arguments)]
unsafe extern "C" fn jacobian_trampoline<D: Dae>(
    t: f64,
    cj: f64,
    yy: sys::N_Vector,
    yp: sys::N_Vector,
    _rr: sys::N_Vector,
    _jac: sys::SUNMatrix,
    user_data: *mut c_void,
    _t1: sys::N_Vector,
    _t2: sys::N_Vector,
    _t3: sys::N_Vector,
) -> c_int {
    // SAFETY: as for the residual; the values live in the same boxed UserData.
    unsafe { jacobian_into_values::<D>(t, cj, yy, yp, user_data) }
}

/// Fills the iteration matrix's values at (t, y, ẏ, cj) by [`Dae::jacobian`]: the status
/// of [`dae_code`].
///
/// # Safety
/// `user_data` is the boxed `UserData<D>`; `yy` and `yp` are valid serial vectors.
unsafe fn jacobian_into_values<D: Dae>(
    t: f64,
    cj: f64,
    yy: sys::N_Vector,
    yp: sys::N_Vector,
    user_data: *mut c_void,
) -> c_int {
    // SAFETY: per the contract.
    unsafe {
        let user = &mut *(user_data as *mut UserData<D>);
        let (y, ypv) = (view(yy), view(yp));
        let UserData { dae, ls, .. } = user;
        ls.cj = cj;
        let out = guard(|| {
            timing::time(Phase::Jacobian, || {
                dae.jacobian(State::new(t, y, ypv), cj, &mut ls.values)
            })
        });
        dae_code(user, out, "jacobian")
    }
}

/// A callback's status as IDA's preconditioner routines return it: 0, positive
/// (recoverable: IDA retries with a smaller step or a new set-up) or negative.
fn prec_code(code: c_int) -> c_int {
    code.signum()
}

unsafe extern "C" fn prec_setup<D: Dae>(
    t: f64,
    yy: sys::N_Vector,
    yp: sys::N_Vector,
    _rr: sys::N_Vector,
    cj: f64,
    user_data: *mut c_void,
) -> c_int {
    // SAFETY: as for the Jacobian: user_data is the boxed UserData<D>, the vectors valid.
    unsafe {
        let code = jacobian_into_values::<D>(t, cj, yy, yp, user_data);
        if code != 0 {
            return prec_code(code);
        }
        let user = &mut *(user_data as *mut UserData<D>);
        prec_code(factorize(&mut user.ls))
    }
}

#[allow(clippy::too_many_arguments)]
unsafe extern "C" fn prec_solve<D: Dae>(
    _t: f64,
    _yy: sys::N_Vector,
    _yp: sys::N_Vector,
    _rr: sys::N_Vector,
    r: sys::N_Vector,
    z: sys::N_Vector,
    _cj: f64,
    _delta: f64,
    user_data: *mut c_void,
) -> c_int {
    // SAFETY: user_data is the boxed UserData<D>; r and z are serial vectors of length n.
    unsafe {
        let user = &mut *(user_data as *mut UserData<D>);
        prec_code(solve(&mut user.ls, r, z))
    }
}

unsafe extern "C" fn err_handler<D>(
    error_code: c_int,
    module: *const c_char,
    function: *const c_char,
    msg: *mut c_char,
    user_data: *mut c_void,
) {
    let _ = guard(|| {
        // SAFETY: IDA passes NUL-terminated strings and our boxed UserData.
        unsafe {
            let s = |p: *const c_char| {
                if p.is_null() {
                    String::new()
                } else {
                    std::ffi::CStr::from_ptr(p).to_string_lossy().into_owned()
                }
            };
            let user = &mut *(user_data as *mut UserData<D>);
            user.ida_message = format!("[{} {} {error_code}] {}", s(module), s(function), s(msg));
        }
    });
}

unsafe fn ls_state<'a>(content: *mut c_void) -> &'a mut LsState {
    // SAFETY: content was set to the boxed LsState in `attach_linear_solver`.
    unsafe { &mut *(content as *mut LsState) }
}

unsafe extern "C" fn mat_getid(_a: sys::SUNMatrix) -> sys::SUNMatrix_ID {
    sys::SUNMatrix_ID_SUNMATRIX_CUSTOM
}

unsafe extern "C" fn mat_zero(a: sys::SUNMatrix) -> c_int {
    // SAFETY: `a` is our thin matrix; its content is the LsState.
    unsafe {
        let st = ls_state((*a).content);
        st.values.fill(0.0);
    }
    0
}

unsafe extern "C" fn mat_destroy(a: sys::SUNMatrix) {
    // SAFETY: the content is owned by Rust; only the empty shell and its ops are freed.
    unsafe {
        if !a.is_null() {
            (*a).content = ptr::null_mut();
            sys::SUNMatFreeEmpty(a);
        }
    }
}

unsafe extern "C" fn ls_gettype(_s: sys::SUNLinearSolver) -> sys::SUNLinearSolver_Type {
    sys::SUNLinearSolver_Type_SUNLINEARSOLVER_DIRECT
}

unsafe extern "C" fn ls_getid(_s: sys::SUNLinearSolver) -> sys::SUNLinearSolver_ID {
    sys::SUNLinearSolver_ID_SUNLINEARSOLVER_CUSTOM
}

fn ls_code(st: &mut LsState, r: Result<Result<(), LinearSolverError>, String>) -> c_int {
    match r {
        Ok(Ok(())) => 0,
        Ok(Err(e @ LinearSolverError::Singular { .. })) => {
            st.last_error = Some(e.to_string());
            sys::SUNLS_PACKAGE_FAIL_REC as c_int
        }
        Ok(Err(e)) => {
            st.last_error = Some(e.to_string());
            -1
        }
        Err(p) => {
            st.last_error = Some(format!("panic: {p}"));
            -1
        }
    }
}

unsafe extern "C" fn ls_setup(s: sys::SUNLinearSolver, _a: sys::SUNMatrix) -> c_int {
    // SAFETY: our solver; content is the LsState.
    unsafe { factorize(ls_state((*s).content)) }
}

/// Factorizes the iteration matrix in `st.values`, counted.
fn factorize(st: &mut LsState) -> c_int {
    let LsState { solver, values, .. } = st;
    let r = guard(|| timing::time(Phase::Factorize, || solver.factorize(values)));
    if matches!(r, Ok(Ok(()))) {
        st.factorizations += 1;
    }
    ls_code(st, r)
}

/// `x = A⁻¹ b` by the factorization of `st` (x and b possibly the same vector).
///
/// # Safety
/// `x` and `b` are valid serial vectors of the solver's length.
unsafe fn solve(st: &mut LsState, b: sys::N_Vector, x: sys::N_Vector) -> c_int {
    // SAFETY: per the contract.
    unsafe {
        if x != b {
            view_mut(x).copy_from_slice(view(b));
        }
        let xs = view_mut(x);
        let LsState { solver, .. } = st;
        let r = guard(|| timing::time(Phase::Solve, || solver.solve_in_place(xs)));
        ls_code(st, r)
    }
}

unsafe extern "C" fn ls_solve(
    s: sys::SUNLinearSolver,
    _a: sys::SUNMatrix,
    x: sys::N_Vector,
    b: sys::N_Vector,
    _tol: f64,
) -> c_int {
    // SAFETY: our solver; x and b are serial vectors of length n (possibly the same one).
    unsafe { solve(ls_state((*s).content), b, x) }
}

unsafe extern "C" fn ls_free(s: sys::SUNLinearSolver) -> c_int {
    // SAFETY: the content is owned by Rust; only the empty shell and its ops are freed.
    unsafe {
        if !s.is_null() {
            (*s).content = ptr::null_mut();
            sys::SUNLinSolFreeEmpty(s);
        }
    }
    0
}
