//! The time switches of the loading history (MODEL.md §5, "Phases" and "Gravity").
//!
//! `t_g = S(t; 0, T_g0)`, `t_as = S(t; T_g0, T_as0)`, `t_a = S(t; T_as0, T_a0)`, and the
//! gravity sign `s_g`, +1 or a smooth flip from +1 to −1 (upside-down scene). The
//! adhesion and active ramps may instead start when a [`Condition`] on the cell's state
//! first holds (MODEL.md §11).

use super::smooth::smooth_step;
use super::{PhysicsError, check};
use serde::{Deserialize, Serialize};

/// Smooth reversal of gravity: `s_g(t) = 1 − 2 S(t; start, start + duration)`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Flip {
    /// Time at which the flip starts \[s\] (MODEL.md: `T_a0`).
    pub start: f64,
    /// Duration of the flip \[s\] (MODEL.md: 10 000 s).
    pub duration: f64,
}

/// The loading history: the gravity ramp over `[0, T_g0]` and the adhesion and active
/// ramps, each over `[start, end]`. In the paper's scenes (MODEL.md §5) the adhesion ramp
/// is `[T_g0, T_as0]` and the active one `[T_as0, T_a0]`; a phase the cell starts itself
/// (MODEL.md §11, [`Condition`]) has no ramp (`None`, its switch 0) until its condition
/// holds, and then runs from that time over its duration.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Phases {
    /// End of the gravity ramp `T_g0` \[s\]; gravity ramps over `[0, T_g0]`.
    pub t_g0: f64,
    /// The adhesion ramp `[start, end]` \[s\] (the paper: `[T_g0, T_as0]`); `None` while its
    /// start is a condition not yet met.
    pub adhesion: Option<[f64; 2]>,
    /// The active-strain ramp `[start, end]` \[s\] (the paper: `[T_as0, T_a0]`); `None`
    /// while its start is a condition not yet met.
    pub active: Option<[f64; 2]>,
    /// Optional gravity flip (upside-down scene); `None` also while its start, in the
    /// active phase, is not known.
    pub flip: Option<Flip>,
}

/// A condition on the cell's state that starts a phase (MODEL.md §11), located as the
/// zero of a root function of the DAE once the condition is armed.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Condition {
    /// The cell has settled: the vertical speed of the centre falls below `speed` \[µm/s\],
    /// armed once the contact carries half the weight then acting.
    Settled {
        /// The speed \[µm/s\].
        speed: f64,
    },
    /// Spreading slows: the adhered reference radius grows slower than `rate` \[µm/s\],
    /// armed once it has grown faster (and adhesion has started).
    SpreadingSlows {
        /// The rate \[µm/s\].
        rate: f64,
    },
}

/// As a case writes it: `Settled(1e-5)`, `SpreadingSlows(1e-4)`.
impl std::fmt::Display for Condition {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Condition::Settled { speed } => write!(f, "Settled({speed:e})"),
            Condition::SpreadingSlows { rate } => write!(f, "SpreadingSlows({rate:e})"),
        }
    }
}

impl Phases {
    /// Checks `T_g0 > 0` and that each known ramp has `0 ≤ start < end`, and for a flip
    /// `start ≥ 0`, `duration > 0`, all finite.
    pub fn validate(&self) -> Result<(), PhysicsError> {
        check(
            self.t_g0.is_finite() && self.t_g0 > 0.0,
            "t_g0",
            self.t_g0,
            "must be finite and > 0",
        )?;
        for (ramp, start, end) in [
            (self.adhesion, "adhesion start", "t_as0"),
            (self.active, "active start", "t_a0"),
        ] {
            if let Some([a, b]) = ramp {
                check(
                    a.is_finite() && a >= 0.0,
                    start,
                    a,
                    "must be finite and ≥ 0",
                )?;
                check(
                    b.is_finite() && b > a,
                    end,
                    b,
                    "must be finite and > the ramp's start",
                )?;
            }
        }
        if let Some(f) = self.flip {
            check(
                f.start.is_finite() && f.start >= 0.0,
                "flip.start",
                f.start,
                "must be finite and ≥ 0",
            )?;
            check(
                f.duration.is_finite() && f.duration > 0.0,
                "flip.duration",
                f.duration,
                "must be finite and > 0",
            )?;
        }
        Ok(())
    }

    /// Gravity switch `t_g(t) = S(t; 0, T_g0)`.
    pub fn t_g(&self, t: f64) -> f64 {
        smooth_step(t, 0.0, self.t_g0)
    }

    /// Adhesion switch `t_as(t) = S(t; start, end)` (the paper: `S(t; T_g0, T_as0)`), 0
    /// while the phase has not started.
    pub fn t_as(&self, t: f64) -> f64 {
        self.adhesion.map_or(0.0, |[a, b]| smooth_step(t, a, b))
    }

    /// Active-strain switch `t_a(t) = S(t; start, end)` (the paper: `S(t; T_as0, T_a0)`),
    /// 0 while the phase has not started.
    pub fn t_a(&self, t: f64) -> f64 {
        self.active.map_or(0.0, |[a, b]| smooth_step(t, a, b))
    }

