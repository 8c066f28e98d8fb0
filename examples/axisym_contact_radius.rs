//! The contact radius of the flat scene in the axisymmetric model beside the plane-strain
//! one (MODEL.md §10), both frames, from two run directories:
//!
//! ```sh
//! cellsim run cases/flat.ron --out runs/flat
//! cellsim run cases/3d/flat-axisym.ron --out runs/flat-axisym
//! cargo run --release --example axisym_contact_radius -- runs/flat runs/flat-axisym \
//!     plots/3d/flat-axisym-contact-radius.png
//! ```
//!
//! The figure is `cellsim plot`'s contact-radius figure with the two runs on one axis
//! (solid: along the reference contour, dashed: along the deformed contour), each run
//! named by its kinematic model.

use std::path::PathBuf;
use std::process::ExitCode;

use cellsim::render::figures::{contact_radius_plot, time_figure};
use cellsim::run_files::RunData;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [plane, axisym, out] = args.as_slice() else {
        eprintln!("usage: axisym_contact_radius PLANE_STRAIN_RUN AXISYMMETRIC_RUN OUT.png");
        return ExitCode::from(2);
    };
    let load = |dir: &str, label: &str| -> Result<RunData, String> {
        let mut run = RunData::load(dir).map_err(|e| e.to_string())?;
        run.name = format!("{}, {label}", run.name);
        Ok(run)
    };
    let runs = match (
        load(plane, "plane strain (cylinder, per unit length)"),
        load(axisym, "axisymmetric (sphere)"),
    ) {
        (Ok(a), Ok(b)) => [a, b],
        (Err(e), _) | (_, Err(e)) => {
            eprintln!("error: {e}");
            return ExitCode::from(2);
        }
    };
    let refs: Vec<&RunData> = runs.iter().collect();
    let mut plot = contact_radius_plot(&refs, &[], "");
    plot.title = "Contact radius on the flat substrate: spherical (axisymmetric) and cylindrical \
                  (plane strain) cell"
        .into();
    let out = PathBuf::from(out);
    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        if let Err(e) = std::fs::create_dir_all(dir) {
            eprintln!("error: {}: {e}", dir.display());
            return ExitCode::from(1);
        }
    }
    match time_figure(&out, &plot) {
        Ok(()) => {
            println!("{}", out.display());
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(1)
        }
    }
}
