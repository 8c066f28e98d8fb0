//! The velocities of a first-order (u, v) system eliminated inside the linear solve.
//!
//! A second-order system written in first order has kinematic rows `u̇ − v = 0`, so its
//! iteration matrix has the block form (rows: kinematic, momentum, others)
//!
//! ```text
//!     [ cj·I    −I        0 ] [δu]   [r_u]
//!     [ K       cj·M + C  B ] [δv] = [r_v]
//!     [ R_u     R_v       R ] [δμ]   [r_μ]
//! ```
//!
//! The kinematic rows give `δv = cj δu − r_u`; substituted into the other rows, they leave
//! the half-size system
//!
//! ```text
//!     [ K + cj (cj·M + C)   B ] [δu]   [r_v + (cj·M + C) r_u]
//!     [ R_u + cj R_v        R ] [δμ] = [r_μ + R_v r_u       ]
//! ```
//!
//! which [`CondensedLu`] factorizes with faer's LU, before recovering δv. Nothing assumes
//! `cj` or the `−1`: with `J_pp = α` and `J_pq = γ` read from each pair's kinematic row at
//! every factorization, `δv = (r_u − α δu)/γ`, and the condensed entries are
//! `S = J_(·,u) − (α/γ) J_(·,v)` and the right-hand side `b − J_(·,v) r_u/γ`.
//!
//! [`CondensedLu::analyse`] checks the layout (each kinematic row has exactly its two
//! entries), computes the condensed pattern and a map from J's values to the condensed
//! values; [`CondensedLu::factorize`] fills them through that map (no allocation, no
//! search) and factorizes; [`CondensedLu::solve_in_place`] condenses the right-hand side,
//! solves and recovers the velocities.

use super::linsolve::{FaerLu, LinearSolver, LinearSolverError, Operand};
use super::{FirstOrderBlocks, Pattern};
use crate::fem::assembly::position;

/// Marker for "no index".
const NONE: usize = usize::MAX;

/// An entry of J in a velocity column q_k outside the kinematic rows: it is added, times
/// `−α_k/γ_k`, to the condensed entry of the pair's position column, and it carries the
/// kinematic right-hand side into the condensed one.
#[derive(Debug, Clone, Copy)]
struct VelocityEntry {
    /// Position in J's values.
    src: usize,
    /// Position in the condensed values.
    dst: usize,
    /// Condensed row.
    row: usize,
    /// The pair.
    pair: usize,
}

/// Everything [`CondensedLu::analyse`] computes once for a pattern.
struct Plan {
    /// Full size n.
    n: usize,
    /// Number of nonzeros of the full pattern.
    nnz: usize,
    /// Position unknowns (kinematic rows) p_k and velocity unknowns q_k.
    p: Vec<usize>,
    q: Vec<usize>,
    /// Positions of J_(p_k, p_k) and J_(p_k, q_k) in J's values.
    pos_pp: Vec<usize>,
    pos_pq: Vec<usize>,
    /// Original row of each condensed row, original column of each condensed column.
    row_of: Vec<usize>,
    col_of: Vec<usize>,
    /// (position in J, position in the condensed values): entries copied as they are.
    direct: Vec<(usize, usize)>,
    /// Velocity-column entries.
    velocity: Vec<VelocityEntry>,
    /// Nonzeros of the condensed pattern.
    condensed_nnz: usize,
    // Work arrays, sized once.
    /// Condensed values.
    s: Vec<f64>,
    /// J's velocity-column values at the last factorization (order of `velocity`).
    vel_values: Vec<f64>,
    /// α_k/γ_k and 1/γ_k at the last factorization.
    alpha_over_gamma: Vec<f64>,
    inv_gamma: Vec<f64>,
    /// r_(p_k)/γ_k during a solve.
    g: Vec<f64>,
    /// Condensed right-hand side and solution.
    x: Vec<f64>,
}

/// faer's sparse LU on the condensed system of a first-order (u, v) problem (module
/// documentation). Same answers as the full LU up to round-off, on a system of n − m
/// unknowns instead of n (m the number of pairs).
pub struct CondensedLu {
    blocks: Option<FirstOrderBlocks>,
    inner: Box<dyn LinearSolver>,
    plan: Option<Plan>,
    factorized: bool,
}

impl CondensedLu {
    /// A solver for a problem with the (position, velocity) pairs `blocks`.
    pub fn new(blocks: FirstOrderBlocks) -> Self {
        Self::with_inner(blocks, Box::new(FaerLu::new()))
    }

