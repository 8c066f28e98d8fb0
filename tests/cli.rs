//! The `cellsim` binary: exit statuses, error messages, output files.

use std::process::Command;

use crate::scenes::read_csv;

/// `cellsim ARGS` in the project's directory, allowed 24 GB whatever the machine has (the
/// memory estimate's refusals name the limit).
fn cellsim(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_cellsim"))
        .args(args)
        .env("CELLSIM_MEMORY_GB", "24")
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("run cellsim")
}

#[test]
fn every_bad_case_exits_with_status_2_and_names_its_field() {
    let dir = format!("{}/cases/bad", env!("CARGO_MANIFEST_DIR"));
    let mut seen = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|x| x != "ron") {
            continue;
        }
        // Read bytes: some files are deliberately not UTF-8 (their comments are ASCII).
        let text = String::from_utf8_lossy(&std::fs::read(&path).unwrap()).into_owned();
        let expect = |key: &str| {
            text.lines()
                .find_map(|l| l.strip_prefix(&format!("// {key}:")))
                .map(|s| s.trim().to_string())
                .unwrap_or_else(|| panic!("{} has no `{key}` comment", path.display()))
        };
        // An empty `expect-field:` means the error names no field (an empty file, say).
        let (field, message) = (expect("expect-field"), expect("expect-error"));
        let rel = format!("cases/bad/{}", path.file_name().unwrap().to_string_lossy());
        let out_dir = format!("{}/bad", env!("CARGO_TARGET_TMPDIR"));
        // Every command that reads a case refuses it the same way, before doing anything.
        for args in [
            vec!["check", rel.as_str()],
            vec!["mesh", rel.as_str()],
            vec!["run", rel.as_str(), "--quiet", "--out", out_dir.as_str()],
        ] {
            let out = cellsim(&args);
            let stderr = String::from_utf8_lossy(&out.stderr);
            assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
            assert!(
                stderr.contains(&field),
                "{args:?}: `{field}` not named in: {stderr}"
            );
            assert_eq!(
                stderr.trim_end(),
                format!("error: {message}"),
                "{args:?}: not the expected message"
            );
        }
        seen += 1;
    }
    assert!(seen >= 40, "only {seen} bad cases");
}

#[test]
fn bad_command_line_values_and_missing_files_exit_with_status_2() {
    for (args, needle) in [
        (
            vec!["run", "cases/fast/flat-gravity.ron", "--rtol", "2"],
            "error: --rtol 2: solver.rtol = 2 is out of range",
        ),
        (
            vec!["run", "cases/fast/flat-gravity.ron", "--dt=-1"],
            "error: --dt -1: solver.bdf2_dt = -1 is out of range (must satisfy bdf2_dt > 0)",
        ),
        (
            vec!["run", "cases/does-not-exist.ron"],
            "does-not-exist.ron",
        ),
        (
            vec![
                "run",
                "cases/fast/flat-gravity.ron",
                "--linear-solver",
                "lu",
            ],
            "error: --linear-solver lu: solver.linear_solver: unknown variant `lu`; expected \
             one of `Faer`, `Klu`, `FaerCondensed`, `KluMetis`, `Umfpack`, `UmfpackNd`, \
             `UmfpackCondensed`",
        ),
        (
            vec!["run", "cases/fast/flat-gravity.ron", "--integrator", "rk4"],
            "error: --integrator rk4: solver.integrator: unknown variant `rk4`; expected one \
             of `Ida`, `Bdf2`",
        ),
        (
            vec!["run", "cases/fast/flat-gravity.ron", "--max-wall", "0"],
            "error: --max-wall = 0 is out of range (must satisfy max-wall > 0)",
        ),
        (
            vec!["check", "cases/bad/nu-half.ron"],
            "materials.nucleus.nu",
        ),
    ] {
        let out = cellsim(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(needle), "{args:?}: {stderr}");
    }
}

/// `cellsim run cases/fast/flat-gravity.ron` into a fresh `<tmp>/<dir>`; returns the path.
fn run_flat_gravity(dir: &str) -> String {
    let out = format!("{}/{dir}", env!("CARGO_TARGET_TMPDIR"));
    let _ = std::fs::remove_dir_all(&out);
    let res = cellsim(&[
        "run",
        "cases/fast/flat-gravity.ron",
        "--out",
        &out,
        "--quiet",
    ]);
    assert!(
        res.status.success(),
        "{}",
        String::from_utf8_lossy(&res.stderr)
    );
    out
}

