//! `cellsim sweep` end to end on tiny sweeps of fast cases: the table, resume, invalid
//! points, bad overrides, shards and collect, one-at-a-time sensitivities, Slurm scripts,
//! and a sweep stopped by SIGINT.

use std::path::Path;
use std::process::{Command, Output};

fn cellsim(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_cellsim"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("run cellsim")
}

fn tmp(dir: &str) -> String {
    let out = format!("{}/{dir}", env!("CARGO_TARGET_TMPDIR"));
    let _ = std::fs::remove_dir_all(&out);
    out
}

fn text(o: &Output) -> (String, String) {
    (
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// The rows of a sweep.csv as maps from column name to field (no quoted commas in the
/// columns the tests look at, except `reason`, which is last).
fn csv(path: &str) -> Vec<std::collections::HashMap<String, String>> {
    let t = std::fs::read_to_string(path).unwrap();
    let mut lines = t.lines();
    let head: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    lines
        .map(|l| {
            let mut f: Vec<String> = l
                .splitn(head.len(), ',')
                .map(|s| s.trim_matches('"').to_string())
                .collect();
            f.resize(head.len(), String::new());
            head.iter().cloned().zip(f).collect()
        })
        .collect()
}

/// The CSV without its wall_seconds column (which differs from run to run).
fn without_wall(path: &str) -> String {
    let t = std::fs::read_to_string(path).unwrap();
    let k = t
        .lines()
        .next()
        .unwrap()
        .split(',')
        .position(|c| c == "wall_seconds")
        .unwrap();
    t.lines()
        .map(|l| {
            l.split(',')
                .enumerate()
                .filter(|(i, _)| *i != k)
                .map(|(_, f)| f)
                .collect::<Vec<_>>()
                .join(",")
        })
        .collect::<Vec<_>>()
        .join("\n")
}

fn mtime(path: &str) -> std::time::SystemTime {
    std::fs::metadata(path).unwrap().modified().unwrap()
}

const SWEEP: &str = "cases/sweeps/fast-flat.ron";

#[test]
fn a_tiny_sweep_writes_its_table_resumes_and_shards_collect_to_the_same_table() {
    let dir = tmp("sweep-fast-flat");
    let t0 = std::time::Instant::now();
    let res = cellsim(&["sweep", SWEEP, "--out", &dir, "--jobs", "2"]);
    let first = t0.elapsed().as_secs_f64();
    let (stdout, stderr) = text(&res);
    assert_eq!(res.status.code(), Some(0), "{stdout}\n{stderr}");
    // Not a terminal: one plain line per finished point.
    assert_eq!(stderr.matches(" finished in ").count(), 4, "{stderr}");
    assert!(
        stdout.contains(
            "6 points: 4 finished, 0 failed, 2 invalid, 0 interrupted, 0 missing (4 run, 0 reused)"
        ),
        "{stdout}"
    );
    let rows = csv(&format!("{dir}/sweep.csv"));
    let ids: Vec<&str> = rows.iter().map(|r| r["id"].as_str()).collect();
    assert_eq!(ids, ["g0_0", "g0_1", "g0_2", "g1_0", "g1_1", "g1_2"]);
    for r in &rows {
        let invalid = r["materials.nucleus.nu"] == "0.5";
        assert_eq!(
            r["status"],
            if invalid { "invalid" } else { "finished" },
            "{r:?}"
        );
        if invalid {
            // Named by the sweep file's axis that set it, not as a command-line override.
            assert_eq!(
                r["reason"],
                "sweep axis `materials.nucleus.nu` = 0.5: materials.nucleus.nu = 0.5 is out \
                 of range (must satisfy -1 < nu < 0.5)"
            );
            continue;
        }
        assert_eq!(r["t"], "12");
        assert_eq!(r["penetration_depth"], "0", "flat substrate");
        assert!(r["steps"].parse::<u64>().unwrap() > 10);
        // The cell falls by the gap (0.5 or 0.6 µm) less the 0.1 µm contact band.
        let uy: f64 = r["uy_top"].parse().unwrap();
        let y_s: f64 = r["substrate.y_s"].parse().unwrap();
        let fall = -1.5 - y_s - 0.1;
        assert!((uy + fall).abs() < 0.02, "{r:?}");
    }
    // sweep.csv holds each point's own numbers: the same text as the last row of its
    // timeseries.csv, and the same doubles as its summary.json.
    for r in rows.iter().filter(|r| r["status"] == "finished") {
        let point = format!("{dir}/points/{}", r["id"]);
        let series = std::fs::read_to_string(format!("{point}/timeseries.csv")).unwrap();
        let head: Vec<&str> = series.lines().next().unwrap().split(',').collect();
        let last: Vec<&str> = series.lines().last().unwrap().split(',').collect();
        let summary: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(format!("{point}/summary.json")).unwrap(),
        )
        .unwrap();
        let mut compared = 0;
        for (column, value) in head.iter().zip(&last) {
            let Some(in_sweep) = r.get(*column) else {
                continue;
            };
            assert_eq!(in_sweep, value, "{}: {column}", r["id"]);
            let in_summary = summary["final_values"][column].as_f64().unwrap();
            assert_eq!(in_summary.to_string(), *value, "{}: {column}", r["id"]);
            compared += 1;
        }
        assert!(compared >= 8, "{compared} columns compared");
    }

    // The resolved case is what `cellsim check` prints with the same overrides.
    let check = cellsim(&[
        "check",
        "cases/fast/flat-gravity.ron",
        "--set",
        "phases.t_end=12.0",
        "--set",
        "substrate.y_s=-2.1",
        "--set",
        "materials.nucleus.nu=0.45",
    ]);
    assert_eq!(
        std::fs::read_to_string(format!("{dir}/points/g1_1/case.ron")).unwrap(),
        String::from_utf8_lossy(&check.stdout).trim_end()
    );
    assert!(Path::new(&format!("{dir}/points/g0_2/invalid.txt")).exists());
    assert!(Path::new(&format!("{dir}/heatmap-penetration_depth.png")).exists());
    let record: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(format!("{dir}/sweep.json")).unwrap())
            .unwrap();
    assert_eq!(record["design"]["kind"], "Grid");
    assert_eq!(record["points"].as_array().unwrap().len(), 6);
    assert_eq!(record["cellsim_version"], env!("CARGO_PKG_VERSION"));

    // Again: every finished point is reused, nothing is rewritten.
    let summary = format!("{dir}/points/g0_0/summary.json");
    let before = mtime(&summary);
    let t1 = std::time::Instant::now();
    let res = cellsim(&["sweep", SWEEP, "--out", &dir, "--jobs", "2"]);
    let second = t1.elapsed().as_secs_f64();
    let (stdout, stderr) = text(&res);
    assert_eq!(res.status.code(), Some(0), "{stderr}");
    assert!(stdout.contains("(0 run, 4 reused)"), "{stdout}");
    assert_eq!(mtime(&summary), before);
    let direct = without_wall(&format!("{dir}/sweep.csv"));
    // A point run when a default was different: `case.ron` omits the field at its default,
    // so only `resolved.txt` tells; the point runs again, and so does one from before
    // `resolved.txt` was written.
    let resolved = format!("{dir}/points/g1_1/resolved.txt");
    let was = std::fs::read_to_string(&resolved).unwrap();
    let case_ron = std::fs::read_to_string(format!("{dir}/points/g1_1/case.ron")).unwrap();
    assert!(
        was.contains("krylov: None") && !case_ron.contains("krylov"),
        "{was}"
    );
    std::fs::write(&resolved, was.replacen("nu: 0.45", "nu: 0.4", 1)).unwrap();
    assert_ne!(std::fs::read_to_string(&resolved).unwrap(), was);
    std::fs::remove_file(format!("{dir}/points/g0_0/resolved.txt")).unwrap();
    let res = cellsim(&["sweep", SWEEP, "--out", &dir, "--jobs", "2"]);
    let (stdout, stderr) = text(&res);
    assert_eq!(res.status.code(), Some(0), "{stderr}");
    assert!(stdout.contains("(2 run, 2 reused)"), "{stdout}");
    assert_eq!(std::fs::read_to_string(&resolved).unwrap(), was);
    assert_eq!(without_wall(&format!("{dir}/sweep.csv")), direct);
    eprintln!("fast-flat sweep: {first:.1} s wall, resumed in {second:.1} s");

    // The figures are redrawn from the table alone.
    let res = cellsim(&["sweep", "plot", &dir, "--quantity", "uy_top"]);
    assert!(res.status.success(), "{}", text(&res).1);
    assert!(Path::new(&format!("{dir}/heatmap-uy_top.png")).exists());
    heat_map_title_and_colour_bar_label_fit(&dir);
    let res = cellsim(&["sweep", "plot", &dir, "--quantity", "nope"]);
    assert_eq!(res.status.code(), Some(2));
    assert!(text(&res).1.contains("not a column of sweep.csv"));

    // Two shards into another directory, then collect: the same table.
    let sharded = tmp("sweep-fast-flat-shards");
    let res = cellsim(&[
        "sweep", SWEEP, "--out", &sharded, "--shard", "0/2", "--jobs", "2",
    ]);
    let (stdout, stderr) = text(&res);
    assert!(res.status.success(), "{stderr}");
    assert!(
        stdout.contains("3 points: 2 finished, 0 failed, 1 invalid"),
        "{stdout}"
    );
    assert!(!Path::new(&format!("{sharded}/sweep.csv")).exists());
    let res = cellsim(&["sweep", "collect", &sharded]);
    let (_, stderr) = text(&res);
    assert_eq!(res.status.code(), Some(1));
    assert!(
        stderr.contains("3 points without a run: g0_1 g1_0 g1_2"),
        "{stderr}"
    );
    let res = cellsim(&[
        "sweep", SWEEP, "--out", &sharded, "--shard", "1/2", "--jobs", "2",
    ]);
    assert!(res.status.success(), "{}", text(&res).1);
    let res = cellsim(&["sweep", "collect", &sharded]);
    let (stdout, stderr) = text(&res);
    assert_eq!(res.status.code(), Some(0), "{stderr}");
    assert!(stdout.contains("6 points: 4 finished"), "{stdout}");
    assert_eq!(without_wall(&format!("{sharded}/sweep.csv")), direct);
}

