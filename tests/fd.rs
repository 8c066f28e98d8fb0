//! The finite-difference checks of the cell model's iteration matrix, for every shape:
//! a deformed test state with the cell sunk into the contact and adhesion bands, and the
//! worst column error of `J = ∂F/∂y + cj ∂F/∂ẏ` against central differences of the
//! residual. Used by the plane-strain, axisymmetric, deferred and 3-D tests.

use cellsim::dae::Dae;
use cellsim::dae::State;
use cellsim::fem::CellMesh;
use cellsim::model::{CellOf, Shape};
use oorandom::Rand64;

/// A deformed state: a rigid shift down by `sink` plus a smooth random field (in 3-D
/// with z terms), random velocities and exposures μ_as.
pub fn deformed_state<S: Shape<D, N, E>, const D: usize, const N: usize, const E: usize>(
    m: &CellOf<S, D, N, E>,
    sink: f64,
    seed: u64,
) -> (Vec<f64>, Vec<f64>) {
    let mut rng = Rand64::new(seed as u128);
    let n = m.size();
    let (mut y, mut yp) = (vec![0.0; n], vec![0.0; n]);
    let (a, b, c) = (rng.rand_float(), rng.rand_float(), rng.rand_float());
    for (i, x) in m.mesh.nodes().iter().enumerate() {
        let mut uy = -sink + 0.04 * (0.25 * x[0] + b).cos() + 0.02 * (0.2 * x[1] + c).sin();
        let mut du = [0.05 * (0.3 * x[1] + a).sin() * x[0] / 10.0, 0.0, 0.0];
        if D == 3 {
            uy += 0.03 * (0.3 * x[2] + a).cos();
            du[2] = 0.04 * (0.2 * x[1] + b).cos() * x[2] / 10.0;
        }
        du[1] = uy;
        for k in 0..D {
            let d = m.dofs.u[i][k];
            if d != usize::MAX {
                y[d] = du[k];
                yp[d] = 1e-3 * (rng.rand_float() - 0.5);
                let v = m.dofs.v[i][k];
                if v != usize::MAX {
                    y[v] = 1e-2 * (rng.rand_float() - 0.5);
                    yp[v] = 1e-1 * (rng.rand_float() - 0.5);
                }
            }
        }
    }
    let off = m.dofs.mu_offset();
    for k in 0..m.dofs.n_mu() {
        y[off + k] = 1.4e3 * rng.rand_float();
        yp[off + k] = rng.rand_float();
    }
    (y, yp)
}

