//! The hard-case suite (`cases/hard/`): every case either finishes with sane output or
//! stops with a diagnostic that names the time and the cause, its partial output intact
//! and free of NaN. The fast cases run here; the README's "Hard cases" table has all.

use std::path::Path;

use cellsim::case::Case;
use cellsim::run::{self, RunError, RunOptions};
use cellsim::run_files::{FailureKind, Summary};

use crate::scenes::read_csv;

/// Runs a hard case and checks the outcome; returns the summary read back from disk.
fn run_hard(name: &str) -> Summary {
    run_hard_with(name, "", |_| {})
}

/// The file of the hard case `name` and the case it holds.
fn hard_case(name: &str) -> (String, Case) {
    let file = format!("{}/cases/hard/{name}.ron", env!("CARGO_MANIFEST_DIR"));
    let case = Case::load(&file).unwrap_or_else(|e| panic!("{name}: {e}"));
    (file, case)
}

/// [`run_hard`] with the case changed by `change` (`tag` names the output directory).
fn run_hard_with(name: &str, tag: &str, change: impl Fn(&mut Case)) -> Summary {
    let (file, mut case) = hard_case(name);
    change(&mut case);
    case.validate().unwrap_or_else(|e| panic!("{name}: {e:?}"));
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("hard-{name}{tag}"));
    let _ = std::fs::remove_dir_all(&out);
    let opts = RunOptions::new(out.clone(), case.solver.clone());
    let result = run::run(&case, &file, &opts);

    // Whatever happened, the summary on disk says it, and the time series is intact.
    let text = std::fs::read_to_string(out.join("summary.json")).expect("summary.json");
    let summary: Summary = serde_json::from_str(&text).expect("summary.json parses");
    let rows = read_csv(&out.join("timeseries.csv"));
    assert!(rows.len() >= 2, "{name}: at least t = 0 and one output");
    assert!(
        rows.iter().flatten().all(|v| v.is_finite()),
        "{name}: a non-finite value in timeseries.csv"
    );
    assert!(
        rows.windows(2).all(|w| w[1][0] > w[0][0]),
        "{name}: output times increase"
    );
    assert_eq!(rows.len(), summary.outputs, "{name}: CSV rows = outputs");
    let last = summary.final_values.expect("final values");
    assert_eq!(
        rows.last().unwrap()[0],
        last.t,
        "{name}: summary = last row"
    );
    // Sane: the nucleus top moves down by less than the cell's radius plus its fall to
    // the substrate, strains are fractions of order one.
    let fall = match &case.substrate {
        cellsim::case::Substrate::Pillars(p) => p.gap,
        cellsim::case::Substrate::Flat(f) => case.geometry.centre()[1] - case.geometry.r_c - f.y_s,
    };
    for r in &rows {
        assert!(
            r[2] <= 1e-9 && r[2] > -case.geometry.r_c - fall,
            "{name}: uy_top {}",
            r[2]
        );
        assert!(r[5] >= 0.0 && r[5] < 2.0 && r[6] >= 0.0 && r[6] < 2.0);
    }
    match result {
        Ok(s) => {
            assert!(s.finished && summary.finished && summary.failure.is_none());
            assert_eq!(last.t, case.phases.t_end, "{name}: finished at t_end");
        }
        Err(RunError::Integration { reason, .. }) => {
            let f = summary.failure.as_ref().expect("failure recorded");
            assert!(!summary.finished);
            assert_eq!(f.reason, reason);
            // The reason names the time of the failure and its cause.
            assert!(reason.contains("t = "), "{name}: no time in {reason:?}");
            assert!(reason.len() > 40, "{name}: terse reason {reason:?}");
            assert!(f.t_last_output == last.t && f.step > 0);
            // The time reached and, for an inverted element, where, as fields.
            let t_stop = f.t_stop.expect("t_stop recorded");
            assert!(t_stop >= f.t_last_output, "{name}: t_stop {t_stop}");
            if f.kind == FailureKind::Inverted {
                let p = f.place.as_ref().expect("an inverted element's place");
                assert!(p.value <= 0.0 && p.t >= f.t_last_output, "{name}: {p:?}");
                assert!(
                    reason.contains(&format!("element {}", p.element)),
                    "{reason}"
                );
                assert_eq!(p.x.len(), 2, "{name}: {p:?}");
            }
            eprintln!("{name}: stopped cleanly: {reason}");
        }
        Err(e) => panic!("{name}: not an integration failure: {e}"),
    }
    summary
}

#[test]
fn coarsest_mesh_finishes() {
    let s = run_hard("mesh-coarse");
    assert!(s.finished);
}

