//! Draws every figure of the 3-D quarter cell ([`cellsim::render::cell3d_views`]), a VTU file
//! and a GIF into a directory, from states built here:
//!
//! - a synthetic smooth deformation of the default mesh
//!   (`cellsim::scene::terms::tet_mesh_params(&cellsim::case::Case::reference())`, meshed
//!   by gmsh and cached): the cell fallen 0.5 µm, its bottom sagged into the gap under its
//!   centre, flattened and bulging sideways, over MODEL.md's pillars on both lattices (four
//!   pillars around the axis; the gap between two), with both active regions and the
//!   fibronectin layer;
//! - with `--real`, a computed state: the quasi-static flat gravity phase of the quarter
//!   cell integrated by IDA (as `tests/model3d.rs`'s check against the axisymmetric model,
//!   on its coarse mesh: about a minute).
//!
//! ```sh
//! cargo run --release --example figures3 -- OUT_DIR [--real]
//! ```

use std::path::{Path, PathBuf};
use std::time::Instant;

use cellsim::case::{self, Case};
use cellsim::dae::{Atol, Integrator};
use cellsim::fem::{Domain, TetMesh, TetMeshParams, TetRule, TetTabulation};
use cellsim::model::ModelParams;
use cellsim::model::QuarterCell;
use cellsim::physics::{Lattice, LatticeSubstrate, Substrate};
use cellsim::render::cell3d_views::{
    Coloring, FIGURE_SIZE, Section, draw_section, gravity_at, section_figure, surface_figure,
};
use cellsim::render::figures::ShapeStyleOptions;
use cellsim::render::geometry::Bounds;
use cellsim::render::movie::{MovieView, QuarterMovie};
use cellsim::render::vtu::write_vtu;
use cellsim::run_files::{QuarterMeshFile, QuarterSnapshot, write_json};
use cellsim::scene;
use cellsim::sundials::{Ida, IdaOptions};
use nalgebra::Matrix3;
use plotters::prelude::*;

/// The mesh file of `mesh` with the model parameters `p` on `lattice`.
fn mesh_file(mesh: &TetMesh, p: &ModelParams, lattice: Lattice) -> QuarterMeshFile {
    let ph = &p.phases;
    QuarterMeshFile {
        nodes: mesh.nodes.clone(),
        elements: mesh.elements.clone(),
        domains: mesh.domains.clone(),
        outer_faces: mesh.outer_faces.clone(),
        substrate: LatticeSubstrate {
            plane: p.substrate,
            lattice,
        },
        active: p.active,
        contact_eps: p.contact.eps,
        layer_thickness: p.adhesion.map(|a| a.e_f),
        center: [p.center[0], p.center[1], 0.0],
        phase_times: {
            let [tg, tas, ta] = ph.times();
            [
                tg,
                tas,
                ta,
                p.extra_breakpoints.last().copied().unwrap_or(ta),
            ]
        },
    }
}

/// Per element: the reference-volume means of ‖E‖_F and of det F under the displacement
/// `u` (a degree-4 rule: the means of the run's snapshots).
fn element_means(mesh: &QuarterMeshFile, u: &[[f64; 3]]) -> (Vec<f64>, Vec<f64>) {
    let tab = TetTabulation::new(&TetRule::degree(4));
    let (mut strain, mut jac) = (Vec::new(), Vec::new());
    for el in &mesh.elements {
        let x = el.map(|i| mesh.nodes[i]);
        let geo = tab.geometry(&x).expect("a valid reference element");
        let (mut se, mut sj, mut vol) = (0.0, 0.0, 0.0);
        for q in 0..geo.jxw.len() {
            let mut f = Matrix3::<f64>::identity();
            for a in 0..10 {
                for i in 0..3 {
                    for j in 0..3 {
                        f[(i, j)] += u[el[a]][i] * geo.grads[q][a][j];
                    }
                }
            }
            let e = (f.transpose() * f - Matrix3::identity()) * 0.5;
            se += geo.jxw[q] * e.norm();
            sj += geo.jxw[q] * f.determinant();
            vol += geo.jxw[q];
        }
        strain.push(se / vol);
        jac.push(sj / vol);
    }
    (strain, jac)
}

