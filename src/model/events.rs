//! The root functions of the phases the cell starts itself (MODEL.md §11).
//!
//! Each watched [`Condition`] (`ModelParams::events`) gives two functions of
//! (t, y, ẏ), both dimensionless and continuous along the solution:
//! - the arming function, counted when it rises through zero;
//! - the firing function, counted when it falls through zero once armed.
//!
//! `Settled(speed)`: arming `F_ct,y / W − ½ max(t_g(t), 10⁻⁶)` (the contact carries half
//! the weight then acting; W the modelled part's full weight), firing `(u̇_y(c) / speed)² − 1` (the
//! centre's vertical speed below `speed`).
//!
//! `SpreadingSlows(rate)`: both `L̇ / rate − 1`, with L the adhered reference radius:
//! `L = ∫_Γ H_ε(d_sub + e_f) dΓ_ref` along the half cell's outline in plane strain,
//! `√(A/π)` of the adhered reference area A of the whole cell in the axisymmetric model
//! (A = 2π ∫ r H dΓ_ref) and in 3-D (the surface faces, times the wedge's copies), so the
//! rate is in µm/s in every model. `L̇ = (∂L/∂u) u̇`, the indicator differentiated along
//! the nodal velocities with dual numbers. Before adhesion starts both are −1: the
//! condition is armed only by spreading.

use nalgebra::SVector;
use num_dual::Dual64;

use super::{CellModel, CellOf, Shape, State};
use crate::fem::tet10::face_map;
use crate::fem::tri6::edge_map;
use crate::fem::{CellMesh, EdgeRule, TriangleRule};
use crate::physics::{Adhesion, Condition, KinematicModel, Surface, layer};

/// The least fraction of the full weight the `Settled` arming counts as acting: at t = 0
/// no weight acts and no contact carries it, and a function that starts at zero would
/// not be seen to cross it (IDA sets such a function aside until it moves; the
/// fixed-step BDF2 counts a crossing only from a nonzero value).
const MIN_WEIGHT: f64 = 1e-6;

/// Halvings of each outline edge, each piece with a 3-point Gauss rule (8 pieces).
const EDGE_LEVELS: u32 = 3;

/// Sub-triangle levels of the rule on each surface face (as the contact area's).
const FACE_LEVELS: u32 = 3;

/// `H(d(x) + e_f)` of the fibronectin layer at `x` and its rate along `ẋ`.
fn layer_and_rate<Sub: Surface<D>, const D: usize>(
    ad: &Adhesion,
    substrate: &Sub,
    x: &SVector<f64, D>,
    xdot: &SVector<f64, D>,
) -> (f64, f64) {
    let xd = SVector::<Dual64, D>::from_fn(|i, _| Dual64::new(x[i], xdot[i]));
    let h = layer(ad, substrate.eval(&xd).0);
    (h.re, h.eps)
}

impl<S: Shape<D, N, E>, const D: usize, const N: usize, const E: usize> CellOf<S, D, N, E> {
    /// The watched conditions' functions, `[arm, fire]` for each, at `at`.
    pub fn condition_values(&self, at: State, g: &mut [f64]) {
        let ph = &self.params.phases;
        for (k, c) in self.params.events.iter().enumerate() {
            let (arm, fire) = match *c {
                Condition::Settled { speed } => {
                    let weight = self.weight();
                    let carried = if weight > 0.0 {
                        self.contact_force_total(at.y)[1] / weight
                    } else {
                        0.0
                    };
                    let c = self.mesh.points().centre;
                    let v = self.dofs.node_velocity(at.y, at.yp, c)[1];
                    let acting = ph.t_g(at.t).max(MIN_WEIGHT);
                    (carried - 0.5 * acting, (v / speed).powi(2) - 1.0)
                }
                Condition::SpreadingSlows { rate } => {
                    if ph.adhesion_started(at.t) {
                        let (_, rate_now) = S::adhered_radius(self, at.y, at.yp);
                        let f = rate_now / rate - 1.0;
                        (f, f)
                    } else {
                        (-1.0, -1.0)
                    }
                }
            };
            g[2 * k] = arm;
            g[2 * k + 1] = fire;
        }
    }
}