#[test]
fn run_writes_its_time_series_summary_and_states() {
    let out = run_flat_gravity("cli-run");
    let rows = read_csv(&std::path::Path::new(&out).join("timeseries.csv"));
    assert!(rows.len() >= 201, "{} rows", rows.len());
    assert!(rows.iter().all(|r| r.iter().all(|v| v.is_finite())));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(format!("{out}/summary.json")).unwrap())
            .unwrap();
    assert_eq!(summary["finished"], true);
    assert_eq!(summary["case"], "flat-gravity");
    assert!(summary["stats"]["steps"].as_u64().unwrap() > 10);
    let last = rows.last().unwrap();
    assert_eq!(summary["final_values"]["t"].as_f64(), Some(last[0]));
    // The cell has landed: in contact, sunk by about the 0.4 µm gap to the band.
    assert!(
        last[1] > 0.3 && last[2] < -0.39 && last[2] > -0.45,
        "{last:?}"
    );
    // The paper's measures after the original columns: the contact length along the
    // reference contour, the membrane's strain, and the nucleus's lowest u_y, at or below
    // those of p_t and p_b (both nucleus nodes).
    assert_eq!(last.len(), 10, "{last:?}");
    assert!(
        last[7] > 0.0 && (last[7] / last[1] - 1.0).abs() < 0.5,
        "{last:?}"
    );
    assert!(last[8] > 0.0 && last[8] < 0.5, "{last:?}");
    assert!(last[9] <= last[2] && last[9] <= last[4], "{last:?}");
    assert!(std::path::Path::new(&format!("{out}/mesh.json")).exists());
    assert_eq!(
        summary["states"].as_array().unwrap().len(),
        1,
        "state at t_end"
    );
}

#[test]
fn table_prints_a_row_per_run_and_refuses_a_missing_one() {
    let out = run_flat_gravity("cli-table");
    let res = cellsim(&["table", &out]);
    assert!(res.status.success());
    let text = String::from_utf8_lossy(&res.stdout);
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 3, "{text}");
    assert!(
        lines[2].starts_with("| flat-gravity | finished |"),
        "{text}"
    );
    // The final uy_top of the summary appears in the row.
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(format!("{out}/summary.json")).unwrap())
            .unwrap();
    let uy = summary["final_values"]["uy_top"].as_f64().unwrap();
    assert!(lines[2].contains(&format!("{uy:.3}")), "{text}");
    let res = cellsim(&["table", "no/such/run"]);
    assert_eq!(res.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&res.stderr).contains("no/such/run/summary.json"));
}

/// A case file in the test's temporary directory: `base` (a file in cases/) with the
/// replacements applied; returns its path.
fn variant(name: &str, base: &str, replace: &[(&str, &str)]) -> String {
    let mut text = std::fs::read_to_string(format!("{}/{base}", env!("CARGO_MANIFEST_DIR")))
        .expect("read base case");
    for (from, to) in replace {
        assert!(text.contains(from), "{base} has no `{from}`");
        text = text.replacen(from, to, 1);
    }
    let path = format!("{}/{name}.ron", env!("CARGO_TARGET_TMPDIR"));
    std::fs::write(&path, text).expect("write case");
    path
}

fn summary_of(dir: &str) -> serde_json::Value {
    let text = std::fs::read_to_string(format!("{dir}/summary.json")).expect("summary.json");
    serde_json::from_str(&text).expect("summary JSON")
}

fn tmp(dir: &str) -> String {
    let out = format!("{}/{dir}", env!("CARGO_TARGET_TMPDIR"));
    let _ = std::fs::remove_dir_all(&out);
    out
}

