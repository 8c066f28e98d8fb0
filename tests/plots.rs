//! Figures, VTU, GIF and the paper's comparison, from a stored run.
//!
//! The fixture `tests/data/small-push-pull/` is a complete run directory written by
//! `cellsim run tests/data/small-push-pull.ron --out tests/data/small-push-pull` (coarse
//! push-pull, 200 output times, four states). If the run file formats change
//! (`record::MeshFile`, `StateFile`, `Summary`), regenerate it with that command.

use std::path::{Path, PathBuf};
use std::process::Command;

use cellsim::output::RunData;
use cellsim::output::figures::{
    self, CYTOPLASM, LAYER, MEMBRANE, NUCLEUS, SHAPE_SIZE, SUBSTRATE, StrainBars, TIME_SIZE,
    UPSIDE_DOWN_SIZE,
};
use cellsim::output::geometry::{Backdrop, CellShape};
use cellsim::output::movie::{FRAME_SIZE, MAX_FRAMES, Movie};
use cellsim::output::paper::{self, Quantity, SceneOutcome, When};
use cellsim::output::vtu::{QUADRATIC_TRIANGLE, VtuSeries, read_vtu, write_vtu};
use cellsim::physics::Substrate;
use cellsim::record::Snapshot;
use cellsim::record::StateFile;
use cellsim::record::observables::OLD_CSV_HEADER;
use cellsim::record::read::{ReadError, parse_timeseries};

fn fixture() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/small-push-pull")
}

/// A fresh scratch directory for one test.
fn scratch(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("plots-{name}"));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("create scratch dir");
    d
}

fn load_fixture() -> RunData {
    RunData::load(fixture()).expect("the stored run loads")
}

/// Decodes a PNG: (width, height, RGB pixels).
fn png(path: &Path) -> (u32, u32, Vec<[u8; 3]>) {
    let img = image::open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .to_rgb8();
    let (w, h) = img.dimensions();
    (w, h, img.pixels().map(|p| p.0).collect())
}

/// Checks size and that the picture is not blank: at least `min_frac` of the pixels are
/// not white.
fn check_png(path: &Path, size: (u32, u32), min_frac: f64) -> Vec<[u8; 3]> {
    let (w, h, px) = png(path);
    assert_eq!((w, h), size, "{}: pixel size", path.display());
    let inked = px.iter().filter(|p| **p != [255, 255, 255]).count();
    let frac = inked as f64 / px.len() as f64;
    assert!(
        frac >= min_frac,
        "{}: only {:.2} % of the pixels are drawn",
        path.display(),
        100.0 * frac
    );
    px
}

fn count_color(px: &[[u8; 3]], c: plotters::style::RGBColor) -> usize {
    px.iter().filter(|p| **p == [c.0, c.1, c.2]).count()
}

#[test]
fn stored_run_loads_complete() {
    let r = load_fixture();
    assert!(r.finished());
    assert!(r.notes.is_empty(), "{:?}", r.notes);
    assert_eq!(r.series.len(), r.summary.as_ref().map_or(0, |s| s.outputs));
    let phases: Vec<&str> = r.states.iter().map(|s| s.phase.as_str()).collect();
    assert_eq!(phases, ["gravity", "spreading", "active", "end"]);
    assert_eq!(r.t_last(), r.t_end());
}

