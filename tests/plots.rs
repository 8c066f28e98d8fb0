//! Figures, VTU, GIF and the paper's comparison, from a stored run.
//!
//! The fixture `tests/data/small-push-pull/` is a complete run directory written by
//! `cellsim run tests/data/small-push-pull.ron --out tests/data/small-push-pull` (coarse
//! push-pull, 200 output times, four states). If the run file formats change
//! (`record::MeshFile`, `StateFile`, `Summary`), regenerate it with that command.

use std::path::{Path, PathBuf};
use std::process::Command;

use cellsim::fem::Domain;
use cellsim::model::observables::OLD_CSV_HEADER;
use cellsim::physics::Substrate;
use cellsim::render::RunData;
use cellsim::render::figures::{
    self, CYTOPLASM, Compared, DisplacementMarks, FOOT, GravityMark, LAYER, LAYER_EDGE, MEMBRANE,
    NUCLEUS, SHAPE_SIZE, SUBSTRATE, StrainBars, TIME_SIZE, UPSIDE_DOWN_SIZE,
};
use cellsim::render::geometry::{Backdrop, CellShape};
use cellsim::render::movie::{FRAME_SIZE, MAX_FRAMES, Movie};
use cellsim::render::paper::{self, Measure, Quantity, SceneOutcome, When};
use cellsim::render::vtu::{QUADRATIC_TRIANGLE, VtuSeries, read_vtu, write_vtu};
use cellsim::run_files::Observables;
use cellsim::run_files::Snapshot;
use cellsim::run_files::StateFile;
use cellsim::run_files::read::{ReadError, parse_timeseries};

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
    let reported = [(10000.0, 1.0), (55000.0, 8.8)].map(|(t, paper)| Compared {
        t,
        paper,
        ours: r.at(t).expect("row").contact_radius,
    });
    figures::contact_radius_figure(&p, &runs, &reported, "paper").expect("contact radius figure");
    check_png(&p, TIME_SIZE, 0.03);

    let p = d.join("disp.png");
    let marks = vec![DisplacementMarks {
        at_times: vec![Compared {
            t: 10000.0,
            paper: -0.1,
            ours: r.at(10000.0).expect("row").uy_top,
        }],
        maximum: Some(Compared {
            t: 55000.0,
            paper: -9.65,
            ours: r.series.last().expect("rows").uy_nucleus_max,
        }),
        maximum_top: paper::lowest_top(&r),
    }];
    figures::displacement_figure(&p, &runs, &marks, "paper").expect("displacement figure");
    check_png(&p, TIME_SIZE, 0.03);
    // The side panel of maxima (right third) holds the paper's hollow circle and our dot.
    let (w, _, px) = png(&p);
    let side = px
        .iter()
        .enumerate()
        .filter(|(k, c)| (*k as u32 % w) > w * 68 / 100 && **c == [31, 119, 180])
        .count();
    assert!(side > 50, "{side} pixels of our dot in the side panel");

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
        let scale = figures::shape_figure(&p, "fixture", &r.mesh, s, view, None).expect("shape");
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
    // Under the rounded foot of a pillar (x = 4.6, inside the pillar's width) the model's
    // substrate is two strips with a gap above the floor (the undercut)...
    let undercut = column(&b.substrate, 4.61);
    assert_eq!(undercut.len(), 2, "{undercut:?}");
    assert!(
        (undercut[1][1] - floor).abs() < 1e-6 && undercut[0][0] > floor + 0.3,
        "{undercut:?}"
    );
    // ...which the pillar's foot fills: across the pillar's width, substrate and foot
    // together are one piece from below the floor to the pillar's top, so the pillar is
    // drawn standing on its floor. Outside the width (mid-gap) there is no foot.
    let solid_from_floor = |x: f64| -> f64 {
        let mut pieces = column(&b.substrate, x);
        pieces.extend(column(&b.foot, x));
        pieces.sort_by(|a, b| a[0].total_cmp(&b[0]));
        let mut reach = view[2];
        for [lo, hi] in pieces {
            if lo > reach + 1e-9 {
                break;
            }
            reach = reach.max(hi);
        }
        reach
    };
    for x in [4.05, 4.3, 4.61, 5.5, 8.01, 11.7, 11.95, -4.3, -11.95] {
        let top_x = top(&b.substrate, x);
        let reach = solid_from_floor(x);
        assert!(
            (reach - top_x).abs() < 1e-9,
            "x = {x}: solid from the floor up to {reach}, pillar top {top_x}"
        );
    }
    assert!(column(&b.foot, 0.01).is_empty() && column(&b.foot, 3.9).is_empty());
    assert!(column(&b.foot, 12.1).is_empty());
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
    let e = cellsim::run_files::read::read_summary(&d).expect_err("older summary");
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
    // The paper's maximum is compared with the lowest point of the nucleus over the run.
    let max_down = r
        .series
        .iter()
        .map(|o| -o.uy_nucleus_max)
        .fold(f64::MIN, f64::max);
    assert_eq!(disp, max_down);
    let (t_low, low) = paper::lowest_nucleus(&r).expect("rows");
    assert_eq!(-low, disp);
    assert_eq!(r.at(t_low).expect("row").uy_nucleus_max, low);
    // p_t's lowest is the other measure, shown beside it.
    let top = paper::measure_value(
        Quantity::NucleusDisplacement(When::End),
        Measure::NucleusTop,
        &r,
        None,
    )
    .expect("p_t's lowest");
    let (_, low_top) = paper::lowest_top(&r).expect("rows");
    assert_eq!(top, -low_top);
    assert!(
        top < disp,
        "p_t {top} is not the nucleus's lowest point {disp}"
    );
    // Values at a time are p_t's, as on Fig. 9's curve.
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
    assert!(e.to_string().contains("stopped at t = "), "{e}");

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
    let final_row = cells(&md, "| pillars-push-pull | maximum downward");
    assert_eq!(final_row[3], "9.650");
    assert_eq!(final_row[4], format!("{disp:.3}"));
    let rel = 100.0 * (disp - 9.65) / 9.65;
    assert_eq!(final_row[5], format!("{rel:+.1} %"));
    assert!(final_row[2].contains("`uy_nucleus_max`"), "{final_row:?}");
    assert!(
        final_row[6].contains("`uy_top`") && final_row[6].contains(&format!("{top:.3}")),
        "{final_row:?}"
    );
    assert!(md.contains(
        "| flat | contact radius at the end (µm) | reference-frame contour length in contact \
         (`contact_radius_ref`), the paper's definition | 8.800 | n/a: no run | – | – |"
    ));
    assert!(md.contains("| pillars-push-pull | finished |"), "{md}");
}