/// The heat map of a sweep with a long name (the sweep in `dir`, renamed): its title is
/// whole (white margins left and right of the ink in the title band: it was cut off at
/// the left, "etry: penetration depth…"), and its colour bar carries a label (ink in the
/// strip left of the tick labels, where it had none).
fn heat_map_title_and_colour_bar_label_fit(dir: &str) {
    let renamed = tmp("sweep-long-title");
    std::fs::create_dir_all(&renamed).unwrap();
    std::fs::copy(format!("{dir}/sweep.csv"), format!("{renamed}/sweep.csv")).unwrap();
    let record = std::fs::read_to_string(format!("{dir}/sweep.json")).unwrap();
    let record = record.replacen(
        "\"name\": \"fast-flat\"",
        "\"name\": \"pillar-geometry-with-a-much-longer-sweep-name\"",
        1,
    );
    assert!(record.contains("much-longer"), "sweep.json names its sweep");
    std::fs::write(format!("{renamed}/sweep.json"), record).unwrap();
    let res = cellsim(&["sweep", "plot", &renamed]);
    assert!(res.status.success(), "{}", text(&res).1);
    let img = image::open(format!("{renamed}/heatmap-penetration_depth.png"))
        .unwrap()
        .to_rgb8();
    let (w, h) = img.dimensions();
    let ink = |x: u32, y: u32| img.get_pixel(x, y).0.iter().map(|&c| c as u32).sum::<u32>() < 300;
    let title: Vec<u32> = (0..w).filter(|&x| (0..36).any(|y| ink(x, y))).collect();
    let (first, last) = (title[0], *title.last().unwrap());
    assert!(
        first >= 10 && last + 10 < w,
        "title ink from x = {first} to {last} of {w}"
    );
    assert!(last - first > 400, "a title of {} px", last - first);
    let strip = (w - 190..w - 160).filter(|&x| (h / 3..2 * h / 3).any(|y| ink(x, y)));
    assert!(strip.count() > 3, "no colour bar label");
}

