//! IDAS's forward sensitivities on [`Ida`]: `sᵢ = ∂y/∂pᵢ` integrated with the solution,
//! their residuals `F_y sᵢ + F_ẏ ṡᵢ + F_{pᵢ}` from [`SensitivityDae::sensitivity_residuals`]
//! (IDAS's own difference quotients are never used), solved with the state's linear
//! solver and factorization.

use std::os::raw::{c_int, c_void};

use sundials_sys as sys;

use super::{Ida, IdaOptions, UserData, dae_code, non_null};
use crate::dae::timing::{self, Phase};
use crate::dae::{IntegratorError, SensitivityDae, State};
use crate::sundials::{Context, guard, view, view_mut};

/// How IDAS corrects the sensitivities at each step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SensitivityMethod {
    /// `IDA_SIMULTANEOUS`: one Newton iteration on the state and the sensitivities together.
    Simultaneous,
    /// `IDA_STAGGERED`: the sensitivities' (linear) corrector after the state's has
    /// converged, on the same factorization.
    Staggered,
}

/// The forward sensitivities' settings.
#[derive(Debug, Clone, PartialEq)]
pub struct SensitivityOptions {
    /// How the sensitivities are corrected.
    pub method: SensitivityMethod,
    /// Include the sensitivities in the local error test (IDASetSensErrCon): their own
    /// accuracy is then controlled, not only the solution's.
    pub error_control: bool,
    /// The parameters' magnitudes |pᵢ| (`pbar`): the sensitivities' absolute tolerances are
    /// the state's divided by them (IDASensEEtolerances). One per parameter, each > 0.
    pub scales: Vec<f64>,
}

/// What [`Ida::build`] needs to start the sensitivities: the options, the residual
/// callback (typed on the DAE) and the initial values.
pub(super) struct SensitivityInit {
    options: SensitivityOptions,
    residual: sys::IDASensResFn,
    s0: Vec<Vec<f64>>,
    sp0: Vec<Vec<f64>>,
}

/// An array of `count` serial N_Vectors (N_VCloneVectorArray), destroyed on drop.
struct VectorArray {
    ptr: *mut sys::N_Vector,
    count: usize,
}

impl VectorArray {
    /// `values.len()` vectors holding `values`, cloned from `template`'s shape.
    fn from_values(
        values: &[Vec<f64>],
        n: usize,
        ctx: &Context,
        t0: f64,
    ) -> Result<Self, IntegratorError> {
        let template = super::NVector::new(n, ctx).map_err(IntegratorError::Input)?;
        // SAFETY: a valid template vector; NULL checked below.
        let ptr = unsafe { sys::N_VCloneVectorArray(values.len() as c_int, template.0) };
        non_null(ptr, "N_VCloneVectorArray", t0)?;
        let array = Self {
            ptr,
            count: values.len(),
        };
        for (i, v) in values.iter().enumerate() {
            if v.len() != n {
                return Err(IntegratorError::Input(format!(
                    "sensitivity {i} has {} entries for {n} unknowns",
                    v.len()
                )));
            }
            // SAFETY: i < count; each vector is a serial vector of length n.
            unsafe { view_mut(*ptr.add(i)) }.copy_from_slice(v);
        }
        Ok(array)
    }

    /// The values of vector `i` (< count).
    fn get(&self, i: usize) -> &[f64] {
        assert!(i < self.count);
        // SAFETY: i < count, a valid serial vector owned by this array.
        unsafe { view(*self.ptr.add(i)) }
    }
}

impl Drop for VectorArray {
    fn drop(&mut self) {
        // SAFETY: made by N_VCloneVectorArray with this count, destroyed once.
        unsafe { sys::N_VDestroyVectorArray(self.ptr, self.count as c_int) }
    }
}

/// The sensitivities' vectors: the initial values IDAS copied, and the output array
/// interpolated into.
pub(super) struct Sensitivities {
    _initial: (VectorArray, VectorArray),
    out: VectorArray,
}

impl<D: SensitivityDae> Ida<D> {
    /// [`Ida::new`] carrying the forward sensitivities of the DAE's parameters
    /// ([`SensitivityDae`]) from their initial values [`SensitivityDae::initial_sensitivities`]
    /// (corrected with the solution's when `opts.calc_ic` asks for it).
    pub fn with_sensitivities(
        dae: D,
        opts: IdaOptions,
        sens: SensitivityOptions,
    ) -> Result<Self, IntegratorError> {
        let m = dae.parameter_count();
        if m == 0 || sens.scales.len() != m || !sens.scales.iter().all(|&p| p > 0.0) {
            return Err(IntegratorError::Input(format!(
                "forward sensitivities need at least one parameter and a scale > 0 per \
                 parameter: {m} parameters, scales {:?}",
                sens.scales
            )));
        }
        let (s0, sp0) = dae.initial_sensitivities();
        if s0.len() != m || sp0.len() != m {
            return Err(IntegratorError::Input(format!(
                "initial_sensitivities gave {} and {} vectors for {m} parameters",
                s0.len(),
                sp0.len()
            )));
        }
        let init = SensitivityInit {
            options: sens,
            residual: Some(sensitivity_trampoline::<D>),
            s0,
            sp0,
        };
        Self::build(dae, opts, Some(init))
    }
}