#[test]
fn time_figures_have_their_size_and_ink() {
    let r = load_fixture();
    let d = scratch("time");
    let runs = [&r];

    let p = d.join("contact.png");
    figures::contact_radius_figure(&p, &runs, &[(10000.0, 1.0), (55000.0, 8.8)], "paper")
        .expect("contact radius figure");
    check_png(&p, TIME_SIZE, 0.03);

    let p = d.join("disp.png");
    let marks = vec![vec![(10000.0, -0.1), (40000.0, -5.0)]];
    figures::displacement_figure(&p, &runs, &marks, "paper").expect("displacement figure");
    check_png(&p, TIME_SIZE, 0.03);

    let p = d.join("strain.png");
    figures::strain_time_figure(&p, &runs).expect("strain figure");
    check_png(&p, TIME_SIZE, 0.03);

    let p = d.join("upside.png");
    figures::upside_down_figure(&p, &r, &r, Some(0.006)).expect("upside-down figure");
    check_png(&p, UPSIDE_DOWN_SIZE, 0.03);

    let p = d.join("bars.png");
    let bars = vec![
        StrainBars {
            scene: "push".into(),
            paper_nucleus: Some(0.13),
            ours_nucleus: Some(0.2),
            paper_cytoplasm: Some(0.56),
            ours_cytoplasm: Some(0.6),
        },
        StrainBars {
            scene: "pull".into(),
            paper_nucleus: Some(0.37),
            ours_nucleus: None,
            paper_cytoplasm: Some(0.59),
            ours_cytoplasm: None,
        },
    ];
    figures::strain_bars_figure(&p, &bars, "ours", "paper").expect("bars figure");
    let px = check_png(&p, TIME_SIZE, 0.03);
    // Both bar colours are there.
    assert!(count_color(&px, plotters::style::RGBColor(170, 170, 170)) > 1000);
    assert!(count_color(&px, plotters::style::RGBColor(31, 119, 180)) > 1000);
}

#[test]
fn shape_figure_fills_domains_and_keeps_equal_aspect() {
    let r = load_fixture();
    let d = scratch("shape");
    let states: Vec<&StateFile> = r.states.iter().collect();
    let view = figures::shape_view(&r.mesh, &states);
    for s in &r.states {
        let p = d.join(format!("shape-{}.png", s.phase));
        let scale = figures::shape_figure(&p, "fixture", &r.mesh, s, view).expect("shape");
        let rel = (scale.px_per_um_x - scale.px_per_um_y).abs() / scale.px_per_um_x;
        assert!(rel < 0.01, "{}: aspect {scale:?}", s.phase);
        assert!(scale.px_per_um_x > 10.0, "{scale:?}");
        let px = check_png(&p, SHAPE_SIZE, 0.2);
        for (name, c, least) in [
            ("nucleus", NUCLEUS, 5000),
            ("cytoplasm", CYTOPLASM, 20000),
            // The membrane is 0.25 µm thick: a thin ring, plus its legend swatch.
            ("membrane", MEMBRANE, 300),
            ("substrate", SUBSTRATE, 20000),
            ("fibronectin layer", LAYER, 5000),
        ] {
            let n = count_color(&px, c);
            assert!(n >= least, "{}: {n} pixels of {name}", s.phase);
        }
        // Active regions outlined (PAC blue, bottom purple).
        assert!(
            count_color(&px, figures::PAC) > 200,
            "{}: PAC outline",
            s.phase
        );
        assert!(
            count_color(&px, figures::BOTTOM) > 200,
            "{}: bottom outline",
            s.phase
        );
    }
}

#[test]
fn cell_shape_geometry_follows_the_displacement() {
    let r = load_fixture();
    let zero = vec![[0.0; 2]; r.mesh.nodes.len()];
    let rest = CellShape::new(&r.mesh, &zero);
    assert_eq!(rest.elements.len(), r.mesh.elements.len());
    // At rest: the cell is the reference disk of radius 10 about (0, 8.5).
    let b = rest.bounds();
    assert!(
        (b.y_max - 18.5).abs() < 1e-9 && (b.y_min + 1.5).abs() < 1e-9,
        "{b:?}"
    );
    assert!(
        b.x_min.abs() < 1e-9 && (b.x_max - 10.0).abs() < 1e-6,
        "{b:?}"
    );
    let full = rest.mirrored().bounds();
    assert!((full.x_min + 10.0).abs() < 1e-6);
    // Markers p_t, c, p_b at rest.
    assert_eq!(rest.markers, vec![[0.0, 13.5], [0.0, 8.5], [0.0, 3.5]]);
    // Both active regions have an outline; PAC lies within the outer ellipse (7.5, 7).
    assert!(!rest.pac.is_empty() && !rest.bottom.is_empty());
    for s in &rest.pac {
        for p in s {
            let q = (p[0] / 7.5).powi(2) + ((p[1] - 8.5) / 7.0).powi(2);
            assert!(
                q < 1.0 + 0.1,
                "PAC outline point {p:?} outside the outer ellipse"
            );
        }
    }
    // A rigid shift moves everything by the shift.
    let shift = vec![[0.0, -2.0]; r.mesh.nodes.len()];
    let moved = CellShape::new(&r.mesh, &shift).bounds();
    assert!((moved.y_max - 16.5).abs() < 1e-9);
    // The end state is lower than the reference.
    let end = r.state("end").expect("end state");
    let e = CellShape::new(&r.mesh, &end.u);
    assert!(
        e.markers[0][1] < 13.5 - 5.0,
        "p_t went down: {:?}",
        e.markers[0]
    );
}

