//! The 3-D quarter cell (MODEL.md §10) on its gmsh mesh: the mesh's size and quality, and
//! optionally a scene integrated by IDA, with its cost and its observables at each
//! output time.
//!
//! ```sh
//! cargo run --release --example cell3d -- [--h-bottom 0.3] [--h-nucleus 1.0] [--refine 1]
//!     [--case cases/flat.ron] [--t-end 10000] [--outputs 20] [--rtol 1e-4]
//!     [--drag D]   # quasi-static: inertia off with medium drag D [pN·s/µm⁴]
//!     [--lattice four|gap] [--threads]
//!     [--bench-lu [--lu faer,umfpack,...]]   # time the LUs on the Jacobian at rest
//!     [--lu-memory]   # the 3-D runs' UMFPACK on it: its memory estimate, fill and peak
//! ```
//!
//! Without `--t-end` it only meshes. With inertia (the case's `OffAfter`) the run keeps
//! inertia throughout; `--drag` replaces it by the medium drag (no switch needed).

use cellsim::dae::State;
use std::time::Instant;

use cellsim::case::Case;
use cellsim::dae::linsolve::{ColumnOrdering, FaerLu, LinearSolver, LinearSolverError};
use cellsim::dae::{Atol, Dae, Integrator, LinearSolverFactory, SharedFactory};
use cellsim::fem::{TetMesh, TetMeshParams};
use cellsim::model::{ModelParams, QuarterCell};
use cellsim::physics::Lattice;
use cellsim::scene;
use cellsim::solver;
use cellsim::sundials::{Ida, IdaOptions};
use cellsim::sundials::{UmfpackLu, UmfpackOrdering, nested_dissection_ata};