    /// Whether adhesion has started by `t` (its ramp begun: `t > start`).
    pub fn adhesion_started(&self, t: f64) -> bool {
        self.adhesion.is_some_and(|[a, _]| t > a)
    }

    /// The phase lines of the figures: the adhesion ramp's start, the active ramp's start
    /// and end (the paper: T_g0, T_as0, T_a0; NaN for a ramp not started).
    pub fn times(&self) -> [f64; 3] {
        let [a, b] = self.active.unwrap_or([f64::NAN; 2]);
        [self.adhesion.map_or(f64::NAN, |r| r[0]), a, b]
    }

    /// Gravity sign `s_g(t)`: +1 without flip, else `1 − 2 S(t; start, start + duration)`.
    pub fn gravity_sign(&self, t: f64) -> f64 {
        match self.flip {
            None => 1.0,
            Some(f) => 1.0 - 2.0 * smooth_step(t, f.start, f.start + f.duration),
        }
    }

    /// Times where the forcing is not C^∞ (ends of the smooth steps, where the third
    /// derivative jumps): `0, T_g0`, the known ramps' ends and the flip's start and end.
    /// Sorted increasingly, duplicates removed; includes `0` (the caller skips the initial
    /// time).
    pub fn breakpoints(&self) -> Vec<f64> {
        let mut b = vec![0.0, self.t_g0];
        for [s, e] in self.adhesion.into_iter().chain(self.active) {
            b.push(s);
            b.push(e);
        }
        if let Some(f) = self.flip {
            b.push(f.start);
            b.push(f.start + f.duration);
        }
        b.sort_by(f64::total_cmp);
        b.dedup();
        b
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn switches_have_the_right_ends() {
        let p = crate::physics::reference::phases();
        p.validate().unwrap();
        assert_eq!(p.t_g(0.0), 0.0);
        assert_eq!(p.t_g(1.0e4), 1.0);
        assert!((p.t_g(5.0e3) - 0.5).abs() < 1e-15);
        assert_eq!(p.t_as(1.0e4), 0.0);
        assert!((p.t_as(2.5e4) - 0.5).abs() < 1e-15);
        assert_eq!(p.t_as(4.0e4), 1.0);
        assert_eq!(p.t_a(3.9e4), 0.0);
        assert!((p.t_a(4.5e4) - 0.5).abs() < 1e-15);
        assert_eq!(p.t_a(6.0e4), 1.0);
        assert_eq!(p.gravity_sign(1.0e5), 1.0);
        // Early gravity: g·S ≈ 10 (t/T_g0)³ (MODEL.md §9).
        let t = 1.0;
        let r = p.t_g(t) / (10.0 * (t / 1.0e4_f64).powi(3));
        assert!((r - 1.0).abs() < 1e-3);
    }

    #[test]
    fn flip_and_breakpoints() {
        let p = Phases {
            flip: Some(Flip {
                start: 5.0e4,
                duration: 1.0e4,
            }),
            ..crate::physics::reference::phases()
        };
        p.validate().unwrap();
        assert_eq!(p.gravity_sign(4.0e4), 1.0);
        assert!(p.gravity_sign(5.5e4).abs() < 1e-15);
        assert_eq!(p.gravity_sign(6.0e4), -1.0);
        assert_eq!(p.breakpoints(), vec![0.0, 1.0e4, 4.0e4, 5.0e4, 6.0e4]);
    }

    #[test]
    fn a_phase_not_started_is_off_and_has_no_breakpoints() {
        let p = Phases {
            adhesion: Some([5_581.0, 35_581.0]),
            active: None,
            ..crate::physics::reference::phases()
        };
        p.validate().unwrap();
        assert_eq!(p.t_a(1e9), 0.0);
        assert_eq!(p.t_as(5_581.0), 0.0);
        assert!((p.t_as(20_581.0) - 0.5).abs() < 1e-15);
        assert!(!p.adhesion_started(5_581.0) && p.adhesion_started(5_582.0));
        assert_eq!(p.breakpoints(), vec![0.0, 5_581.0, 1.0e4, 35_581.0]);
        assert!(p.times()[0] == 5_581.0 && p.times()[1].is_nan());
        // The paper's phases are [T_g0, T_as0] and [T_as0, T_a0].
        let paper = crate::physics::reference::phases();
        assert_eq!(paper.times(), [1.0e4, 4.0e4, 5.0e4]);
    }

    #[test]
    fn rejects_bad_orders() {
        let p = Phases {
            adhesion: Some([1.0e4, 5.0e3]),
            ..crate::physics::reference::phases()
        };
        assert!(p.validate().is_err());
        let p = Phases {
            t_g0: 0.0,
            ..crate::physics::reference::phases()
        };
        assert!(p.validate().is_err());
        let p = Phases {
            flip: Some(Flip {
                start: 1.0,
                duration: 0.0,
            }),
            ..crate::physics::reference::phases()
        };
        assert!(p.validate().is_err());
    }
}
