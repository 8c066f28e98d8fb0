//! Tests of the case schema, the scene files in `cases/` and the error messages.

use std::path::{Path, PathBuf};

use super::*;

/// A table of test rows, one row a line: `a => b => c;` is the tuple `(a, b, c)` of a `Vec`.
macro_rules! rows {
    ($($a:expr => $b:expr => $c:expr;)*) => {
        vec![$(($a, $b, $c)),*]
    };
}

fn cases_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("cases")
}

/// The `.ron` files of a folder under `cases/`, sorted.
fn ron_files(sub: &str) -> Vec<PathBuf> {
    let dir = cases_dir().join(sub);
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|entry| entry.expect("directory entry").path())
        .filter(|p| p.extension().is_some_and(|x| x == "ron"))
        .collect();
    files.sort();
    files
}

fn load(rel: &str) -> Case {
    Case::load(cases_dir().join(rel)).unwrap_or_else(|e| panic!("{e}"))
}

/// Parses `text` and expects an error.
fn error_of(text: &str) -> CaseError {
    match Case::from_str(text, "test.ron") {
        Ok(case) => panic!("expected an error, got {case:?}"),
        Err(e) => e,
    }
}

/// A small valid case to which a test adds one field.
fn with(extra: &str) -> String {
    format!("(name: \"t\", substrate: Flat(), phases: (t_end: 100.0), {extra})")
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * b.abs()
}

#[test]
fn case_every_scene_file_loads_and_validates() {
    let scenes = ron_files("");
    let fast = ron_files("fast");
    let beyond = ron_files("3d");
    assert_eq!(scenes.len(), 5, "the five paper scenes: {scenes:?}");
    assert!(fast.len() >= 2, "fast variants: {fast:?}");
    assert!(
        !beyond.is_empty(),
        "the scenes beyond the paper (MODEL.md §10)"
    );
    for path in scenes.iter().chain(&fast).chain(&beyond) {
        let case = Case::load(path).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(case.validate(), Ok(()));
        // Each file is named after its case; in cases/3d/ the name of a 3-D scene adds
        // `-3d` to its file's (the 2-D scene's name), so the two runs' outputs stay apart.
        let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("");
        let named = if beyond.contains(path) && case.geometry.model == KinematicModel::ThreeD {
            format!("{stem}-3d")
        } else {
            stem.to_string()
        };
        assert_eq!(case.name, named, "{}", path.display());
    }
}

#[test]
fn case_scenes_match_model_section_7() {
    let all_with_adhesion_and_inertia = |c: &Case| {
        assert_eq!(c.adhesion, Some(Adhesion::default()), "{}", c.name);
        assert_eq!(c.inertia.mode, InertiaMode::OffAfter(9.0), "{}", c.name);
        assert_eq!(c.phases.t_g0, 10_000.0);
        assert_eq!(c.phases.t_as0, 40_000.0);
        assert_eq!(c.phases.t_a0, 50_000.0);
        // Everything not stated in a scene is the default.
        assert_eq!(c.geometry, Geometry::default());
        assert_eq!(c.materials, Materials::default());
        assert_eq!(c.mesh, Mesh::default());
    };

    let flat = load("flat.ron");
    all_with_adhesion_and_inertia(&flat);
    assert_eq!(flat.substrate, Substrate::flat());
    assert_eq!(flat.active, Active::default());
    assert_eq!(flat.phases.t_end, 40_000.0);
    assert!(!flat.gravity.upside_down);

    let push = load("pillars-push.ron");
    all_with_adhesion_and_inertia(&push);
    assert_eq!(push.substrate, Substrate::pillars());
    assert_eq!(push.active.pac, Some(Pac::default()));
    assert_eq!(push.active.bottom, None);
    assert_eq!(push.phases.t_end, 50_000.0);

    let pull = load("pillars-pull.ron");
    all_with_adhesion_and_inertia(&pull);
    assert_eq!(pull.substrate, Substrate::pillars());
    assert_eq!(pull.active.pac, None);
    assert_eq!(pull.active.bottom, Some(Bottom::default()));
    assert_eq!(pull.phases.t_end, 50_000.0);

    let both = load("pillars-push-pull.ron");
    all_with_adhesion_and_inertia(&both);
    assert_eq!(both.active.pac, Some(Pac::default()));
    assert_eq!(both.active.bottom, Some(Bottom::default()));
    assert_eq!(both.phases.t_end, 50_000.0);
    assert!(!both.gravity.upside_down);

    let flip = load("upside-down.ron");
    all_with_adhesion_and_inertia(&flip);
    assert!(flip.gravity.upside_down);
    assert_eq!(flip.gravity.flip_duration, 10_000.0);
    assert_eq!(flip.active, both.active);
    assert_eq!(flip.substrate, both.substrate);
    assert_eq!(flip.phases.t_end, 60_000.0);

    let short = load("fast/push-pull-short.ron");
    assert_eq!(short.mesh.refine, 0.5);
    assert_eq!(
        (short.phases.t_g0, short.phases.t_as0, short.phases.t_a0),
        (100.0, 400.0, 500.0)
    );
    assert_eq!(short.phases.t_end, 600.0);
    let gravity = load("fast/flat-gravity.ron");
    assert_eq!((gravity.mesh.refine, gravity.phases.t_end), (0.5, 200.0));
    assert_eq!(short.inertia.mode, InertiaMode::OffAfter(0.5));
    let drag = load("fast/push-pull-short-drag.ron");
    assert_eq!(
        (drag.inertia.mode, drag.inertia.drag),
        (InertiaMode::Off, 4.5e-5)
    );
}

