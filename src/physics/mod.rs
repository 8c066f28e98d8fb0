//! Material laws, active strain, substrate, contact, adhesion, gravity and phases: pure functions.