#[test]
#[ignore = "stops at t = 24 689 s (IDA_CONV_FAIL, the cell's bottom reaching the gap's floor) \
            since the inertia switch looks at every step; at rtol 1e-2 this landing fails at \
            about half the tolerances near it with either switch (README, Hard cases)"]
fn very_loose_tolerance_finishes() {
    // IDA at rtol 1e-2 used to stop at t ≈ 9.66 s, just after the inertia switch, with
    // repeated corrector convergence failures (IDA_CONV_FAIL, h ≈ 3e-7 s), while the
    // switch carried the landing's velocities over; with the cell placed at rest there
    // it finishes (977 steps; final uy_top within 0.1 % of rtol 1e-4's).
    let s = run_hard("rtol-loose");
    assert!(s.finished);
}

#[test]
fn very_loose_tolerance_finishes_with_a_contact_that_stiffens_beyond_its_band() {
    // The paper's force stays J μ_ct beyond ε_ct; growing there (contact.stiffening), it
    // stops the Newton iterates that overshoot into the gap's floor at t ≈ 24 700 s.
    let s = run_hard_with("rtol-loose", "-stiffened", |c| c.contact.stiffening = 1.0);
    assert!(s.finished, "{:?}", s.failure);
}

#[test]
fn strong_contraction_finishes_or_stops_cleanly() {
    // Measured: with e = 0.9 an element at the pillar edge inverts at t ≈ 47 119 s, in
    // the active phase; the reason names the element and its det F.
    let s = run_hard("e-09");
    // Measured: the element is 16 (cytoplasm, above the pillar's top-left corner), folded
    // inside between its solid points: until 2026-12-07 a band point refused the state
    // (t = 47 119 s, det F ≈ −3e-15); since the contact takes J₊ there the output at
    // t = 47 125 s finds it folded (det F −4.4e-4 at a band point) and the run stops, a
    // stop classified as an inverted element, the fold in the summary.
    if let Some(f) = &s.failure {
        assert_eq!(f.kind, FailureKind::Inverted, "{}", f.reason);
        let (folded, smallest) = s.folded_elements.expect("reported");
        if f.reason.contains("folded inside") {
            assert!(
                folded > 0 && smallest.is_some_and(|j| j <= 0.0),
                "{folded}, {smallest:?}"
            );
        }
    }
}

#[test]
fn narrow_pillars_with_a_wide_gap_finish() {
    // Stalled at t = 34 355 s with the sharp foot corner (`fillet: 0.0`); the default
    // fillet turns the normal continuously round the corner (cases/hard/narrow-pillars.ron).
    let s = run_hard("narrow-pillars");
    assert!(s.finished, "{:?}", s.failure);
}

#[test]
fn a_snap_through_is_followed_not_taken_for_a_stall() {
    // The J f_as reading of push-pull, without the fold release (with it this reading does
    // not snap): at t ≈ 47 200–47 400 s the cell's edge lets go of a pillar's top corner and
    // the cell springs back, a motion over ~1e-5 s with the paper's shear viscosity that
    // IDA follows in thousands of short steps. The stall rule stopped it at
    // t = 47 225 s while those steps were still moving the solution (1.0e4 tolerance units
    // over its window); it must finish, and show the snap: u_y(p_t) rises by more than
    // 0.5 µm between two consecutive outputs in [47 000, 47 500] s (measured: 0.72 µm
    // between 47 125 and 47 250 s with the rounded feet, 0.70 µm between 47 250 and
    // 47 375 s with the straight ones).
    let s = run_hard("snap-through");
    assert!(s.finished, "{:?}", s.failure);
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("hard-snap-through");
    let rows = read_csv(&out.join("timeseries.csv"));
    let window: Vec<&Vec<f64>> = rows
        .iter()
        .filter(|r| (47_000.0..=47_500.0).contains(&r[0]))
        .collect();
    assert!(window.len() >= 4, "{} outputs in the window", window.len());
    let rise = window
        .windows(2)
        .map(|w| w[1][2] - w[0][2])
        .fold(f64::NEG_INFINITY, f64::max);
    assert!(
        rise > 0.5,
        "largest rise of u_y(p_t) between outputs: {rise} µm"
    );
}