/// The cells of the table row of `md` starting with `start`, trimmed.
fn cells(md: &str, start: &str) -> Vec<String> {
    let line = md
        .lines()
        .find(|l| l.starts_with(start))
        .unwrap_or_else(|| panic!("no row {start}"));
    line.trim_matches('|')
        .split(" | ")
        .map(|c| c.trim().to_string())
        .collect()
}

#[test]
fn comparison_uses_the_papers_measures() {
    let r = load_fixture();
    let t_end = r.t_end();
    let end = r.at(t_end).expect("last row");
    // The fixture's contacting membrane is stretched: the two frames differ.
    assert!(
        end.contact_radius > 1.05 * end.contact_radius_ref,
        "{} vs {}",
        end.contact_radius,
        end.contact_radius_ref
    );
    // Every scene pointed at the stored run.
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
    let data: Vec<(String, RunData)> = names.iter().map(|n| (n.to_string(), r.clone())).collect();
    let md = paper::comparison_markdown(&runs, &data);
    // Contact radius: the reference frame compared, the deformed one beside it.
    let row = cells(&md, "| flat | contact radius at the end");
    assert!(row[2].contains("reference-frame"), "{row:?}");
    assert_eq!(row[4], format!("{:.3}", end.contact_radius_ref), "{row:?}");
    let rel = 100.0 * (end.contact_radius_ref - 8.8) / 8.8;
    assert_eq!(row[5], format!("{rel:+.1} %"));
    assert!(
        row[6].starts_with("deformed contour length (`contact_radius`): ")
            && row[6].contains(&format!("{:.3}", end.contact_radius)),
        "{row:?}"
    );
    // Cytoplasm: with the membrane (the paper's Ω_cp) compared; without it and the
    // membrane alone beside it.
    let row = cells(&md, "| pillars-push | mean ‖E‖ of the cytoplasm");
    assert!(row[2].contains("incl. membrane"), "{row:?}");
    assert_eq!(row[4], format!("{:.1}", 100.0 * end.strain_cytoplasm));
    let (a_cp, a_m) = (
        r.mesh.area(Domain::Cytoplasm),
        r.mesh.area(Domain::Membrane),
    );
    let alone = paper::cytoplasm_alone(&end, a_cp, a_m);
    assert!(
        row[6].contains(&format!("without the membrane: {:.1}", 100.0 * alone))
            && row[6].contains(&format!(
                "(`strain_membrane`): {:.1}",
                100.0 * end.strain_membrane
            )),
        "{row:?}"
    );
    // Every row names its measure, a column of timeseries.csv.
    for rep in paper::REPORTED.iter() {
        let (m, _) = rep.quantity.measures();
        let d = m.describe(rep.quantity);
        assert!(d.contains('`'), "{d}");
        assert!(
            md.lines().any(|l| l.starts_with(&format!(
                "| {} | {} | {d} |",
                rep.scene,
                rep.quantity.describe()
            ))),
            "no row for {rep:?} with {d}"
        );
    }
}