impl CellModel {
    /// The adhered reference radius L and its rate L̇ [µm, µm/s] (module documentation):
    /// each outline edge sampled by 3-point Gauss rules on 2^`EDGE_LEVELS` pieces. (0, 0) without
    /// adhesion.
    pub fn adhered_radius(&self, y: &[f64], yp: &[f64]) -> (f64, f64) {
        let Some(ad) = &self.params.adhesion else {
            return (0.0, 0.0);
        };
        let axisymmetric = self.params.kinematics == KinematicModel::Axisymmetric;
        let rule = EdgeRule::degree(5).subdivided(EDGE_LEVELS);
        let (mut m, mut mdot) = (0.0, 0.0);
        for edge in &self.mesh.outer_edges {
            let p = edge.map(|i| self.mesh.nodes[i]);
            let u = edge.map(|i| self.dofs.node_u(y, i));
            let v = edge.map(|i| self.dofs.node_velocity(y, yp, i));
            for (&s, &w) in rule.points.iter().zip(&rule.weights) {
                let (x_ref, tangent) = edge_map(&p, s);
                let (du, _) = edge_map(&u, s);
                let (dv, _) = edge_map(&v, s);
                let x = SVector::<f64, 2>::new(x_ref[0] + du[0], x_ref[1] + du[1]);
                let xdot = SVector::<f64, 2>::new(dv[0], dv[1]);
                let (h, hdot) = layer_and_rate(ad, &self.substrate, &x, &xdot);
                let mut dl = w * tangent[0].hypot(tangent[1]);
                if axisymmetric {
                    dl *= x_ref[0];
                }
                m += h * dl;
                mdot += hdot * dl;
            }
        }
        if axisymmetric {
            // A = 2π m, L = √(A/π) = √(2m), L̇ = Ȧ / (2π L) = ṁ / L.
            area_radius(
                2.0 * std::f64::consts::PI * m,
                2.0 * std::f64::consts::PI * mdot,
            )
        } else {
            (m, mdot)
        }
    }
}

/// `(√(A/π), Ȧ / (2π √(A/π)))`: the radius of the disc of area A and its rate; (0, 0) for
/// no area.
fn area_radius(a: f64, adot: f64) -> (f64, f64) {
    if a <= 0.0 {
        return (0.0, 0.0);
    }
    let l = (a / std::f64::consts::PI).sqrt();
    (l, adot / (2.0 * std::f64::consts::PI * l))
}

impl super::QuarterCell {
    /// The adhered reference radius √(A/π) of the whole cell's adhered reference area A
    /// and its rate [µm, µm/s] (module documentation): each surface face sampled by a
    /// degree-2 rule on 4^`FACE_LEVELS` sub-triangles. (0, 0) without adhesion.
    pub fn adhered_radius(&self, y: &[f64], yp: &[f64]) -> (f64, f64) {
        let Some(ad) = &self.params.adhesion else {
            return (0.0, 0.0);
        };
        let rule = TriangleRule::degree(2).subdivided(FACE_LEVELS);
        let (mut a, mut adot) = (0.0, 0.0);
        for f in &self.mesh.outer_faces {
            let reference: [[f64; 3]; 6] = f.map(|i| self.mesh.nodes[i]);
            let u: [[f64; 3]; 6] = f.map(|i| self.dofs.node_u(y, i));
            let v: [[f64; 3]; 6] = f.map(|i| self.dofs.node_velocity(y, yp, i));
            for (xi, w) in rule.points.iter().zip(&rule.weights) {
                let (x_ref, n_ref) = face_map(&reference, *xi);
                let (du, _) = face_map(&u, *xi);
                let (dv, _) = face_map(&v, *xi);
                let x = SVector::<f64, 3>::from_fn(|i, _| x_ref[i] + du[i]);
                let xdot = SVector::<f64, 3>::from(dv);
                let (h, hdot) = layer_and_rate(ad, &self.substrate, &x, &xdot);
                let da = w * SVector::<f64, 3>::from(n_ref).norm();
                a += h * da;
                adot += hdot * da;
            }
        }
        let copies = self.mesh.params.wedge.copies();
        area_radius(copies * a, copies * adot)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_radius_of_an_area_and_its_rate() {
        let (l, ldot) = area_radius(std::f64::consts::PI * 4.0, std::f64::consts::PI * 4.0);
        assert!((l - 2.0).abs() < 1e-14);
        // A = π L², Ȧ = 2π L L̇: L̇ = 4π / (4π) = 1.
        assert!((ldot - 1.0).abs() < 1e-14);
        assert_eq!(area_radius(0.0, 1.0), (0.0, 0.0));
    }
}
