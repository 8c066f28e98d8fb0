//! The time switches of the loading history (MODEL.md §5, "Phases" and "Gravity").
//!
//! `t_g = S(t; 0, T_g0)`, `t_as = S(t; T_g0, T_as0)`, `t_a = S(t; T_as0, T_a0)`, and the
//! gravity sign `s_g`, +1 or a smooth flip from +1 to −1 (upside-down scene).

use super::smooth::smooth_step;
use super::{PhysicsError, check};
use serde::{Deserialize, Serialize};

/// Smooth reversal of gravity: `s_g(t) = 1 − 2 S(t; start, start + duration)`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Flip {
    /// Time at which the flip starts [s] (MODEL.md: `T_a0`).
    pub start: f64,
    /// Duration of the flip [s] (MODEL.md: 10 000 s).
    pub duration: f64,
}

/// Phase end times of the loading history, all in seconds.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Phases {
    /// End of the gravity ramp `T_g0` [s]; gravity ramps over `[0, T_g0]`.
    pub t_g0: f64,
    /// End of the adhesion ramp `T_as0` [s]; adhesion ramps over `[T_g0, T_as0]`.
    pub t_as0: f64,
    /// End of the active-strain ramp `T_a0` [s]; active strain ramps over `[T_as0, T_a0]`.
    pub t_a0: f64,
    /// Optional gravity flip (upside-down scene).
    pub flip: Option<Flip>,
}

impl Phases {
    /// Checks `0 < T_g0 < T_as0 < T_a0` (each ramp has positive length), and for a flip
    /// `start ≥ 0`, `duration > 0`, all finite.
    pub fn validate(&self) -> Result<(), PhysicsError> {
        check(
            self.t_g0.is_finite() && self.t_g0 > 0.0,
            "t_g0",
            self.t_g0,
            "must be finite and > 0",
        )?;
        check(
            self.t_as0.is_finite() && self.t_as0 > self.t_g0,
            "t_as0",
            self.t_as0,
            "must be finite and > t_g0",
        )?;
        check(
            self.t_a0.is_finite() && self.t_a0 > self.t_as0,
            "t_a0",
            self.t_a0,
            "must be finite and > t_as0",
        )?;
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

    /// Adhesion switch `t_as(t) = S(t; T_g0, T_as0)`.
    pub fn t_as(&self, t: f64) -> f64 {
        smooth_step(t, self.t_g0, self.t_as0)
    }

    /// Active-strain switch `t_a(t) = S(t; T_as0, T_a0)`.
    pub fn t_a(&self, t: f64) -> f64 {
        smooth_step(t, self.t_as0, self.t_a0)
    }

    /// Gravity sign `s_g(t)`: +1 without flip, else `1 − 2 S(t; start, start + duration)`.
    pub fn gravity_sign(&self, t: f64) -> f64 {
        match self.flip {
            None => 1.0,
            Some(f) => 1.0 - 2.0 * smooth_step(t, f.start, f.start + f.duration),
        }
    }

    /// Times where the forcing is not C^∞ (ends of the smooth steps, where the third
    /// derivative jumps): `0, T_g0, T_as0, T_a0` and the flip's start and end. Sorted
    /// increasingly, duplicates removed; includes `0` (the caller skips the initial time).
    pub fn breakpoints(&self) -> Vec<f64> {
        let mut b = vec![0.0, self.t_g0, self.t_as0, self.t_a0];
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
    fn rejects_bad_orders() {
        let p = Phases {
            t_as0: 5.0e3,
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