#[test]
fn case_defaults_are_model_values() {
    let c = Case::new("defaults", Substrate::flat(), 40_000.0);
    assert_eq!(c.validate(), Ok(()));
    let g = &c.geometry;
    assert_eq!(
        (g.centre(), g.r_n, g.r_cp, g.r_c),
        ([0.0, 8.5], 5.0, 9.75, 10.0)
    );
    assert_eq!(g.bottom_y(), -1.5);
    let m = &c.mesh;
    assert_eq!((m.h_bottom, m.h_nucleus, m.refine), (0.3, 1.0, 1.0));
    assert_eq!(
        (m.contact_quadrature_degree, m.contact_subdivisions),
        (10, 0)
    );
    let mat = &c.materials;
    assert_eq!(
        (mat.nucleus.e, mat.nucleus.nu, mat.nucleus.rho_kg_m3),
        (500.0, 0.485, 1400.0)
    );
    for d in [&mat.cytoplasm, &mat.membrane] {
        assert_eq!((d.e, d.nu, d.rho_kg_m3), (100.0, 0.485, 1000.0));
    }
    assert_eq!((mat.gamma, mat.beta_fraction), (0.1, 0.2));
    assert_eq!((c.viscosity.lambda_f, c.viscosity.mu_f), (1000.0, 2e-3));
    assert_eq!((c.gravity.g_m_s2, c.gravity.upside_down), (9.81, false));
    assert_eq!(c.gravity.flip_duration, 10_000.0);
    assert_eq!((c.contact.mu_ct_n_m3, c.contact.eps_ct), (2e9, 0.1));
    let a = Adhesion::default();
    assert_eq!(
        (a.e_f, a.eps, a.mu_as0_n_m3s, a.mu_as_max_n_m3),
        (1.5, 0.1, 1e6, 1.4e9)
    );
    let p = Pac::default();
    assert_eq!((p.e, p.theta_deg), (0.7, -18.0));
    assert_eq!(
        (p.inner_semi_axes, p.outer_semi_axes),
        ((5.0, 4.5), (7.5, 7.0))
    );
    let b = Bottom::default();
    assert_eq!((b.e, b.theta_deg), (0.7, -35.0));
    assert_eq!(c.active.eps_a, 0.25);
    let s = match Substrate::pillars() {
        Substrate::Pillars(s) => s,
        Substrate::Flat(_) => unreachable!(),
    };
    assert_eq!(
        (s.width, s.spacing, s.height, s.first_center),
        (8.0, 8.0, 8.0, 8.0)
    );
    assert_eq!((s.q, s.gap, s.y_top), (4.0, 0.5, None));
    assert_eq!(c.substrate, Substrate::Flat(Flat { y_s: -2.0 }));
    let ph = &c.phases;
    assert_eq!((ph.t_g0, ph.t_as0, ph.t_a0, ph.t_end), (1e4, 4e4, 5e4, 4e4));
    assert_eq!((c.inertia.mode, c.inertia.drag), (InertiaMode::On, 0.0));
    assert_eq!(c.solver.integrator, Integrator::Ida);
    assert_eq!(
        (c.solver.rtol, c.solver.atol, c.solver.max_order),
        (1e-4, 1e-6, 5)
    );
    assert_eq!((c.output.n_times, c.output.phase_states), (400, true));
    // An absent optional section is off.
    assert_eq!((c.adhesion.clone(), c.active.pac.clone()), (None, None));
}

#[test]
fn case_unit_conversions_match_model_section_1() {
    let c = Case::new("units", Substrate::flat(), 1.0);
    let mat = &c.materials;
    let g = c.gravity.g();
    assert_eq!(g, 9.81e6); // µm/s²
    // ρg for 1000 kg/m³ is 9.81e-3 pN/µm³.
    assert!(close(mat.cytoplasm.rho() * g, 9.81e-3, 1e-12));
    // The contact coefficient 2e9 N/m³ is 2e3 pN/µm³.
    assert!(close(c.contact.mu_ct(), 2e3, 1e-12));
    let a = Adhesion::default();
    assert!(close(a.mu_as_max(), 1.4e3, 1e-12)); // pN/µm³
    assert!(close(a.mu_as0(), 1.0, 1e-12)); // pN/(µm³·s)
    // The weight of the half cell is 1.695 pN/µm (MODEL.md §9): ρg times the half-disk
    // areas of the nucleus and of the rest of the cell.
    let geo = &c.geometry;
    let half_disk = |r: f64| 0.5 * std::f64::consts::PI * r * r;
    let weight = g
        * (mat.nucleus.rho() * half_disk(geo.r_n)
            + mat.cytoplasm.rho() * (half_disk(geo.r_cp) - half_disk(geo.r_n))
            + mat.membrane.rho() * (half_disk(geo.r_c) - half_disk(geo.r_cp)));
    assert!(
        (weight - 1.695).abs() < 5e-4,
        "half-cell weight {weight} pN/µm"
    );
}

