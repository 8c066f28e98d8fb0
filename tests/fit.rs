//! `cellsim fit`: its gradients from the IDAS sensitivities against central differences of
//! whole runs, and a twin experiment (data made by the model with noise) whose parameters
//! the fit recovers. On the settling cell (flat substrate, the weight ramped over the
//! 200 s run, inertia off): a second each.

use std::path::Path;

use cellsim::fit::spec::{self, Gradient};
use cellsim::fit::{FitOptions, jacobian_at_start, make_data, run_fit};

/// The fit file: the cytoplasm's and the nucleus' moduli from the contact radius, the
/// apex's displacement and the nucleus' mean strain over time.
fn fit_file(dir: &Path, start_cp: f64, start_n: f64, rtol: f64) -> std::path::PathBuf {
    let atol = 1e-2 * rtol;
    let case = Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/fast/flat-gravity.ron");
    let text = format!(
        r#"(
    name: "settling-twin",
    cases: [(name: "settling", file: {case:?},
             set: ["inertia.mode=Off", "inertia.drag=4.5e-5", "phases.t_g0=200.0",
                   "solver.rtol={rtol:e}", "solver.atol={atol:e}"])],
    parameters: [
        (path: "materials.cytoplasm.e", lower: 20.0, upper: 1000.0, scale: Log, start: Some({start_cp})),
        (path: "materials.nucleus.e", lower: 50.0, upper: 5000.0, scale: Log, start: Some({start_n})),
    ],
    targets: [Series(case: "settling", file: "data.csv")],
)"#
    );
    let path = dir.join("fit.ron");
    std::fs::write(&path, text).unwrap();
    path
}

