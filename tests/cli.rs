//! The `cellsim` binary: exit statuses, error messages, output files.

use std::process::Command;

use crate::scenes::read_csv;

fn cellsim(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_cellsim"))
        .args(args)
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
            "--rtol = 2 is out of range",
        ),
        (
            vec!["run", "cases/fast/flat-gravity.ron", "--dt=-1"],
            "--dt = -1 is out of range",
        ),
        (
            vec!["run", "cases/does-not-exist.ron"],
            "does-not-exist.ron",
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
