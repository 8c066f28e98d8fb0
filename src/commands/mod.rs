//! The commands above the driver ([`crate::run`]): each runs cases and draws what they
//! wrote. (`cellsim run`, `check`, `table` and `plot` are thin enough to live in the
//! binary's `main.rs`.)
//!
//! - [`paper`]: `cellsim paper`, the paper's scenes run together, their figures and the
//!   comparison with the paper's numbers;
//! - [`step_study`]: `cellsim study`, a scene over a ladder of time steps and tolerances
//!   (BDF2 and IDA): errors against a reference, orders, work-precision;
//! - [`sweep`]: `cellsim sweep`, a case over a grid or list of parameter values (maps,
//!   sensitivities, comparisons; resumable, sharded, Slurm arrays).

pub mod paper;
pub mod step_study;
pub mod sweep;