/// A snapshot at `t` of the displacement `u`, velocity `v`, with the element means.
fn snapshot(mesh: &QuarterMeshFile, t: f64, u: Vec<[f64; 3]>, v: Vec<[f64; 3]>) -> QuarterSnapshot {
    let (element_strain, element_jacobian) = element_means(mesh, &u);
    let membrane: Vec<bool> = {
        let mut m = vec![false; mesh.nodes.len()];
        for (el, d) in mesh.elements.iter().zip(&mesh.domains) {
            if *d == Domain::Membrane {
                for &i in el {
                    m[i] = true;
                }
            }
        }
        m
    };
    let mu_as = membrane
        .iter()
        .zip(&u)
        .map(|(&m, d)| (m && mesh.layer_thickness.is_some()).then_some(-2e8 * d[1].min(0.0)))
        .collect();
    QuarterSnapshot {
        t,
        u,
        v,
        mu_as,
        element_strain,
        element_jacobian,
    }
}

/// softplus with sharpness β: ≈ max(s, 0), smooth.
fn softplus(s: f64, beta: f64) -> f64 {
    (beta * s).max(0.0) / beta + (-(beta * s).abs()).exp().ln_1p() / beta
}

/// The synthetic deformation at reference point `x` (centre `c`, radius `r_c`), scaled by
/// `w` ∈ [0, 1]: a fall of 0.5 µm, a sag of the bottom under the centre (1.5 µm on the
/// axis, Gaussian of width 4 µm), the bottom flattened at 0.6 µm above the sagged lowest
/// point, and a sideways bulge near the bottom. Symmetric about x = 0 and z = 0.
fn synthetic_u(x: [f64; 3], c: [f64; 3], r_c: f64, w: f64) -> [f64; 3] {
    let p = [x[0] - c[0], x[1] - c[1], x[2] - c[2]];
    let rho2 = p[0] * p[0] + p[2] * p[2];
    let from_bottom = (p[1] + r_c) / (2.0 * r_c); // 0 at the bottom, 1 at the top
    let sag = 1.5 * (-rho2 / (2.0 * 16.0)).exp() * (1.0 - from_bottom).powi(2);
    let y1 = x[1] - w * (0.5 + sag);
    let lowest = c[1] - r_c - w * 2.0;
    let y_f = lowest + w * 0.6;
    let y2 = if w > 0.0 {
        y_f + softplus(y1 - y_f, 4.0)
    } else {
        y1
    };
    let bulge = w * 0.1 * (-(p[1] + r_c).powi(2) / (2.0 * 9.0)).exp();
    [bulge * p[0], y2 - x[1], bulge * p[2]]
}

fn synthetic(mesh: &QuarterMeshFile, w: f64, t: f64) -> QuarterSnapshot {
    let c = mesh.center;
    let u: Vec<[f64; 3]> = mesh
        .nodes
        .iter()
        .map(|&x| synthetic_u(x, c, 10.0, w))
        .collect();
    let v = vec![[0.0; 3]; u.len()];
    snapshot(mesh, t, u, v)
}

fn draw_all(
    out: &Path,
    tag: &str,
    mesh: &QuarterMeshFile,
    s: &QuarterSnapshot,
    what: &str,
) -> Vec<PathBuf> {
    let mut written = Vec::new();
    for plane in Section::ALL {
        let p = out.join(format!("{tag}-section-{}.png", plane.tag()));
        let t0 = Instant::now();
        section_figure(
            &p,
            mesh,
            s,
            plane,
            &format!("{what}: section {}, t = {} s", plane.name(), s.t),
        )
        .expect("section figure");
        eprintln!("{} ({:.2} s)", p.display(), t0.elapsed().as_secs_f64());
        written.push(p);
    }
    // A close-up of the cell's bottom in the diagonal section: the cut's detail.
    let p = out.join(format!("{tag}-section-diagonal-bottom.png"));
    {
        let root = BitMapBackend::new(&p, FIGURE_SIZE).into_drawing_area();
        root.fill(&WHITE).expect("fill");
        let c = mesh.center;
        let view = Bounds {
            x_min: -8.0,
            x_max: 8.0,
            y_min: c[1] - 13.0,
            y_max: c[1] - 3.0,
        };
        let opts = ShapeStyleOptions {
            title: format!("{what}: section x = z, the bottom, t = {} s", s.t),
            legend: false,
            font: 28,
            mesh_lines: true,
            gravity: Some(gravity_at(mesh, s.t)),
        };
        draw_section(&root, mesh, &s.u, Section::Diagonal, view, &opts, &mut None)
            .expect("close-up");
        root.present().expect("png");
    }
    written.push(p);
    for (coloring, name) in [(Coloring::Domain, "domain"), (Coloring::Strain, "strain")] {
        let p = out.join(format!("{tag}-surface-{name}.png"));
        let t0 = Instant::now();
        let title = match coloring {
            Coloring::Domain => format!("{what}, t = {} s", s.t),
            Coloring::Strain => format!("{what}: element mean ‖E‖ on the surface, t = {} s", s.t),
        };
        surface_figure(&p, mesh, s, coloring, &title).expect("surface figure");
        eprintln!("{} ({:.2} s)", p.display(), t0.elapsed().as_secs_f64());
        written.push(p);
    }
    written
}