    /// A solver for a problem with the (position, velocity) pairs `blocks` that factorizes
    /// the condensed system with `inner` (faer's LU with another column ordering, UMFPACK).
    pub fn with_inner(blocks: FirstOrderBlocks, inner: Box<dyn LinearSolver>) -> Self {
        Self {
            blocks: Some(blocks),
            inner,
            plan: None,
            factorized: false,
        }
    }

    /// The LU of the condensed system.
    pub fn inner(&self) -> &dyn LinearSolver {
        self.inner.as_ref()
    }

    /// A solver that does not know the problem's pairs: `analyse` fails with
    /// [`LinearSolverError::Unsupported`]. What [`crate::solver::LinearSolver::build`] returns
    /// for the condensed kind, which has no problem to ask.
    pub fn unconfigured() -> Self {
        Self {
            blocks: None,
            inner: Box::new(FaerLu::new()),
            plan: None,
            factorized: false,
        }
    }

    /// Size of the condensed system (n − number of pairs), once analysed.
    pub fn condensed_size(&self) -> Option<usize> {
        self.plan.as_ref().map(|p| p.row_of.len())
    }

    /// Nonzeros of the condensed pattern, once analysed.
    pub fn condensed_nnz(&self) -> Option<usize> {
        self.plan.as_ref().map(|p| p.condensed_nnz)
    }

    /// Checks the layout and computes the plan and the condensed pattern (module
    /// documentation); the error says why the pattern cannot be condensed.
    fn plan(pattern: &Pattern, blocks: &FirstOrderBlocks) -> Result<(Plan, Pattern), String> {
        let n = pattern.nrows();
        if pattern.ncols() != n {
            return Err(format!(
                "the iteration matrix is {} × {}, not square",
                n,
                pattern.ncols()
            ));
        }
        let roles = Roles::new(blocks, n)?;
        let (pos_pp, pos_pq) = roles.kinematic_positions(pattern)?;
        let numbering = Numbering::new(&roles, n);
        let condensed = numbering.pattern(&roles, pattern);
        let (direct, velocity) = numbering.value_map(&roles, pattern, &condensed);
        let m = roles.p.len();
        let nc = numbering.col_of.len();
        let condensed_nnz = condensed.compute_nnz();
        let plan = Plan {
            n,
            nnz: pattern.compute_nnz(),
            p: roles.p,
            q: roles.q,
            pos_pp,
            pos_pq,
            row_of: numbering.row_of,
            col_of: numbering.col_of,
            vel_values: vec![0.0; velocity.len()],
            direct,
            velocity,
            condensed_nnz,
            s: vec![0.0; condensed_nnz],
            alpha_over_gamma: vec![0.0; m],
            inv_gamma: vec![0.0; m],
            g: vec![0.0; m],
            x: vec![0.0; nc],
        };
        Ok((plan, condensed))
    }
}

impl LinearSolver for CondensedLu {
    fn analyse(&mut self, pattern: &Pattern) -> Result<(), LinearSolverError> {
        self.plan = None;
        self.factorized = false;
        let Some(blocks) = &self.blocks else {
            return Err(LinearSolverError::Unsupported(
                "the condensed solver (faer-condensed) was built without the problem's \
                 (u, v) pairs: build it with LinearSolver::build_for"
                    .into(),
            ));
        };
        let (plan, condensed) = Self::plan(pattern, blocks)
            .map_err(|e| LinearSolverError::Unsupported(format!("condensed solver: {e}")))?;
        self.inner.analyse(&condensed)?;
        self.plan = Some(plan);
        Ok(())
    }

    fn factorize(&mut self, values: &[f64]) -> Result<(), LinearSolverError> {
        let plan = LinearSolverError::analysed(self.plan.as_mut())?;
        self.factorized = false;
        LinearSolverError::check_length(
            "condensed solver",
            Operand::Values,
            values.len(),
            plan.nnz,
        )?;
        for k in 0..plan.p.len() {
            let (alpha, gamma) = (values[plan.pos_pp[k]], values[plan.pos_pq[k]]);
            if gamma == 0.0 || !gamma.is_finite() || !alpha.is_finite() {
                return Err(LinearSolverError::Singular {
                    solver: "condensed",
                    column: Some(plan.q[k]),
                    detail: format!(
                        "kinematic row {} has J = ({alpha:e}, {gamma:e}) in columns ({}, {}); \
                         the velocity cannot be eliminated",
                        plan.p[k], plan.p[k], plan.q[k]
                    ),
                });
            }
            plan.inv_gamma[k] = 1.0 / gamma;
            plan.alpha_over_gamma[k] = alpha / gamma;
        }
        plan.s.fill(0.0);
        for &(src, dst) in &plan.direct {
            plan.s[dst] += values[src];
        }
        for (e, vv) in plan.velocity.iter().zip(plan.vel_values.iter_mut()) {
            *vv = values[e.src];
            plan.s[e.dst] -= plan.alpha_over_gamma[e.pair] * *vv;
        }
        self.inner.factorize(&plan.s)?;
        self.factorized = true;
        Ok(())
    }

