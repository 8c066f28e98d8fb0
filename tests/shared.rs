//! Cases computed together while they agree (`run::run_all`, as `cellsim paper` runs its
//! scenes): each member's outputs against the same case run on its own.

use std::path::PathBuf;

use cellsim::case::Case;
use cellsim::run::{self, Member, Progress, RunOptions};
use cellsim::run_files::Summary;

use crate::scenes::{read_csv, tmp};

// scenes): each member's outputs against the same case run on its own.

/// The fast push-pull case and four cases that part from it: push and pull (other active
/// regions, from T_as0), the gravity flip from T_a0 and the same case run longer.
fn family() -> Vec<Case> {
    let file = format!(
        "{}/cases/fast/push-pull-short.ron",
        env!("CARGO_MANIFEST_DIR")
    );
    let base = Case::load(&file).unwrap();
    let mut push = base.clone();
    push.name = "push".into();
    push.active.bottom = None;
    let mut pull = base.clone();
    pull.name = "pull".into();
    pull.active.pac = None;
    let mut flip = base.clone();
    flip.name = "flip".into();
    flip.gravity.upside_down = true;
    flip.gravity.flip_duration = 100.0;
    flip.phases.t_end = 700.0;
    let mut longer = base.clone();
    longer.name = "longer".into();
    longer.phases.t_end = 700.0;
    vec![base, push, pull, flip, longer]
}

fn options(case: &Case, dir: PathBuf) -> RunOptions {
    RunOptions::new(dir, case.solver.clone())
}

#[test]
fn parting_times_follow_what_the_cases_differ_in() {
    let f = family();
    let (base, push, pull, flip, longer) = (&f[0], &f[1], &f[2], &f[3], &f[4]);
    let ph = &base.phases;
    assert_eq!(run::shared_until(base, base), ph.t_end);
    assert_eq!(run::shared_until(base, push), ph.t_as0);
    assert_eq!(run::shared_until(push, pull), ph.t_as0);
    assert_eq!(run::shared_until(base, flip), ph.t_a0);
    assert_eq!(run::shared_until(flip, push), ph.t_as0);
    assert_eq!(run::shared_until(base, longer), ph.t_end);
    assert_eq!(run::shared_until(flip, longer), ph.t_a0);
    let mut other = base.clone();
    other.materials.nucleus.e *= 1.01;
    assert_eq!(run::shared_until(base, &other), 0.0);
    let mut later = base.clone();
    later.phases.t_as0 += 1.0;
    assert_eq!(run::shared_until(&later, push), 0.0);
}

#[test]
fn cases_run_together_match_their_own_runs() {
    let cases = family();
    let file = "cases/fast/push-pull-short.ron (family)";
    let alone: Vec<(Summary, Vec<Vec<f64>>)> = cases
        .iter()
        .map(|c| {
            let dir = tmp(&format!("shared-alone-{}", c.name));
            let s = run::run(c, file, &options(c, dir.clone())).unwrap();
            (s, read_csv(&dir.join("timeseries.csv")))
        })
        .collect();
    let members: Vec<Member> = cases
        .iter()
        .map(|c| Member {
            case: c,
            file,
            opts: options(c, tmp(&format!("shared-together-{}", c.name))),
        })
        .collect();
    let results = run::run_all(&members, 2, true, &|_, _| Progress::Hidden, &|_, _| {});
    let t_as0 = cases[0].phases.t_as0;
    for ((case, (own, own_rows)), result) in cases.iter().zip(&alone).zip(results) {
        let s = result.unwrap_or_else(|e| panic!("{}: {e}", case.name));
        assert!(s.finished, "{}", case.name);
        assert!(!s.shared.is_empty(), "{}: no parting recorded", case.name);
        let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
            .join(format!("shared-together-{}", case.name));
        let rows = read_csv(&dir.join("timeseries.csv"));
        assert_eq!(rows.len(), own_rows.len(), "{}", case.name);
        let mut worst = 0.0_f64;
        for (r, o) in rows.iter().zip(own_rows) {
            assert_eq!(r[0], o[0], "{}: output times", case.name);
            if r[0] <= t_as0 {
                // Before any parting: the same computation.
                assert_eq!(r, o, "{}: row at t = {}", case.name, r[0]);
            }
        }
        // After the restart: the final values agree to the integrator's tolerance.
        let (fin, own_fin) = (s.final_values.unwrap(), own.final_values.unwrap());
        for (name, a, b, scale) in [
            ("uy_top", fin.uy_top, own_fin.uy_top, own_fin.uy_top.abs()),
            (
                "uy_bottom",
                fin.uy_bottom,
                own_fin.uy_bottom,
                own_fin.uy_top.abs(),
            ),
            (
                "contact radius",
                fin.contact_radius,
                own_fin.contact_radius,
                own_fin.contact_radius,
            ),
        ] {
            let rel = (a - b).abs() / scale;
            worst = worst.max(rel);
            eprintln!(
                "{}: {name} together {a} alone {b} (rel {rel:.2e})",
                case.name
            );
        }
        assert!(
            worst < 1e-3,
            "{}: final values differ by {worst:.2e}",
            case.name
        );
    }
}