/// A sweep file in the test's temporary directory over `cases/fast/flat-gravity.ron`.
fn sweep_file(name: &str, body: &str) -> String {
    let dir = tmp(&format!("sweep-files-{name}"));
    std::fs::create_dir_all(&dir).unwrap();
    let base = format!("{}/cases/fast/flat-gravity.ron", env!("CARGO_MANIFEST_DIR"));
    let path = format!("{dir}/{name}.ron");
    std::fs::write(
        &path,
        format!("(\n    name: \"{name}\",\n    base: \"{base}\",\n{body}\n)\n"),
    )
    .unwrap();
    path
}

#[test]
fn a_bad_override_or_sweep_file_stops_the_sweep_with_status_2() {
    let cases = [
        (
            "typo",
            r#"    design: Grid([(path: "substrate.ys", values: [-2.0])]),"#,
            "point g0: sweep axis `substrate.ys` = -2.0: substrate.ys: unknown field `ys`; expected one of `y_s`",
        ),
        (
            "wrong-type",
            r#"    design: Zip([(path: "output.n_times", values: [400.5])]),"#,
            "sweep axis `output.n_times` = 400.5: output.n_times: expected an integer, found the decimal number `400.5`",
        ),
        (
            "bad-set",
            "    design: Grid([(path: \"substrate.y_s\", values: [-2.0])]),\n    set: [\"phases.t_end\"],",
            "set: `phases.t_end` is not PATH=VALUE",
        ),
        (
            "syntax",
            r#"    design: Grid([(path: "substrate.y_s", values: [-2.0)]),"#,
            "syntax.ron:4:",
        ),
        (
            "range",
            r#"    design: Grid([(path: "substrate.y_s", values: Range(start: -2.0, stop: -3.0))]),"#,
            "axis `substrate.y_s`: the range needs `n`",
        ),
    ];
    for (name, body, needle) in cases {
        let file = sweep_file(name, body);
        let out = tmp(&format!("sweep-bad-{name}"));
        let res = cellsim(&["sweep", &file, "--out", &out]);
        let (_, stderr) = text(&res);
        assert_eq!(res.status.code(), Some(2), "{name}: {stderr}");
        assert!(
            stderr.contains(needle),
            "{name}: `{needle}` not in {stderr}"
        );
        assert!(!Path::new(&out).exists(), "{name}: nothing is written");
    }
}

