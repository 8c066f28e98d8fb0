//! The self-contact of the cell's outline in the half-plane models (plane strain and
//! axisymmetric): a node of the outer surface is pushed out from behind a face of the same
//! surface ([`crate::physics::self_contact_force`]), so that a fold of the membrane closes
//! on itself instead of passing through.
//!
//! The candidates are fixed once, on the reference outline: every node with every face (a
//! straight piece between consecutive outline nodes, vertices and mid-edge nodes alike)
//! within [`SELF_CONTACT_REACH`] of it along the outline, but the two faces the node ends.
//! A fold brings together parts of the outline that were close along it, so the pairs, and
//! with them the pattern of the iteration matrix, never change. Each pair couples five
//! nodes: the node, its two neighbours (its normal) and the face's two ends.

use nalgebra::Vector2;
use num_dual::DualSVec64;

use super::shape::Seeded;
use crate::fem::assembly::{BlockPositions, NONE, Pattern};
use crate::physics::{Contact, self_contact_force};

/// How far apart along the reference outline a node and a face may be and still touch
/// \[µm\]: what the deepest fold of the fine geometry map needs (at w = 10, s = 14 µm the fold
/// forms at the pillar's foot; with 2 µm it passes through itself and an element inverts at
/// t = 49 410 s). README, "What the sweeps answer".
pub(crate) const SELF_CONTACT_REACH: f64 = 4.0;

/// One candidate: the outline indices of the node's neighbours, the node and the face's
/// ends, `[i − 1, i, i + 1, j, j + 1]`.
type Pair = [usize; 5];

/// The candidates and where their tangents go.
pub(crate) struct SelfContact {
    /// Mesh nodes of the outline, in order along it (the cell on the left).
    outline: Vec<usize>,
    pairs: Vec<Pair>,
    /// Per pair, the positions of its (momentum rows × u columns) block, filled by
    /// [`Self::locate`].
    blocks: Vec<BlockPositions>,
    /// The axisymmetric model (forces per radian).
    axisymmetric: bool,
}

impl SelfContact {
    /// The candidates of `outline` (mesh nodes in order, the cell on the left) whose
    /// reference positions are `reference`.
    pub(crate) fn new(
        outline: Vec<usize>,
        reference: impl Fn(usize) -> [f64; 2],
        axisymmetric: bool,
    ) -> Self {
        let m = outline.len();
        let mut arc = vec![0.0; m];
        for k in 1..m {
            let (a, b) = (reference(outline[k - 1]), reference(outline[k]));
            arc[k] = arc[k - 1] + (b[0] - a[0]).hypot(b[1] - a[1]);
        }
        let mut pairs = Vec::new();
        for i in 1..m.saturating_sub(1) {
            for j in 0..m - 1 {
                let near = (arc[i] - arc[j]).abs().min((arc[i] - arc[j + 1]).abs());
                if j + 1 != i && j != i && near <= SELF_CONTACT_REACH {
                    pairs.push([i - 1, i, i + 1, j, j + 1]);
                }
            }
        }
        Self {
            outline,
            pairs,
            blocks: Vec::new(),
            axisymmetric,
        }
    }

