//! cellsim: a finite-element model of a living cell settling under gravity, spreading by
//! adhesion and contracting its actin on a flat or micropillared substrate.
//!
//! The semi-discrete system is one implicit DAE `F(t, y, ẏ) = 0` (module [`dae`]),
//! integrated by SUNDIALS IDA (variable-order BDF, [`sundials`]) or by a fixed-step BDF2
//! that verifies it ([`dae::bdf2`]).
#![deny(unsafe_code)]
// Index loops are the clearest way to write element kernels; `!(x > 0.0)` is meant to
// catch NaN as well.
#![allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]

pub mod case;
pub mod dae;
pub mod fem;
pub mod model;
pub mod output;
pub mod paper;
pub mod physics;
pub mod record;
pub mod run;
pub mod scene;
pub mod solver;
pub mod stop;
pub mod study;
pub mod sundials;
pub mod sweep;
pub mod tensor;