#[test]
fn one_at_a_time_gives_sensitivities_and_slurm_gets_a_job_array() {
    let file = sweep_file(
        "oat",
        r#"    design: OneAtATime([
        (path: "substrate.y_s", values: [-2.0, -2.1]),
        (path: "gravity.g_m_s2", values: [19.62]),
    ]),
    set: ["phases.t_end=12.0"],"#,
    );
    let dir = tmp("sweep-oat");
    let res = cellsim(&["sweep", &file, "--out", &dir, "--jobs", "2", "--quiet"]);
    let (stdout, stderr) = text(&res);
    assert!(res.status.success(), "{stderr}");
    // y_s = -2.0 is the base's own value: that point is the base, run once.
    assert!(stdout.contains("3 points: 3 finished"), "{stdout}");
    let rows = csv(&format!("{dir}/sweep.csv"));
    let ids: Vec<&str> = rows.iter().map(|r| r["id"].as_str()).collect();
    assert_eq!(ids, ["base", "o0_1", "o1_0"]);
    assert_eq!(rows[0]["substrate.y_s"], "-2.0");
    assert_eq!(rows[0]["gravity.g_m_s2"], "9.81");
    assert!(Path::new(&format!("{dir}/tornado.png")).exists());
    let s = std::fs::read_to_string(format!("{dir}/sensitivities.csv")).unwrap();
    // uy_top = −(fall − 0.1): (ΔQ/Q)/(Δp/p) = ((−0.5 + 0.4)/−0.4)/((−2.1 + 2)/−2) ≈ 5.
    let line = s
        .lines()
        .find(|l| l.starts_with("uy_top,substrate.y_s,"))
        .unwrap_or_else(|| panic!("{s}"));
    let sens: f64 = line.rsplit(',').next().unwrap().parse().unwrap();
    assert!((sens - 5.0).abs() < 0.3, "{line}");

    // --slurm writes the job array script and runs nothing.
    let sl = tmp("sweep-slurm");
    let res = cellsim(&[
        "sweep",
        &file,
        "--out",
        &sl,
        "--slurm",
        "--shard-size",
        "2",
        "--throttle",
        "4",
        "--slurm-opt=--partition=short",
        "--slurm-opt",
        "--time=00:10:00",
    ]);
    let (stdout, stderr) = text(&res);
    assert!(res.status.success(), "{stderr}");
    assert!(stdout.contains("3 points in 2 array tasks"), "{stdout}");
    let script = std::fs::read_to_string(format!("{sl}/sweep.sbatch")).unwrap();
    for needle in [
        "#SBATCH --array=0-1%4\n",
        "#SBATCH --partition=short\n",
        "#SBATCH --time=00:10:00\n",
        "#SBATCH --cpus-per-task=1\n",
        "--shard \"${SLURM_ARRAY_TASK_ID}/2\"",
        "/slurm/%A_%a.out\n",
    ] {
        assert!(script.contains(needle), "`{needle}` not in:\n{script}");
    }
    // The user's --time replaces the estimate; the memory is estimated (MB, at least the
    // process's own 200 MB).
    assert_eq!(script.matches("#SBATCH --time").count(), 1, "{script}");
    let mem: u64 = script
        .lines()
        .find_map(|l| l.strip_prefix("#SBATCH --mem="))
        .and_then(|v| v.strip_suffix('M'))
        .unwrap_or_else(|| panic!("no estimated --mem in:\n{script}"))
        .parse()
        .expect("MB");
    assert!((200..2000).contains(&mem), "{mem} MB");
    assert!(script.contains("# Estimated before meshing:"), "{script}");
    assert!(!Path::new(&format!("{sl}/points")).exists());
}

