//! The assembly plan of the cell model: the pattern of the iteration matrix and, for every
//! element and nodal row, where its contributions go — built once from the unknown
//! numbering, then used to scatter the kernels' element vectors and tangents.
//!
//! Blocks of J (rows × columns), in terms of the element tangents ([`TangentOf`]):
//!
//! - momentum × u: `K` (with inertia), `K + cj C` (without: v = u̇);
//! - momentum × v (inertia only): `C` (including `cj M`);
//! - momentum × μ_as (membrane elements with adhesion): `B`;
//! - kinematic rows (inertia only): `u̇ − v`, entries `cj` (u_k) and `−1` (v_k);
//! - adhesion rows: `μ̇_as − r(x, μ_as)`, entries on μ_k and on the node's u.
//!
//! Written once for any dimension `D`, nodes per element `N` and element unknowns
//! `E = D·N` (the three as const parameters: stable Rust cannot compute `E` from the
//! others in a type).

use super::dofs::DofMapOf;
use crate::fem::assembly::{BlockPositions, NONE, Pattern, PatternBuilder, position_or_none};

/// The element tangents `K`, `C` (rows and columns node-major, `D · a + i`, E = D·N of
/// them) and `B` (columns: the μ_as of the element's N nodes).
pub(crate) struct TangentOf<const E: usize, const N: usize> {
    /// `K = ∂f_e/∂u`.
    pub(crate) k: [[f64; E]; E],
    /// `C = ∂f_e/∂v` (v with inertia, u̇ without).
    pub(crate) c: [[f64; E]; E],
    /// `B = ∂f_e/∂μ_as`.
    pub(crate) b: [[f64; N]; E],
}

impl<const E: usize, const N: usize> TangentOf<E, N> {
    /// All zero.
    pub(crate) fn zeros() -> Self {
        Self {
            k: [[0.0; E]; E],
            c: [[0.0; E]; E],
            b: [[0.0; N]; E],
        }
    }

    /// Zeroes `K` and `C`, and `B` when `with_mu`.
    #[inline]
    pub(crate) fn reset(&mut self, with_mu: bool) {
        for row in self.k.iter_mut() {
            row.fill(0.0);
        }
        for row in self.c.iter_mut() {
            row.fill(0.0);
        }
        if with_mu {
            for row in self.b.iter_mut() {
                row.fill(0.0);
            }
        }
    }
}

/// Where one element's contributions go.
pub(crate) struct ElementPositions<const E: usize> {
    /// Momentum rows of the element's displacement components, node-major
    /// ([`NONE`] where eliminated): the rows of the residual scatter.
    pub(crate) momentum_rows: [usize; E],
    /// (momentum rows × u columns).
    pub(crate) momentum_u: BlockPositions,
    /// (momentum rows × v columns); empty without inertia.
    pub(crate) momentum_v: BlockPositions,
    /// (momentum rows × μ_as columns); empty unless the element carries μ_as.
    pub(crate) momentum_mu: BlockPositions,
}

/// The pattern of J and the positions of every block in it.
pub(crate) struct PlanOf<const D: usize, const N: usize, const E: usize> {
    /// The pattern of the iteration matrix.
    pub(crate) pattern: Pattern,
    /// Per element, in mesh order.
    pub(crate) elements: Vec<ElementPositions<E>>,
    /// Kinematic rows (inertia): positions of (u_k, u_k) and (u_k, v_k).
    pub(crate) kinematic: Vec<[usize; 2]>,
    /// Adhesion rows: positions of (μ_k, μ_k) and of (μ_k, u) for its node's components.
    pub(crate) mu_rate: Vec<(usize, [usize; D])>,
}

/// An element's unknowns: momentum rows, u, v and μ_as columns.
struct ElementDofs<const N: usize, const E: usize> {
    rows: [usize; E],
    u: [usize; E],
    v: [usize; E],
    mu: [usize; N],
}

impl<const N: usize, const E: usize> ElementDofs<N, E> {
    fn new<const D: usize>(dofs: &DofMapOf<D>, nodes: &[usize; N]) -> Self {
        let mut d = Self {
            rows: [NONE; E],
            u: [NONE; E],
            v: [NONE; E],
            mu: nodes.map(|i| dofs.mu[i]),
        };
        for (a, &n) in nodes.iter().enumerate() {
            let m = dofs.momentum_rows(n);
            for i in 0..D {
                d.rows[D * a + i] = m[i];
                d.u[D * a + i] = dofs.u[n][i];
                d.v[D * a + i] = dofs.v[n][i];
            }
        }
        d
    }
}

