//! cellsim: a finite-element model of a living cell settling under gravity, spreading by
//! adhesion and contracting its actin on a flat or micropillared substrate.
//!
//! The semi-discrete system is one implicit DAE `F(t, y, ẏ) = 0` (module [`dae`]),
//! integrated by SUNDIALS IDA (variable-order BDF, [`sundials`]) or by a fixed-step BDF2
//! that verifies it ([`dae::bdf2`]).
//!
//! # Layers
//!
//! Each module uses only the ones below it (tests aside):
//!
//! ```text
//!  commands   paper · step_study · sweep     the paper's scenes, step studies, maps
//!                      │
//!  driver             run                    a case through its phases into its files
//!              ┌───────┼────────┐
//!  files    render  run_files    │           figures, VTU, tables  ·  the files as types
//!              └───────┼────────┘
//!  setup             scene                   a case in the lower layers' terms
//!              ┌───────┼────────┐
//!  model     model    case      solver       the cell's residual and Jacobian · the case
//!              │                  │          file's schema · the solver settings
//!  numerics   dae ─── sundials (FFI) ─┘      the DAE, BDF2, the linear solvers; IDA
//!              │
//!  basis     physics → fem → tensor          laws and loads · meshes and elements ·
//!                                            the scalar type and cof(F)
//! ```
//!
//! - [`tensor`]: [`tensor::Real`] (f64 or a dual number, for exact tangents) and
//!   [`tensor::cofactor`];
//! - [`fem`]: the meshes (half cell, quarter cell), elements and quadrature;
//! - [`physics`]: the material laws, active strain, substrate, contact, adhesion and
//!   phases, as pure functions of a material point (MODEL.md);
//! - [`dae`], [`sundials`], [`solver`]: the implicit DAE, its integrators and linear
//!   solvers (all `unsafe` and FFI in [`sundials`]), the settings a case chooses;
//! - [`case`]: the case file (RON): its schema, defaults, rules, `--set` overrides and
//!   located errors; [`scene`]: a case in the lower layers' terms (mesh and model
//!   parameters, the checks those layers make, loading a case with them, its cost);
//! - [`model`]: the cell, generic over its kinematics (plane strain, axisymmetric, 3-D),
//!   and what it reports ([`model::observables`]);
//! - [`run_files`]: the files a run writes, as types, and reading them back; [`render`]:
//!   the figures, movies, VTU and tables drawn from them;
//! - [`run`]: one case (or several sharing their start) through its phases;
//! - [`commands`]: [`commands::paper`], [`commands::step_study`] and
//!   [`commands::sweep`], above it.
//!
//! # Running a case
//!
//! ```no_run
//! use cellsim::case::Case;
//! use cellsim::run::{self, RunOptions};
//!
//! let case = Case::load("cases/flat.ron")?;
//! let opts = RunOptions::new("runs/flat", case.solver.clone());
//! let summary = run::run(&case, "cases/flat.ron", &opts)?;
//! let uy_top = summary.final_values.map(|o| o.uy_top);
//! println!("finished: {}, u_y(p_t) = {uy_top:?} µm", summary.finished);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![deny(unsafe_code)]
// Index loops are the clearest way to write element kernels; `!(x > 0.0)` is meant to
// catch NaN as well.
#![allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]

pub mod case;
pub mod commands;
pub mod dae;
pub mod fem;
pub mod fit;
pub mod model;
pub mod physics;
pub mod render;
pub mod run;
pub mod run_files;
pub mod scene;
pub mod solver;
pub mod stop;
pub mod sundials;
pub mod tensor;