    /// Every pair's five mesh nodes (the blocks the pattern must hold).
    pub(crate) fn node_sets(&self) -> impl Iterator<Item = [usize; 5]> + '_ {
        self.pairs.iter().map(|p| p.map(|k| self.outline[k]))
    }

    /// Finds each pair's block in `pattern`, rows and columns given per mesh node.
    pub(crate) fn locate(
        &mut self,
        pattern: &Pattern,
        rows: impl Fn(usize) -> [usize; 2],
        cols: impl Fn(usize) -> [usize; 2],
    ) {
        self.blocks = self
            .node_sets()
            .map(|nodes| {
                let r: Vec<usize> = nodes.iter().flat_map(|&n| rows(n)).collect();
                let c: Vec<usize> = nodes.iter().flat_map(|&n| cols(n)).collect();
                BlockPositions::new(pattern, &r, &c)
            })
            .collect();
    }

    /// The current positions of the outline's nodes, in its order.
    fn current(&self, x: &impl Fn(usize) -> [f64; 2]) -> Vec<Vector2<f64>> {
        self.outline
            .iter()
            .map(|&i| {
                let p = x(i);
                Vector2::new(p[0], p[1])
            })
            .collect()
    }

    /// Subtracts the self-contact forces from the momentum rows of `r`: `x` the current
    /// position of a mesh node, `rows` its momentum rows.
    pub(crate) fn residual(
        &self,
        law: &Contact,
        x: impl Fn(usize) -> [f64; 2],
        rows: impl Fn(usize) -> [usize; 2],
        r: &mut [f64],
    ) {
        let at = self.current(&x);
        for pair in &self.pairs {
            let xs = pair.map(|k| at[k]);
            let Some(f) = self_contact_force(law, xs, self.axisymmetric) else {
                continue;
            };
            for (k, fk) in pair.iter().zip(&f) {
                for (c, row) in rows(self.outline[*k]).into_iter().enumerate() {
                    if row != NONE {
                        r[row] -= fk[c];
                    }
                }
            }
        }
    }

    /// Adds `∂(−f)/∂u` of every pair in contact to the iteration matrix's values `v`
    /// (dual numbers along the pair's ten coordinates).
    pub(crate) fn tangent(&self, law: &Contact, x: impl Fn(usize) -> [f64; 2], v: &mut [f64]) {
        type Dual = DualSVec64<10>;
        let at = self.current(&x);
        for (pair, block) in self.pairs.iter().zip(&self.blocks) {
            let xs = pair.map(|k| at[k]);
            // The f64 evaluation first: most pairs are apart.
            if self_contact_force(law, xs, self.axisymmetric).is_none() {
                continue;
            }
            let xd: [Vector2<Dual>; 5] = std::array::from_fn(|a| {
                Vector2::new(
                    Dual::seeded(xs[a][0], 2 * a),
                    Dual::seeded(xs[a][1], 2 * a + 1),
                )
            });
            let Some(f) = self_contact_force(law, xd, self.axisymmetric) else {
                continue;
            };
            let mut k = [[0.0; 10]; 10];
            for (a, fa) in f.iter().enumerate() {
                for c in 0..2 {
                    let g = fa[c].gradient();
                    for (col, kc) in k[2 * a + c].iter_mut().enumerate() {
                        *kc = -g[col];
                    }
                }
            }
            block.scatter(&k, v);
        }
    }

    /// Number of candidate pairs.
    #[cfg(test)]
    pub(crate) fn len(&self) -> usize {
        self.pairs.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fem::assembly::{PatternBuilder, position_or_none};

    /// A fold of an outline of 18 nodes 0.25 µm apart at rest: nine along y = 0 towards
    /// −x, the tip, nine back along y = 0.05 towards +x (the cell below the first arm and
    /// above the second: the arms' outward normals face each other across 0.05 µm < ε),
    /// every node moved a little off the lines so that pairs sit in the switches too.
    fn folded() -> Vec<[f64; 2]> {
        let mut x = Vec::new();
        for k in 0..9 {
            x.push([2.0 - 0.25 * k as f64, 0.0]);
        }
        for k in 0..9 {
            x.push([0.25 * k as f64, 0.05]);
        }
        for (k, p) in x.iter_mut().enumerate() {
            let w = k as f64;
            p[0] += 0.02 * (1.3 * w).sin();
            p[1] += 0.015 * (0.7 * w).cos();
        }
        x
    }

    #[test]
    fn the_assembled_tangent_is_the_derivative_of_the_assembled_residual() {
        let law = crate::physics::reference::contact();
        for axisymmetric in [false, true] {
            let rest: Vec<[f64; 2]> = (0..18).map(|k| [0.25 * k as f64, 0.0]).collect();
            let mut sc = SelfContact::new((0..18).collect(), |i| rest[i], axisymmetric);
            // Every pair but the node's own two faces is within reach at 0.25 µm spacing.
            assert_eq!(sc.len(), 16 * 15);
            let two = |i: usize| [2 * i, 2 * i + 1];
            let mut b = PatternBuilder::new();
            for nodes in sc.node_sets() {
                let idx: Vec<usize> = nodes.iter().flat_map(|&n| two(n)).collect();
                b.add_block(&idx, &idx);
            }
            let pattern = b.build(36);
            sc.locate(&pattern, two, two);
            // Off the axis in the axisymmetric model.
            let shift = if axisymmetric { 3.0 } else { 0.0 };
            let x0: Vec<[f64; 2]> = folded().iter().map(|p| [p[0] + shift, p[1]]).collect();
            let residual = |x: &[[f64; 2]]| {
                let mut r = vec![0.0; 36];
                sc.residual(&law, |i| x[i], two, &mut r);
                r
            };
            let r0 = residual(&x0);
            assert!(r0.iter().any(|v| v.abs() > 1.0), "the fold is in contact");
            let total: f64 = r0.iter().step_by(2).sum::<f64>().abs()
                + r0.iter().skip(1).step_by(2).sum::<f64>().abs();
            assert!(total < 1e-9 * 1e3, "the forces balance: {total}");
            let mut v = vec![0.0; pattern.row_idx().len()];
            sc.tangent(&law, |i| x0[i], &mut v);
            let h = 1e-7;
            let scale = r0.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for col in 0..36 {
                let mut xp = x0.clone();
                let mut xm = x0.clone();
                xp[col / 2][col % 2] += h;
                xm[col / 2][col % 2] -= h;
                let (rp, rm) = (residual(&xp), residual(&xm));
                for row in 0..36 {
                    let num = (rp[row] - rm[row]) / (2.0 * h);
                    let pos = position_or_none(&pattern, row, col);
                    let exact = if pos == NONE { 0.0 } else { v[pos] };
                    assert!(
                        (num - exact).abs() < 1e-6 * scale / 0.25,
                        "axisymmetric {axisymmetric}: J[{row}][{col}] {exact} against {num}"
                    );
                }
            }
        }
    }
}