#[test]
fn sigterm_and_sighup_stop_a_run_cleanly_with_128_plus_the_signal() {
    for (signal, status) in [("TERM", 143), ("HUP", 129), ("INT", 130)] {
        let out = tmp(&format!("cli-signal-{signal}"));
        let child = Command::new(env!("CARGO_BIN_EXE_cellsim"))
            .args([
                "run",
                "cases/fast/push-pull-short.ron",
                "--out",
                &out,
                "--quiet",
            ])
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .expect("start cellsim");
        // Wait for a few output rows, then look at the summary written so far.
        let csv = format!("{out}/timeseries.csv");
        let start = std::time::Instant::now();
        while std::fs::read_to_string(&csv).map_or(0, |t| t.lines().count()) < 4 {
            assert!(start.elapsed().as_secs() < 60, "no output rows");
            std::thread::sleep(std::time::Duration::from_millis(20));
        }
        let during = summary_of(&out);
        assert!(during["wall_seconds"].as_f64().unwrap() > 0.0, "{during}");
        let killed = Command::new("kill")
            .args([&format!("-{signal}"), &child.id().to_string()])
            .status()
            .expect("kill");
        assert!(killed.success());
        let res = child.wait_with_output().expect("wait");
        let stderr = String::from_utf8_lossy(&res.stderr);
        assert_eq!(res.status.code(), Some(status), "SIG{signal}: {stderr}");
        let s = summary_of(&out);
        assert_eq!(s["finished"], false);
        assert_eq!(s["failure"]["kind"], "interrupted", "{s}");
        let reason = s["failure"]["reason"].as_str().unwrap();
        assert!(
            reason.starts_with(&format!("interrupted by SIG{signal} at t = ")),
            "{reason}"
        );
        assert!(s["wall_seconds"].as_f64().unwrap() > 0.0);
        // Every row in the summary's count is in the CSV, each complete.
        let rows = crate::scenes::read_csv(std::path::Path::new(&csv));
        assert_eq!(rows.len() as u64, s["outputs"].as_u64().unwrap());
        assert_eq!(
            rows.last().unwrap()[0],
            s["final_values"]["t"].as_f64().unwrap()
        );
        // With the state where the signal stopped it.
        assert!(
            std::path::Path::new(&format!("{out}/state_stopped.json")).exists(),
            "{s}"
        );
    }
}