    fn solve_in_place(&mut self, b: &mut [f64]) -> Result<(), LinearSolverError> {
        let plan = LinearSolverError::ready(self.plan.as_mut(), self.factorized)?;
        LinearSolverError::check_length("condensed solver", Operand::Rhs, b.len(), plan.n)?;
        // g_k = b_(p_k)/γ_k; condensed right-hand side b_i − Σ_k J_(i, q_k) g_k.
        for k in 0..plan.p.len() {
            plan.g[k] = b[plan.p[k]] * plan.inv_gamma[k];
        }
        for (x, &i) in plan.x.iter_mut().zip(&plan.row_of) {
            *x = b[i];
        }
        for (e, &vv) in plan.velocity.iter().zip(&plan.vel_values) {
            plan.x[e.row] -= vv * plan.g[e.pair];
        }
        self.inner.solve_in_place(&mut plan.x)?;
        for (&x, &j) in plan.x.iter().zip(&plan.col_of) {
            b[j] = x;
        }
        // Velocities from the kinematic rows: x_q = (b_p − α x_p)/γ.
        for k in 0..plan.p.len() {
            b[plan.q[k]] = plan.g[k] - plan.alpha_over_gamma[k] * b[plan.p[k]];
        }
        Ok(())
    }

    fn name(&self) -> &'static str {
        "faer-condensed"
    }
}

/// The part each unknown plays in the (position, velocity) pairs.
struct Roles {
    /// NONE, or 2k for p_k, 2k + 1 for q_k.
    role: Vec<usize>,
    /// Position unknowns (kinematic rows) p_k and velocity unknowns q_k.
    p: Vec<usize>,
    q: Vec<usize>,
}

impl Roles {
    /// The roles of `n` unknowns in the pairs `blocks`; refuses a pair that is not two
    /// distinct unknowns and an unknown in two pairs.
    fn new(blocks: &FirstOrderBlocks, n: usize) -> Result<Self, String> {
        let mut role = vec![NONE; n];
        for (k, &[p, q]) in blocks.pairs.iter().enumerate() {
            if p >= n || q >= n || p == q {
                return Err(format!(
                    "pair {k} = ({p}, {q}) is not two distinct unknowns of {n}"
                ));
            }
            for (idx, r) in [(p, 2 * k), (q, 2 * k + 1)] {
                if role[idx] != NONE {
                    return Err(format!("unknown {idx} appears in two pairs"));
                }
                role[idx] = r;
            }
        }
        let (p, q): (Vec<usize>, Vec<usize>) = blocks.pairs.iter().map(|&[p, q]| (p, q)).unzip();
        Ok(Self { role, p, q })
    }

    /// Whether unknown i is a position p_k (its row is kinematic).
    fn is_p(&self, i: usize) -> bool {
        self.role[i] != NONE && self.role[i] % 2 == 0
    }

    /// Whether unknown i is a velocity q_k (its row is a momentum row).
    fn is_q(&self, i: usize) -> bool {
        self.role[i] != NONE && self.role[i] % 2 == 1
    }

    /// The pair k of an unknown that belongs to one.
    fn pair(&self, i: usize) -> usize {
        self.role[i] / 2
    }