#[test]
fn sigint_stops_a_sweep_cleanly_and_a_rerun_finishes_it() {
    let dir = tmp("sweep-sigint");
    let child = Command::new(env!("CARGO_BIN_EXE_cellsim"))
        .args(["sweep", SWEEP, "--out", &dir, "--jobs", "1"])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("start cellsim");
    // Wait until the first point has written a few rows.
    let series = format!("{dir}/points/g0_0/timeseries.csv");
    let start = std::time::Instant::now();
    while std::fs::read_to_string(&series).map_or(0, |t| t.lines().count()) < 3 {
        assert!(start.elapsed().as_secs() < 60, "no output rows");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let killed = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .expect("kill");
    assert!(killed.success());
    let res = child.wait_with_output().expect("wait");
    let (stdout, stderr) = text(&res);
    assert_eq!(res.status.code(), Some(130), "{stdout}\n{stderr}");
    let rows = csv(&format!("{dir}/sweep.csv"));
    let status: Vec<&str> = rows.iter().map(|r| r["status"].as_str()).collect();
    assert_eq!(status[0], "interrupted", "{rows:?}");
    assert!(
        rows[0]["reason"].starts_with("interrupted by SIGINT"),
        "{rows:?}"
    );
    assert!(status.contains(&"missing"), "{status:?}");
    // The rerun runs the interrupted and missing points.
    let res = cellsim(&["sweep", SWEEP, "--out", &dir, "--jobs", "2", "--quiet"]);
    let (stdout, stderr) = text(&res);
    assert!(res.status.success(), "{stderr}");
    assert!(stdout.contains("4 finished"), "{stdout}");
}

#[test]
fn variant_axes_run_a_case_once_and_write_the_comparison_table() {
    let file = sweep_file(
        "variants",
        r#"    design: Grid([
        (name: "reading", variants: [
            (name: "base"),
            (name: "same", set: ["materials.gamma=0.1"]),
            (name: "lower", set: ["substrate.y_s=-2.1"]),
        ]),
        (name: "scene", variants: [(name: "fall", set: ["phases.t_end=12.0"])]),
    ]),
    table: (
        rows: "reading",
        reference: "paper",
        groups: [(title: "The fall", columns: [
            (key: "down", label: "p_t down at the end", of: "fall", quantity: "uy_top",
             scale: -1.0, reference: 0.4, score: true, digits: 3),
        ])],
        summary: ["down"],
        documents: [(path: "doc.md", part: Full)],
    ),"#,
    );
    let doc = Path::new(&file).with_file_name("doc.md");
    let marks = "<!-- cellsim sweep variants: begin -->\n<!-- cellsim sweep variants: end -->\n";
    std::fs::write(&doc, format!("# Doc\n{marks}after\n")).unwrap();
    let out = tmp("sweep-variants");
    let res = cellsim(&["sweep", &file, "--out", &out, "--jobs", "2"]);
    let (stdout, stderr) = text(&res);
    assert_eq!(res.status.code(), Some(0), "{stdout}\n{stderr}");
    // `same` resolves to the base's case (γ = 0.1 is the default): copied, not run.
    assert!(stdout.contains("(2 run, 0 reused, 1 copied)"), "{stdout}");
    assert!(
        stderr.contains("g1_0 finished: the same case as g0_0, copied"),
        "{stderr}"
    );
    let rows = csv(&format!("{out}/sweep.csv"));
    assert_eq!(rows[1]["reading"], "same");
    assert_eq!(rows[1]["scene"], "fall");
    assert_eq!(rows[1]["uy_top"], rows[0]["uy_top"]);
    // The table: the paper's row, `=` for the copy, the lower substrate 0.1 µm further.
    let table = std::fs::read_to_string(format!("{out}/table.csv")).unwrap();
    let lines: Vec<&str> = table.lines().collect();
    assert_eq!(lines[..2], ["reading,down", "paper,0.4"], "{table}");
    let down = |l: &str| l.split(',').nth(1).unwrap().parse::<f64>().unwrap();
    assert!(
        (down(lines[4]) - down(lines[2]) - 0.1).abs() < 0.01,
        "{table}"
    );
    assert_eq!(down(lines[3]), down(lines[2]));
    let md = std::fs::read_to_string(format!("{out}/table.md")).unwrap();
    assert!(md.contains("| reading | p_t down at the end |"), "{md}");
    assert!(md.contains("| same | = |"), "{md}");
    assert!(md.contains("| lower | `substrate.y_s=-2.1` |"), "{md}");
    let written = std::fs::read_to_string(&doc).unwrap();
    assert!(written.starts_with("# Doc\n<!-- cellsim sweep variants: begin -->\n_Generated by"));
    assert!(
        written.contains("| same | = |") && written.ends_with("end -->\nafter\n"),
        "{written}"
    );
    // Again: everything reused, the document unchanged.
    let res = cellsim(&["sweep", &file, "--out", &out, "--jobs", "2"]);
    let (stdout, _) = text(&res);
    assert!(stdout.contains("(0 run, 3 reused)"), "{stdout}");
    assert_eq!(std::fs::read_to_string(&doc).unwrap(), written);
}