impl<D: crate::dae::Dae> Ida<D> {
    /// Starts the sensitivities on IDA's memory (IDASensInit and its settings).
    pub(super) fn init_sensitivities(
        &mut self,
        init: SensitivityInit,
    ) -> Result<(), IntegratorError> {
        let n = self.user.dae.size();
        let t0 = self.t_internal;
        let s0 = VectorArray::from_values(&init.s0, n, &self.ctx, t0)?;
        let sp0 = VectorArray::from_values(&init.sp0, n, &self.ctx, t0)?;
        let out = VectorArray::from_values(&init.s0, n, &self.ctx, t0)?;
        let m = init.s0.len() as c_int;
        let method = match init.options.method {
            SensitivityMethod::Simultaneous => sys::IDA_SIMULTANEOUS,
            SensitivityMethod::Staggered => sys::IDA_STAGGERED,
        };
        let mut pbar = init.options.scales.clone();
        let mem = self.mem;
        // SAFETY: valid IDA memory (made by `create_memory`); IDAS copies the initial
        // vectors and the scales; the residual callback receives the boxed UserData.
        unsafe {
            self.check(
                "IDASensInit",
                sys::IDASensInit(mem, m, method, init.residual, s0.ptr, sp0.ptr),
            )?;
            self.check("IDASensEEtolerances", sys::IDASensEEtolerances(mem))?;
            self.check(
                "IDASetSensErrCon",
                sys::IDASetSensErrCon(mem, init.options.error_control as c_int),
            )?;
            self.check(
                "IDASetSensParams",
                sys::IDASetSensParams(
                    mem,
                    std::ptr::null_mut(),
                    pbar.as_mut_ptr(),
                    std::ptr::null_mut(),
                ),
            )?;
        }
        self.sens = Some(Sensitivities {
            _initial: (s0, sp0),
            out,
        });
        Ok(())
    }

    /// The `k`-th time derivative (0 or 1) of the sensitivities at `t`, which must lie in
    /// the last step's interval (its end, say, after a step returned by an interrupted
    /// [`crate::dae::Integrator::advance_to`]).
    pub fn sensitivities_at(
        &mut self,
        t: f64,
        k: u32,
    ) -> Option<Result<Vec<Vec<f64>>, IntegratorError>> {
        let sens = self.sens.as_ref()?;
        // SAFETY: as in `sensitivities`.
        let flag = unsafe { sys::IDAGetSensDky(self.mem, t, k as c_int, sens.out.ptr) };
        Some(self.check("IDAGetSensDky", flag).map(|()| {
            (0..sens.out.count)
                .map(|i| sens.out.get(i).to_vec())
                .collect()
        }))
    }

    /// The `k`-th time derivative (0 or 1) of the sensitivities at the output time
    /// ([`crate::dae::Integrator::t`]), one vector per parameter, interpolated by IDAS.
    /// `None` when the integrator carries no sensitivities.
    pub fn sensitivities(&mut self, k: u32) -> Option<Result<Vec<Vec<f64>>, IntegratorError>> {
        let sens = self.sens.as_ref()?;
        // SAFETY: valid IDA memory with sensitivities; the array holds one serial vector of
        // the problem's length per parameter.
        let flag = unsafe { sys::IDAGetSensDky(self.mem, self.t_out, k as c_int, sens.out.ptr) };
        Some(self.check("IDAGetSensDky", flag).map(|()| {
            (0..sens.out.count)
                .map(|i| sens.out.get(i).to_vec())
                .collect()
        }))
    }
}

#[allow(clippy::too_many_arguments)]
unsafe extern "C" fn sensitivity_trampoline<D: SensitivityDae>(
    ns: c_int,
    t: f64,
    yy: sys::N_Vector,
    yp: sys::N_Vector,
    rr: sys::N_Vector,
    ys: *mut sys::N_Vector,
    yps: *mut sys::N_Vector,
    rs: *mut sys::N_Vector,
    user_data: *mut c_void,
    _t1: sys::N_Vector,
    _t2: sys::N_Vector,
    _t3: sys::N_Vector,
) -> c_int {
    // SAFETY: user_data is the boxed UserData<D> set in `create_memory`; IDAS passes valid
    // vectors of length n and arrays of `ns` of them, the outputs distinct from the inputs.
    unsafe {
        let user = &mut *(user_data as *mut UserData<D>);
        let m = ns.max(0) as usize;
        let (y, ypv, r) = (view(yy), view(yp), view(rr));
        let s: Vec<&[f64]> = (0..m).map(|i| view(*ys.add(i))).collect();
        let sp: Vec<&[f64]> = (0..m).map(|i| view(*yps.add(i))).collect();
        let mut out: Vec<&mut [f64]> = (0..m).map(|i| view_mut(*rs.add(i))).collect();
        let result = guard(|| {
            timing::time(Phase::Residual, || {
                user.dae
                    .sensitivity_residuals(State::new(t, y, ypv), r, &s, &sp, &mut out)
            })
        });
        dae_code(user, result, "sensitivity residuals")
    }
}
