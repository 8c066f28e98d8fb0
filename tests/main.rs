//! The integration tests: one binary, one module per concern.
#![allow(clippy::needless_range_loop)]

mod axisym;
mod cli;
mod dae;
mod deferred;
mod docs;
mod events;
mod fd;
mod fem3;
mod fit;
mod hard;
mod linsolve;
mod model;
mod model3d;
mod output3;
mod plots;
mod scenes;
mod sensitivity;
mod shared;
mod study;
mod sweep;