/// Worst relative column error of `J = ∂F/∂y + cj ∂F/∂ẏ` for each `cj` of `cjs` against
/// finite differences of the residual, on the columns `cols`; with the column where it is.
///
/// `∂F/∂y` by Richardson-extrapolated central differences (error O(h⁴), so that the steps
/// can be large enough to keep round-off far below the tolerance: relative 1e-4 on u and
/// v); `∂F/∂ẏ` by one central difference in ẏ at the same step, exact (to round-off) where
/// `F` is affine in ẏ, as the model's residual is (inertia, viscosity and drag are linear
/// in the rates, and so is the exposure row): a dependence of higher order would show as
/// an error here, not hide one. Every `cj` is then checked on the same differences.
///
/// An exposure (~1e3) enters the residual linearly except in the cap's band
/// (0.98–1 μ_as,max), and a node at the edge of the adhesion layer has a column of ~1e-8
/// in rows of ~1: there the round-off of a small step (∝ 1/h) exceeds 1e-6 of the column,
/// while a large step crosses the cap's band of other nodes. So, as in Ridders' method,
/// an exposure's `∂F/∂y` is differenced at `mu_step` × 100, × 10 and × 1, and of the two
/// larger steps' estimates the one kept is that which agrees better with the next smaller
/// step's (the smallest step serves only as that comparison).
#[allow(clippy::too_many_arguments)]
pub fn jacobian_fd_error<M: Dae + ?Sized>(
    m: &mut M,
    mu_offset: usize,
    mu_step: f64,
    t: f64,
    y: &[f64],
    yp: &[f64],
    cjs: &[f64],
    cols: &[usize],
) -> Vec<(f64, usize)> {
    let n = m.size();
    let pat = m.pattern().clone();
    let jacobians: Vec<Vec<f64>> = cjs
        .iter()
        .map(|&cj| {
            let mut vals = vec![0.0; pat.compute_nnz()];
            m.jacobian(State::new(t, y, yp), cj, &mut vals).unwrap();
            vals
        })
        .collect();
    let mut worst = vec![(0.0, usize::MAX); cjs.len()];
    let (mut rp, mut rm) = (vec![0.0; n], vec![0.0; n]);
    for &j in cols {
        // Central difference along unknown j of y (`rate` false) or of ẏ (true).
        let mut central = |h: f64, rate: bool| -> Vec<f64> {
            let (mut y1, mut yp1) = (y.to_vec(), yp.to_vec());
            let v = if rate { &mut yp1 } else { &mut y1 };
            v[j] += h;
            m.residual(State::new(t, &y1, &yp1), &mut rp).unwrap();
            let v = if rate { &mut yp1 } else { &mut y1 };
            v[j] -= 2.0 * h;
            m.residual(State::new(t, &y1, &yp1), &mut rm).unwrap();
            rp.iter()
                .zip(&rm)
                .map(|(a, b)| (a - b) / (2.0 * h))
                .collect()
        };
        let mut richardson = |h: f64| -> Vec<f64> {
            let (d1, d2) = (central(h, false), central(h / 2.0, false));
            d1.iter()
                .zip(&d2)
                .map(|(a, b)| (4.0 * b - a) / 3.0)
                .collect()
        };
        let h = 1e-4 * y[j].abs().max(0.1);
        let dy = if j >= mu_offset {
            let [large, middle, small] = [100.0, 10.0, 1.0].map(|k| richardson(k * mu_step));
            let gap = |a: &[f64], b: &[f64]| -> f64 {
                a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum()
            };
            if gap(&large, &middle) <= gap(&middle, &small) {
                large
            } else {
                middle
            }
        } else {
            richardson(h)
        };
        let dyp = central(if j >= mu_offset { mu_step } else { h }, true);
        for ((&cj, vals), worst) in cjs.iter().zip(&jacobians).zip(&mut worst) {
            let mut col = vec![0.0; n];
            for k in pat.col_ptr()[j]..pat.col_ptr()[j + 1] {
                col[pat.row_idx()[k]] = vals[k];
            }
            let norm = col.iter().map(|v| v * v).sum::<f64>().sqrt();
            let diff = col
                .iter()
                .zip(dy.iter().zip(&dyp))
                .map(|(a, (d, p))| (a - (d + cj * p)).powi(2))
                .sum::<f64>()
                .sqrt();
            // A column may vanish (e.g. μ_as of a node out of the layer with cj = 0): then
            // the finite differences must vanish too.
            if norm == 0.0 {
                assert!(
                    diff < 1e-9,
                    "column {j}, cj {cj}: J is zero there, finite differences give {diff:.2e}"
                );
            } else if diff / norm > worst.0 {
                *worst = (diff / norm, j);
            }
        }
    }
    worst
}

/// `count` random columns plus every unknown (u, v, μ_as) of the nodes below y = −1 µm
/// (in contact), or of `lowest` of them drawn at random when given.
pub fn contact_columns<S: Shape<D, N, E>, const D: usize, const N: usize, const E: usize>(
    m: &CellOf<S, D, N, E>,
    count: usize,
    lowest: Option<usize>,
) -> Vec<usize> {
    let n = m.size();
    let mut rng = Rand64::new(3);
    let mut cols: Vec<usize> = (0..count)
        .map(|_| (rng.rand_float() * n as f64) as usize)
        .collect();
    let low: Vec<usize> = (0..m.mesh.nodes().len())
        .filter(|&i| m.mesh.nodes()[i][1] < -1.0)
        .collect();
    let picked: Vec<usize> = match lowest {
        None => low,
        Some(k) => (0..k)
            .map(|_| low[(rng.rand_float() * low.len() as f64) as usize])
            .collect(),
    };
    for i in picked {
        cols.extend(
            m.dofs.u[i]
                .iter()
                .chain(m.dofs.v[i].iter())
                .filter(|&&d| d != usize::MAX),
        );
        if m.dofs.mu[i] != usize::MAX {
            cols.push(m.dofs.mu[i]);
        }
    }
    cols
}
