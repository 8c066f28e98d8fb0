//! The μ_as unknowns left out until adhesion acts (T_g0): the smaller system is the same
//! cell before T_g0, and μ_as integrated beside it matches μ_as integrated in it.

use cellsim::case::{self, Case};
use cellsim::dae::Dae;
use cellsim::dae::State;
use cellsim::model::CellModel;
use cellsim::run::{self, RunOptions};
use cellsim::run_files::RunData;
use oorandom::Rand64;

use crate::model::{active_pillars_params, coarse_mesh, deformed_state, jacobian_fd_error};

/// A time in the gravity phase: t_as = 0, adhesion cannot act yet.
const T: f64 = 5_000.0;

#[test]
fn before_adhesion_acts_the_smaller_system_is_the_same_cell() {
    for inertia in [true, false] {
        let params = active_pillars_params(inertia);
        let mut full = CellModel::new(params.clone(), coarse_mesh()).unwrap();
        let mut small = CellModel::deferring_adhesion(params, coarse_mesh()).unwrap();
        assert!(small.adhesion_deferred());
        let n_mu = full.dofs.n_mu();
        assert!(n_mu > 0);
        assert_eq!(small.size() + n_mu, full.size());
        let (y, yp) = deformed_state(&full, 0.5, 11);
        let f = full.contact_force_total(&y);
        assert!(f.y > 1e-3, "no contact in the test state");
        // The μ_as block is last: the smaller system's unknowns are the first ones.
        let m = small.size();
        let (mut r_full, mut r_small) = (vec![0.0; full.size()], vec![0.0; m]);
        full.residual(State::new(T, &y, &yp), &mut r_full).unwrap();
        small
            .residual(State::new(T, &y[..m], &yp[..m]), &mut r_small)
            .unwrap();
        assert_eq!(&r_full[..m], &r_small[..], "inertia {inertia}");
        // Its iteration matrix is exact too.
        let mut rng = Rand64::new(5);
        let cols: Vec<usize> = (0..120)
            .map(|_| (rng.rand_float() * m as f64) as usize)
            .collect();
        for (cj, err) in jacobian_fd_error(&mut small, T, &y[..m], &yp[..m], &cols) {
            assert!(err < 1e-6, "inertia {inertia}, cj {cj}: {err:.2e}");
        }
    }
}

#[test]
fn adding_the_adhesion_unknowns_keeps_the_state_consistent() {
    let params = active_pillars_params(false);
    let mut small = CellModel::deferring_adhesion(params, coarse_mesh()).unwrap();
    let (y, yp) = deformed_state(&small, 0.5, 13);
    let t0 = small.params.phases.t_g0;
    // Advance the history over one step into the layer, then join at its end.
    small.accepted_step(t0, &y, &yp);
    // The element loops on the thread pool carry over to the new system.
    small.set_parallel(true);
    let mut big = small.with_adhesion_unknowns(t0, &y, &yp).unwrap();
    assert!(big.parallel());
    let (t, y2, yp2) = big.initial();
    assert_eq!(t, t0);
    let mut r = vec![0.0; big.size()];
    big.residual(State::new(t, &y2, &yp2), &mut r).unwrap();
    let mut r_small = vec![0.0; small.size()];
    small
        .residual(State::new(t, &y, &yp), &mut r_small)
        .unwrap();
    // The old rows are unchanged, the μ_as rows hold exactly.
    assert_eq!(&r[..small.size()], &r_small[..]);
    assert!(r[small.size()..].iter().all(|v| v.abs() < 1e-9));
    // The nodes that sank into the layer got μ_as > 0 from the history.
    let mu = &y2[small.size()..];
    assert!(mu.iter().any(|&m| m > 0.0) && mu.iter().all(|&m| m >= 0.0));
    // The same cell cannot join twice.
    assert!(big.with_adhesion_unknowns(t, &y2, &yp2).is_err());
}