impl<const D: usize, const N: usize, const E: usize> PlanOf<D, N, E> {
    /// The plan for elements given as (nodes, whether the element carries μ_as), in mesh
    /// order, under the numbering `dofs`.
    ///
    /// `extra`: further sets of five nodes whose momentum rows are coupled to their u
    /// columns (the outline's self-contact pairs).
    pub(crate) fn new(
        dofs: &DofMapOf<D>,
        elements: &[([usize; N], bool)],
        extra: &[[usize; 5]],
    ) -> Self {
        assert_eq!(E, D * N, "element unknowns E must be D·N");
        let inertia = dofs.inertia;
        let el_dofs: Vec<ElementDofs<N, E>> = elements
            .iter()
            .map(|(nodes, _)| ElementDofs::new(dofs, nodes))
            .collect();
        let mut b = PatternBuilder::new();
        for ((_, with_mu), d) in elements.iter().zip(&el_dofs) {
            b.add_block(&d.rows, &d.u);
            if inertia {
                b.add_block(&d.rows, &d.v);
            }
            if *with_mu {
                b.add_block(&d.rows, &d.mu);
            }
        }
        for nodes in extra {
            let rows: Vec<usize> = nodes.iter().flat_map(|&n| dofs.momentum_rows(n)).collect();
            let cols: Vec<usize> = nodes.iter().flat_map(|&n| dofs.u[n]).collect();
            b.add_block(&rows, &cols);
        }
        // One kinematic row per u unknown (a tied component shares its row).
        let kinematic_pairs: Vec<(usize, usize)> = if inertia {
            let mut pairs: Vec<(usize, usize)> = (0..dofs.u.len())
                .flat_map(|i| (0..D).map(move |k| (i, k)))
                .map(|(i, k)| (dofs.u[i][k], dofs.v[i][k]))
                .filter(|&(uk, _)| uk != NONE)
                .collect();
            pairs.sort_unstable();
            pairs.dedup();
            pairs
        } else {
            Vec::new()
        };
        for &(uk, vk) in &kinematic_pairs {
            b.add(uk, uk);
            b.add(uk, vk);
        }
        let mu_row = |k: usize| dofs.mu_offset() + k;
        for (k, &i) in dofs.mu_nodes.iter().enumerate() {
            b.add(mu_row(k), mu_row(k));
            b.add_block(&[mu_row(k)], &dofs.u[i]);
        }
        let pattern = b.build(dofs.n);
        let pos = |r: usize, c: usize| position_or_none(&pattern, r, c);
        let elements = elements
            .iter()
            .zip(&el_dofs)
            .map(|((_, with_mu), d)| ElementPositions {
                momentum_rows: d.rows,
                momentum_u: BlockPositions::new(&pattern, &d.rows, &d.u),
                momentum_v: if inertia {
                    BlockPositions::new(&pattern, &d.rows, &d.v)
                } else {
                    BlockPositions::empty()
                },
                momentum_mu: if *with_mu {
                    BlockPositions::new(&pattern, &d.rows, &d.mu)
                } else {
                    BlockPositions::empty()
                },
            })
            .collect();
        let kinematic = kinematic_pairs
            .iter()
            .map(|&(uk, vk)| [pos(uk, uk), pos(uk, vk)])
            .collect();
        let mu_rate = dofs
            .mu_nodes
            .iter()
            .enumerate()
            .map(|(k, &i)| {
                let row = mu_row(k);
                (pos(row, row), dofs.u[i].map(|c| pos(row, c)))
            })
            .collect();
        Self {
            pattern,
            elements,
            kinematic,
            mu_rate,
        }
    }

    /// `r[row] += f_e[a][i]` over element `e`'s momentum rows.
    #[inline(always)]
    pub(crate) fn scatter_residual(&self, e: usize, fe: &[[f64; D]; N], r: &mut [f64]) {
        let rows = &self.elements[e].momentum_rows;
        for a in 0..N {
            for i in 0..D {
                let row = rows[D * a + i];
                if row != NONE {
                    r[row] += fe[a][i];
                }
            }
        }
    }

    /// Adds element `e`'s tangents to J's values: `K` (u columns) and `C` (v columns)
    /// with inertia, `K + cj C` (u columns) without, and `B` (μ_as columns) where present.
    #[inline(always)]
    pub(crate) fn scatter_tangent(&self, e: usize, tan: &TangentOf<E, N>, cj: f64, v: &mut [f64]) {
        let ep = &self.elements[e];
        if ep.momentum_v.is_empty() {
            ep.momentum_u.scatter_combined(&tan.k, cj, &tan.c, v);
        } else {
            ep.momentum_u.scatter(&tan.k, v);
            ep.momentum_v.scatter(&tan.c, v);
        }
        if !ep.momentum_mu.is_empty() {
            ep.momentum_mu.scatter(&tan.b, v);
        }
    }

    /// The kinematic rows `u̇ − v`: `cj` at (u_k, u_k) and `−1` at (u_k, v_k).
    pub(crate) fn add_kinematic(&self, cj: f64, v: &mut [f64]) {
        for &[puu, puv] in &self.kinematic {
            v[puu] += cj;
            v[puv] -= 1.0;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fem::{Mesh, MeshParams};
    use crate::model::{CellModel, ModelParams};

    /// Every entry of every element block whose row and column exist has its place in the
    /// pattern, and the eliminated ones none.
    #[test]
    fn every_element_entry_has_its_place_in_the_pattern() {
        let mesh = Mesh::generate(&MeshParams {
            refine: 0.5,
            ..crate::fem::reference::mesh_params()
        })
        .expect("mesh");
        for inertia in [true, false] {
            let params = ModelParams {
                inertia,
                ..crate::scene::reference_params()
            };
            let m = CellModel::new(params, mesh.clone()).expect("model");
            let nnz = m.plan.pattern.compute_nnz();
            for (el, ep) in m.elements.iter().zip(&m.plan.elements) {
                let d: ElementDofs<6, 12> = ElementDofs::new(&m.dofs, &el.nodes);
                assert_eq!(ep.momentum_v.is_empty(), !inertia);
                assert_eq!(ep.momentum_mu.is_empty(), !el.with_mu);
                let blocks: [(&BlockPositions, &[usize]); 3] = [
                    (&ep.momentum_u, &d.u),
                    (&ep.momentum_v, &d.v),
                    (&ep.momentum_mu, &d.mu),
                ];
                for (block, cols) in blocks {
                    for (k, &p) in block.positions().iter().enumerate() {
                        let (r, c) = (d.rows[k / cols.len()], cols[k % cols.len()]);
                        assert_eq!(p == NONE, r == NONE || c == NONE);
                        assert!(p == NONE || p < nnz);
                    }
                }
            }
            assert!(m.plan.kinematic.iter().flatten().all(|&p| p < nnz));
            assert!(m.plan.mu_rate.iter().all(|p| p.0 < nnz));
        }
    }
}