#[test]
fn a_ringing_landing_stops_at_the_step_limit_with_its_outputs_kept() {
    // Inertia kept on through the landing: the cell rings on the contact with steps of
    // 0.1–0.5 ms, far below the stall threshold of an 8 000-s case with 400 outputs (2 ms),
    // for ever. The steps are short but each moves the solution by hundreds of tolerance
    // units: motion the model makes, not a collapsed step (the stall rule asks for both),
    // so the run goes on until `solver.max_steps` steps between two outputs. (Short steps
    // that no longer move the solution are the stall: the `run` module's unit tests.)
    let out = tmp("cli-stall");
    let res = cellsim(&[
        "run",
        "cases/fast/flat-gravity.ron",
        "--set",
        "inertia.mode=On",
        "--set",
        "phases.t_end=8000.0",
        "--out",
        &out,
        "--quiet",
    ]);
    let stderr = String::from_utf8_lossy(&res.stderr);
    assert_eq!(res.status.code(), Some(1), "{stderr}");
    let s = summary_of(&out);
    assert_eq!(s["failure"]["kind"], "step_limit", "{s}");
    let reason = s["failure"]["reason"].as_str().unwrap();
    for needle in [
        "step limit",
        "solver.max_steps = 5000",
        "at t = ",
        "next output at",
    ] {
        assert!(reason.contains(needle), "{reason}");
    }
    // The outputs before the stop are kept, and the state where it stopped (past the
    // last output time) is written, listed and drawn by `plot`.
    assert!(s["outputs"].as_u64().unwrap() >= 2, "{s}");
    let listed: Vec<&str> = s["states"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    assert!(listed.contains(&"state_stopped.json"), "{s}");
    let stopped: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(format!("{out}/state_stopped.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(stopped["phase"], "stopped");
    let t_stopped = stopped["t"].as_f64().unwrap();
    let t_last = s["final_values"]["t"].as_f64().unwrap();
    let at = reason.find("at t = ").unwrap() + "at t = ".len();
    let t_stop: f64 = reason[at..].split(' ').next().unwrap().parse().unwrap();
    assert!(t_stopped > t_last, "{t_stopped} vs last output {t_last}");
    assert!(
        (t_stopped - t_stop).abs() <= 1e-6 * t_stop,
        "{t_stopped} vs {reason}"
    );
    let plots = format!("{out}/plots");
    let res = cellsim(&["plot", &out, "--out", &plots]);
    assert!(
        res.status.success(),
        "{}",
        String::from_utf8_lossy(&res.stderr)
    );
    assert!(std::path::Path::new(&format!("{plots}/shape-stopped.png")).exists());
}

#[test]
fn max_steps_is_enforced_for_ida_and_bdf2() {
    let case = variant(
        "max-steps-1",
        "cases/fast/push-pull-short.ron",
        &[(
            "inertia: (mode:",
            "solver: (max_steps: 1),\n    inertia: (mode:",
        )],
    );
    for integrator in ["ida", "bdf2"] {
        let out = tmp(&format!("cli-max-steps-{integrator}"));
        let res = cellsim(&[
            "run",
            &case,
            "--integrator",
            integrator,
            "--dt",
            "0.1",
            "--out",
            &out,
            "--quiet",
        ]);
        let stderr = String::from_utf8_lossy(&res.stderr);
        assert_eq!(res.status.code(), Some(1), "{integrator}: {stderr}");
        let s = summary_of(&out);
        assert_eq!(s["failure"]["kind"], "step_limit", "{integrator}: {s}");
        assert!(stderr.contains("solver.max_steps = 1"), "{stderr}");
    }
}

#[test]
fn an_end_time_just_after_the_inertia_switch_finishes() {
    // The switch (at a step, 9.5765 s) comes just before the end; the restarted IDA must
    // reach the last output time from there.
    let case = variant(
        "push-pull-9.6",
        "cases/pillars-push-pull.ron",
        &[("t_end: 50000.0", "t_end: 9.6")],
    );
    let out = tmp("cli-switch-end");
    let res = cellsim(&["run", &case, "--out", &out, "--quiet"]);
    let stderr = String::from_utf8_lossy(&res.stderr);
    assert!(res.status.success(), "{stderr}");
    let s = summary_of(&out);
    assert_eq!(s["finished"], true);
    assert!(s["inertia_switched_off_at"].as_f64().unwrap() <= 9.6);
}

#[test]
fn a_closed_stdout_ends_quietly() {
    let mut child = Command::new(env!("CARGO_BIN_EXE_cellsim"))
        .args(["check", "cases/flat.ron"])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("start cellsim");
    // Close the reading end before cellsim writes (as `| head -1` does once it has read
    // its line).
    drop(child.stdout.take());
    let res = child.wait_with_output().expect("wait");
    let stderr = String::from_utf8_lossy(&res.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(res.status.code(), Some(0), "{stderr}");
}

#[test]
fn negative_numbers_reach_the_range_check_and_help_is_for_users() {
    for args in [
        vec!["run", "cases/fast/flat-gravity.ron", "--rtol", "-1"],
        vec!["run", "cases/fast/flat-gravity.ron", "--atol", "-1e-6"],
        vec!["study", "cases/fast/flat-gravity.ron", "--dt-max", "-5"],
    ] {
        let res = cellsim(&args);
        let stderr = String::from_utf8_lossy(&res.stderr);
        assert_eq!(res.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains("is out of range"), "{args:?}: {stderr}");
    }
    for sub in ["run", "paper", "study", "check", "mesh", "plot", "table"] {
        let res = cellsim(&[sub, "--help"]);
        let text = String::from_utf8_lossy(&res.stdout);
        assert!(res.status.success());
        assert!(!text.contains("[`"), "{sub} --help: {text}");
    }
    let res = cellsim(&["--help"]);
    let text = String::from_utf8_lossy(&res.stdout);
    for needle in ["IDA", "BDF2", "Exit status", "143", "130", "bad input"] {
        assert!(text.contains(needle), "--help lacks {needle}: {text}");
    }
}

#[test]
fn progress_goes_to_a_log_as_plain_lines() {
    let out = tmp("cli-progress");
    let res = cellsim(&["run", "cases/fast/flat-gravity.ron", "--out", &out]);
    let stderr = String::from_utf8_lossy(&res.stderr);
    assert!(res.status.success(), "{stderr}");
    let line = stderr
        .lines()
        .find(|l| l.starts_with("flat-gravity: t = "))
        .unwrap_or_else(|| panic!("no progress line in: {stderr}"));
    for needle in [" s of 2.0000e2 s (", " steps, h = ", "wall "] {
        assert!(line.contains(needle), "{line}");
    }
    assert!(
        !stderr.contains('\r'),
        "no terminal redraws in a log: {stderr:?}"
    );
}

#[test]
fn a_mesh_drawing_that_cannot_be_written_says_so() {
    let res = cellsim(&[
        "mesh",
        "cases/fast/flat-gravity.ron",
        "--svg",
        "/nonexistent-dir/mesh.svg",
    ]);
    let stderr = String::from_utf8_lossy(&res.stderr);
    assert_eq!(res.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("cannot write /nonexistent-dir/mesh.svg"),
        "{stderr}"
    );
    assert!(!stderr.contains("read"), "{stderr}");
}

#[test]
fn set_overrides_a_field_on_check_and_run() {
    // check prints the case with the overrides applied, inside the substrate's variant.
    let out = cellsim(&[
        "check",
        "cases/pillars-push-pull.ron",
        "--set",
        "substrate.width=6.0",
        "--set",
        "substrate.spacing=10.0",
        "--set",
        "solver.rtol=1e-3",
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        stdout.contains("width: 6.0,") && stdout.contains("spacing: 10.0,"),
        "{stdout}"
    );
    assert!(stdout.contains("rtol: 0.001,"), "{stdout}");
    // run: the override reaches the integration (an end time of 12 s).
    let dir = format!("{}/cli-set-run", env!("CARGO_TARGET_TMPDIR"));
    let _ = std::fs::remove_dir_all(&dir);
    let res = cellsim(&[
        "run",
        "cases/fast/flat-gravity.ron",
        "--quiet",
        "--out",
        &dir,
        "--set",
        "phases.t_end=12.0",
    ]);
    assert!(
        res.status.success(),
        "{}",
        String::from_utf8_lossy(&res.stderr)
    );
    let summary = summary_of(&dir);
    assert_eq!(summary["final_values"]["t"].as_f64(), Some(12.0));
}

#[test]
fn a_bad_override_exits_with_status_2_and_names_the_set_argument() {
    for (args, expected) in [
        (
            vec![
                "check",
                "cases/pillars-push-pull.ron",
                "--set",
                "substrate.spacing=abc",
            ],
            "error: --set substrate.spacing=abc: substrate.spacing: Expected float",
        ),
        (
            vec![
                "run",
                "cases/fast/flat-gravity.ron",
                "--set",
                "materials.nucleus.nu=0.5",
            ],
            "error: --set materials.nucleus.nu=0.5: materials.nucleus.nu = 0.5 is out of range \
             (must satisfy -1 < nu < 0.5)",
        ),
        (
            vec![
                "study",
                "cases/fast/flat-gravity.ron",
                "--set",
                "solver.rtool=1e-3",
            ],
            "error: --set solver.rtool=1e-3: solver.rtool: unknown field `rtool`; expected one \
             of `integrator`, `rtol`, `atol`, `bdf2_dt`, `max_order`, `max_steps`, \
             `linear_solver`, `initial_step`, `defer_adhesion`, `delta_cj`, `newton_iters`, `krylov`, \
             `nonlinear`, `parallel_elements`",
        ),
        (
            // The file's own rule, located in the file, broken by the new spacing.
            vec![
                "check",
                "cases/pillars-push-pull.ron",
                "--set",
                "substrate.spacing=9.0",
            ],
            "error: cases/pillars-push-pull.ron:19:9: substrate.first_center = 8 is out of range \
             (must satisfy first_center = k (width + spacing)/2 = k 8.5 for an integer k, so \
             that the pillars are mirror symmetric about the symmetry line x = 0)",
        ),
    ] {
        let out = cellsim(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert_eq!(stderr.trim_end(), expected, "{args:?}");
    }
    // Not PATH=VALUE: refused by the command line parser, also with status 2.
    let out = cellsim(&["check", "cases/flat.ron", "--set", "substrate"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("is not PATH=VALUE"));
}

#[test]
fn delta_cj_keeps_factorizations_longer_at_the_same_values() {
    // solver.delta_cj reaches IDA (IDASetDeltaCjLSetup): at 0.9 the flat gravity phase
    // takes fewer Jacobians than at IDA's 0.25 (measured 17 against 32) and ends at the
    // same nucleus displacement to the tolerance (measured 7e-6 relative).
    let mut uy = Vec::new();
    let mut jac = Vec::new();
    for d in ["0.25", "0.9"] {
        let out = tmp(&format!("delta-cj-{d}"));
        let set = format!("solver.delta_cj={d}");
        let run = cellsim(&[
            "run",
            "cases/fast/flat-gravity.ron",
            "--set",
            &set,
            "--out",
            &out,
            "--quiet",
        ]);
        assert!(
            run.status.success(),
            "{}",
            String::from_utf8_lossy(&run.stderr)
        );
        let s = summary_of(&out);
        assert_eq!(s["settings"]["delta_cj"].as_f64(), Some(d.parse().unwrap()));
        jac.push(s["stats"]["jacobian_evals"].as_u64().unwrap());
        uy.push(s["final_values"]["uy_top"].as_f64().unwrap());
    }
    assert!(jac[1] < jac[0], "Jacobians {jac:?}");
    assert!((uy[1] / uy[0] - 1.0).abs() < 1e-4, "uy_top {uy:?}");
}

/// `check` refuses every case `run` refuses before integrating, in every model, with the
/// same message: a rule of the schema, the mesh generator's element limit and the memory
/// estimate (one function, the case's validation, serves both). `run` refuses before
/// meshing: its output directory is never made.
#[test]
fn check_refuses_what_run_refuses_before_integrating_in_every_model() {
    let schema = "materials.nucleus.nu=0.5";
    let too_fine = "mesh.refine=40.0";
    for (base, refusals) in [
        (
            "cases/fast/flat-gravity.ron",
            [schema, too_fine, "mesh.refine=25.0"],
        ),
        (
            "cases/fast/flat-axisym-gravity.ron",
            [schema, too_fine, "mesh.refine=25.0"],
        ),
        (
            "cases/fast/flat-3d-coarse.ron",
            [schema, too_fine, "mesh.refine=4.0"],
        ),
    ] {
        let mut layers = Vec::new();
        for set in refusals {
            let check = cellsim(&["check", base, "--set", set]);
            let message = String::from_utf8_lossy(&check.stderr).into_owned();
            assert_eq!(
                check.status.code(),
                Some(2),
                "check {base} {set}: {message}"
            );
            assert!(
                message.starts_with(&format!("error: --set {set}: ")),
                "{message}"
            );
            let out = tmp(&format!("refused-{}", layers.len()));
            let run = cellsim(&["run", base, "--set", set, "--quiet", "--out", &out]);
            assert_eq!(run.status.code(), Some(2), "run {base} {set}");
            assert_eq!(
                String::from_utf8_lossy(&run.stderr),
                message,
                "{base} {set}"
            );
            assert!(!std::path::Path::new(&out).exists(), "{base} {set}: ran");
            layers.push(message);
        }
        assert!(layers[1].contains("refused by the mesh generator: mesh too fine"));
        assert!(layers[2].contains("refused by the memory estimate: mesh too large"));
    }
}

/// A value set by `--set` is named by its `--set` argument, not by the file's line that
/// holds another value: `substrate.y_s` replaced in place (its name stays the file's).
#[test]
fn an_override_in_place_is_named_by_its_set_argument() {
    let out = cellsim(&[
        "check",
        "cases/fast/flat-gravity.ron",
        "--set",
        "substrate.y_s=-1.2",
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert_eq!(
        String::from_utf8_lossy(&out.stderr).trim_end(),
        "error: --set substrate.y_s=-1.2: substrate.y_s = -1.2 is out of range (must \
         satisfy y_s < centre_y - r_c = -1.5)"
    );
}

/// Tolerances past their bounds are refused (exit 2) with the bound; the loosest allowed
/// still runs to physical values. At `--rtol 0.5` this run once ended 13 cm above its
/// start with exit 0.
#[test]
fn loose_tolerances_are_refused_and_the_loosest_allowed_stays_physical() {
    let base = [
        "run",
        "cases/fast/flat-gravity.ron",
        "--set",
        "phases.t_end=12.0",
    ];
    for (flag, value, bound) in [
        ("--rtol", "0.5", "0 < rtol <= 0.1"),
        ("--atol", "0.1", "0 < atol <= 0.01"),
    ] {
        let out = tmp("loose-refused");
        let mut args = base.to_vec();
        args.extend([flag, value, "--quiet", "--out", out.as_str()]);
        let res = cellsim(&args);
        let stderr = String::from_utf8_lossy(&res.stderr);
        assert_eq!(res.status.code(), Some(2), "{stderr}");
        assert!(stderr.contains(bound), "{stderr}");
        assert!(!std::path::Path::new(&out).exists());
    }
    let e = cellsim(&[
        "check",
        "cases/fast/flat-gravity.ron",
        "--set",
        "solver.rtol=0.2",
    ]);
    assert_eq!(e.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&e.stderr).contains("(must satisfy 0 < rtol <= 0.1)"));
    let out = tmp("loosest");
    let mut args = base.to_vec();
    args.extend([
        "--rtol",
        "0.1",
        "--atol",
        "0.01",
        "--quiet",
        "--out",
        out.as_str(),
    ]);
    let res = cellsim(&args);
    assert!(
        res.status.success(),
        "{}",
        String::from_utf8_lossy(&res.stderr)
    );
    let uy = summary_of(&out)["final_values"]["uy_top"].as_f64().unwrap();
    // The fall is 0.5 µm less the 0.1 µm contact band.
    assert!((-0.5..=-0.3).contains(&uy), "uy_top {uy}");
}

/// The case's `flat-gravity` with a `solver` section `solver` (RON fields) written into a
/// copy; returns the copy's path and the line and column of the section's first field.
fn flat_gravity_with_solver(name: &str, solver: &str) -> (String, usize, usize) {
    let anchor = "inertia: (mode: OffAfter(9.0)),";
    let line = format!("solver: ({solver}),");
    let path = variant(
        name,
        "cases/fast/flat-gravity.ron",
        &[(anchor, &format!("{line}\n    {anchor}"))],
    );
    let text = std::fs::read_to_string(&path).unwrap();
    let row = text
        .lines()
        .position(|l| l == format!("    {line}"))
        .unwrap()
        + 1;
    (path, row, 4 + line.find('(').unwrap() + 2)
}

/// `--rtol R`, `--set solver.rtol=R` and a case file's `rtol: R` are one setting with one
/// check: a bad value gets the same message from each, after the place that wrote it, and
/// exit status 2 before anything is written.
#[test]
fn a_bad_rtol_gets_one_message_from_the_flag_the_set_and_the_file() {
    let (file, row, col) = flat_gravity_with_solver("rtol-half", "rtol: 0.5");
    let message = "solver.rtol = 0.5 is out of range (must satisfy 0 < rtol <= 0.1)";
    let out = tmp("rtol-half");
    let base = "cases/fast/flat-gravity.ron";
    for (source, place) in [
        (vec![base, "--rtol", "0.5"], "--rtol 0.5".to_string()),
        (
            vec![base, "--set", "solver.rtol=0.5"],
            "--set solver.rtol=0.5".to_string(),
        ),
        (vec![file.as_str()], format!("{file}:{row}:{col}")),
    ] {
        let mut args = vec!["run"];
        args.extend(source);
        args.extend(["--quiet", "--out", out.as_str()]);
        let res = cellsim(&args);
        let stderr = String::from_utf8_lossy(&res.stderr);
        assert_eq!(res.status.code(), Some(2), "{args:?}: {stderr}");
        assert_eq!(stderr.trim_end(), format!("error: {place}: {message}"));
        assert!(!std::path::Path::new(&out).exists());
    }
    // A flag is applied after the `--set` arguments: it wins.
    let out = tmp("rtol-flag-wins");
    let res = cellsim(&[
        "run",
        base,
        "--set",
        "solver.rtol=0.5",
        "--rtol",
        "1e-3",
        "--set",
        "phases.t_end=1.0",
        "--quiet",
        "--out",
        &out,
    ]);
    assert!(
        res.status.success(),
        "{}",
        String::from_utf8_lossy(&res.stderr)
    );
    assert_eq!(summary_of(&out)["settings"]["rtol"], 1e-3);
}

/// The same rtol from the flag, from `--set` and from the case file gives the same run, bit
/// for bit, and the same settings in summary.json.
#[test]
fn rtol_from_the_flag_the_set_or_the_file_gives_the_same_run() {
    let (file, _, _) = flat_gravity_with_solver("rtol-1e-3", "rtol: 1e-3");
    let base = "cases/fast/flat-gravity.ron";
    let mut runs = Vec::new();
    for (dir, source) in [
        ("rtol-by-flag", vec![base, "--rtol", "1e-3"]),
        ("rtol-by-set", vec![base, "--set", "solver.rtol=1e-3"]),
        ("rtol-by-file", vec![file.as_str()]),
    ] {
        let out = tmp(dir);
        let mut args = vec!["run"];
        args.extend(source);
        args.extend(["--quiet", "--out", out.as_str()]);
        let res = cellsim(&args);
        assert!(
            res.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&res.stderr)
        );
        let csv = std::fs::read(format!("{out}/timeseries.csv")).unwrap();
        runs.push((csv, summary_of(&out)["settings"].clone()));
    }
    assert_eq!(runs[0].1["rtol"], 1e-3);
    for (csv, settings) in &runs[1..] {
        assert!(csv == &runs[0].0, "timeseries.csv differs");
        assert_eq!(settings, &runs[0].1);
    }
}

/// `--linear-solver` takes the command line's names; summary.json writes the case file's,
/// and reads back as the same solver.
#[test]
fn the_linear_solver_flag_takes_kebab_case_names() {
    let out = tmp("umfpack-nd");
    let res = cellsim(&[
        "run",
        "cases/fast/flat-gravity.ron",
        "--linear-solver",
        "umfpack-nd",
        "--set",
        "phases.t_end=20.0",
        "--quiet",
        "--out",
        &out,
    ]);
    assert!(
        res.status.success(),
        "{}",
        String::from_utf8_lossy(&res.stderr)
    );
    assert_eq!(summary_of(&out)["settings"]["linear_solver"], "UmfpackNd");
    let summary = cellsim::run_files::read::read_summary(std::path::Path::new(&out)).unwrap();
    assert!(summary.finished);
    assert_eq!(
        summary.settings.solver.linear_solver,
        cellsim::solver::LinearSolver::UmfpackNd
    );
}

/// A summary.json as cellsim wrote it before the settings had one type (583760b: `dt`, the
/// linear solver in kebab case, the limits beside the solver's fields) still reads, for
/// `cellsim table`, a study's `--reuse` and a sweep's resume.
#[test]
fn a_summary_of_the_format_before_reads() {
    let fixture = format!(
        "{}/tests/data/summary-583760b.json",
        env!("CARGO_MANIFEST_DIR")
    );
    let text = std::fs::read_to_string(&fixture).unwrap();
    assert!(text.contains("\"dt\": 1.0") && text.contains("\"faer-condensed\""));
    let s: cellsim::run_files::Summary = serde_json::from_str(&text).unwrap();
    assert_eq!(s.settings.solver, cellsim::solver::Settings::default());
    assert_eq!(s.settings.limits, cellsim::solver::Limits::default());
    assert!(s.finished);
    // Its `dt` is BDF2's step.
    let text = text.replace("\"dt\": 1.0", "\"dt\": 2.5");
    let s: cellsim::run_files::Summary = serde_json::from_str(&text).unwrap();
    assert_eq!(s.settings.solver.bdf2_dt, 2.5);
    // `cellsim table` on a directory holding it.
    let dir = tmp("old-summary");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::copy(&fixture, format!("{dir}/summary.json")).unwrap();
    let res = cellsim(&["table", &dir]);
    assert!(
        res.status.success(),
        "{}",
        String::from_utf8_lossy(&res.stderr)
    );
    assert!(String::from_utf8_lossy(&res.stdout).contains("| flat-gravity | finished |"));
}

#[test]
fn the_measures_table_gives_each_run_and_its_difference_from_the_first() {
    // A 2-D summary, and the same with u_y(p_t) 1 % deeper and a 3-D run's measures: the
    // table prints each run's measures and, after the first, the relative differences.
    let fixture = format!(
        "{}/tests/data/summary-583760b.json",
        env!("CARGO_MANIFEST_DIR")
    );
    let mut s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&fixture).unwrap()).unwrap();
    let uy = s["final_values"]["uy_top"].as_f64().unwrap();
    let (a, b) = (tmp("measures-a"), tmp("measures-b"));
    for d in [&a, &b] {
        std::fs::create_dir_all(d).unwrap();
    }
    std::fs::write(format!("{a}/summary.json"), s.to_string()).unwrap();
    s["final_values"]["uy_top"] = (1.01 * uy).into();
    s["final_values_3d"] = serde_json::json!({"contact_area": 100.0, "contact_area_ref": 90.0,
        "contact_radius_equiv": 5.6, "penetration_depth": 1.5});
    s["strain_nucleus_max"] = 0.25.into();
    std::fs::write(format!("{b}/summary.json"), s.to_string()).unwrap();
    let res = cellsim(&["table", "--measures", &a, &b]);
    assert!(
        res.status.success(),
        "{}",
        String::from_utf8_lossy(&res.stderr)
    );
    let out = String::from_utf8_lossy(&res.stdout).to_string();
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(lines.len(), 5, "{out}");
    assert!(lines[0].starts_with("| run | outcome | t reached [s] | penetration [µm] |"));
    // The first run has no 3-D measures and no largest strain: dashes.
    assert!(lines[2].contains("| – | "), "{}", lines[2]);
    assert!(lines[3].contains("| 1.500 |") && lines[3].contains("| 25.0 % |"));
    // u_y(p_t) is negative and 1 % larger in magnitude: −1.00 %; a value the first run
    // lacks has no difference.
    let diff: Vec<&str> = lines[4].split('|').map(str::trim).collect();
    assert_eq!(diff[1], "difference from the first run");
    assert_eq!(diff[4], "–");
    assert_eq!(diff[5], format!("{:+.2} %", 100.0 * (0.01 * uy) / uy.abs()));
    // Both flags at once are refused.
    assert_eq!(
        cellsim(&["table", "--measures", "--phases", &a])
            .status
            .code(),
        Some(2)
    );
}

#[test]
fn sensitivity_refuses_what_it_cannot_follow_with_status_2() {
    // A case with phases started by a condition, and a parameter that is no number field:
    // each refused before anything is integrated, naming the fields.
    for (args, expected) in [
        (
            vec![
                "sensitivity",
                "cases/events/flat.ron",
                "--param",
                "materials.cytoplasm.e",
            ],
            "error: cases/events/flat.ron: sensitivities through a change of the system are \
             not implemented yet; this case changes it: phases.adhesion_start / \
             active_start (a phase started by a condition)",
        ),
        (
            vec![
                "sensitivity",
                "cases/fast/push-pull-short-drag.ron",
                "--set",
                "solver.defer_adhesion=false",
                "--param",
                "materials.cytoplasm.modulus",
            ],
            "error: --param materials.cytoplasm.modulus: not a number field of \
             cases/fast/push-pull-short-drag.ron (a dotted path, e.g. materials.cytoplasm.e)",
        ),
    ] {
        let out = cellsim(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert_eq!(stderr.trim_end(), expected, "{args:?}");
    }
}