/// `sweep plane-vs-3d` reads two sweep directories (here the committed plane-strain map,
/// twice) and draws the figure; a sweep without pillars is refused with the reason.
#[test]
fn plane_vs_3d_draws_two_geometry_sweeps_and_refuses_a_flat_one() {
    let out = format!("{}/plane-vs-3d.png", tmp("sweep-plane-vs-3d"));
    std::fs::create_dir_all(Path::new(&out).parent().unwrap()).unwrap();
    let map = "plots/sweeps/pillar-geometry";
    let res = cellsim(&["sweep", "plane-vs-3d", map, map, "--out", &out]);
    let (stdout, stderr) = text(&res);
    assert!(res.status.success(), "{stderr}");
    assert_eq!(stdout.trim(), out);
    assert!(std::fs::metadata(&out).unwrap().len() > 1000);
    // A flat sweep has no pillar geometry.
    let flat = tmp("sweep-plane-vs-3d-flat");
    let res = cellsim(&["sweep", SWEEP, "--out", &flat, "--quiet"]);
    assert!(res.status.success(), "{}", text(&res).1);
    let res = cellsim(&["sweep", "plane-vs-3d", map, &flat]);
    let (_, stderr) = text(&res);
    assert_eq!(res.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("no point on pillars"), "{stderr}");
}