#[test]
fn cytoplasm_alone_undoes_the_membrane() {
    let r = load_fixture();
    // The three domains tile the half disc of radius r_c.
    let areas = [Domain::Nucleus, Domain::Cytoplasm, Domain::Membrane].map(|d| r.mesh.area(d));
    assert!(areas.iter().all(|a| *a > 0.0), "{areas:?}");
    let c = r.mesh.center;
    let r_c = r
        .mesh
        .nodes
        .iter()
        .map(|p| (p[0] - c[0]).hypot(p[1] - c[1]))
        .fold(0.0, f64::max);
    let half_disc = 0.5 * std::f64::consts::PI * r_c * r_c;
    let total: f64 = areas.iter().sum();
    assert!(
        (total - half_disc).abs() < 1e-3 * half_disc,
        "{total} against {half_disc}"
    );
    // Means over the union undone: cytoplasm 0.6 over 3 µm², membrane 0.2 over 1 µm²
    // make 0.5 over both.
    let o = Observables {
        strain_cytoplasm: 0.5,
        strain_membrane: 0.2,
        ..Default::default()
    };
    assert!((paper::cytoplasm_alone(&o, 3.0, 1.0) - 0.6).abs() < 1e-15);
}

#[test]
fn contact_radius_marks_sit_on_the_reference_frame_curve() {
    let mut r = load_fixture();
    r.name = "flat".into();
    let compared = paper::contact_radius_compared(&r);
    assert_eq!(compared.len(), 2, "{compared:?}");
    let end = compared[1];
    assert_eq!(end.paper, 8.8);
    assert_eq!(end.ours, r.at(end.t).expect("row").contact_radius_ref);
    let plot = figures::contact_radius_plot(&[&r], &compared, "paper");
    let reference = plot
        .curves
        .iter()
        .find(|c| c.label.contains(figures::CONTACT_REFERENCE_LABEL))
        .expect("reference-frame curve");
    let deformed = plot
        .curves
        .iter()
        .find(|c| c.label.contains(figures::CONTACT_DEFORMED_LABEL))
        .expect("deformed-frame curve");
    assert_eq!(reference.stroke, figures::Stroke::Solid);
    assert_eq!(deformed.stroke, figures::Stroke::Dashed);
    // Our dots (filled marks) are points of the solid curve, not of the dashed one.
    let dots: Vec<(f64, f64)> = plot
        .marks
        .iter()
        .filter(|m| m.filled)
        .flat_map(|m| m.points.iter().copied())
        .collect();
    assert_eq!(dots.len(), 2);
    for d in &dots {
        assert!(
            reference.points.contains(d),
            "{d:?} not on the reference curve"
        );
    }
    assert!(
        !deformed.points.contains(&dots[1]),
        "the end dot is on the deformed curve"
    );
    // The paper's circles are joined to those dots.
    assert_eq!(
        plot.links,
        compared
            .iter()
            .map(|c| (c.t, c.paper, c.ours))
            .collect::<Vec<_>>()
    );
}