#[test]
fn backdrop_matches_the_substrate_geometry() {
    let flat = Substrate::Flat { y_s: -2.0 };
    let b = Backdrop::new(&flat, Some(1.5), [-3.0, 3.0, -5.0, 5.0], 10);
    assert_eq!(b.substrate, vec![[-3.0, 3.0, -5.0, -2.0]]);
    assert_eq!(b.layer, vec![[-3.0, 3.0, -5.0, -0.5]]);
    assert_eq!(b.surface, vec![vec![[-3.0, -2.0], [3.0, -2.0]]]);

    let r = load_fixture();
    let sub = r.mesh.substrate;
    let Substrate::Pillars(p) = sub else {
        panic!("fixture is on pillars")
    };
    let floor = p.y_top - p.height;
    let view = [-16.0, 16.0, floor - 2.0, p.y_top + 4.0];
    let b = Backdrop::new(&sub, Some(1.5), view, 640);
    // The strips of the column holding x.
    let column = |rects: &[[f64; 4]], x: f64| -> Vec<[f64; 2]> {
        rects
            .iter()
            .filter(|r| r[0] <= x && x < r[1])
            .map(|r| [r[2], r[3]])
            .collect()
    };
    let top = |rects: &[[f64; 4]], x: f64| {
        column(rects, x)
            .iter()
            .map(|i| i[1])
            .fold(f64::NEG_INFINITY, f64::max)
    };
    // Pillar top at x = ±8, floor mid-gap at x = 0.
    assert!(
        (top(&b.substrate, 8.01) - p.y_top).abs() < 1e-3,
        "{}",
        top(&b.substrate, 8.01)
    );
    assert!((top(&b.substrate, -8.01) - p.y_top).abs() < 1e-3);
    assert!((top(&b.substrate, 0.01) - floor).abs() < 1e-6);
    // Under the rounded foot of a pillar (x = 4.6, inside the pillar's width) the
    // substrate is two strips with a gap above the floor: the undercut is drawn open.
    let foot = column(&b.substrate, 4.61);
    assert_eq!(foot.len(), 2, "{foot:?}");
    assert!(
        (foot[1][1] - floor).abs() < 1e-6 && foot[0][0] > floor + 0.3,
        "{foot:?}"
    );
    // The layer reaches e_f above the pillar top and above the floor.
    assert!((top(&b.layer, 8.01) - (p.y_top + 1.5)).abs() < 1e-3);
    assert!((top(&b.layer, 0.01) - (floor + 1.5)).abs() < 1e-6);
    // The layer's edge lies where the depth is −e_f (to the contouring grid's accuracy).
    assert!(!b.layer_edge.is_empty());
    for s in &b.layer_edge {
        for q in s {
            let d = sub.eval(&nalgebra::Vector2::new(q[0], q[1])).0;
            assert!((d + 1.5).abs() < 0.02, "edge point {q:?} at depth {d}");
        }
    }
    // The surface outline stays in the view.
    assert!(
        b.surface
            .iter()
            .flatten()
            .all(|q| q[0] >= -16.0 && q[0] <= 16.0)
    );
}

/// Copies the stored run and cuts it as an interruption would: fewer rows and a last
/// line cut short, the last two states missing, the summary unfinished.
fn interrupted_copy(name: &str) -> PathBuf {
    let d = scratch(name);
    for f in [
        "mesh.json",
        "state_gravity.json",
        "state_spreading.json",
        "summary.json",
    ] {
        std::fs::copy(fixture().join(f), d.join(f)).expect("copy fixture");
    }
    let csv = std::fs::read_to_string(fixture().join("timeseries.csv")).expect("csv");
    let lines: Vec<&str> = csv.lines().collect();
    let mut cut = lines[..121].join("\n"); // header + 120 rows
    cut.push('\n');
    cut.push_str(&lines[121][..lines[121].len() / 2]); // half a row, no newline
    std::fs::write(d.join("timeseries.csv"), cut).expect("write csv");
    let text = std::fs::read_to_string(d.join("summary.json")).expect("summary");
    let mut v: serde_json::Value = serde_json::from_str(&text).expect("summary json");
    v["finished"] = serde_json::Value::Bool(false);
    v["failure"] = serde_json::json!({
        "reason": "interrupted", "t_last_output": 33000.0, "step": 900
    });
    std::fs::write(d.join("summary.json"), v.to_string()).expect("write summary");
    d
}

