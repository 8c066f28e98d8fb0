//! Phases the cell starts itself (MODEL.md §11): the root functions' derivative, the
//! scenes that use them, the event case files.

use cellsim::case::{Case, Start};
use cellsim::dae::State;
use cellsim::model::{CellModel, ModelParams, QuarterCell};
use cellsim::physics::{Condition, KinematicModel, Lattice};
use cellsim::scene;

use crate::fd::deformed_state;
use crate::model::coarse_mesh;
use crate::model3d::coarse_quarter;
use crate::scenes::run_changed_case;

/// The reference case (flat substrate, adhesion) without inertia, with adhesion started
/// at t = 0 so that the spreading condition is evaluated, watching `SpreadingSlows`.
fn spreading_params(model: KinematicModel) -> ModelParams {
    let mut c = Case::reference();
    c.geometry.model = model;
    c.phases.active_start = Some(Start::SpreadingSlows(1e-4));
    c.validate().expect("a valid case");
    let mut p = scene::model_params(&c, "events", false).expect("a valid case");
    p.phases.adhesion = Some([0.0, 30_000.0]);
    p.drag = 1e-3;
    if model == KinematicModel::ThreeD {
        p.lattice = Lattice::FourPillars;
    }
    p
}

/// The rate of the adhered radius against central differences of the radius along the
/// motion y ± h ẏ: relative error.
fn rate_error(radius: impl Fn(&[f64], &[f64]) -> (f64, f64), y: &[f64], yp: &[f64]) -> f64 {
    let (l, rate) = radius(y, yp);
    assert!(
        l > 1.0,
        "the cell is not adhered in the test state (L = {l})"
    );
    assert!(
        rate.abs() > 1e-6,
        "no spreading in the test state (L̇ = {rate})"
    );
    let h = 1e-3;
    let moved = |s: f64| -> Vec<f64> { y.iter().zip(yp).map(|(a, b)| a + s * h * b).collect() };
    let fd = (radius(&moved(1.0), yp).0 - radius(&moved(-1.0), yp).0) / (2.0 * h);
    (fd - rate).abs() / rate.abs()
}

#[test]
fn the_adhered_radius_rate_is_its_derivative_along_the_motion() {
    // In the test state the cell is sunk 0.5 µm into the flat substrate's band: the
    // outline crosses the edge of the fibronectin layer, where the indicator varies.
    for model in [KinematicModel::PlaneStrain, KinematicModel::Axisymmetric] {
        let m = CellModel::new(spreading_params(model), coarse_mesh()).unwrap();
        let (y, yp) = deformed_state(&m, 0.5, 3);
        let err = rate_error(|y, yp| m.adhered_radius(y, yp), &y, &yp);
        assert!(err < 1e-6, "{model:?}: relative error {err:.2e}");
    }
    let m = QuarterCell::new(spreading_params(KinematicModel::ThreeD), coarse_quarter()).unwrap();
    let (y, yp) = deformed_state(&m, 0.5, 3);
    let err = rate_error(|y, yp| m.adhered_radius(y, yp), &y, &yp);
    assert!(err < 1e-6, "3-D: relative error {err:.2e}");
}

#[test]
fn the_conditions_read_the_centre_speed_and_the_spreading_rate() {
    let mut p = spreading_params(KinematicModel::PlaneStrain);
    p.events = vec![
        Condition::Settled { speed: 1e-5 },
        Condition::SpreadingSlows { rate: 1e-4 },
    ];
    let m = CellModel::new(p, coarse_mesh()).unwrap();
    let (y, mut yp) = deformed_state(&m, 0.5, 3);
    // The centre sinks at 2e-5 µm/s: (2e-5 / 1e-5)² − 1 = 3.
    let c = m.mesh.points.centre;
    yp[m.dofs.u[c][1]] = -2e-5;
    let mut g = [0.0; 4];
    let t = 20_000.0;
    m.condition_values(State::new(t, &y, &yp), &mut g);
    assert!((g[1] - 3.0).abs() < 1e-12, "Settled fires at {}", g[1]);
    // Sunk 0.5 µm at full gravity, the contact carries far more than half the weight.
    assert!(g[0] > 0.0, "Settled arms at {}", g[0]);
    let (_, rate) = m.adhered_radius(&y, &yp);
    assert!((g[2] - (rate / 1e-4 - 1.0)).abs() < 1e-12 && g[2] == g[3]);
    // Before adhesion starts the spreading condition is −1, armed by nothing.
    let mut p = m.params.clone();
    p.phases.adhesion = Some([30_000.0, 60_000.0]);
    let m = CellModel::new(p, coarse_mesh()).unwrap();
    m.condition_values(State::new(t, &y, &yp), &mut g);
    assert_eq!([g[2], g[3]], [-1.0, -1.0]);
}