#[test]
fn case_pillar_tops_are_placed_by_the_gap() {
    let geo = Geometry::default();
    let p = Pillars::default();
    let y_top = p.resolved_y_top(&geo);
    // MODEL.md §5: y_top = −0.3 µm for a 0.5 µm gap.
    assert!((y_top + 0.30).abs() < 0.01, "y_top = {y_top}");
    assert!((p.smallest_gap(&geo, y_top) - 0.5).abs() < 1e-9);
    // Check against the gap evaluated by hand at x = 5 µm, where MODEL.md says it is
    // smallest: cell bottom 8.5 − √75, pillar top y_top − 4 + 4·(1 − (3/4)⁴)^¼.
    let cell = 8.5 - 75f64.sqrt();
    let top = y_top - 4.0 + 4.0 * (1.0 - 0.75f64.powi(4)).powf(0.25);
    assert!(
        ((cell - top) - 0.5).abs() < 0.02,
        "gap at x = 5: {}",
        cell - top
    );
    // Far from the pillars the surface is the floor.
    assert_eq!(p.at_height(y_top).surface_height(0.0), y_top - 8.0);
    assert!((p.at_height(y_top).surface_height(8.0) - y_top).abs() < 1e-12);
    assert!((p.at_height(y_top).surface_height(24.0) - y_top).abs() < 1e-12);
    // An explicit y_top wins.
    let q = Pillars {
        y_top: Some(-1.0),
        ..Pillars::default()
    };
    assert_eq!(q.resolved_y_top(&geo), -1.0);
    // The vertical gap to a pillar-free floor is the cell's height above it.
    let sparse = Pillars {
        first_center: 32.0,
        spacing: 56.0,
        ..Pillars::default()
    };
    let y = sparse.resolved_y_top(&geo);
    assert!((geo.bottom_y() - (y - 8.0) - 0.5).abs() < 1e-6);
}

#[test]
fn case_round_trip_of_defaults_and_scenes() {
    let mut c = Case::new("round trip", Substrate::pillars(), 50_000.0);
    c.description = Some("every section written".into());
    c.adhesion = Some(Adhesion::default());
    c.active.pac = Some(Pac::default());
    c.active.bottom = Some(Bottom::default());
    c.inertia.mode = InertiaMode::OffAfter(10_000.0);
    c.solver.initial_step = Some(1e-3);
    let text = c.to_ron().unwrap_or_else(|e| panic!("{e}"));
    let back = Case::from_str(&text, "round-trip.ron").unwrap_or_else(|e| panic!("{e}\n{text}"));
    assert_eq!(back, c);

    let plain = Case::new("plain", Substrate::flat(), 1.0);
    let text = plain.to_ron().unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(Case::from_str(&text, "plain.ron").ok(), Some(plain));

    for path in ron_files("")
        .iter()
        .chain(&ron_files("fast"))
        .chain(&ron_files("3d"))
    {
        let case = Case::load(path).unwrap_or_else(|e| panic!("{e}"));
        let text = case.to_ron().unwrap_or_else(|e| panic!("{e}"));
        let back = Case::from_str(&text, "again.ron").unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(back, case, "{}", path.display());
    }
}

/// Reads the `// expect-field:` and `// expect-error:` lines of a file in `cases/bad/`.
fn expectations(text: &str) -> (String, String) {
    let get = |key: &str| {
        text.lines()
            .find_map(|l| l.strip_prefix(key))
            .map(|s| s.trim().to_string())
            .unwrap_or_else(|| panic!("missing {key}"))
    };
    (get("// expect-field:"), get("// expect-error:"))
}

#[test]
fn case_bad_files_fail_with_the_expected_field_and_message() {
    let files = ron_files("bad");
    let names: Vec<String> = files
        .iter()
        .filter_map(|p| p.file_stem().and_then(|s| s.to_str()).map(str::to_string))
        .collect();
    for classic in [
        "missing-name",
        "wrong-type",
        "unknown-field",
        "unknown-variant",
        "rn-ge-rcp",
        "nu-half",
        "negative-time",
        "mesh-too-fine",
        "n-times-too-large",
        "rc-negative",
        "name-with-slash",
        "name-dot-dot",
        "integer-as-decimal",
        "not-utf8",
    ] {
        assert!(
            names.iter().any(|n| n == classic),
            "cases/bad/{classic}.ron"
        );
    }
    assert!(files.len() >= 40, "only {} bad cases", files.len());
    for path in &files {
        // Read bytes: some files are deliberately not UTF-8 (their comments are ASCII).
        let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{e}"));
        let (field, message) = expectations(&String::from_utf8_lossy(&bytes));
        let name = path.file_name().and_then(|s| s.to_str()).unwrap_or("");
        let label = format!("cases/bad/{name}");
        let err = match Case::from_bytes(&bytes, &label) {
            Ok(_) => panic!("{label} loaded"),
            Err(e) => e,
        };
        // An empty `expect-field:` means the error names no field (an empty file, say).
        let field = (!field.is_empty()).then_some(field.as_str());
        assert_eq!(err.field(), field, "{label}: {err}");
        // The memory limit is the machine's here (the CLI test sets CELLSIM_MEMORY_GB):
        // the message up to it.
        match message.split_once(" GB allowed (") {
            Some((head, _)) => {
                let (head, _) = head.rsplit_once("more than the").unwrap_or((head, ""));
                assert!(err.to_string().starts_with(head), "{label}: {err}");
            }
            None => assert_eq!(err.to_string(), message, "{label}"),
        }
        assert_eq!(err.file(), label);
    }
}