#[test]
fn a_ten_micrometre_fall_lands_and_finishes() {
    // Stalled at t = 49.6 s while the switch looked for the contact carrying the weight on
    // a grid of times 0.01 s apart: after this fall the cell bounces, its impacts last
    // microseconds and fell between the grid's times, so inertia stayed on and IDA
    // resolved the ringing (steps of 0.26 ms) until the stall rule stopped it. The switch
    // now looks at every step, and it must happen at the first impact: under the C² ramp
    // t_g = S(t; 0, T_g0) ≈ 10 (t/T_g0)³ the cell falls g t⁵ / (2 T_g0³), and its lowest
    // point meets the contact band (ε_ct above the pillar top) after falling gap − ε_ct.
    let s = run_hard("gap-large");
    assert!(s.finished, "{:?}", s.failure);
    let (_, case) = hard_case("gap-large");
    let cellsim::case::Substrate::Pillars(p) = &case.substrate else {
        panic!("gap-large is on pillars")
    };
    let (g, t0) = (case.gravity.g(), case.phases.t_g0);
    let fall = p.gap - case.contact.eps_ct;
    let t_land = (2.0 * fall * t0.powi(3) / g).powf(0.2);
    let t_switch = s.inertia_switched_off_at.expect("inertia switched off");
    assert!(
        (t_switch - t_land).abs() < 0.01 * t_land,
        "switched at {t_switch} s, the cell lands at {t_land} s"
    );
}

/// The outline of a run's state `state` (mesh.json's outer edges at mesh.json's nodes
/// moved by the state's u), as a polyline through every outer node.
fn outline_at(out: &Path, state: &str) -> Vec<[f64; 2]> {
    let read = |f: &str| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(out.join(f)).expect(f)).expect(f)
    };
    let (mesh, st) = (read("mesh.json"), read(state));
    let at = |i: usize| -> [f64; 2] {
        let x = &mesh["nodes"][i];
        let u = &st["u"][i];
        [0, 1].map(|k| x[k].as_f64().unwrap() + u[k].as_f64().unwrap())
    };
    let mut line = Vec::new();
    for (k, e) in mesh["outer_edges"].as_array().unwrap().iter().enumerate() {
        let e: Vec<usize> = e
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_u64().unwrap() as usize)
            .collect();
        if k == 0 {
            line.push(at(e[0]));
        }
        line.extend([at(e[1]), at(e[2])]);
    }
    line
}

/// How deep a polyline (the cell on its left) passes through itself: over the pairs of
/// its pieces that cross (pieces sharing an end excepted), the larger of the depths at
/// which the crossing ends of each lie behind the other piece, the smaller of the two.
/// A penalty contact holds its faces a few hundredths of a µm into each other; a fold
/// passing through itself goes as deep as the fold.
fn deepest_crossing(line: &[[f64; 2]]) -> f64 {
    let cross = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| {
        (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
    };
    // Depth of `p` behind the piece a → b (its outward normal (e_y, −e_x)/|e|).
    let behind =
        |p: [f64; 2], a: [f64; 2], b: [f64; 2]| -cross(a, b, p) / (b[0] - a[0]).hypot(b[1] - a[1]);
    let mut deepest: f64 = 0.0;
    for i in 0..line.len() - 1 {
        for j in i + 2..line.len() - 1 {
            let (p, q, r, s) = (line[i], line[i + 1], line[j], line[j + 1]);
            if cross(r, s, p) * cross(r, s, q) < 0.0 && cross(p, q, r) * cross(p, q, s) < 0.0 {
                let into_j = behind(p, r, s).max(behind(q, r, s));
                let into_i = behind(r, p, q).max(behind(s, p, q));
                deepest = deepest.max(into_j.min(into_i));
            }
        }
    }
    deepest
}

/// Runs the hard case `name` (a wide-gap fold) and checks that it finishes with its fold
/// closed: the outline at the end passes through itself nowhere deeper than the contact
/// band, and two stretches of it more than 1 µm apart along it lie within 0.2 µm of each
/// other. Returns the final u_y(p_t).
fn fold_closes_and_the_scene_finishes(name: &str) -> f64 {
    let s = run_hard(name);
    assert!(s.finished, "{name}: {:?}", s.failure);
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("hard-{name}"));
    let line = outline_at(&out, "state_end.json");
    assert!(line.len() > 100, "{} outline nodes", line.len());
    let (_, case) = hard_case(name);
    let depth = deepest_crossing(&line);
    assert!(
        depth < case.contact.eps_ct,
        "{name}: the outline passes {depth} µm through itself"
    );
    let arc: Vec<f64> = std::iter::once(0.0)
        .chain(line.windows(2).scan(0.0, |a, w| {
            *a += (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]);
            Some(*a)
        }))
        .collect();
    let folded = (0..line.len()).any(|i| {
        (0..line.len()).any(|j| {
            arc[j] - arc[i] > 1.0
                && arc[j] - arc[i] < 4.0
                && (line[i][0] - line[j][0]).hypot(line[i][1] - line[j][1]) < 0.2
        })
    });
    assert!(folded, "{name}: no fold in the outline at the end");
    s.final_values.expect("final values").uy_top
}