/// The last frame of the GIF at `path` as a PNG beside it (`<name>-last.png`), to look at.
fn last_frame_png(path: &Path) -> PathBuf {
    let mut opts = gif::DecodeOptions::new();
    opts.set_color_output(gif::ColorOutput::RGBA);
    let mut dec = opts
        .read_info(std::fs::File::open(path).expect("open gif"))
        .expect("gif header");
    let (w, h) = (dec.width() as u32, dec.height() as u32);
    let mut last = None;
    while let Some(f) = dec.read_next_frame().expect("gif frame") {
        last = Some(f.buffer.to_vec());
    }
    let rgb: Vec<u8> = last
        .expect("a frame")
        .chunks_exact(4)
        .flat_map(|p| [p[0], p[1], p[2]])
        .collect();
    let png = path.with_file_name(format!(
        "{}-last.png",
        path.file_stem().unwrap().to_string_lossy()
    ));
    {
        let root = BitMapBackend::new(&png, (w, h)).into_drawing_area();
        let img =
            BitMapElement::<(i32, i32)>::with_owned_buffer((0, 0), (w, h), rgb).expect("size");
        root.draw(&img).expect("blit");
        root.present().expect("png");
    }
    png
}

/// The pillar case's parameters on `lattice`, the tops placed for the 0.5 µm gap in 3-D.
fn pillar_params(lattice: Lattice) -> ModelParams {
    let mut c = Case::reference_active();
    c.substrate = case::Substrate::pillars();
    let mut p = scene::model_params(&c, "pillars-3d", false).expect("a valid case");
    if let Substrate::Pillars(pl) = &mut p.substrate {
        let c3 = [p.center[0], p.center[1], 0.0];
        pl.y_top = pl
            .y_top_for_gap_on_lattice(0.5, lattice, c3, c.geometry.r_c)
            .expect("placed");
    }
    p
}

/// The flat gravity phase of the quarter cell, quasi-statically (tests/model3d.rs), kept
/// in `OUT_DIR/flat-gravity-{mesh,state}.json`: a second `--real` redraws from them.
fn real_state(out: &Path) -> Vec<PathBuf> {
    let (mesh_json, state_json) = (
        out.join("flat-gravity-mesh.json"),
        out.join("flat-gravity-state.json"),
    );
    let read = |p: &Path| std::fs::read_to_string(p).ok();
    let (mf, s) = match (read(&mesh_json), read(&state_json)) {
        (Some(m), Some(st)) => {
            eprintln!("the computed state from {}", state_json.display());
            (
                serde_json::from_str(&m).expect("a mesh file"),
                serde_json::from_str(&st).expect("a state"),
            )
        }
        _ => {
            let (mf, s) = integrate_flat_gravity();
            write_json(&mesh_json, &mf).expect("mesh json");
            write_json(&state_json, &s).expect("state json");
            (mf, s)
        }
    };
    let vtu = out.join("flat-gravity.vtu");
    write_vtu(&vtu, &mf, &s).expect("vtu");
    let mut files = draw_all(
        out,
        "flat-gravity",
        &mf,
        &s,
        "flat, end of gravity (computed)",
    );
    files.push(vtu);
    files
}