/// The flat scene with adhesion, its gravity phase shortened to 2 000 s so that μ_as
/// saturates at the first contact nodes (after 1 400 s) and rises at the later ones;
/// without inertia (medium drag), so that a tight tolerance does not have to resolve the
/// landing's ringing.
fn short_flat() -> (Case, String) {
    let file = format!("{}/cases/fast/flat-gravity.ron", env!("CARGO_MANIFEST_DIR"));
    let mut c = Case::load(&file).unwrap();
    c.adhesion = Some(case::Case::reference().adhesion.unwrap());
    c.phases.t_g0 = 2_000.0;
    c.phases.t_end = 2_600.0;
    c.output.phase_states = true;
    c.inertia = case::Inertia {
        mode: case::InertiaMode::Off,
        drag: 4.5e-5,
    };
    (c, file)
}

fn run_short_flat(out: &str, defer: bool, rtol: f64) -> RunData {
    let (case, file) = short_flat();
    let mut settings = case.solver.clone();
    settings.defer_adhesion = defer;
    settings.rtol = rtol;
    settings.atol = rtol * 1e-2;
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(out);
    let _ = std::fs::remove_dir_all(&dir);
    let opts = RunOptions::new(dir.clone(), settings);
    let s = run::run(&case, &file, &opts).unwrap();
    assert!(s.finished, "{out}: {:?}", s.failure);
    if defer {
        assert_eq!(s.adhesion_unknowns_added_at, Some(case.phases.t_g0));
    } else {
        assert_eq!(s.adhesion_unknowns_added_at, None);
    }
    RunData::load(&dir).unwrap()
}

#[test]
fn mu_as_beside_the_system_matches_mu_as_in_it() {
    // Reference: μ_as as unknowns of IDA at a tight tolerance.
    let reference = run_short_flat("deferred-ref", false, 1e-7);
    let deferred = run_short_flat("deferred-on", true, 1e-4);
    let in_system = run_short_flat("deferred-off", false, 1e-4);
    let gravity = |d: &RunData| {
        d.states
            .iter()
            .find(|s| s.phase == "gravity")
            .expect("state at T_g0")
            .clone()
    };
    let (r, a, b) = (gravity(&reference), gravity(&deferred), gravity(&in_system));
    let mu_max = Case::reference().adhesion.unwrap().mu_as_max();
    let err = |s: &cellsim::run_files::StateFile| {
        s.mu_as
            .iter()
            .zip(&r.mu_as)
            .filter_map(|(x, y)| Some((x.as_ref()? - y.as_ref()?).abs()))
            .fold(0.0f64, f64::max)
            / mu_max
    };
    let saturated = r
        .mu_as
        .iter()
        .flatten()
        .filter(|&&m| m > 0.98 * mu_max)
        .count();
    let rising = r
        .mu_as
        .iter()
        .flatten()
        .filter(|&&m| m > 0.0 && m < 0.9 * mu_max)
        .count();
    assert!(
        saturated > 0 && rising > 0,
        "{saturated} saturated, {rising} rising"
    );
    let (e_deferred, e_in_system) = (err(&a), err(&b));
    eprintln!(
        "μ_as at T_g0, max error / μ_as,max: beside {e_deferred:.2e}, in the system {e_in_system:.2e}"
    );
    // Beside the system μ_as is at least as accurate as in it at the same tolerance.
    assert!(e_deferred < 1e-4, "{e_deferred:.2e}");
    assert!(
        e_deferred <= e_in_system.max(1e-6),
        "{e_deferred:.2e} vs {e_in_system:.2e}"
    );
    // And the cell after T_g0 is the same to the tolerance.
    let last = |d: &RunData| *d.series.last().unwrap();
    let (fr, fa) = (last(&reference), last(&deferred));
    let rel = (fa.uy_top - fr.uy_top).abs() / fr.uy_top.abs();
    assert!(rel < 1e-4, "uy_top {} vs {}", fa.uy_top, fr.uy_top);
}