#[test]
fn plot_works_on_an_interrupted_run() {
    let d = interrupted_copy("interrupted");
    let r = RunData::load(&d).expect("partial run loads");
    assert!(!r.finished());
    assert_eq!(r.series.len(), 120);
    assert_eq!(r.states.len(), 2);
    assert!(
        r.notes.iter().any(|n| n.contains("cut short")),
        "{:?}",
        r.notes
    );
    assert!(
        r.notes.iter().any(|n| n.contains("did not finish")),
        "{:?}",
        r.notes
    );
    let out = d.join("plots");
    let files = figures::plot_run(&r, &out).expect("plot_run");
    let names: Vec<String> = files
        .iter()
        .filter_map(|p| p.file_name().map(|n| n.to_string_lossy().into_owned()))
        .collect();
    assert_eq!(
        names,
        [
            "contact-radius.png",
            "displacement.png",
            "strain.png",
            "shape-gravity.png",
            "shape-spreading.png"
        ]
    );
    for f in &files {
        let size = if names
            .iter()
            .any(|n| f.ends_with(n) && n.starts_with("shape"))
        {
            SHAPE_SIZE
        } else {
            TIME_SIZE
        };
        check_png(f, size, 0.03);
    }
}

#[test]
fn plot_command_on_partial_and_missing_runs() {
    let exe = env!("CARGO_BIN_EXE_cellsim");
    let d = interrupted_copy("cli-interrupted");
    let out = Command::new(exe)
        .arg("plot")
        .arg(&d)
        .output()
        .expect("run cellsim plot");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("did not finish"), "{stderr}");
    assert!(d.join("plots/shape-spreading.png").exists());

    // No mesh.json: a clear error naming it, exit status 2.
    std::fs::remove_file(d.join("mesh.json")).expect("remove mesh");
    let out = Command::new(exe)
        .arg("plot")
        .arg(&d)
        .output()
        .expect("run cellsim plot");
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("mesh.json"), "{stderr}");
}

