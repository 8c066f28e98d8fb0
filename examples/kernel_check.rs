//! The cell model's residual and Jacobian on a fixed deformed state, written to a file or
//! compared with one written earlier, and the time of repeated evaluations.
//!
//! The state is `cases/fast/push-pull-short.ron`'s model (with and without inertia) and
//! `cases/fast/push-pull-short-drag.ron`'s (medium drag, without inertia), its cell moved
//! 0.5 µm down into the pillars' contact band with a smooth deformation, random rates and
//! μ_as, at t = 550 s (gravity, adhesion and active strain on). A restructuring of the
//! assembly that keeps the arithmetic must give the same numbers bit for bit.
//!
//! `cargo run --release --example kernel_check -- dump FILE` writes the values;
//! `cargo run --release --example kernel_check -- compare FILE` compares with them and
//! prints the largest absolute and relative differences;
//! `cargo run --release --example kernel_check -- time [REPS]` times REPS (default 200)
//! residual and Jacobian evaluations of each model.

use cellsim::dae::State;
use std::time::Instant;

use cellsim::case::Case;
use cellsim::dae::Dae;
use cellsim::fem::Mesh;
use cellsim::model::CellModel;
use cellsim::scene;

const T: f64 = 550.0;

/// Deterministic scattered numbers in [0, 1): the fractional parts of k·φ⁻¹ (no random
/// generator needed for a fixed state).
fn scatter(k: &mut u64) -> f64 {
    *k += 1;
    (*k as f64 * 0.618_033_988_749_894_9).fract()
}

fn model(case: &str, inertia: bool) -> Result<CellModel, String> {
    let file = format!("{}/cases/fast/{case}.ron", env!("CARGO_MANIFEST_DIR"));
    let case = Case::load(&file).map_err(|e| e.to_string())?;
    let mesh = Mesh::generate(&scene::mesh_params(&case)).map_err(|e| e.to_string())?;
    let params = scene::model_params(&case, &file, inertia).map_err(|e| e.to_string())?;
    CellModel::new(params, mesh).map_err(|e| e.to_string())
}

fn state(m: &CellModel) -> (Vec<f64>, Vec<f64>) {
    let mut seq = 0u64;
    let n = m.size();
    let (mut y, mut yp) = (vec![0.0; n], vec![0.0; n]);
    for (i, x) in m.mesh.nodes.iter().enumerate() {
        let du = [
            0.05 * (0.3 * x[1]).sin() * x[0] / 10.0,
            -0.5 + 0.04 * (0.25 * x[0]).cos() + 0.02 * (0.2 * x[1]).sin(),
        ];
        for (k, &duk) in du.iter().enumerate() {
            let d = m.dofs.u[i][k];
            if d != usize::MAX {
                y[d] = duk;
                yp[d] = 1e-3 * (scatter(&mut seq) - 0.5);
                let v = m.dofs.v[i][k];
                if v != usize::MAX {
                    y[v] = 1e-2 * (scatter(&mut seq) - 0.5);
                    yp[v] = 1e-1 * (scatter(&mut seq) - 0.5);
                }
            }
        }
    }
    let off = m.dofs.mu_offset();
    for k in 0..m.dofs.n_mu() {
        y[off + k] = 1.4e3 * scatter(&mut seq);
        yp[off + k] = scatter(&mut seq);
    }
    (y, yp)
}

const MODELS: [(&str, bool); 3] = [
    ("push-pull-short", true),
    ("push-pull-short", false),
    ("push-pull-short-drag", false),
];

/// Residual then Jacobian (cj = 0.1 and 100) of every model, concatenated.
fn values() -> Result<Vec<f64>, String> {
    let mut out = Vec::new();
    for (case, inertia) in MODELS {
        let mut m = model(case, inertia)?;
        let (y, yp) = state(&m);
        let mut r = vec![0.0; m.size()];
        m.residual(State::new(T, &y, &yp), &mut r)
            .map_err(|e| e.to_string())?;
        out.extend_from_slice(&r);
        for cj in [0.1, 100.0] {
            let mut v = vec![0.0; m.pattern().compute_nnz()];
            m.jacobian(State::new(T, &y, &yp), cj, &mut v)
                .map_err(|e| e.to_string())?;
            out.extend_from_slice(&v);
        }
    }
    Ok(out)
}

fn time(reps: usize) -> Result<(), String> {
    for (case, inertia) in MODELS {
        let mut m = model(case, inertia)?;
        let (y, yp) = state(&m);
        let mut r = vec![0.0; m.size()];
        let mut v = vec![0.0; m.pattern().compute_nnz()];
        let start = Instant::now();
        for _ in 0..reps {
            m.residual(State::new(T, &y, &yp), &mut r)
                .map_err(|e| e.to_string())?;
        }
        let tr = start.elapsed().as_secs_f64() / reps as f64;
        let start = Instant::now();
        for _ in 0..reps {
            m.jacobian(State::new(T, &y, &yp), 0.1, &mut v)
                .map_err(|e| e.to_string())?;
        }
        let tj = start.elapsed().as_secs_f64() / reps as f64;
        println!(
            "{case} inertia={inertia} n={}: residual {:.3} ms, jacobian {:.3} ms",
            m.size(),
            tr * 1e3,
            tj * 1e3
        );
    }
    Ok(())
}

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.first().map(String::as_str) {
        Some("dump") => {
            let file = args.get(1).ok_or("dump needs a file")?;
            let bytes: Vec<u8> = values()?.iter().flat_map(|x| x.to_le_bytes()).collect();
            let count = bytes.len() / 8;
            std::fs::write(file, bytes).map_err(|e| format!("{file}: {e}"))?;
            println!("wrote {count} values to {file}");
            Ok(())
        }
        Some("compare") => {
            let file = args.get(1).ok_or("compare needs a file")?;
            let bytes = std::fs::read(file).map_err(|e| format!("{file}: {e}"))?;
            let old: Vec<f64> = bytes
                .chunks_exact(8)
                .map(|c| f64::from_le_bytes(c.try_into().unwrap_or([0; 8])))
                .collect();
            let new = values()?;
            if old.len() != new.len() {
                return Err(format!("{} values, {} stored", new.len(), old.len()));
            }
            let (mut abs, mut rel, mut differ) = (0.0f64, 0.0f64, 0usize);
            for (a, b) in new.iter().zip(&old) {
                if a.to_bits() != b.to_bits() {
                    differ += 1;
                }
                let d = (a - b).abs();
                abs = abs.max(d);
                rel = rel.max(d / b.abs().max(f64::MIN_POSITIVE));
            }
            println!(
                "{} values: {differ} differ bitwise, max |diff| {abs:e}, max relative {rel:e}",
                new.len()
            );
            Ok(())
        }
        Some("time") => time(args.get(1).and_then(|s| s.parse().ok()).unwrap_or(200)),
        _ => Err("usage: kernel_check dump FILE | compare FILE | time [REPS]".into()),
    }
}
