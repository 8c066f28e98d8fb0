//! Numbering of the unknowns y = (u, v, μ_as): one block after the other.
//!
//! - u: D displacement components per node, except those a symmetry eliminates (in the
//!   half-plane models u_x on the symmetry line x = 0, so u_x = v_x = 0 there; in the 3-D
//!   quarter cell u_x on x = 0 and u_z on z = 0) or ties to another component of the same
//!   node (the 3-D eighth cell's diagonal mirror plane, u_z = u_x: both components are the
//!   one unknown, so the assembly adds both components' rows and columns into it);
//! - v: the same layout again when inertia is modelled (offset `n_u`);
//! - μ_as: one value per node of the membrane elements, when adhesion is modelled.
//!
//! Blocks make the iteration matrix `[cj·I, −I; K, cj·M + C]` visible, so the velocity can
//! be condensed out of the linear solve. The numbering is written once for any dimension
//! ([`DofMapOf`]).

/// Marker for an eliminated (or absent) unknown (the assembly's marker).
pub use crate::fem::assembly::NONE;

/// Where each nodal unknown lives in y, for nodes with `D` displacement components.
#[derive(Debug, Clone)]
pub struct DofMapOf<const D: usize> {
    /// Displacement unknowns per node ([`NONE`] where eliminated).
    pub u: Vec<[usize; D]>,
    /// Velocity unknowns per node (all [`NONE`] without inertia).
    pub v: Vec<[usize; D]>,
    /// Adhesion-coefficient unknown per node ([`NONE`] off the membrane or without adhesion).
    pub mu: Vec<usize>,
    /// The node of each μ_as unknown, in order.
    pub mu_nodes: Vec<usize>,
    /// Number of displacement unknowns.
    pub n_u: usize,
    /// Whether the v block exists.
    pub inertia: bool,
    /// Total number of unknowns.
    pub n: usize,
}

impl<const D: usize> DofMapOf<D> {
    /// Numbers the unknowns of `n_nodes` nodes: u node by node, component by component,
    /// leaving out the components where `eliminated(node, component)` and giving a
    /// component where `tied(node, component) = Some(k)` (k < component) the unknown of
    /// component k; then v if `inertia`; then μ_as at the nodes where `membrane` is true
    /// if `adhesion`.
    pub fn numbered(
        n_nodes: usize,
        eliminated: impl Fn(usize, usize) -> bool,
        tied: impl Fn(usize, usize) -> Option<usize>,
        membrane: &[bool],
        inertia: bool,
        adhesion: bool,
    ) -> Self {
        let mut u = vec![[NONE; D]; n_nodes];
        let mut k = 0;
        for (i, ui) in u.iter_mut().enumerate() {
            for c in 0..D {
                if eliminated(i, c) {
                    continue;
                }
                if let Some(j) = tied(i, c) {
                    assert!(j < c, "a component is tied to one numbered before it");
                    ui[c] = ui[j];
                    continue;
                }
                ui[c] = k;
                k += 1;
            }
        }
        let n_u = k;
        let v = if inertia {
            u.iter()
                .map(|d| d.map(|x| if x == NONE { NONE } else { x + n_u }))
                .collect()
        } else {
            vec![[NONE; D]; n_nodes]
        };
        let mut next = if inertia { 2 * n_u } else { n_u };
        let mut mu = vec![NONE; n_nodes];
        let mut mu_nodes = Vec::new();
        if adhesion {
            for (i, &m) in membrane.iter().enumerate() {
                if m {
                    mu[i] = next;
                    mu_nodes.push(i);
                    next += 1;
                }
            }
        }
        Self {
            u,
            v,
            mu,
            mu_nodes,
            n_u,
            inertia,
            n: next,
        }
    }

    /// Offset of the μ_as block.
    pub fn mu_offset(&self) -> usize {
        if self.inertia { 2 * self.n_u } else { self.n_u }
    }

    /// Number of μ_as unknowns.
    pub fn n_mu(&self) -> usize {
        self.mu_nodes.len()
    }

    /// A state (`y`, `yp`) of this layout mapped to the same one without inertia: u and
    /// μ_as carried over, u̇ = v (u̇ itself without inertia), μ̇_as kept. Returns (y, ẏ)
    /// of the smaller system.
    pub fn drop_inertia(&self, y: &[f64], yp: &[f64]) -> (Vec<f64>, Vec<f64>) {
        let (n_u, n_mu, off) = (self.n_u, self.n_mu(), self.mu_offset());
        let mut y2 = Vec::with_capacity(n_u + n_mu);
        let mut yp2 = Vec::with_capacity(n_u + n_mu);
        y2.extend_from_slice(&y[..n_u]);
        if self.inertia {
            yp2.extend_from_slice(&y[n_u..2 * n_u]);
        } else {
            yp2.extend_from_slice(&yp[..n_u]);
        }
        y2.extend_from_slice(&y[off..off + n_mu]);
        yp2.extend_from_slice(&yp[off..off + n_mu]);
        (y2, yp2)
    }

    /// Velocity of node `i`: its v unknowns with inertia (from `y`), u̇ without (from
    /// `yp`); 0 for eliminated components.
    pub fn node_velocity(&self, y: &[f64], yp: &[f64], i: usize) -> [f64; D] {
        if self.inertia {
            self.v[i].map(|d| if d == NONE { 0.0 } else { y[d] })
        } else {
            self.node_u(yp, i)
        }
    }

    /// Displacement of node `i` read from y (0 for eliminated components).
    pub fn node_u(&self, y: &[f64], i: usize) -> [f64; D] {
        self.u[i].map(|d| if d == NONE { 0.0 } else { y[d] })
    }

    /// The node that moved furthest in `y` and the length of its displacement.
    pub fn largest_displacement(&self, y: &[f64]) -> (usize, f64) {
        (0..self.u.len())
            .map(|i| {
                (
                    i,
                    self.node_u(y, i).iter().map(|c| c * c).sum::<f64>().sqrt(),
                )
            })
            .fold((0, 0.0), |a, b| if b.1 > a.1 { b } else { a })
    }

    /// The rows of the momentum balance of node `i`: the v rows with inertia, else the u rows.
    pub fn momentum_rows(&self, i: usize) -> [usize; D] {
        if self.inertia { self.v[i] } else { self.u[i] }
    }
}