#[test]
fn nucleus_maximum_set_against_the_lowest_point_of_the_nucleus() {
    let r = load_fixture();
    let m = paper::displacement_marks("pillars-pull", &r);
    let max = m.maximum.expect("maximum");
    let (t, low) = paper::lowest_nucleus(&r).expect("rows");
    assert_eq!((max.t, max.paper, max.ours), (t, -9.63, low));
    assert_eq!(m.maximum_top, paper::lowest_top(&r));
    // At T_g0 and T_as0 on the p_t curve.
    assert_eq!(m.at_times.len(), 2);
    for c in &m.at_times {
        assert_eq!(c.ours, r.at(c.t).expect("row").uy_top);
    }
    // A scene the paper reports nothing for has no marks.
    assert_eq!(
        paper::displacement_marks("flat", &r),
        figures::DisplacementMarks::default()
    );
    // The side panel draws the square of p_t's lowest beside the dot.
    let d = scratch("maxima");
    let p = d.join("disp.png");
    figures::displacement_figure(&p, &[&r], std::slice::from_ref(&m), "paper").expect("figure");
    let (w, _, px) = png(&p);
    let blue = [31u8, 119, 180];
    let side_x0 = (w as f64 * 0.68) as u32;
    let without = figures::DisplacementMarks {
        maximum_top: None,
        ..m
    };
    let p2 = d.join("disp-no-top.png");
    figures::displacement_figure(&p2, &[&r], &[without], "paper").expect("figure");
    let (_, _, px2) = png(&p2);
    let count = |px: &[[u8; 3]]| {
        px.iter()
            .enumerate()
            .filter(|(k, c)| (*k as u32 % w) > side_x0 && **c == blue)
            .count()
    };
    assert!(
        count(&px) > count(&px2) + 50,
        "the square adds no blue to the side panel: {} vs {}",
        count(&px),
        count(&px2)
    );
}

#[test]
fn strain_curves_are_the_papers_cytoplasm() {
    let r = load_fixture();
    let plot = figures::strain_time_plot(&[&r]);
    let dashed: Vec<_> = plot
        .curves
        .iter()
        .filter(|c| c.stroke == figures::Stroke::Dashed && !c.points.is_empty())
        .collect();
    assert_eq!(dashed.len(), 1);
    let expected: Vec<(f64, f64)> = r
        .series
        .iter()
        .map(|o| (o.t, 100.0 * o.strain_cytoplasm))
        .collect();
    assert_eq!(dashed[0].points, expected);
    // The legend says so.
    assert!(
        plot.curves
            .iter()
            .any(|c| c.stroke == figures::Stroke::Dashed && c.label == figures::CYTOPLASM_LABEL)
    );
    assert!(figures::CYTOPLASM_LABEL.contains("incl. membrane"));
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
    let cases = cellsim::commands::paper::paper_cases(None).expect("scene files");
    assert_eq!(cases.len(), 6);
    let control = &cases[5].0;
    assert_eq!(control.name, paper::CONTROL);
    assert_eq!(control.phases.t_end, cases[4].0.phases.t_end);
    assert_eq!(control.active, cases[3].0.active);
}

#[test]
fn contact_radius_and_strain_axes_start_at_zero() {
    let r = load_fixture();
    let runs = [&r];
    // The fixture starts at 0 (no contact, no strain): a padded axis would start below.
    let contact = figures::contact_radius_plot(&runs, &[], "");
    let (lo, hi) = figures::value_range(&contact);
    assert_eq!(lo, 0.0);
    let top = r
        .series
        .iter()
        .map(|o| o.contact_radius)
        .fold(0.0, f64::max);
    assert!(hi > top, "{hi} above {top}");
    let strain = figures::strain_time_plot(&runs);
    assert_eq!(figures::value_range(&strain).0, 0.0);
    // The rule: 0 when asked and nothing is negative; padded otherwise.
    let vals = [1.2, 13.9];
    assert_eq!(figures::value_axis(vals.into_iter(), true, 0).0, 0.0);
    assert!(figures::value_axis(vals.into_iter(), false, 0).0 > 0.0);
    let (lo, _) = figures::value_axis([-0.5, 3.0].into_iter(), true, 0);
    assert!(lo < -0.5, "{lo}");
}

