//! Which unknowns limit IDA's steps in a 3-D run: after each output interval, the last
//! step's weighted local errors (IDA's estimate times its error weight), their sum of
//! squares (what IDA's error test sums) split by kind of unknown and by where the node is.
//!
//! ```sh
//! cargo run --release --example limiting3d -- [--case cases/fast/flat-3d-coarse.ron]
//!     [--from 100] [--to 250] [--every 1] [--mu-atol F]   # F: the μ_as atol times F
//! ```

use cellsim::case::Case;
use cellsim::dae::{Atol, Dae, Integrator};
use cellsim::fem::TetMesh;
use cellsim::model::{ModelParams, QuarterCell};
use cellsim::physics::Lattice;
use cellsim::scene;
use cellsim::solver::LinearSolver;
use cellsim::sundials::{Ida, IdaOptions};

/// The example's options (see the module's doc).
#[derive(clap::Parser)]
struct Args {
    /// The case file.
    #[arg(long, default_value = "cases/fast/flat-3d-coarse.ron")]
    case: String,
    /// The μ_as absolute tolerance is the case's times this factor.
    #[arg(long, default_value_t = 1.0)]
    mu_atol: f64,
    /// First output time [s].
    #[arg(long, default_value_t = 100.0)]
    from: f64,
    /// Last output time [s].
    #[arg(long, default_value_t = 250.0)]
    to: f64,
    /// Output interval [s].
    #[arg(long, default_value_t = 1.0)]
    every: f64,
}

fn main() {
    let args = <Args as clap::Parser>::parse();
    let file = args.case;
    let case = Case::load(&file).expect("case");
    let mesh = TetMesh::generate(&scene::tet_mesh_params(&case)).expect("mesh");
    let plane = scene::model_params(&case, &file, false).expect("params");
    let bottom = case.geometry.centre()[1] - case.geometry.r_c;
    let m = QuarterCell::new(
        ModelParams {
            kinematics: cellsim::physics::KinematicModel::ThreeD,
            lattice: Lattice::FourPillars,
            ..plane
        },
        mesh,
    )
    .expect("model");
    // Kind and height above the cell's bottom of each unknown.
    let n = m.size();
    let mut kind = vec![""; n];
    let mut height = vec![0.0; n];
    for (node, ids) in m.dofs.u.iter().enumerate() {
        for (k, &i) in ids.iter().enumerate() {
            if i < n {
                kind[i] = ["u_x", "u_y", "u_z"][k];
                height[i] = m.mesh.nodes[node][1] - bottom;
            }
        }
    }
    for &node in &m.dofs.mu_nodes {
        let i = m.dofs.mu[node];
        kind[i] = "mu";
        height[i] = m.mesh.nodes[node][1] - bottom;
    }
    let mut atol = m.atol_vector(case.solver.atol);
    let f = args.mu_atol;
    for &node in &m.dofs.mu_nodes {
        atol[m.dofs.mu[node]] *= f;
    }
    let atol = Atol::Vector(atol);
    let mut ida = Ida::new(
        m,
        IdaOptions {
            rtol: case.solver.rtol,
            atol,
            linear_solver: LinearSolver::UmfpackNd.into(),
            delta_cj: Some(case.solver.delta_cj),
            ..Default::default()
        },
    )
    .expect("ida");
    let (from, to, every) = (args.from, args.to, args.every);
    ida.advance_to(from, &mut |_, _| true).expect("to --from");
    let groups = ["u_x", "u_y", "u_z", "mu"];
    let band = 2.0; // µm above the bottom: the contact and adhesion region
    let mut total = [[0.0f64; 2]; 4];
    let mut argmax = [[0usize; 2]; 4];
    let mut t = from;
    println!("t\tsteps\tshare of sum e^2 by (kind, below/above {band} µm)");
    while t < to {
        t += every;
        let s0 = ida.stats().steps;
        ida.advance_to(t, &mut |_, _| true).expect("advance");
        let e = ida.weighted_local_errors().expect("errors");
        let mut share = [[0.0f64; 2]; 4];
        let (mut imax, mut emax) = (0, 0.0);
        for i in 0..n {
            let g = groups.iter().position(|k| *k == kind[i]).unwrap_or(0);
            let b = usize::from(height[i] > band);
            share[g][b] += e[i] * e[i];
            if e[i].abs() > emax {
                (imax, emax) = (i, e[i].abs());
            }
        }
        let sum: f64 = share.iter().flatten().sum();
        for g in 0..4 {
            for b in 0..2 {
                total[g][b] += share[g][b] / sum.max(1e-300);
            }
        }
        let g = groups.iter().position(|k| *k == kind[imax]).unwrap_or(0);
        argmax[g][usize::from(height[imax] > band)] += 1;
        let cells: Vec<String> = share
            .iter()
            .flatten()
            .map(|v| format!("{:.2}", v / sum.max(1e-300)))
            .collect();
        println!(
            "{t}\t{}\t{}\tmax |e w| {emax:.2e} at {} h = {:.2}",
            ida.stats().steps - s0,
            cells.join(" "),
            kind[imax],
            height[imax]
        );
    }
    let o = ida.dae().observe(t, ida.y());
    println!(
        "\n{} steps, {} Jacobians to t = {t}; uy_top {:.6} µm, contact radius {:.5} µm",
        ida.stats().steps,
        ida.stats().jacobian_evals,
        o.uy_top,
        o.contact_radius
    );
    println!("mean share of the error-test sum and argmax counts:");
    for g in 0..4 {
        for (b, place) in ["bottom band", "above"].iter().enumerate() {
            println!(
                "{:4} {place:12} share {:.3}  argmax {}",
                groups[g],
                total[g][b] / ((to - from) / every),
                argmax[g][b]
            );
        }
    }
}