/// The 3-D map at the default 3-D mesh is one command away on a cluster: `--set` overrides
/// the sweep file's map configuration for every point, the batch script passes it on to
/// the array's tasks, and its estimates follow the finer mesh (the map configuration's
/// 722 s and 0.86 GB a point against the default mesh's 1 551 s and 2.63 GB).
#[test]
fn set_on_the_command_line_runs_the_3d_map_on_the_default_mesh_on_a_cluster() {
    let file = "cases/sweeps/pillar-geometry-3d.ron";
    let estimate = |dir: &str, set: &[&str]| {
        let mut args = vec!["sweep", file, "--out", dir, "--slurm"];
        args.extend_from_slice(set);
        let res = cellsim(&args);
        let (_, stderr) = text(&res);
        assert!(res.status.success(), "{stderr}");
        let script = std::fs::read_to_string(format!("{dir}/sweep.sbatch")).unwrap();
        let line = script
            .lines()
            .find(|l| l.starts_with("# Estimated before meshing:"))
            .unwrap_or_else(|| panic!("{script}"))
            .to_string();
        let number = |before: &str| -> f64 {
            let (_, rest) = line.split_once("the longest task ").unwrap();
            let rest = if before == "s" {
                rest
            } else {
                rest.split_once(" s and ").unwrap().1
            };
            rest.split_whitespace().next().unwrap().parse().unwrap()
        };
        (number("s"), number("MB"), script)
    };
    let (coarse_s, coarse_mb, _) = estimate(&tmp("sweep-3d-map"), &[]);
    let (s, mb, script) = estimate(
        &tmp("sweep-3d-default"),
        &["--set", "mesh.h_bottom=0.3", "--set", "mesh.h_nucleus=1.0"],
    );
    assert!(
        (coarse_s - 722.0).abs() < 1.0 && (coarse_mb - 860.0).abs() < 1.0,
        "{coarse_s} s, {coarse_mb} MB"
    );
    assert!(
        (s - 1_551.0).abs() < 1.0 && (mb - 2_630.0).abs() < 1.0,
        "{s} s, {mb} MB"
    );
    assert!(
        script.contains("--set 'mesh.h_bottom=0.3' --set 'mesh.h_nucleus=1.0'"),
        "{script}"
    );
    // A bad --set is refused with the sweep file's name and the field.
    let res = cellsim(&["sweep", file, "--list", "--set", "mesh.h_botom=0.3"]);
    let (_, stderr) = text(&res);
    assert_eq!(res.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("pillar-geometry-3d.ron (with the command line's --set)"),
        "{stderr}"
    );
    assert!(stderr.contains("h_botom"), "{stderr}");
}