fn temp_dir(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("cellsim-fit-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Data at the case's own moduli (100 and 500 Pa): σ about 1 % of each final value.
fn twin_data(dir: &Path, file: &Path) {
    let fit = spec::load(file, false).unwrap();
    let truth = [
        ("materials.cytoplasm.e".to_string(), 100.0),
        ("materials.nucleus.e".to_string(), 500.0),
    ];
    let noise = [
        ("contact_radius".to_string(), 0.01),
        ("uy_top".to_string(), 0.005),
        ("strain_nucleus".to_string(), 5e-6),
    ];
    make_data(&fit, &truth, &noise, 7, &dir.join("truth")).unwrap();
}

#[test]
fn fit_gradients_from_sensitivities_match_central_differences_of_whole_runs() {
    let dir = temp_dir("jacobian");
    // A tight tolerance: a difference of runs at rtol 1e-4 carries their error divided
    // by the step (1e-4 / 2e-2 of the measure), the sensitivities do not.
    let file = fit_file(&dir, 150.0, 300.0, 1e-7);
    twin_data(&dir, &file);
    let fit = spec::load(&file, true).unwrap();
    let sens = jacobian_at_start(&fit, Gradient::Sensitivities, &dir.join("s"), 2).unwrap();
    let diff = jacobian_at_start(&fit, Gradient::Differences, &dir.join("d"), 2).unwrap();
    // Column by column, relative to the column's norm (single rows near t = 0 are ~0).
    for j in 0..2 {
        let norm: f64 = diff.iter().map(|r| r[j] * r[j]).sum::<f64>().sqrt();
        let err: f64 = sens
            .iter()
            .zip(&diff)
            .map(|(a, b)| (a[j] - b[j]).powi(2))
            .sum::<f64>()
            .sqrt();
        assert!(norm > 1.0, "column {j} is not informative: |J_j| = {norm}");
        // Central differences with a step of 1e-2 in ln p: O(1e-5) truncation where the
        // measure is smooth. Measured (2026-12-07): 5e-4 and 1e-5 of the column's norm,
        // nearly all of it the contact radius (up to 1 % at single times, where the edge
        // of the contact crosses a node: a measure with kinks; the apex and the strain
        // agree to 1e-4 and better).
        assert!(
            err < 1e-3 * norm,
            "column {j}: |J_sens − J_diff| = {err:.3e} against |J| = {norm:.3e}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn twin_fit_recovers_its_parameters_within_their_standard_errors() {
    let dir = temp_dir("twin");
    let file = fit_file(&dir, 150.0, 300.0, 1e-4);
    twin_data(&dir, &file);
    let fit = spec::load(&file, true).unwrap();
    let opts = FitOptions {
        out: dir.join("out"),
        jobs: 2,
        quiet: true,
    };
    let r = run_fit(&fit, &opts).unwrap();
    // χ² of the noise alone: about the degrees of freedom.
    let nu = r.degrees_of_freedom as f64;
    assert!(
        (r.reduced_chi2 - 1.0).abs() < 4.0 * (2.0 / nu).sqrt(),
        "reduced χ² {} for {} degrees of freedom",
        r.reduced_chi2,
        r.degrees_of_freedom
    );
    // The truth inside the fit's 95 % confidence ellipse: (z − z_true)ᵀ C⁻¹ (z − z_true)
    // ≤ 5.99 (χ² with 2 degrees of freedom), C from the standard errors and correlation.
    let truth = [100.0f64, 500.0];
    let dz: Vec<f64> = r
        .parameters
        .iter()
        .zip(truth)
        .map(|(p, t)| (p.value / t).ln())
        .collect();
    let s: Vec<f64> = r.parameters.iter().map(|p| p.standard_error_z).collect();
    let rho = r.correlation[0][1];
    let (a, b) = (dz[0] / s[0], dz[1] / s[1]);
    let d2 = (a * a - 2.0 * rho * a * b + b * b) / (1.0 - rho * rho);
    assert!(
        d2 <= 5.99,
        "Mahalanobis distance² {d2} of the truth, fit {:?}",
        r.parameters
    );
    // And each within 3 of its standard errors, started 50 % and 40 % away.
    for (p, t) in r.parameters.iter().zip(truth) {
        assert!(
            (p.value - t).abs() < 3.0 * p.standard_error,
            "{}: {} ± {} against {t}",
            p.path,
            p.value,
            p.standard_error
        );
        assert!(!p.at_bound);
    }
    for f in [
        "fit.json",
        "history.csv",
        "residuals.csv",
        "fit-settling-strain_nucleus.png",
    ] {
        assert!(dir.join("out").join(f).exists(), "{f} not written");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_fit_files_are_refused_with_the_file_and_the_field() {
    let dir = temp_dir("bad");
    let case = Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/fast/flat-gravity.ron");
    let run = |name: &str, body: &str| -> String {
        let path = dir.join(name);
        std::fs::write(&path, body).unwrap();
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_cellsim"))
            .args([
                "fit",
                path.to_str().unwrap(),
                "--out",
                dir.join("o").to_str().unwrap(),
            ])
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2), "{name}: exit status");
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    let head = format!(r#"name: "bad", cases: [(name: "c", file: {case:?})],"#);
    let e = run(
        "measure.ron",
        &format!(
            r#"({head} parameters: [(path: "materials.cytoplasm.e", lower: 10.0, upper: 1000.0)],
               targets: [Final(case: "c", measure: "radius", value: 1.0, sigma: 0.1)])"#
        ),
    );
    assert!(
        e.contains("measure.ron") && e.contains("targets[0]") && e.contains("contact_radius"),
        "{e}"
    );
    let e = run(
        "param.ron",
        &format!(
            r#"({head} parameters: [(path: "materials.cytoplasm.stiffness", lower: 10.0, upper: 1000.0)],
               targets: [Final(case: "c", measure: "uy_top", value: 1.0, sigma: 0.1)])"#
        ),
    );
    assert!(
        e.contains("parameters[0] (materials.cytoplasm.stiffness)")
            && e.contains("not a number field"),
        "{e}"
    );
    let e = run(
        "bounds.ron",
        &format!(
            r#"({head} parameters: [(path: "materials.cytoplasm.e", lower: 0.0, upper: 1000.0, scale: Log)],
               targets: [Final(case: "c", measure: "uy_top", value: 1.0, sigma: 0.1)])"#
        ),
    );
    assert!(e.contains("scale = Log needs lower > 0"), "{e}");
    let e = run(
        "syntax.ron",
        &format!("({head} parameters: [(path: 3)], targets: [])"),
    );
    assert!(e.contains("syntax.ron:1:"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}