/// The LUs compared on the 3-D Jacobians.
#[derive(Debug, Clone, Copy)]
struct Lu(&'static str);

impl LinearSolverFactory for Lu {
    fn build_for(&self, _dae: &dyn Dae) -> Result<Box<dyn LinearSolver>, LinearSolverError> {
        Ok(match self.0 {
            "klu" => solver::LinearSolver::Klu.build(),
            "klu-metis" => solver::LinearSolver::KluMetis.build(),
            "umfpack" => Box::new(UmfpackLu::new(UmfpackOrdering::Amd)),
            "umfpack-metis" => Box::new(UmfpackLu::new(UmfpackOrdering::Metis)),
            "umfpack-noir" => Box::new(UmfpackLu::new(UmfpackOrdering::Amd).without_refinement()),
            "faer-metis-ata" => Box::new(FaerLu::with_ordering(ColumnOrdering::External {
                name: "faer-metis-ata",
                order: nested_dissection_ata,
            })),
            "faer-metis" => Box::new(FaerLu::with_ordering(cellsim::solver::METIS_ORDERING)),
            "faer-par" => Box::new(FaerLu::with_options(
                faer::Par::rayon(2),
                faer::sparse::linalg::SupernodalThreshold::FORCE_SUPERNODAL,
            )),
            _ => solver::LinearSolver::Faer.build(),
        })
    }
}

/// The example's options (see the module's doc).
#[derive(clap::Parser)]
struct Args {
    /// The case file.
    #[arg(long, default_value = "cases/flat.ron")]
    case: String,
    /// Quasi-static: inertia off with this medium drag [pN·s/µm⁴].
    #[arg(long)]
    drag: Option<f64>,
    /// Element size at the cell's bottom [µm] (default: the case's).
    #[arg(long)]
    h_bottom: Option<f64>,
    /// Element size in the nucleus [µm] (default: the case's).
    #[arg(long)]
    h_nucleus: Option<f64>,
    /// Refinement factor (default: the case's).
    #[arg(long)]
    refine: Option<f64>,
    /// Integrate to this time [s]; without it the example only meshes.
    #[arg(long)]
    t_end: Option<f64>,
    /// Measure the 3-D runs' UMFPACK on the Jacobian at rest: memory estimate, fill, peak.
    #[arg(long)]
    lu_memory: bool,
    /// Pillar lattice: four or gap.
    #[arg(long, default_value = "four")]
    lattice: String,
    /// Assemble in parallel.
    #[arg(long)]
    threads: bool,
    /// Time the LUs on the Jacobian at rest instead of integrating.
    #[arg(long)]
    bench_lu: bool,
    /// The LU(s): one name, or a comma-separated list with --bench-lu.
    #[arg(long)]
    lu: Option<String>,
    /// IDA's relative tolerance.
    #[arg(long, default_value_t = 1e-4)]
    rtol: f64,
    /// IDA's absolute tolerance on displacements [µm].
    #[arg(long, default_value_t = 1e-6)]
    atol: f64,
    /// Output times.
    #[arg(long, default_value_t = 20)]
    outputs: usize,
}

fn main() {
    let args = <Args as clap::Parser>::parse();
    let case_file = args.case.clone();
    let mut case = Case::load(&case_file).expect("case");
    let drag = args.drag;
    if let Some(d) = drag {
        case.inertia.mode = cellsim::case::InertiaMode::Off;
        case.inertia.drag = d;
    }
    let mp = TetMeshParams {
        h_bottom: args.h_bottom.unwrap_or(case.mesh.h_bottom),
        h_nucleus: args.h_nucleus.unwrap_or(case.mesh.h_nucleus),
        refine: args.refine.unwrap_or(case.mesh.refine),
        ..cellsim::scene::terms::tet_mesh_params(&case)
    };
    let t0 = Instant::now();
    let mesh = TetMesh::generate(&mp).expect("mesh");
    println!(
        "mesh: {:.2} s\n{}",
        t0.elapsed().as_secs_f64(),
        mesh.quality()
    );
    let Some(t_end) = args.t_end else {
        return;
    };
    let inertia = drag.is_none() && scene::starts_with_inertia(&case);
    let plane = scene::model_params(&case, &case_file, inertia).expect("params");
    let lattice = match args.lattice.as_str() {
        "gap" => Lattice::Gap,
        _ => Lattice::FourPillars,
    };
    let t1 = Instant::now();
    let params = ModelParams {
        kinematics: cellsim::physics::KinematicModel::ThreeD,
        lattice,
        ..plane
    };
    let mut m = QuarterCell::new(params, mesh).expect("model");
    m.set_parallel(args.threads);
    println!(
        "model: {} unknowns ({} u, {} μ_as), {} elements, set-up {:.2} s",
        m.size(),
        m.dofs.n_u,
        m.dofs.n_mu(),
        m.n_elements(),
        t1.elapsed().as_secs_f64()
    );
    if args.bench_lu {
        bench_lu(&mut m, args.lu.as_deref());
        return;
    }
    if args.lu_memory {
        lu_memory(&mut m);
        return;
    }
    let rtol = args.rtol;
    let atol = Atol::Vector(m.atol_vector(args.atol));
    let mut ida = Ida::new(
        m,
        IdaOptions {
            rtol,
            atol,
            linear_solver: {
                let name: &'static str = match args.lu.as_deref() {
                    Some("klu") => "klu",
                    Some("klu-metis") => "klu-metis",
                    Some("umfpack") => "umfpack",
                    Some("umfpack-metis") => "umfpack-metis",
                    Some("faer-metis-ata") => "faer-metis-ata",
                    Some("faer-par") => "faer-par",
                    _ => "faer",
                };
                let f: SharedFactory = std::sync::Arc::new(Lu(name));
                f
            },
            ..Default::default()
        },
    )
    .expect("IDA");
    let n_out = args.outputs;
    println!(
        "t\tsteps\tjac\twall\tuy_top\tcontact_radius\tcontact_radius_ref\tcontact_area\tforce_y/weight"
    );
    let t2 = Instant::now();
    for k in 1..=n_out {
        let t = t_end * k as f64 / n_out as f64;
        if let Err(e) = ida.advance_to(t, &mut |_, _| true) {
            println!("failed: {e}");
            break;
        }
        let (m, y) = (ida.dae(), ida.y());
        let o = m.observe(t, y);
        let o3 = m.observe_quarter(y);
        let s = ida.stats();
        println!(
            "{t}\t{}\t{}\t{:.2}\t{:.5}\t{:.4}\t{:.4}\t{:.4}\t{:.4}",
            s.steps,
            s.jacobian_evals,
            t2.elapsed().as_secs_f64(),
            o.uy_top,
            o.contact_radius,
            o.contact_radius_ref,
            o3.contact_area,
            m.contact_force_total(y).y / m.weight()
        );
    }
}