#[test]
fn identical_runs_are_found_and_named() {
    let r = load_fixture();
    // A copy of the run that leaves it at t = 40 000 s.
    let mut other = r.clone();
    other.name = "pillars-pull".into();
    let k = other
        .series
        .iter()
        .position(|o| o.t > 40000.0)
        .expect("rows after T_as0");
    for o in &mut other.series[k..] {
        o.uy_top -= 1e-6;
    }
    let mut first = r.clone();
    first.name = "pillars-push".into();
    assert_eq!(
        figures::identical_until(&[&first, &other]),
        Some(other.series[k - 1].t)
    );
    assert_eq!(other.series[k - 1].t, 40000.0);
    let note = figures::identical_note(&[&first, &other], "push, pull").expect("a note");
    assert_eq!((note.from, note.to), (0.0, 40000.0));
    assert!(
        note.text.contains("push, pull") && note.text.contains("40 000 s = T_as0"),
        "{}",
        note.text
    );
    assert_eq!(
        figures::short_names(&[&first, &other]),
        vec!["push".to_string(), "pull".to_string()]
    );
    // One run, or runs apart from the first row: no note.
    assert_eq!(figures::identical_until(&[&r]), None);
    let mut apart = r.clone();
    apart.series[0].contact_radius += 1.0;
    assert_eq!(figures::identical_until(&[&r, &apart]), None);
    assert!(figures::identical_note(&[&r, &apart], "x").is_none());
    // The same run twice: identical throughout.
    assert_eq!(figures::identical_until(&[&r, &r]), Some(r.t_last()));
}

#[test]
fn strain_bar_panels_share_their_scale() {
    let d = scratch("bars-scale");
    // Equal paper values in both domains, ours far apart: the grey bars must be equally
    // tall in both panels.
    let bars = vec![StrainBars {
        scene: "push".into(),
        paper_nucleus: Some(0.5),
        ours_nucleus: Some(0.2),
        paper_cytoplasm: Some(0.5),
        ours_cytoplasm: Some(0.9),
    }];
    assert!((figures::strain_bars_top(&bars) - 117.0).abs() < 1e-9);
    let p = d.join("bars.png");
    figures::strain_bars_figure(&p, &bars, "ours", "paper").expect("bars figure");
    let (w, h, px) = png(&p);
    let grey = [170u8, 170, 170];
    // Height of the grey bar: the rows holding a long run of grey pixels, per half.
    let bar_rows = |x0: u32, x1: u32| {
        (0..h)
            .filter(|y| {
                (x0..x1)
                    .filter(|x| px[(y * w + x) as usize] == grey)
                    .count()
                    > 40
            })
            .count()
    };
    let (left, right) = (bar_rows(0, w / 2), bar_rows(w / 2, w));
    assert!(left > 100, "{left} rows");
    assert!(
        left.abs_diff(right) <= 2,
        "grey bars {left} and {right} px tall"
    );
}

#[test]
fn timings_stay_out_of_the_comparison() {
    let r = load_fixture();
    let outcome = |reused: bool| {
        vec![SceneOutcome {
            name: "pillars-push-pull".into(),
            dir: fixture(),
            result: Ok(!reused),
        }]
    };
    let data = vec![("pillars-push-pull".to_string(), r.clone())];
    // The same physics with another wall time and step count, reused or not.
    let mut slower = r.clone();
    let sm = slower.summary.as_mut().expect("summary");
    sm.wall_seconds = 1234.5;
    sm.stats.steps += 7;
    let data_slower = vec![("pillars-push-pull".to_string(), slower)];
    let md = paper::comparison_markdown(&outcome(false), &data);
    assert_eq!(
        md,
        paper::comparison_markdown(&outcome(true), &data_slower),
        "comparison.md changed with the wall time, steps or reuse"
    );
    let wall = format!("{:.1}", r.summary.as_ref().expect("summary").wall_seconds);
    assert!(
        !md.contains("wall (s)") && !md.contains(&format!("| {wall} |")),
        "{md}"
    );
    assert!(md.contains(paper::TIMINGS_FILE));
    // The timings file has them.
    let t = paper::timings_markdown(&outcome(false), &data);
    assert!(t.contains(&format!("| {wall} |")), "{t}");
    let t2 = paper::timings_markdown(&outcome(true), &data_slower);
    assert!(
        t2.contains("| 1234.5 |") && t2.contains("finished (reused)"),
        "{t2}"
    );
    // cellsim paper writes both, apart.
    let d = scratch("timings");
    let report = paper::draw_paper(&d, &outcome(false));
    assert!(report.problems.is_empty(), "{:?}", report.problems);
    let written = std::fs::read_to_string(d.join(paper::COMPARISON_FILE)).expect("comparison");
    assert_eq!(written, md);
    assert!(d.join(paper::TIMINGS_FILE).exists());
    // plots/timings.md is not under version control.
    let ignore = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join(".gitignore"))
        .expect(".gitignore");
    assert!(
        ignore.lines().any(|l| l.trim() == "/plots/timings.md"),
        "{ignore}"
    );
}