#[test]
fn malformed_files_are_named() {
    let d = interrupted_copy("malformed");
    // A bad row in the middle of the CSV: error with the file and the line.
    let csv = std::fs::read_to_string(d.join("timeseries.csv")).expect("csv");
    let mut lines: Vec<String> = csv.lines().map(String::from).collect();
    lines[10] = "1.0,2.0,oops,4,5,6,7".into();
    std::fs::write(d.join("timeseries.csv"), lines.join("\n") + "\n").expect("write");
    let msg = RunData::load(&d).expect_err("bad row").to_string();
    assert!(
        msg.contains("timeseries.csv") && msg.contains("line 11"),
        "{msg}"
    );

    // A wrong header.
    let e = parse_timeseries(Path::new("x.csv"), "t,r\n0,0\n").expect_err("header");
    assert!(e.to_string().contains("header"), "{e}");
    assert!(parse_timeseries(Path::new("x.csv"), "").is_err());

    // The files of an older cellsim, before the paper's measures (contact_radius_ref,
    // strain_membrane, uy_nucleus_max) and with strain_cytoplasm without the membrane:
    // refused, saying so, not misread.
    let d = interrupted_copy("older");
    let csv = std::fs::read_to_string(d.join("timeseries.csv")).expect("csv");
    let old: Vec<String> = std::iter::once(OLD_CSV_HEADER.to_string())
        .chain(csv.lines().skip(1).take(5).map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            f[..7].join(",")
        }))
        .collect();
    std::fs::write(d.join("timeseries.csv"), old.join("\n") + "\n").expect("write");
    let e = RunData::load(&d).expect_err("older csv").to_string();
    assert!(
        e.contains("timeseries.csv")
            && e.contains("older cellsim")
            && e.contains("strain_membrane"),
        "{e}"
    );
    let text = std::fs::read_to_string(d.join("summary.json")).expect("summary");
    let mut v: serde_json::Value = serde_json::from_str(&text).expect("json");
    for c in ["contact_radius_ref", "strain_membrane", "uy_nucleus_max"] {
        v["final_values"]
            .as_object_mut()
            .expect("final values")
            .remove(c);
    }
    std::fs::write(d.join("summary.json"), v.to_string()).expect("write");
    let e = cellsim::record::read::read_summary(&d).expect_err("older summary");
    assert!(
        e.to_string().contains("summary.json") && e.to_string().contains("older cellsim"),
        "{e}"
    );

    // A state file with the wrong number of nodes.
    let d = interrupted_copy("malformed-state");
    let text = std::fs::read_to_string(d.join("state_gravity.json")).expect("state");
    let mut v: serde_json::Value = serde_json::from_str(&text).expect("json");
    if let Some(u) = v["u"].as_array_mut() {
        u.pop();
    }
    std::fs::write(d.join("state_gravity.json"), v.to_string()).expect("write");
    let e = RunData::load(&d).expect_err("short state");
    assert!(matches!(e, ReadError::Malformed { .. }));
    assert!(e.to_string().contains("state_gravity.json"), "{e}");

    // A mesh with an element pointing past the nodes.
    let d = interrupted_copy("malformed-mesh");
    let text = std::fs::read_to_string(d.join("mesh.json")).expect("mesh");
    let mut v: serde_json::Value = serde_json::from_str(&text).expect("json");
    v["elements"][0][0] = serde_json::json!(1_000_000);
    std::fs::write(d.join("mesh.json"), v.to_string()).expect("write");
    let e = RunData::load(&d).expect_err("bad mesh").to_string();
    assert!(e.contains("mesh.json") && e.contains("element 0"), "{e}");

    // Not JSON at all.
    std::fs::write(d.join("mesh.json"), "{ not json").expect("write");
    let e = RunData::load(&d).expect_err("not json").to_string();
    assert!(e.contains("mesh.json"), "{e}");
}

fn snapshot_of(s: &StateFile) -> Snapshot {
    Snapshot {
        t: s.t,
        u: s.u.clone(),
        v: s.u.iter().map(|u| [0.5 * u[0], 0.5 * u[1]]).collect(),
        mu_as: s.mu_as.clone(),
        element_strain: s.element_strain.clone(),
        element_jacobian: s.element_jacobian.clone(),
    }
}

#[test]
fn vtu_reads_back_with_its_points_cells_and_arrays() {
    let r = load_fixture();
    let d = scratch("vtu");
    let end = r.state("end").expect("end state");
    let p = d.join("end.vtu");
    write_vtu(&p, &r.mesh, &snapshot_of(end)).expect("write vtu");
    let v = read_vtu(&p).expect("read vtu");
    assert_eq!(v.points, r.mesh.nodes.len());
    assert_eq!(v.cells, r.mesh.elements.len());
    assert!(v.cell_types.iter().all(|&t| t == QUADRATIC_TRIANGLE));
    assert_eq!(v.point_arrays, ["displacement", "velocity", "mu_as"]);
    assert_eq!(v.cell_arrays, ["domain", "mean_E_norm", "det_F"]);
    let disp = v.displacement.expect("displacement array");
    assert_eq!(disp.len(), 3 * r.mesh.nodes.len());
    for (i, u) in end.u.iter().enumerate() {
        assert_eq!(
            [disp[3 * i], disp[3 * i + 1], disp[3 * i + 2]],
            [u[0], u[1], 0.0]
        );
    }
    // A snapshot that does not fit the mesh is refused, naming the file.
    let mut bad = snapshot_of(end);
    bad.u.pop();
    let e = write_vtu(&d.join("bad.vtu"), &r.mesh, &bad).expect_err("short snapshot");
    assert!(e.to_string().contains("bad.vtu"), "{e}");
}