#[test]
fn case_errors_give_line_and_column() {
    let at = |rel: &str| {
        let path = cases_dir().join(rel);
        match Case::load(&path) {
            Ok(_) => panic!("{rel} loaded"),
            Err(e) => e.position().map(|p| (p.line, p.col)),
        }
    };
    // Validation error: the position of the field's name.
    assert_eq!(at("bad/nu-half.ron"), Some((9, 13)));
    assert_eq!(at("bad/rn-ge-rcp.ron"), Some((8, 9)));
    // Parse errors: ron's position, moved onto the offending token.
    assert_eq!(at("bad/unknown-field.ron"), Some((8, 30)));
    assert_eq!(at("bad/wrong-type.ron"), Some((8, 14)));
    // A missing field: the closing bracket of the struct that lacks it.
    let e =
        error_of("(\n  name: \"x\",\n  substrate: Flat(),\n  phases: (\n    t_g0: 1.0,\n  ),\n)");
    assert_eq!(e.field(), Some("phases.t_end"));
    assert_eq!(e.position(), Some(Position { line: 6, col: 3 }));
}

#[test]
fn case_default_values_are_reported_as_defaults() {
    // Lifting the cell centre under the substrate breaks y_s < c_y − r_c; y_s is a
    // default, so the message says so and gives no position.
    let e = error_of(&with("geometry: (centre_y: -5.0)"));
    assert_eq!(e.field(), Some("substrate.y_s"));
    assert_eq!(e.position(), None);
    assert_eq!(
        e.to_string(),
        "test.ron: substrate.y_s = -2 (the default: not written in the file) is out of \
         range (must satisfy y_s < centre_y - r_c = -15)"
    );
}

#[test]
fn case_two_field_rules_blame_the_written_field() {
    let e = error_of(&with("geometry: (r_cp: 4.0)"));
    assert_eq!(e.field(), Some("geometry.r_cp"));
    assert_eq!(
        e.to_string(),
        "test.ron:1:67: geometry.r_cp = 4 is out of range (must satisfy r_cp > r_n = 5)"
    );
    // Both written: the first of the pair is blamed.
    let e = error_of(
        &with("phases: (t_g0: 5.0, t_as0: 5.0, t_end: 9.0)")
            .replace("phases: (t_end: 100.0), ", ""),
    );
    assert_eq!(e.field(), Some("phases.t_g0"));
    assert!(e.to_string().contains("t_g0 < t_as0 = 5"), "{e}");
    // Nothing written: the programmatic validate() blames the first.
    let mut c = Case::new("x", Substrate::flat(), 1.0);
    c.geometry.r_c = 9.0;
    let v = c.validate().err().unwrap_or_default();
    assert_eq!(v.len(), 1);
    assert_eq!(v[0].field, "geometry.r_cp");
    assert_eq!(
        v[0].to_string(),
        "geometry.r_cp = 9.75 is out of range (must satisfy r_cp < r_c = 9)"
    );
}

#[test]
fn case_every_problem_is_listed() {
    let e = error_of(&with(
        "materials: (nucleus: (e: -1.0), membrane: (nu: 0.7)), solver: (rtol: 0.0, max_order: 6)",
    ));
    let CaseError::Invalid { problems, .. } = &e else {
        panic!("{e:?}");
    };
    let fields: Vec<&str> = problems
        .iter()
        .map(|p| p.violation.field.as_str())
        .collect();
    assert_eq!(
        fields,
        [
            "materials.nucleus.e",
            "materials.membrane.nu",
            "solver.rtol",
            "solver.max_order"
        ]
    );
    assert_eq!(e.to_string().lines().count(), 4);
    assert!(problems.iter().all(|p| p.position.is_some()));
}