#[test]
fn a_fold_against_a_pillar_wall_closes_on_itself_and_the_scene_finishes() {
    // The geometry map's w = 12, s = 12 µm point: without the outline's self-contact the
    // membrane's fold passed through itself and an element at its tip turned inside out
    // (t ≈ 48 257 s, classified `inverted`; since J₊ it finishes without, see below); with
    // it the scene finishes, and its outline
    // at the end passes through itself nowhere deeper than the contact band (the fold's
    // faces held in each other's band).
    fold_closes_and_the_scene_finishes("wide-gap-fold");
}

#[test]
fn the_wide_gap_on_a_mesh_refined_twice_finishes_with_the_default_mesh_answer() {
    // The geometry map's w = s = 12 µm point on the default straight pillar feet, refined
    // x2. With the rounded feet the membrane creased at the lip of the undercut under the
    // pillar's foot, and refined meshes let the crease curl into the cell until an element
    // inverted (docs/MODEL.md §5). On straight feet the scene finishes on every mesh, and
    // the nucleus ends where the default mesh's does: the default mesh's discretisation
    // error on this scene is under 1 % (measured 2026-12-07 with the 0.25 µm fillet then:
    // −9.137 refined x2 against −9.072 µm, 0.72 % apart).
    finishes_near_the_default_mesh("wide-gap-refined-2");
}

/// `name` finishes on its refined mesh, and its u_y(p_t) at the end is within 1 % of the
/// same scene's on the default mesh.
fn finishes_near_the_default_mesh(name: &str) -> Summary {
    let s = run_hard(name);
    assert!(s.finished, "{name}, refined: {:?}", s.failure);
    let fine = s.final_values.expect("final values").uy_top;
    let default = run_hard_with(name, "-default-mesh", |c| c.mesh.refine = 1.0);
    assert!(
        default.finished,
        "{name}, default mesh: {:?}",
        default.failure
    );
    let coarse = default.final_values.expect("final values").uy_top;
    assert!(
        ((fine - coarse) / coarse).abs() < 1e-2,
        "{name}: u_y(p_t) {fine} refined against {coarse} µm on the default mesh"
    );
    s
}

#[test]
fn the_membrane_creased_at_the_widest_gap_finishes_on_the_refined_mesh() {
    // w = s = 14 µm refined x1.5: a P2 membrane element at the crease's tip folds between
    // its solid points; its band points refused the state until the contact took
    // J+ = max(J, 0) there (docs/MODEL.md §5). Measured 2026-12-07: −8.858 µm refined
    // x1.5 against −8.790 µm on the default mesh (0.25 µm fillet then).
    let s = finishes_near_the_default_mesh("wide-gap-crease");
    // The crease's tip unfolds again: no element is folded at the end.
    let (folded, smallest) = s.folded_elements.expect("reported");
    assert_eq!(folded, 0, "smallest det F at a band point {smallest:?}");
}

#[test]
fn the_cell_reaching_the_corner_of_a_narrow_gap_finishes_on_the_refined_mesh() {
    // w = 4, s = 5 µm refined x1.5: with the 0.25 µm fillet IDA's kept Jacobian diverged at
    // every step size where the cell's lower lobe entered the corner at the pillar's foot
    // (t = 32 114 s); with the default 0.5 µm it finishes (docs/MODEL.md §10). Measured
    // 2026-12-07: −7.664 µm refined x1.5.
    finishes_near_the_default_mesh("narrow-gap-corner");
}

#[test]
fn without_self_contact_the_fold_finishes_within_the_band() {
    // The paper's model (no self-contact, the spreading force without the fold release).
    // Until 2026-12-07 the fold's faces passed through each other and the element at its
    // tip inverted at a band point (t > 45 000 s); since the contact takes J₊ there (the
    // tip's map degenerate between the solid rule's points, docs/MODEL.md §5) it finishes,
    // nothing folded at any output, and its outline crosses itself by no more than the
    // contact band at the end (measured: 0.011 µm).
    let s = run_hard_with("wide-gap-fold", "-without", |c| {
        c.contact.self_contact = false;
        c.adhesion.as_mut().expect("adhesion").fold_release = false;
    });
    assert!(s.finished, "{:?}", s.failure);
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("hard-wide-gap-fold-without");
    let depth = deepest_crossing(&outline_at(&out, "state_end.json"));
    let (_, case) = hard_case("wide-gap-fold");
    assert!(
        depth < case.contact.eps_ct,
        "the outline passes {depth} µm through itself"
    );
}