#[test]
fn vtu_series_writes_a_collection() {
    let r = load_fixture();
    let d = scratch("pvd");
    let mut series = VtuSeries::new(&d, "fixture", &r.mesh).expect("series");
    for s in &r.states {
        series.write(&snapshot_of(s)).expect("write");
    }
    let pvd = std::fs::read_to_string(d.join("fixture.pvd")).expect("pvd");
    assert_eq!(pvd.matches("<DataSet ").count(), r.states.len());
    for k in 0..r.states.len() {
        let f = format!("vtu/fixture_{k:05}.vtu");
        assert!(pvd.contains(&f), "{pvd}");
        assert!(d.join(&f).exists());
    }
}

/// Frames and size of a GIF.
fn gif_frames(path: &Path) -> (usize, (u16, u16)) {
    let file = std::fs::File::open(path).expect("open gif");
    let mut opts = gif::DecodeOptions::new();
    opts.set_color_output(gif::ColorOutput::Indexed);
    let mut dec = opts.read_info(file).expect("gif header");
    let size = (dec.width(), dec.height());
    let mut n = 0;
    while dec.read_next_frame().expect("gif frame").is_some() {
        n += 1;
    }
    (n, size)
}

#[test]
fn movie_has_one_frame_per_offered_state_up_to_its_cap() {
    let r = load_fixture();
    let d = scratch("movie");
    let end = r.state("end").expect("end state");
    let snap = |k: usize, n: usize| {
        let mut s = snapshot_of(end);
        let w = k as f64 / (n - 1) as f64;
        s.t = w * end.t;
        s.u = end.u.iter().map(|u| [w * u[0], w * u[1]]).collect();
        s
    };
    let p = d.join("short.gif");
    let mut m = Movie::new(&p, "fixture", &r.mesh, 5).expect("movie");
    for k in 0..5 {
        m.frame(&snap(k, 5)).expect("frame");
    }
    m.finish().expect("finish");
    assert_eq!(
        gif_frames(&p),
        (5, (FRAME_SIZE.0 as u16, FRAME_SIZE.1 as u16))
    );

    // More outputs than MAX_FRAMES: every stride-th, and the last one.
    let n = 2 * MAX_FRAMES + 7;
    let p = d.join("long.gif");
    let mut m = Movie::new(&p, "fixture", &r.mesh, n).expect("movie");
    let stride = n.div_ceil(MAX_FRAMES);
    for k in 0..n {
        m.frame(&snap(k, n)).expect("frame");
    }
    m.finish().expect("finish");
    let expected = n.div_ceil(stride) + usize::from((n - 1) % stride != 0);
    assert_eq!(gif_frames(&p).0, expected);
    assert!(expected <= MAX_FRAMES + 1);
}

#[test]
fn run_writes_vtu_and_gif_per_output_time() {
    let exe = env!("CARGO_BIN_EXE_cellsim");
    let case = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/tiny-fall.ron");
    let d = scratch("run-vtu");
    let out = Command::new(exe)
        .args(["run", "--quiet", "--vtu", "--gif", "--out"])
        .arg(&d)
        .arg(&case)
        .output()
        .expect("run cellsim");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r = RunData::load(&d).expect("run loads");
    let n = r.series.len();
    let pvd = std::fs::read_to_string(d.join("tiny-fall.pvd")).expect("pvd");
    assert_eq!(pvd.matches("<DataSet ").count(), n);
    let last = d.join(format!("vtu/tiny-fall_{:05}.vtu", n - 1));
    let v = read_vtu(&last).expect("last vtu");
    assert_eq!(
        (v.points, v.cells),
        (r.mesh.nodes.len(), r.mesh.elements.len())
    );
    // Its displacement is the run's: u_y at p_t equals the CSV's last uy_top.
    let disp = v.displacement.expect("displacement");
    let top = r
        .mesh
        .nodes
        .iter()
        .position(|p| p[0] == 0.0 && (p[1] - 13.5).abs() < 1e-9)
        .expect("p_t is a node");
    let uy_top = r.series[n - 1].uy_top;
    assert!((disp[3 * top + 1] - uy_top).abs() <= 1e-12 * uy_top.abs().max(1.0));
    assert!(uy_top < -0.01, "the cell fell: {uy_top}");
    let (frames, size) = gif_frames(&d.join("tiny-fall.gif"));
    assert_eq!(size, (FRAME_SIZE.0 as u16, FRAME_SIZE.1 as u16));
    assert!((2..=MAX_FRAMES + 1).contains(&frames), "{frames} frames");
}