/// The 3-D runs' LU (UMFPACK, nested dissection, symmetric strategy) on the model's
/// iteration matrix at rest: UMFPACK's memory estimate after the analysis, then one
/// factorization's fill, time and peak memory, and the process's peak resident set.
fn lu_memory(m: &mut QuarterCell) {
    let n = m.size();
    let (y, yp) = (vec![0.0; n], vec![0.0; n]);
    let pattern = m.pattern().clone();
    let mut vals = vec![0.0; pattern.compute_nnz()];
    m.jacobian(State::new(50.0, &y, &yp), 0.1, &mut vals)
        .expect("jacobian");
    let mut lu = UmfpackLu::new(UmfpackOrdering::Metis)
        .with_symmetric_strategy(true)
        .without_refinement();
    let t = Instant::now();
    lu.analyse(&pattern).expect("analyse");
    let gb = |b: Option<f64>| b.unwrap_or(f64::NAN) / 1e9;
    println!(
        "n = {n}, nnz(J) = {}, analyse {:.2} s, UMFPACK peak memory estimate {:.3} GB",
        vals.len(),
        t.elapsed().as_secs_f64(),
        gb(lu.peak_memory_estimate())
    );
    let t = Instant::now();
    match lu.factorize(&vals) {
        Ok(()) => println!(
            "factorize {:.2} s, nnz(L+U) = {:?}, UMFPACK peak memory {:.3} GB, process peak RSS {:.3} GB",
            t.elapsed().as_secs_f64(),
            lu.factor_nnz(),
            gb(lu.peak_memory()),
            peak_rss_gb()
        ),
        Err(e) => println!(
            "factorize failed: {e}; process peak RSS {:.3} GB",
            peak_rss_gb()
        ),
    }
}

/// The process's peak resident set size [GB] (VmHWM in /proc/self/status).
fn peak_rss_gb() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find_map(|l| l.strip_prefix("VmHWM:"))
                .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<f64>().ok())
        })
        .map_or(f64::NAN, |kb| kb * 1024.0 / 1e9)
}

/// Times each LU on the model's iteration matrix at the rest state (cj = 0.1): analysis,
/// numeric factorization (median of 3) and solve; for UMFPACK also its strategy, fill and
/// flop count.
fn bench_lu(m: &mut QuarterCell, only: Option<&str>) {
    let n = m.size();
    let (y, yp) = (vec![0.0; n], vec![0.0; n]);
    let pattern = m.pattern().clone();
    let mut vals = vec![0.0; pattern.compute_nnz()];
    m.jacobian(State::new(50.0, &y, &yp), 0.1, &mut vals)
        .expect("jacobian");
    println!("n = {n}, nnz(J) = {}", vals.len());
    for name in [
        "faer",
        "faer-par",
        "faer-metis",
        "faer-metis-ata",
        "klu-metis",
        "umfpack",
        "umfpack-metis",
        "umfpack-noir",
        "umfpack-sym",
        "umfpack-unsym",
        "umfpack-metis-sym",
    ] {
        if only.is_some_and(|o| !o.split(',').any(|x| x == name)) {
            continue;
        }
        let umfpack = match name {
            "umfpack" => Some(UmfpackLu::new(UmfpackOrdering::Amd)),
            "umfpack-metis" => Some(UmfpackLu::new(UmfpackOrdering::Metis)),
            "umfpack-noir" => Some(UmfpackLu::new(UmfpackOrdering::Amd).without_refinement()),
            "umfpack-metis-sym" => Some(
                UmfpackLu::new(UmfpackOrdering::Metis)
                    .without_refinement()
                    .with_symmetric_strategy(true),
            ),
            "umfpack-sym" | "umfpack-unsym" => Some(
                UmfpackLu::new(UmfpackOrdering::Amd)
                    .without_refinement()
                    .with_symmetric_strategy(name == "umfpack-sym"),
            ),
            _ => None,
        };
        match umfpack {
            Some(mut lu) => {
                let line = time_lu(&mut lu, &pattern, &vals);
                println!(
                    "{name:16} {line}  symmetric strategy {:?}, fill {:?}, flops {:.3e}",
                    lu.used_symmetric_strategy(),
                    lu.factor_nnz(),
                    lu.factor_flops().unwrap_or(f64::NAN)
                );
            }
            None => {
                let mut lu = Lu(name).build_for(m).expect("lu");
                println!("{name:16} {}", time_lu(lu.as_mut(), &pattern, &vals));
            }
        }
    }
}

/// Analysis, median of 3 numeric factorizations and one solve of `lu` on `vals`.
fn time_lu(lu: &mut dyn LinearSolver, pattern: &cellsim::dae::Pattern, vals: &[f64]) -> String {
    let n = pattern.ncols();
    let t = Instant::now();
    lu.analyse(pattern).expect("analyse");
    let analyse = t.elapsed().as_secs_f64();
    let mut times = Vec::new();
    for _ in 0..3 {
        let t = Instant::now();
        lu.factorize(vals).expect("factorize");
        times.push(t.elapsed().as_secs_f64());
    }
    times.sort_by(f64::total_cmp);
    let mut b = vec![1.0; n];
    let t = Instant::now();
    lu.solve_in_place(&mut b).expect("solve");
    let solve = t.elapsed().as_secs_f64();
    format!(
        "analyse {analyse:.3} s  factorize {:.3} s  solve {:.4} s",
        times[1], solve
    )
}