/// The short push-pull with adhesion started by `Settled(1e-3)` and the active strain by
/// `SpreadingSlows(1e-2)` (its phases are 100× shorter than the paper's, its speeds 100×
/// larger).
fn with_events(c: &mut Case) {
    c.phases.adhesion_start = Some(Start::Settled(1e-3));
    c.phases.active_start = Some(Start::SpreadingSlows(1e-2));
}

#[test]
fn a_scene_starts_its_phases_itself_and_bdf2_finds_the_same_times() {
    let path = "cases/fast/push-pull-short.ron";
    let (s, rows, _) = run_changed_case(path, "events-ida", with_events, |_| {});
    assert!(s.finished, "{:?}", s.failure);
    let [ad, act] = [&s.events[0], &s.events[1]];
    assert_eq!(
        (ad.phase.as_str(), act.phase.as_str()),
        ("adhesion", "active")
    );
    let (t_ad, t_act) = (ad.t.unwrap(), act.t.unwrap());
    // Armed at landing, settled during the gravity ramp; spreading slowed after adhesion
    // started (measured: 0.61, 55.2; 137.0, 285.4 s).
    assert!(
        ad.armed_at.unwrap() < 5.0 && (20.0..100.0).contains(&t_ad),
        "{ad:?}"
    );
    assert!(
        act.armed_at.unwrap() > t_ad && t_act > act.armed_at.unwrap(),
        "{act:?}"
    );
    // The μ_as unknowns join at adhesion's start; the active ramp lasts T_a0 − T_as0 =
    // 100 s, and the end (600 s, 200 s after T_as0) moves with the active phase.
    assert_eq!(s.adhesion_unknowns_added_at, Some(t_ad));
    let pt = s.phase_times.unwrap().map(|t| t.unwrap());
    assert_eq!(pt[..2], [t_ad, t_act]);
    assert!((pt[2] - (t_act + 100.0)).abs() < 1e-9 && (pt[3] - (t_act + 200.0)).abs() < 1e-9);
    // Rows at both events and at the end.
    for t in [t_ad, t_act, pt[3]] {
        assert!(
            rows.iter().any(|r| (r[0] - t).abs() < 1e-9),
            "no output row at t = {t}"
        );
    }
    assert!((rows.last().unwrap()[0] - pt[3]).abs() < 1e-9);
    // The same scene with the phases started At those times: no root functions, no
    // restart at the starts, the same clock; the same answer to the tolerance.
    let (a, at_rows, _) = run_changed_case(
        path,
        "events-at",
        |c| {
            c.phases.adhesion_start = Some(Start::At(t_ad));
            c.phases.active_start = Some(Start::At(t_act));
        },
        |_| {},
    );
    assert!(a.finished && a.events.is_empty());
    let (x, z) = (rows.last().unwrap(), at_rows.last().unwrap());
    assert_eq!(x[0], z[0]);
    for k in 1..x.len() {
        let d = (x[k] - z[k]).abs() / z[k].abs().max(1e-3);
        assert!(
            d < 1e-4,
            "column {k}: {} with events, {} with At",
            x[k],
            z[k]
        );
    }
    // The fixed-step BDF2 (dt = 1 s) locates the same events to within its step.
    let (b, _, _) = run_changed_case(path, "events-bdf2", with_events, |st| {
        st.integrator = cellsim::case::Integrator::Bdf2;
        st.bdf2_dt = 1.0;
    });
    assert!(b.finished, "{:?}", b.failure);
    for (i, e) in s.events.iter().enumerate() {
        let d = (b.events[i].t.unwrap() - e.t.unwrap()).abs();
        assert!(
            d < 1.0,
            "{}: BDF2 {:?} against IDA {:?}",
            e.phase,
            b.events[i].t,
            e.t
        );
    }
}

#[test]
fn event_scenes_are_the_scene_files() {
    // cases/events/X.ron is cases/X.ron but for its name, its description and the two
    // phase starts.
    let dir = format!("{}/cases", env!("CARGO_MANIFEST_DIR"));
    for scene in [
        "flat",
        "pillars-push",
        "pillars-pull",
        "pillars-push-pull",
        "upside-down",
    ] {
        let plain = Case::load(format!("{dir}/{scene}.ron")).unwrap();
        let mut ev = Case::load(format!("{dir}/events/{scene}.ron")).unwrap();
        ev.validate().unwrap();
        assert_eq!(ev.name, format!("{scene}-events"));
        assert_eq!(ev.phases.adhesion_start, Some(Start::Settled(1e-5)));
        assert_eq!(ev.phases.active_start, Some(Start::SpreadingSlows(1e-4)));
        ev.name = plain.name.clone();
        ev.description = plain.description.clone();
        ev.phases.adhesion_start = None;
        ev.phases.active_start = None;
        assert_eq!(ev, plain, "{scene}");
    }
}