#[test]
fn comparison_uses_the_reported_table() {
    let r = load_fixture();
    // Our values from the stored run, read as if it were the push-pull scene.
    let disp = paper::our_value(Quantity::NucleusDisplacement(When::End), &r, None)
        .expect("final displacement");
    let max_down = r.series.iter().map(|o| -o.uy_top).fold(f64::MIN, f64::max);
    assert_eq!(disp, max_down);
    let g = paper::our_value(Quantity::NucleusDisplacement(When::GravityEnd), &r, None)
        .expect("at T_g0");
    let row = r.at(10000.0).expect("row at T_g0");
    assert_eq!(g, -row.uy_top);
    assert!(paper::our_value(Quantity::UpsideDownDifference, &r, None).is_err());
    assert_eq!(
        paper::our_value(Quantity::UpsideDownDifference, &r, Some(&r)),
        Ok(0.0)
    );
    // A partial run has no final value, and says why.
    let partial = RunData::load(interrupted_copy("partial-values")).expect("partial");
    let e = paper::our_value(Quantity::StrainNucleus, &partial, None).expect_err("no end");
    assert!(e.contains("stopped at t = "), "{e}");

    let runs = vec![SceneOutcome {
        name: "pillars-push-pull".into(),
        dir: fixture(),
        result: Ok(true),
    }];
    let data = vec![("pillars-push-pull".to_string(), r.clone())];
    let md = paper::comparison_markdown(&runs, &data);
    // Every reported value has a row; push-pull's are filled, the others say "no run".
    assert_eq!(
        md.lines().filter(|l| l.starts_with("| ")).count(),
        paper::REPORTED.len() + 1 + runs.len() + 1
    );
    let final_row = md
        .lines()
        .find(|l| l.starts_with("| pillars-push-pull | largest downward"))
        .expect("final displacement row");
    assert!(final_row.contains("| 9.650 |"), "{final_row}");
    assert!(final_row.contains(&format!("{disp:.3}")), "{final_row}");
    let rel = 100.0 * (disp - 9.65) / 9.65;
    assert!(final_row.contains(&format!("{rel:+.1} %")), "{final_row}");
    assert!(md.contains("| flat | contact radius at the end (µm) | 8.800 | n/a: no run |"));
    assert!(md.contains("| pillars-push-pull | finished |"), "{md}");
}

#[test]
fn paper_figures_from_stored_runs() {
    // Every scene pointed at the stored run: all the paper's files are drawn.
    let d = scratch("paper");
    let mut names: Vec<&str> = paper::SCENES.iter().map(|s| s.name).collect();
    names.push(paper::CONTROL);
    let runs: Vec<SceneOutcome> = names
        .iter()
        .map(|n| SceneOutcome {
            name: n.to_string(),
            dir: fixture(),
            result: Ok(false),
        })
        .collect();
    let report = paper::draw_paper(&d, &runs);
    assert!(report.problems.is_empty(), "{:?}", report.problems);
    for f in [
        "contact-radius.png",
        "nucleus-displacement.png",
        "upside-down.png",
        "strain-norms.png",
        "strain-time.png",
        "comparison.md",
    ] {
        assert!(d.join(f).exists(), "{f} missing");
    }
    for s in paper::SCENES {
        for phase in ["gravity", "spreading", "active", "end"] {
            let p = d.join(format!("shape-{}-{phase}.png", s.name));
            check_png(&p, SHAPE_SIZE, 0.2);
        }
    }
    check_png(&d.join("nucleus-displacement.png"), TIME_SIZE, 0.03);
    check_png(&d.join("upside-down.png"), UPSIDE_DOWN_SIZE, 0.03);
    // The reported values are one table, each scene's values from the paper's Sect. 3.
    assert_eq!(paper::reported_for("pillars-pull").count(), 5);
    assert!(
        paper::REPORTED
            .iter()
            .all(|r| r.value > 0.0 && !r.source.is_empty())
    );
    // The compiled-in scenes parse, and the control continues push-pull.
    let cases = cellsim::paper::paper_cases(None).expect("scene files");
    assert_eq!(cases.len(), 6);
    let control = &cases[5].0;
    assert_eq!(control.name, paper::CONTROL);
    assert_eq!(control.phases.t_end, cases[4].0.phases.t_end);
    assert_eq!(control.active, cases[3].0.active);
}