    /// Checks that each kinematic row p_k has exactly the entries (p_k, p_k) and
    /// (p_k, q_k), and returns their positions in J's values: α_k's and γ_k's.
    fn kinematic_positions(&self, pattern: &Pattern) -> Result<(Vec<usize>, Vec<usize>), String> {
        let (p, q) = (&self.p, &self.q);
        let m = p.len();
        let cp = pattern.col_ptr();
        let ri = pattern.row_idx();
        let mut seen = vec![0u8; m];
        for j in 0..pattern.ncols() {
            for &i in &ri[cp[j]..cp[j + 1]] {
                if self.is_p(i) {
                    let k = self.pair(i);
                    if j != p[k] && j != q[k] {
                        return Err(format!(
                            "row {i} is declared kinematic (pair {k}) but has an entry in \
                             column {j}, besides {} and {}",
                            p[k], q[k]
                        ));
                    }
                    seen[k] += 1;
                }
            }
        }
        if let Some(k) = seen.iter().position(|&s| s != 2) {
            return Err(format!(
                "kinematic row {} lacks its entry in column {} or {}",
                p[k], p[k], q[k]
            ));
        }
        let pos = |r: usize, c: usize| position(pattern, r, c).ok_or(());
        let pos_pp: Vec<usize> = (0..m)
            .map(|k| pos(p[k], p[k]))
            .collect::<Result<_, _>>()
            .map_err(|_| "kinematic diagonal missing".to_string())?;
        let pos_pq: Vec<usize> = (0..m)
            .map(|k| pos(p[k], q[k]))
            .collect::<Result<_, _>>()
            .map_err(|_| "kinematic velocity entry missing".to_string())?;
        Ok((pos_pp, pos_pq))
    }
}

/// The condensed numbering: columns are the unknowns that are not velocities, in order;
/// the momentum row q_k takes the place of its position column p_k, every other kept row
/// (not kinematic, not momentum) that of its own column.
struct Numbering {
    /// Condensed column of each original column (NONE for a velocity).
    cidx: Vec<usize>,
    /// Condensed row of each original row (NONE for a kinematic row).
    crow: Vec<usize>,
    /// Original row of each condensed row, original column of each condensed column.
    row_of: Vec<usize>,
    col_of: Vec<usize>,
}

impl Numbering {
    /// The condensed numbering of `n` unknowns with the pairs' `roles`.
    fn new(roles: &Roles, n: usize) -> Self {
        let mut cidx = vec![NONE; n];
        let mut col_of = Vec::with_capacity(n - roles.p.len());
        for j in 0..n {
            if !roles.is_q(j) {
                cidx[j] = col_of.len();
                col_of.push(j);
            }
        }
        let crow: Vec<usize> = (0..n)
            .map(|i| {
                if roles.is_p(i) {
                    NONE
                } else if roles.is_q(i) {
                    cidx[roles.p[roles.pair(i)]]
                } else {
                    cidx[i]
                }
            })
            .collect();
        let mut row_of = vec![NONE; col_of.len()];
        for (i, &r) in crow.iter().enumerate() {
            if r != NONE {
                row_of[r] = i;
            }
        }
        Self {
            cidx,
            crow,
            row_of,
            col_of,
        }
    }

    /// The condensed pattern: column c gathers the kept rows of column col_of[c] and, for
    /// a position column p_k, of the velocity column q_k (S = J_(·,u) − (α/γ) J_(·,v)).
    fn pattern(&self, roles: &Roles, pattern: &Pattern) -> Pattern {
        let cp = pattern.col_ptr();
        let ri = pattern.row_idx();
        let nc = self.col_of.len();
        let mut col_ptr = Vec::with_capacity(nc + 1);
        let mut row_idx = Vec::new();
        col_ptr.push(0);
        let mut rows: Vec<usize> = Vec::new();
        for &j in &self.col_of {
            rows.clear();
            let push_col = |jj: usize, rows: &mut Vec<usize>| {
                for &i in &ri[cp[jj]..cp[jj + 1]] {
                    let r = self.crow[i];
                    if r != NONE {
                        rows.push(r);
                    }
                }
            };
            push_col(j, &mut rows);
            if roles.is_p(j) {
                push_col(roles.q[roles.pair(j)], &mut rows);
            }
            rows.sort_unstable();
            rows.dedup();
            row_idx.extend_from_slice(&rows);
            col_ptr.push(row_idx.len());
        }
        Pattern::new_checked(nc, nc, col_ptr, None, row_idx)
    }