#[test]
fn layer_edge_is_drawn_under_the_cell() {
    let r = load_fixture();
    let d = scratch("layer-edge");
    let end = r.state("end").expect("end state");
    let states: Vec<&StateFile> = r.states.iter().collect();
    let view = figures::shape_view(&r.mesh, &states);
    // The layer's edge alone (the cell moved far out of the view), then under the cell.
    let away = StateFile {
        u: vec![[0.0, 1000.0]; r.mesh.nodes.len()],
        ..end.clone()
    };
    let count = |s: &StateFile, name: &str| {
        let p = d.join(name);
        figures::shape_figure(&p, "fixture", &r.mesh, s, view, None).expect("shape");
        count_color(&png(&p).2, LAYER_EDGE)
    };
    let alone = count(&away, "away.png");
    let under = count(end, "end.png");
    assert!(alone > 2000, "{alone} edge pixels");
    // At the end the cell sits in the layer between the pillars: the edge there is hidden.
    assert!(
        (under as f64) < 0.9 * alone as f64,
        "edge pixels {under} with the cell, {alone} without"
    );
}

#[test]
fn pillars_are_drawn_standing_on_their_floor() {
    let r = load_fixture();
    let d = scratch("foot");
    let s = r.state("gravity").expect("state");
    let view = figures::shape_view(&r.mesh, &[s]);
    let p = d.join("shape.png");
    figures::shape_figure(&p, "fixture", &r.mesh, s, view, None).expect("shape");
    let px = png(&p).2;
    // Four feet (two undercut wedges each) in view, a few hundred pixels of foot fill.
    assert!(count_color(&px, FOOT) > 400, "{}", count_color(&px, FOOT));
}

#[test]
fn gravity_is_shown_down_or_flipped() {
    use cellsim::physics::{Flip, Phases};
    let plain = Phases {
        t_g0: 10000.0,
        adhesion: Some([10000.0, 40000.0]),
        active: Some([40000.0, 50000.0]),
        flip: None,
    };
    let g = GravityMark::at(&plain, 50000.0);
    assert_eq!(g.factor, 1.0);
    assert_eq!(g.note, "gravity");
    let flipped = Phases {
        flip: Some(Flip {
            start: 50000.0,
            duration: 10000.0,
        }),
        ..plain
    };
    let before = GravityMark::at(&flipped, 50000.0);
    assert_eq!(before.factor, 1.0);
    assert!(before.note.contains("flipped later"), "{}", before.note);
    let during = GravityMark::at(&flipped, 55000.0);
    assert!(during.factor.abs() < 1e-12 && during.note.contains("flipping"));
    let after = GravityMark::at(&flipped, 60000.0);
    assert_eq!(after.factor, -1.0);
    assert!(after.note.contains("upside down"), "{}", after.note);
    // The arrow is drawn: black pixels in the upper left corner that are not there
    // without it.
    let r = load_fixture();
    let d = scratch("gravity");
    let s = r.state("end").expect("state");
    let view = figures::shape_view(&r.mesh, &[s]);
    let corner_black = |ph: Option<&Phases>, name: &str| {
        let p = d.join(name);
        figures::shape_figure(&p, "fixture", &r.mesh, s, view, ph).expect("shape");
        let (w, _, px) = png(&p);
        px.iter()
            .enumerate()
            .filter(|(k, c)| {
                let (x, y) = (*k as u32 % w, *k as u32 / w);
                (120..300).contains(&x) && (60..200).contains(&y) && **c == [0, 0, 0]
            })
            .count()
    };
    let with = corner_black(Some(&flipped), "with.png");
    let without = corner_black(None, "without.png");
    assert!(
        with > without + 300,
        "{with} black pixels, {without} without"
    );
    // A run's phases come from its case file (the fixture's has no flip).
    let ph = figures::run_phases(&r).expect("the fixture's case file loads");
    assert!(ph.flip.is_none());
    assert_eq!(ph.times()[2], r.mesh.phase_times[2]);
}