#[test]
fn case_malformed_texts_give_errors_not_panics() {
    let flat = std::fs::read_to_string(cases_dir().join("flat.ron")).unwrap_or_default();
    let cut = flat.len() / 2;
    let cut = (0..=cut)
        .rev()
        .find(|&i| flat.is_char_boundary(i))
        .unwrap_or(0);
    let truncated = &flat[..cut];
    // (what, text, field the error must name, if any)
    let malformed: Vec<(&str, String, Option<&str>)> = rows![
        "empty file" => String::new() => None;
        "only a comment" => "// nothing\n".into() => None;
        "truncated file" => truncated.to_string() => None;
        "open bracket" => "(".into() => None;
        "a list, not a struct" => "[1, 2]".into() => None;
        "string for a number" => with("geometry: (r_n: \"five\")") => Some("geometry.r_n");
        "number for a string"
            => "(name: 5, substrate: Flat(), phases: (t_end: 1.0))".into() => Some("name");
        "bool for a number" => with("contact: (eps_ct: true)") => Some("contact.eps_ct");
        "float for an integer" => with("solver: (max_order: 2.5)") => Some("solver.max_order");
        "negative integer" => with("output: (n_times: -3)") => Some("output.n_times");
        "unknown variant" => with("inertia: (mode: Sometimes)") => Some("inertia.mode");
        "unknown section" => with("thermostat: (t: 37.0)") => Some("thermostat");
        "duplicate field" => with("mesh: (refine: 1.0, refine: 2.0)") => Some("mesh.refine");
        "missing substrate" => "(name: \"x\", phases: (t_end: 1.0))".into() => Some("substrate");
        "missing phases" => "(name: \"x\", substrate: Flat())".into() => Some("phases");
        "variant without brackets"
            => "(name: \"x\", substrate: Flat, phases: (t_end: 1.0))".into() => Some("substrate");
        "None for a material value"
            => with("materials: (nucleus: (e: None))") => Some("materials.nucleus.e");
        "three semi-axes"
            => with("active: (pac: (inner_semi_axes: (1, 2, 3)))")
            => Some("active.pac.inner_semi_axes");
        "trailing garbage" => format!("{} )", with("")) => None;
        "infinite" => with("gravity: (g_m_s2: inf)") => Some("gravity.g_m_s2");
        "not a number"
            => "(name: \"x\", substrate: Flat(), phases: (t_end: NaN))".into()
            => Some("phases.t_end");
        "empty name"
            => "(name: \" \", substrate: Flat(), phases: (t_end: 1.0))".into() => Some("name");
        "zero width"
            => "(name: \"x\", substrate: Pillars(width: 0), phases: (t_end: 1.0))".into()
            => Some("substrate.width");
        "pillars not symmetric"
            => "(name: \"x\", substrate: Pillars(first_center: 3.0), phases: (t_end: 1.0))".into()
            => Some("substrate.first_center");
        "pillars into the cell"
            => "(name: \"x\", substrate: Pillars(y_top: 1.0), phases: (t_end: 1.0))".into()
            => Some("substrate.y_top");
        "deep nesting"
            => format!("(name: \"x\", geometry: {}", "(".repeat(10_000)) => Some("geometry");
        "binary junk" => "\u{0}\u{1}(\u{7f}é\"".into() => None;
    ];
    for (what, text, field) in &malformed {
        let r = Case::from_str(text, "malformed.ron");
        let e = r.err().unwrap_or_else(|| panic!("{what}: accepted"));
        assert!(e.to_string().starts_with("malformed.ron:"), "{what}: {e}");
        if field.is_some() {
            assert_eq!(e.field(), *field, "{what}: {e}");
        }
    }
    // Every prefix of a scene file fails cleanly (only the whole text, or the text without
    // its last newline, parses).
    let text =
        std::fs::read_to_string(cases_dir().join("pillars-push-pull.ron")).unwrap_or_default();
    let trimmed = text.trim_end().len();
    for (i, _) in text.char_indices() {
        let r = Case::from_str(&text[..i], "prefix.ron");
        assert_eq!(r.is_ok(), i >= trimmed, "prefix of {i} bytes");
    }
}

#[test]
fn case_optional_sections_may_be_bare_some_or_none() {
    let parse =
        |extra: &str| Case::from_str(&with(extra), "t.ron").unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(parse("").adhesion, None);
    assert_eq!(parse("adhesion: None").adhesion, None);
    assert_eq!(parse("adhesion: ()").adhesion, Some(Adhesion::default()));
    assert_eq!(
        parse("adhesion: Some(())").adhesion,
        Some(Adhesion::default())
    );
    let a = parse("adhesion: Some((e_f: 2.0))").adhesion;
    assert_eq!(a.map(|a| (a.e_f, a.eps)), Some((2.0, 0.1)));
    let pillars = |y_top: &str| {
        let text =
            format!("(name: \"t\", substrate: Pillars(y_top: {y_top}), phases: (t_end: 1.0))");
        match Case::from_str(&text, "t.ron").map(|c| c.substrate) {
            Ok(Substrate::Pillars(p)) => p.y_top,
            other => panic!("{other:?}"),
        }
    };
    assert_eq!(pillars("-0.4"), Some(-0.4));
    assert_eq!(pillars("Some(-0.4)"), Some(-0.4));
    assert_eq!(pillars("None"), None);
    // `Pillars()` is the default array; a named root struct is accepted too.
    let c = Case::from_str(
        "Case(name: \"t\", substrate: Pillars(), phases: (t_end: 1.0))",
        "t.ron",
    );
    assert_eq!(c.map(|c| c.substrate).ok(), Some(Substrate::pillars()));
}