    /// Where each kept entry of J goes in the condensed values: the entries copied as
    /// they are, and the velocity-column entries.
    fn value_map(
        &self,
        roles: &Roles,
        pattern: &Pattern,
        condensed: &Pattern,
    ) -> (Vec<(usize, usize)>, Vec<VelocityEntry>) {
        let cp = pattern.col_ptr();
        let ri = pattern.row_idx();
        let cpos = |r: usize, c: usize| {
            position(condensed, r, c).expect("condensed pattern holds every mapped entry")
        };
        let mut direct = Vec::new();
        let mut velocity = Vec::new();
        for j in 0..pattern.ncols() {
            for k in cp[j]..cp[j + 1] {
                let r = self.crow[ri[k]];
                if r == NONE {
                    continue;
                }
                if roles.is_q(j) {
                    let pair = roles.pair(j);
                    velocity.push(VelocityEntry {
                        src: k,
                        dst: cpos(r, self.cidx[roles.p[pair]]),
                        row: r,
                        pair,
                    });
                } else {
                    direct.push((k, cpos(r, self.cidx[j])));
                }
            }
        }
        (direct, velocity)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fem::assembly::pattern_from_entries;

    /// A small first-order system: m pairs (p_k = k, q_k = m + k) coupled through a
    /// tridiagonal K and C, and two extra unknowns coupled to the positions.
    fn system(m: usize, cj: f64) -> (Pattern, Vec<f64>, FirstOrderBlocks) {
        let n = 2 * m + 2;
        let mut e = Vec::new();
        let mut val = Vec::new();
        let mut add = |r: usize, c: usize, v: f64| {
            e.push((r, c));
            val.push(((r, c), v));
        };
        for k in 0..m {
            add(k, k, cj);
            add(k, m + k, -1.0);
            for l in k.saturating_sub(1)..(k + 2).min(m) {
                let kk = if l == k { 4.0 } else { -1.3 - 0.1 * k as f64 };
                let cc = if l == k { 2.0 } else { 0.4 };
                add(m + k, l, kk);
                add(m + k, m + l, cj * cc + 0.1);
            }
            add(m + k, 2 * m + k % 2, 0.3);
            add(2 * m + k % 2, k, -0.2 + 0.01 * k as f64);
        }
        add(2 * m, 2 * m, cj + 1.0);
        add(2 * m + 1, 2 * m + 1, cj + 2.0);
        let p = pattern_from_entries(n, &e);
        let mut v = vec![0.0; p.compute_nnz()];
        for ((r, c), x) in val {
            v[position(&p, r, c).unwrap()] += x;
        }
        (p, v, FirstOrderBlocks::contiguous(0, m, m))
    }

    fn matvec(p: &Pattern, v: &[f64], x: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; x.len()];
        for j in 0..x.len() {
            for k in p.col_ptr()[j]..p.col_ptr()[j + 1] {
                y[p.row_idx()[k]] += v[k] * x[j];
            }
        }
        y
    }

    #[test]
    fn condensed_solve_has_small_residual() {
        let m = 20;
        let (p, _, blocks) = system(m, 1.0);
        let mut s = CondensedLu::new(blocks);
        s.analyse(&p).unwrap();
        assert_eq!(s.condensed_size(), Some(m + 2));
        for cj in [0.5, 30.0, 1e4] {
            let (_, v, _) = system(m, cj);
            s.factorize(&v).unwrap();
            let b: Vec<f64> = (0..2 * m + 2).map(|i| (i as f64 * 0.7).cos()).collect();
            let mut x = b.clone();
            s.solve_in_place(&mut x).unwrap();
            let r = matvec(&p, &v, &x);
            let scale = b.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            let res = r
                .iter()
                .zip(&b)
                .map(|(a, c)| (a - c).abs())
                .fold(0.0, f64::max);
            assert!(
                res < 1e-10 * scale * cj.max(1.0),
                "cj = {cj}: residual {res}"
            );
        }
    }

    #[test]
    fn a_row_that_is_not_kinematic_is_refused() {
        let m = 4;
        let (p, _, _) = system(m, 1.0);
        // Declare the momentum rows as kinematic: they have many entries.
        let wrong = FirstOrderBlocks::contiguous(m, 0, m);
        let mut s = CondensedLu::new(wrong);
        assert!(matches!(
            s.analyse(&p),
            Err(LinearSolverError::Unsupported(_))
        ));
        let mut u = CondensedLu::unconfigured();
        assert!(matches!(
            u.analyse(&p),
            Err(LinearSolverError::Unsupported(_))
        ));
    }

    #[test]
    fn zero_kinematic_coefficient_is_singular() {
        let m = 3;
        let (p, mut v, blocks) = system(m, 1.0);
        let mut s = CondensedLu::new(blocks);
        s.analyse(&p).unwrap();
        v[position(&p, 1, m + 1).unwrap()] = 0.0;
        assert!(matches!(
            s.factorize(&v),
            Err(LinearSolverError::Singular { .. })
        ));
    }
}
