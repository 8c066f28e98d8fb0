//! The cell model's derivatives, patch test and closed forms.

use cellsim::dae::Dae;
use cellsim::fem::{Mesh, MeshParams};
use cellsim::model::{CellModel, ModelParams};
use cellsim::physics::{ActiveStrain, Bottom, Pac, Pillars, Substrate};

/// Deterministic pseudo-random numbers in [0, 1).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn coarse_mesh() -> Mesh {
    Mesh::generate(&MeshParams {
        refine: 0.5,
        ..Default::default()
    })
    .unwrap()
}

/// A deformed state where the cell bottom has sunk into the contact and adhesion bands:
/// a rigid shift down by `sink` plus a smooth random field, random velocities and μ_as.
fn deformed_state(m: &CellModel, sink: f64, seed: u64) -> (Vec<f64>, Vec<f64>) {
    let mut rng = Lcg(seed);
    let n = m.size();
    let mut y = vec![0.0; n];
    let mut yp = vec![0.0; n];
    let (a, b, c) = (rng.next(), rng.next(), rng.next());
    for (i, x) in m.mesh.nodes.iter().enumerate() {
        let du = [
            0.05 * (0.3 * x[1] + a).sin() * x[0] / 10.0,
            -sink + 0.04 * (0.25 * x[0] + b).cos() + 0.02 * (0.2 * x[1] + c).sin(),
        ];
        for k in 0..2 {
            let d = m.dofs.u[i][k];
            if d != usize::MAX {
                y[d] = du[k];
                yp[d] = 1e-3 * (rng.next() - 0.5);
                let v = m.dofs.v[i][k];
                if v != usize::MAX {
                    y[v] = 1e-2 * (rng.next() - 0.5);
                    yp[v] = 1e-1 * (rng.next() - 0.5);
                }
            }
        }
    }
    let off = m.dofs.mu_offset();
    for k in 0..m.dofs.n_mu() {
        y[off + k] = 1.4e3 * rng.next();
        yp[off + k] = rng.next();
    }
    (y, yp)
}

/// Compares the assembled J = ∂F/∂y + cj ∂F/∂ẏ with central differences of the residual,
/// column by column, on `cols`; returns the worst relative column error.
fn jacobian_fd_error(
    m: &mut CellModel,
    t: f64,
    y: &[f64],
    yp: &[f64],
    cj: f64,
    cols: &[usize],
) -> f64 {
    let n = m.size();
    let nnz = m.pattern().compute_nnz();
    let mut vals = vec![0.0; nnz];
    m.jacobian(t, y, yp, cj, &mut vals).unwrap();
    let pat = m.pattern().clone();
    let mut worst: f64 = 0.0;
    let (mut rp, mut rm) = (vec![0.0; n], vec![0.0; n]);
    for &j in cols {
        // Richardson-extrapolated central differences (error O(h⁴)), so the steps can be
        // large enough to keep round-off far below the tolerance: relative 1e-4 for u and
        // v, 1e-2 absolute for μ_as (~1e3).
        let h = if j >= m.dofs.mu_offset() {
            1e-2
        } else {
            1e-4 * y[j].abs().max(0.1)
        };
        let mut central = |h: f64| -> Vec<f64> {
            let (mut y1, mut yp1) = (y.to_vec(), yp.to_vec());
            y1[j] += h;
            yp1[j] += cj * h;
            m.residual(t, &y1, &yp1, &mut rp).unwrap();
            y1[j] -= 2.0 * h;
            yp1[j] -= 2.0 * cj * h;
            m.residual(t, &y1, &yp1, &mut rm).unwrap();
            rp.iter()
                .zip(&rm)
                .map(|(a, b)| (a - b) / (2.0 * h))
                .collect()
        };
        let (d1, d2) = (central(h), central(h / 2.0));
        let fd: Vec<f64> = d1
            .iter()
            .zip(&d2)
            .map(|(a, b)| (4.0 * b - a) / 3.0)
            .collect();
        let mut col = vec![0.0; n];
        for k in pat.col_ptr()[j]..pat.col_ptr()[j + 1] {
            col[pat.row_idx()[k]] = vals[k];
        }
        let norm = col.iter().map(|v| v * v).sum::<f64>().sqrt();
        let diff = col
            .iter()
            .zip(&fd)
            .map(|(a, b)| (a - b).powi(2))
            .sum::<f64>()
            .sqrt();
        // A column may vanish (e.g. μ_as of a node out of the layer with cj = 0): then the
        // finite differences must vanish too.
        if norm == 0.0 {
            assert!(
                diff < 1e-9,
                "column {j}: J is zero there, finite differences give {diff:.2e}"
            );
        } else {
            worst = worst.max(diff / norm);
        }
    }
    worst
}

fn active_pillars_params(inertia: bool) -> ModelParams {
    let mut p = ModelParams::defaults();
    p.substrate = Substrate::Pillars(Pillars::default());
    p.active = Some(ActiveStrain {
        pac: Some(Pac {
            e: 0.7,
            theta_deg: -18.0,
            inner_axes: [5.0, 4.5],
            outer_axes: [7.5, 7.0],
        }),
        bottom: Some(Bottom {
            e: 0.7,
            theta_deg: -35.0,
        }),
        ..Default::default()
    });
    p.inertia = inertia;
    p.drag = if inertia { 0.0 } else { 1e-3 };
    p
}

#[test]
fn global_jacobian_matches_finite_differences() {
    for (params, sink) in [
        (ModelParams::defaults(), 0.45),
        (active_pillars_params(true), 0.5),
        (active_pillars_params(false), 0.5),
    ] {
        let inertia = params.inertia;
        let mut m = CellModel::new(params, coarse_mesh()).unwrap();
        let (y, yp) = deformed_state(&m, sink, 7);
        // t in the active phase: gravity, adhesion and active strain all switched on.
        let t = 45_000.0;
        // Make sure contact and adhesion are really active in this state.
        let f = m.contact_force_total(&y);
        assert!(f.y > 1e-3, "no contact in the test state (force {f:?})");
        let n = m.size();
        let mut rng = Lcg(3);
        let mut cols: Vec<usize> = (0..150).map(|_| (rng.next() * n as f64) as usize).collect();
        // All unknowns of the lowest nodes (in contact) and some μ_as columns.
        for (i, x) in m.mesh.nodes.iter().enumerate() {
            if x[1] < -1.0 {
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
        }
        for cj in [0.0, 37.0] {
            let err = jacobian_fd_error(&mut m, t, &y, &yp, cj, &cols);
            assert!(
                err < 1e-6,
                "inertia {inertia}, cj {cj}: relative column error {err:.2e}"
            );
        }
    }
}