fn integrate_flat_gravity() -> (QuarterMeshFile, QuarterSnapshot) {
    let t_end = 150.0;
    let mut c = Case::reference();
    c.phases.t_g0 = 100.0;
    c.phases.t_as0 = 200.0;
    c.phases.t_a0 = 300.0;
    c.phases.t_end = t_end;
    c.adhesion = None;
    c.inertia.mode = case::InertiaMode::Off;
    c.inertia.drag = 1e-6;
    c.validate().expect("a valid case");
    let p = scene::model_params(&c, "quasi-static", false).expect("a valid case");
    let g = Case::reference().geometry;
    let centre = g.centre();
    let mesh = TetMesh::generate(&TetMeshParams {
        center: [centre[0], centre[1], 0.0],
        wedge: cellsim::fem::Wedge::Quarter,
        r_n: g.r_n,
        r_cp: g.r_cp,
        r_c: g.r_c,
        h_bottom: 0.6,
        h_nucleus: 1.5,
        refine: 1.0,
        h_surface: None,
    })
    .expect("the quarter cell meshes");
    let lattice = Lattice::FourPillars;
    let mf = mesh_file(&mesh, &p, lattice);
    let params = ModelParams {
        kinematics: cellsim::physics::KinematicModel::ThreeD,
        lattice,
        ..p
    };
    let m = QuarterCell::new(params, mesh).expect("the model builds");
    let atol = m.atol_vector(1e-7);
    let t0 = Instant::now();
    let mut ida = Ida::new(
        m,
        IdaOptions {
            rtol: 1e-5,
            atol: Atol::Vector(atol),
            ..Default::default()
        },
    )
    .expect("IDA starts");
    ida.advance_to(t_end, &mut |_, _| true).expect("integrates");
    eprintln!("flat gravity phase: {:.1} s", t0.elapsed().as_secs_f64());
    let m = ida.dae();
    let (y, yp) = (ida.y(), ida.yp());
    let n = m.mesh.nodes.len();
    let u: Vec<[f64; 3]> = (0..n).map(|i| m.dofs.node_u(y, i)).collect();
    let v: Vec<[f64; 3]> = (0..n).map(|i| m.dofs.node_u(yp, i)).collect();
    let o = m.observe(t_end, y);
    eprintln!(
        "u_y(p_t) {:.4} µm, contact radius {:.3} µm",
        o.uy_top, o.contact_radius
    );
    let s = snapshot(&mf, t_end, u, v);
    (mf, s)
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let out = PathBuf::from(
        args.iter()
            .find(|a| !a.starts_with("--"))
            .expect("usage: figures3 OUT_DIR [--real]"),
    );
    std::fs::create_dir_all(&out).expect("create the output directory");
    let t0 = Instant::now();
    let mesh = TetMesh::generate(&cellsim::scene::terms::tet_mesh_params(
        &cellsim::case::Case::reference(),
    ))
    .expect("the default mesh");
    eprintln!(
        "default mesh: {} tetrahedra, {} nodes ({:.1} s)",
        mesh.elements.len(),
        mesh.nodes.len(),
        t0.elapsed().as_secs_f64()
    );
    let mut files = Vec::new();
    for (lattice, tag) in [(Lattice::FourPillars, "four"), (Lattice::Gap, "gap")] {
        let mf = mesh_file(&mesh, &pillar_params(lattice), lattice);
        let s = synthetic(&mf, 1.0, 10_000.0);
        let what = match lattice {
            Lattice::FourPillars => "synthetic sag, four pillars",
            Lattice::Gap => "synthetic sag, gap lattice",
        };
        files.extend(draw_all(&out, &format!("synthetic-{tag}"), &mf, &s, what));
        let rest = synthetic(&mf, 0.0, 0.0);
        files.extend(draw_all(
            &out,
            &format!("reference-{tag}"),
            &mf,
            &rest,
            &format!("{what} (reference)"),
        ));
        let vtu = out.join(format!("synthetic-{tag}.vtu"));
        write_vtu(&vtu, &mf, &s).expect("vtu");
        files.push(vtu);
        // The deformation ramped in over 12 frames, as a section and as a surface.
        for (view, name) in [
            (MovieView::Section(Section::Z0), "section"),
            (MovieView::Surface(Coloring::Strain), "surface"),
        ] {
            let p = out.join(format!("synthetic-{tag}-{name}.gif"));
            let t1 = Instant::now();
            let n = 12;
            let mut movie = QuarterMovie::with_view(&p, what, &mf, n, view).expect("movie");
            for k in 0..n {
                let w = k as f64 / (n - 1) as f64;
                movie
                    .frame(&synthetic(&mf, w, w * 10_000.0))
                    .expect("frame");
            }
            let gif = movie.finish().expect("gif");
            files.push(last_frame_png(&gif));
            files.push(gif);
            eprintln!("{} ({:.2} s)", p.display(), t1.elapsed().as_secs_f64());
        }
    }
    if args.iter().any(|a| a == "--real") {
        files.extend(real_state(&out));
    }
    for f in files {
        println!("{}", f.display());
    }
}
