//! The only FFI in the crate: SUNDIALS 6 (IDA through the IDAS library, which adds forward
//! sensitivities to the same integrator; serial N_Vector, KLU), SuiteSparse's UMFPACK and
//! METIS's nested-dissection ordering behind safe types.
//!
//! Every C handle is owned by a Rust value that frees it on drop; anything whose address C
//! keeps (the user data, the linear-solver state) is boxed so it never moves. Callbacks are
//! `extern "C"` trampolines that catch panics and map results to SUNDIALS' convention
//! (0 ok, > 0 recoverable, < 0 fatal). Every return code is checked.
#![allow(unsafe_code)]

mod ida;
mod klu;
mod metis;
mod nls;
mod umfpack;

pub use ida::{CalcIc, Ida, IdaOptions, Krylov, SensitivityMethod, SensitivityOptions};
pub use klu::KluLu;
pub use metis::{nested_dissection, nested_dissection_ata};
pub use umfpack::{UmfpackLu, UmfpackOrdering};

use std::ffi::CStr;
use std::os::raw::{c_char, c_int, c_void};
use std::ptr;

use sundials_sys as sys;

// sundials-sys silently builds its bundled SUNDIALS 7 (another API) when it cannot find the
// system library; refuse to compile against anything but the 6.x API this module is written for.
const _: () = assert!(
    sys::SUNDIALS_VERSION_MAJOR == 6,
    "cellsim's SUNDIALS bindings need SUNDIALS 6.x (Debian's libsundials-dev 6.4.1)"
);

/// The SUNDIALS version this crate was built against, e.g. "6.4.1".
pub const SUNDIALS_VERSION: &str = env!("CELLSIM_SUNDIALS_VERSION");

unsafe extern "C" {
    fn free(p: *mut c_void);
}

/// Sets the number of threads of OpenBLAS (the BLAS behind UMFPACK's dense fronts) when it
/// is the BLAS this process has loaded; returns the number OpenBLAS reports afterwards, or
/// `None` for another BLAS. Runs side by side on every core want one each: OpenBLAS's own
/// threads, spinning while they wait for work, would take the cores from the runs.
pub fn set_openblas_threads(n: usize) -> Option<usize> {
    unsafe extern "C" {
        fn dlsym(handle: *mut c_void, symbol: *const c_char) -> *mut c_void;
    }
    // SAFETY: dlsym with glibc's RTLD_DEFAULT (the null handle) looks a name up in the
    // libraries loaded at start; found, `openblas_set_num_threads` and
    // `openblas_get_num_threads` are OpenBLAS's `void (int)` and `int (void)`.
    unsafe {
        let set = dlsym(ptr::null_mut(), c"openblas_set_num_threads".as_ptr());
        let get = dlsym(ptr::null_mut(), c"openblas_get_num_threads".as_ptr());
        if set.is_null() || get.is_null() {
            return None;
        }
        let set: unsafe extern "C" fn(c_int) = std::mem::transmute(set);
        let get: unsafe extern "C" fn() -> c_int = std::mem::transmute(get);
        set(c_int::try_from(n.max(1)).unwrap_or(1));
        usize::try_from(get()).ok()
    }
}

/// A SUNDIALS context (`SUNContext`), freed on drop.
pub(crate) struct Context(sys::SUNContext);

impl Context {
    pub(crate) fn new() -> Result<Self, String> {
        let mut ctx: sys::SUNContext = ptr::null_mut();
        // SAFETY: SUNContext_Create writes a fresh context into `ctx`; NULL communicator
        // is the documented serial usage.
        let flag = unsafe { sys::SUNContext_Create(ptr::null_mut(), &mut ctx) };
        if flag != 0 || ctx.is_null() {
            return Err(format!("SUNContext_Create failed with flag {flag}"));
        }
        Ok(Self(ctx))
    }
}

impl Drop for Context {
    fn drop(&mut self) {
        // SAFETY: created by SUNContext_Create; every object using it is dropped before.
        unsafe {
            sys::SUNContext_Free(&mut self.0);
        }
    }
}

/// A serial N_Vector owning its data, destroyed on drop.
pub(crate) struct NVector(sys::N_Vector);

impl NVector {
    pub(crate) fn new(n: usize, ctx: &Context) -> Result<Self, String> {
        // SAFETY: plain allocation; NULL checked below.
        let v = unsafe { sys::N_VNew_Serial(n as sys::sunindextype, ctx.0) };
        if v.is_null() {
            return Err(format!("N_VNew_Serial({n}) failed"));
        }
        Ok(Self(v))
    }

    pub(crate) fn from_slice(data: &[f64], ctx: &Context) -> Result<Self, String> {
        let mut v = Self::new(data.len(), ctx)?;
        v.as_mut_slice().copy_from_slice(data);
        Ok(v)
    }

    pub(crate) fn as_slice(&self) -> &[f64] {
        // SAFETY: serial vector of the stored length, data owned by the vector.
        unsafe { view(self.0) }
    }

    pub(crate) fn as_mut_slice(&mut self) -> &mut [f64] {
        // SAFETY: as above, and `&mut self` guarantees exclusive access.
        unsafe { view_mut(self.0) }
    }
}

impl Drop for NVector {
    fn drop(&mut self) {
        // SAFETY: created by N_VNew_Serial, not shared with anything that outlives it.
        unsafe { sys::N_VDestroy(self.0) }
    }
}

/// Views a serial N_Vector's data.
///
/// # Safety
/// `v` must be a valid serial N_Vector whose data outlives the returned slice and is not
/// mutated meanwhile.
unsafe fn view<'a>(v: sys::N_Vector) -> &'a [f64] {
    unsafe {
        let n = sys::N_VGetLength(v) as usize;
        let p = sys::N_VGetArrayPointer(v);
        if n == 0 || p.is_null() {
            &[]
        } else {
            std::slice::from_raw_parts(p, n)
        }
    }
}

/// Mutable view of a serial N_Vector's data.
///
/// # Safety
/// As [`view`], plus exclusive access for the slice's lifetime.
unsafe fn view_mut<'a>(v: sys::N_Vector) -> &'a mut [f64] {
    unsafe {
        let n = sys::N_VGetLength(v) as usize;
        let p = sys::N_VGetArrayPointer(v);
        if n == 0 || p.is_null() {
            &mut []
        } else {
            std::slice::from_raw_parts_mut(p, n)
        }
    }
}

/// The name of an IDA return flag (IDAGetReturnFlagName), e.g. "IDA_CONV_FAIL".
pub(crate) fn ida_flag_name(flag: c_int) -> String {
    // SAFETY: returns a malloc'd NUL-terminated string that we own and free.
    unsafe {
        let p = sys::IDAGetReturnFlagName(flag as std::os::raw::c_long);
        if p.is_null() {
            return format!("flag {flag}");
        }
        let s = CStr::from_ptr(p as *const c_char)
            .to_string_lossy()
            .into_owned();
        free(p as *mut c_void);
        s
    }
}

/// Runs `f` catching any panic; a panic becomes `Err(message)`.
pub(crate) fn guard<T>(f: impl FnOnce() -> T) -> Result<T, String> {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)).map_err(|e| {
        if let Some(s) = e.downcast_ref::<&str>() {
            s.to_string()
        } else if let Some(s) = e.downcast_ref::<String>() {
            s.clone()
        } else {
            "panic with a non-string payload".into()
        }
    })
}
