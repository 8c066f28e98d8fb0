//! The `Dae` trait, the sparse linear solvers and the integrators that see only that trait.