#[test]
fn case_materials_fill_each_domain_from_its_own_default() {
    let c = Case::from_str(
        &with("materials: (nucleus: (nu: 0.49), membrane: (e: 200.0), gamma: 0.0)"),
        "t.ron",
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let m = &c.materials;
    assert_eq!(
        (m.nucleus.e, m.nucleus.nu, m.nucleus.rho_kg_m3),
        (500.0, 0.49, 1400.0)
    );
    assert_eq!(
        (m.membrane.e, m.membrane.nu, m.membrane.rho_kg_m3),
        (200.0, 0.485, 1000.0)
    );
    assert_eq!(m.cytoplasm, Material::cytoplasm());
    assert_eq!((m.gamma, m.beta_fraction), (0.0, 0.2));
}

#[test]
fn case_inertia_modes() {
    let mode = |extra: &str| Case::from_str(&with(extra), "t.ron").map(|c| c.inertia);
    assert_eq!(mode("").ok().map(|i| i.mode), Some(InertiaMode::On));
    let i = mode("inertia: (mode: Off, drag: 1e-5)").ok();
    assert_eq!(i.map(|i| (i.mode, i.drag)), Some((InertiaMode::Off, 1e-5)));
    assert_eq!(
        mode("inertia: (mode: OffAfter(10000))")
            .ok()
            .map(|i| i.mode),
        Some(InertiaMode::OffAfter(10_000.0))
    );
    let e = mode("inertia: (mode: OffAfter(0.0))").err();
    assert_eq!(e.as_ref().and_then(|e| e.field()), Some("inertia.mode"));
    let e = mode("inertia: (mode: On, drag: -1.0)").err();
    assert_eq!(e.as_ref().and_then(|e| e.field()), Some("inertia.drag"));
}

#[test]
fn case_pillars_must_be_symmetric_about_the_axis() {
    let first = |x: f64| {
        let mut c = Case::new("p", Substrate::pillars(), 1.0);
        if let Substrate::Pillars(p) = &mut c.substrate {
            p.first_center = x;
        }
        c.validate().err().map(|v| v[0].field.clone())
    };
    assert_eq!(first(0.0), None);
    assert_eq!(first(8.0), None);
    assert_eq!(first(24.0), None);
    assert_eq!(first(16.0), None);
    assert_eq!(first(3.0).as_deref(), Some("substrate.first_center"));
}

#[test]
fn case_read_error_names_the_file() {
    let e = Case::load("cases/no-such-file.ron").err();
    let msg = e.map(|e| e.to_string()).unwrap_or_default();
    assert!(
        msg.starts_with("cases/no-such-file.ron: cannot read the case file"),
        "{msg}"
    );
}

/// Everything the run would refuse before integrating is refused by `Case::load`: for every
/// case that loads, the mesh parameters and the model parameters are accepted too.
#[test]
fn case_check_finds_what_the_run_refuses() {
    // Refused only by the lower layers before this check existed.
    for (text, field, needle) in rows![
        with("mesh: (refine: 1e6)")
            => "mesh.refine"
            => "mesh too fine: about 4223696789826277 elements estimated, limit 4000000";
        // The finer of the written sizes is blamed, not the default refine.
        with("mesh: (h_bottom: 1e-5)") => "mesh.h_bottom" => "limit 4000000";
        with("mesh: (h_nucleus: 1e-4, refine: 2.0)") => "mesh.h_nucleus" => "limit 4000000";
        with("geometry: (centre_y: 1e12)").replace("Flat()", "Flat(y_s: -1e13)")
            => "geometry.centre_y" => "too far from the origin";
        with("geometry: (r_c: inf)") => "geometry.r_c" => "must satisfy r_cp < r_c, and be finite";
        with("").replace("(t_end: 100.0)", "(t_as0: inf, t_a0: inf, t_end: 100.0)")
            => "phases.t_as0" => "must satisfy t_g0 < t_as0, and be finite";
        with("").replace("(t_end: 100.0)", "(t_a0: NaN, t_end: 100.0)")
            => "phases.t_a0" => "and be finite";
    ] {
        let e = error_of(&text);
        assert_eq!(e.field(), Some(field), "{text}: {e}");
        assert!(e.to_string().contains(needle), "{text}: {e}");
        assert!(e.position().is_some(), "{text}: {e}");
        assert_eq!(e.to_string().lines().count(), 1, "{e}");
    }
    // The other way round: whatever loads, the lower layers accept.
    let mut texts: Vec<String> = [
        "",
        "mesh: (refine: 3.0)",
        "mesh: (h_bottom: 0.01)",
        "geometry: (centre_y: 1e5), substrate: Flat(y_s: 0.0)",
        "adhesion: (), active: (pac: (), bottom: ())",
        "gravity: (upside_down: true)",
        "inertia: (mode: Off, drag: 1e-3)",
    ]
    .iter()
    .map(|extra| {
        let text = with(extra);
        // A later `substrate` replaces the default one of `with`.
        if extra.contains("substrate") {
            text.replacen("substrate: Flat(), ", "", 1)
        } else {
            text
        }
    })
    .collect();
    for path in ron_files("").iter().chain(&ron_files("fast")) {
        texts.push(std::fs::read_to_string(path).unwrap_or_default());
    }
    for text in &texts {
        let case = Case::from_str(text, "ok.ron").unwrap_or_else(|e| panic!("{e}\n{text}"));
        let mesh = crate::scene::mesh_params(&case).validate();
        assert!(mesh.is_ok(), "{text}: {mesh:?}");
        let params = crate::scene::model_params(&case, "ok.ron", true);
        assert!(params.is_ok(), "{text}: {params:?}");
    }
    // The estimate the check uses is the mesh generator's.
    let fine = crate::fem::MeshParams {
        refine: 1e6,
        ..crate::fem::reference::mesh_params()
    };
    assert!(fine.estimated_elements() > crate::fem::mesh::MAX_ELEMENTS);
    assert!(crate::fem::reference::mesh_params().estimated_elements() < 1e4);
}

#[test]
fn case_output_times_are_bounded() {
    let n = |v: u64| Case::from_str(&with(&format!("output: (n_times: {v})")), "t.ron");
    assert_eq!(n(200).map(|c| c.output.n_times).ok(), Some(200));
    assert_eq!(n(100_000).map(|c| c.output.n_times).ok(), Some(100_000));
    for v in [199, 100_001, 100_000_000] {
        let e = n(v).err().map(|e| e.to_string()).unwrap_or_default();
        assert!(
            e.ends_with(&format!(
                "output.n_times = {v} is out of range (must satisfy 200 <= n_times <= 100000)"
            )),
            "{v}: {e}"
        );
    }
}

#[test]
fn case_one_mistake_gives_one_message() {
    // A negative cell radius used to blame h_bottom, h_nucleus and the PAC ellipse too.
    let e = error_of(&with("geometry: (r_c: -10.0), active: (pac: ())"));
    let CaseError::Invalid { problems, .. } = &e else {
        panic!("{e:?}");
    };
    assert_eq!(problems.len(), 1, "{e}");
    assert_eq!(
        e.to_string(),
        "test.ron:1:67: geometry.r_c = -10 is out of range (must satisfy r_c > r_cp = 9.75)"
    );
    // The same with the pillars: their placement reads the geometry.
    let e = error_of(&with("geometry: (r_c: -10.0)").replace("Flat()", "Pillars()"));
    assert_eq!(e.to_string().lines().count(), 1, "{e}");
    assert_eq!(e.field(), Some("geometry.r_c"));
    // A non-finite nucleus radius: one message, not a second from r_n < r_cp.
    let e = error_of(&with("geometry: (r_n: NaN)"));
    assert_eq!(e.to_string().lines().count(), 1, "{e}");
    // An invalid pillar width: not also the symmetry of first_center or the gap.
    let e = error_of(&with("").replace("Flat()", "Pillars(width: -8.0)"));
    assert_eq!(e.to_string().lines().count(), 1, "{e}");
    assert_eq!(e.field(), Some("substrate.width"));
    // Independent mistakes are still all listed (see case_every_problem_is_listed).
    let e = error_of(&with("geometry: (r_c: -10.0), solver: (rtol: 2.0)"));
    assert_eq!(e.to_string().lines().count(), 2, "{e}");
}

#[test]
fn case_file_encoding() {
    let valid = with("");
    // A UTF-8 byte-order mark is accepted, from text and from bytes.
    let bom = format!("\u{FEFF}{valid}");
    assert_eq!(
        Case::from_str(&bom, "bom.ron").ok(),
        Case::from_str(&valid, "plain.ron").ok()
    );
    assert!(Case::from_bytes(bom.as_bytes(), "bom.ron").is_ok());
    // ... and columns count from after it.
    let e = Case::from_bytes(b"\xEF\xBB\xBF(name: \"\xFF", "bom.ron").err();
    assert_eq!(
        e.and_then(|e| e.position()),
        Some(Position { line: 1, col: 9 })
    );
    // A byte that is not UTF-8: its line and column, and the field it is in.
    let mut bytes = b"(\n  name: \"caf".to_vec();
    bytes.push(0xE9); // Latin-1 é
    bytes.extend_from_slice(b"\", substrate: Flat(), phases: (t_end: 1.0))");
    let e = Case::from_bytes(&bytes, "latin1.ron").err();
    let msg = e.as_ref().map(|e| e.to_string()).unwrap_or_default();
    assert!(
        msg.starts_with("latin1.ron:2:13: name: not valid UTF-8: byte 0xE9"),
        "{msg}"
    );
    assert_eq!(
        e.and_then(|e| e.position()),
        Some(Position { line: 2, col: 13 })
    );
    // Characters before it count once each, however many bytes they take.
    let e = Case::from_bytes(b"(description: \"\xC2\xB5\xFF", "mu.ron").err();
    assert_eq!(
        e.and_then(|e| e.position()),
        Some(Position { line: 1, col: 17 })
    );
}

#[test]
fn case_integer_fields_refuse_decimal_numbers() {
    for (extra, field, number, col) in [
        ("output: (n_times: 400.5)", "output.n_times", "400.5", 74),
        ("solver: (max_order: 2.5)", "solver.max_order", "2.5", 76),
        ("solver: (max_steps: 1e3)", "solver.max_steps", "1e3", 76),
        (
            "mesh: (contact_subdivisions: 1.0)",
            "mesh.contact_subdivisions",
            "1.0",
            85,
        ),
        (
            "output: (n_times: 400., phase_states: true)",
            "output.n_times",
            "400.",
            74,
        ),
    ] {
        let e = error_of(&with(extra));
        assert_eq!(
            e.to_string(),
            format!(
                "test.ron:1:{col}: {field}: expected an integer, found the decimal number \
                 `{number}`"
            ),
            "{extra}"
        );
        assert_eq!(e.field(), Some(field));
    }
    // Other errors at a number are left alone: a number for a string, a malformed float.
    let e = error_of("(name: 5.5, substrate: Flat(), phases: (t_end: 1.0))");
    assert!(!e.to_string().contains("integer"), "{e}");
    let e = error_of(&with("geometry: (r_n: 5.0.0)"));
    assert!(!e.to_string().contains("integer"), "{e}");
}

#[test]
fn case_names_are_single_path_components() {
    let name = |n: &str| {
        let text = format!("(name: {n:?}, substrate: Flat(), phases: (t_end: 1.0))");
        Case::from_str(&text, "n.ron")
    };
    for ok in ["flat", "push pull 2", "é-ü", "a.b", "..a"] {
        assert!(name(ok).is_ok(), "{ok}");
    }
    for bad in [
        "",
        " ",
        ".",
        "..",
        "a/b",
        "a/b/../../../etc",
        "/abs",
        "a\\b",
        "a\0b",
        "tab\there",
        "nl\n",
    ] {
        let e = name(bad).err();
        let msg = e.as_ref().map(|e| e.to_string()).unwrap_or_default();
        assert_eq!(e.as_ref().and_then(|e| e.field()), Some("name"), "{bad:?}");
        assert!(
            msg.starts_with(&format!("n.ron:1:2: name = {bad:?} is not allowed")),
            "{bad:?}: {msg}"
        );
        assert!(msg.contains("single path component"), "{msg}");
    }
}

#[test]
fn case_wedge_choice_resolves_by_the_substrate_mirror() {
    use crate::fem::Wedge;
    let wedge = |extra: &str| -> Wedge {
        let text = format!(
            "(name: \"t\", geometry: (model: ThreeD{extra}), substrate: Pillars(), \
             phases: (t_end: 100.0))"
        );
        let case = Case::from_str(&text, "t.ron").unwrap_or_else(|e| panic!("{e}"));
        crate::scene::terms::tet_mesh_params(&case).wedge
    };
    // The default pillars: the cell above the centre of four (first_center = P/2).
    assert_eq!(wedge(""), Wedge::Quarter, "the default");
    assert_eq!(wedge(", wedge: Auto"), Wedge::Eighth);
    assert_eq!(wedge(", wedge: Eighth"), Wedge::Eighth);
    let gap = Case::from_str(
        "(name: \"t\", geometry: (model: ThreeD, wedge: Auto), substrate: Pillars(lattice: Gap), \
         phases: (t_end: 100.0))",
        "t.ron",
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        crate::scene::terms::tet_mesh_params(&gap).wedge,
        Wedge::Quarter
    );
}

/// The run-cost estimate against the measured runs it was fitted to, through the element
/// counts estimated before meshing (not the meshes' own counts): the 3-D push-pull in the
/// quarter cell, 1 551 s on the default mesh and 5 544 s refined ×1.5 (the README's runs of
/// 2026-12-02), 722 s on the 3-D maps' configuration at w = s = 8 µm (2026-12-08, two runs
/// side by side on two cores), and the 2-D push-pull 7.3 s: each within 15 %; the peak
/// memory of the 3-D runs (0.80–0.86 GB on the maps' configuration, 2.63 GB on the default
/// mesh, 5.41 GB refined ×1.5) within 15 %, and the Slurm request made from it
/// (× 1.5 + 200 MB) above each.
#[test]
fn run_cost_estimates_the_measured_scenes() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let load = |file: &str| Case::load(root.join(file)).unwrap_or_else(|e| panic!("{e}"));
    let quarter = load("cases/3d/pillars-push-pull.ron");
    let mut refined = quarter.clone();
    refined.mesh.refine = 1.5;
    let mut coarse = quarter.clone();
    coarse.mesh.h_bottom = 0.6;
    coarse.mesh.h_nucleus = 1.5;
    let cases = [
        (quarter, 1_551.0, Some(2.63e9), 3),
        (refined, 5_544.0, Some(5.41e9), 3),
        (coarse, 722.0, Some(0.86e9), 3),
        (load("cases/pillars-push-pull.ron"), 7.3, None, 2),
    ];
    for (case, measured, peak, dim) in &cases {
        let c = crate::scene::terms::run_cost(case).expect("a mesh the generator accepts");
        assert_eq!(c.dimension, *dim);
        let ratio = c.seconds / measured;
        assert!(
            (ratio - 1.0).abs() < 0.15,
            "{}: estimated {:.0} s against {measured} s ({:.0} elements)",
            case.name,
            c.seconds,
            c.elements
        );
        assert!(c.bytes > 0.0);
        if let Some(peak) = peak {
            assert!(
                (c.bytes / peak - 1.0).abs() < 0.15 && 1.5 * c.bytes + 200e6 > *peak,
                "{}: estimated {:.2} GB against a peak of {:.2} GB",
                case.name,
                c.bytes / 1e9,
                peak / 1e9
            );
        }
    }
    // The phases: the whole push-pull is the unit; a run that stops at T_g0 a tenth; a
    // compressed scene (every phase 100 s) the same work.
    let mut p = cases[3].0.phases.clone();
    assert!((crate::scene::terms::work_fraction(&p) - 1.0).abs() < 1e-12);
    p.t_end = p.t_g0;
    assert!((crate::scene::terms::work_fraction(&p) - 0.1).abs() < 1e-12);
    let short = Phases {
        t_g0: 100.0,
        t_as0: 200.0,
        t_a0: 300.0,
        t_end: 300.0,
        adhesion_start: None,
        active_start: None,
    };
    assert!((crate::scene::terms::work_fraction(&short) - 1.0).abs() < 1e-12);
}
