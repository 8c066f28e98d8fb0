//! The `cellsim` command line: load a case → build the model → integrate → write outputs.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use clap::{Parser, Subcommand, ValueEnum};

use cellsim::case::{self, Case};
use cellsim::dae::LinearSolverKind;
use cellsim::fem::Mesh;
use cellsim::output::{self, RunData, SnapshotOptions, paper};
use cellsim::run::{self, Progress, RunOptions, RunSettings};
use cellsim::scene;
use cellsim::study;

/// Finite-element simulation of a cell settling, spreading and contracting on a flat or
/// micropillared substrate (Mondésert-Deveraux, Aubry & Allena 2019), integrated with
/// SUNDIALS IDA or a fixed-step BDF2.
#[derive(Parser)]
#[command(name = "cellsim", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Clone, Copy, ValueEnum)]
enum IntegratorArg {
    /// SUNDIALS IDA (variable-order BDF).
    Ida,
    /// Fixed-step BDF2.
    Bdf2,
}

#[derive(Subcommand)]
enum Command {
    /// Run one scene: writes timeseries.csv, summary.json, mesh.json and state_<phase>.json.
    Run {
        /// The case file (RON), e.g. cases/flat.ron.
        case: PathBuf,
        /// Output directory [default: runs/<case name>].
        #[arg(long)]
        out: Option<PathBuf>,
        /// Integrator [default: the case's].
        #[arg(long, value_enum)]
        integrator: Option<IntegratorArg>,
        /// Relative tolerance [default: the case's].
        #[arg(long)]
        rtol: Option<f64>,
        /// Absolute tolerance on displacements, µm [default: the case's].
        #[arg(long)]
        atol: Option<f64>,
        /// BDF2 time step, s [default: the case's].
        #[arg(long)]
        dt: Option<f64>,
        /// Sparse LU [default: the case's].
        #[arg(long, value_enum)]
        linear_solver: Option<LinearSolverKind>,
        /// BDF2 time step while the cell falls with inertia, s, when smaller than --dt
        /// [default: --dt throughout].
        #[arg(long)]
        dt_inertia: Option<f64>,
        /// Wall-clock budget of the integration, s: past it the run stops cleanly with its
        /// outputs so far and the reason in summary.json [default: none].
        #[arg(long)]
        max_wall: Option<f64>,
        /// No progress line.
        #[arg(long)]
        quiet: bool,
        /// Also write a ParaView file per output time (vtu/<case>_NNNNN.vtu) and their
        /// collection <case>.pvd.
        #[arg(long)]
        vtu: bool,
        /// Also write the deformation as an animated GIF (<case>.gif).
        #[arg(long)]
        gif: bool,
    },
    /// Run the five paper scenes (and the upside-down control) and write the paper's
    /// figures and comparison.md.
    Paper {
        /// Output directory: figures, comparison.md and runs/<scene>/.
        #[arg(long, default_value = "plots")]
        out: PathBuf,
        /// Runs at once [default: the number of cores].
        #[arg(long)]
        jobs: Option<usize>,
        /// Read the scene files from this directory instead of the copies of cases/
        /// compiled into cellsim.
        #[arg(long)]
        cases: Option<PathBuf>,
        /// Keep the runs in <out>/runs that finished; run only the others.
        #[arg(long)]
        reuse: bool,
        /// Also write each run's VTU files (see `run --vtu`).
        #[arg(long)]
        vtu: bool,
        /// Also write each run's animated GIF (see `run --gif`).
        #[arg(long)]
        gif: bool,
        /// No progress lines.
        #[arg(long)]
        quiet: bool,
    },
    /// Time-step sensitivity and work-precision study of one scene: a tight IDA reference,
    /// a BDF2 dt ladder and an IDA rtol ladder; writes study.csv, study.json,
    /// work-precision.png, dt-sensitivity.png and each run in runs/<label>/.
    Study {
        /// The case file (RON).
        case: PathBuf,
        /// Output directory [default: runs/study/<case name>].
        #[arg(long)]
        out: Option<PathBuf>,
        /// Quantities of interest shown in study.csv and the figures (comma-separated)
        /// [default: all].
        #[arg(long, value_enum, value_delimiter = ',')]
        quantities: Vec<study::Quantity>,
        /// Largest BDF2 time step, s [default: t_end / 100]; the ladder halves on past rungs
        /// that fail until --rungs rungs from the largest that converges down.
        #[arg(long)]
        dt_max: Option<f64>,
        /// BDF2 rungs (halvings of dt). Six from t_end/100 reach the rungs where contact
        /// onsets are resolved and the order is visible.
        #[arg(long, default_value_t = study::DEFAULT_RUNGS)]
        rungs: usize,
        /// IDA's rtol ladder (comma-separated).
        #[arg(long, value_delimiter = ',', default_values_t = study::DEFAULT_RTOLS)]
        rtols: Vec<f64>,
        /// rtol of the reference (IDA); 10x looser if it fails, and said so.
        #[arg(long, default_value_t = study::DEFAULT_REF_RTOL)]
        ref_rtol: f64,
        /// rtol of BDF2's Newton convergence test.
        #[arg(long, default_value_t = study::DEFAULT_BDF2_RTOL)]
        bdf2_rtol: f64,
        /// BDF2 step during the fall (with inertia) on the largest rung, s, halved with dt
        /// [default: t_s/16 when the case has inertia OffAfter(t_s), else dt throughout].
        #[arg(long)]
        dt_inertia: Option<f64>,
        /// Wall-clock budget of each run, s [default: none].
        #[arg(long)]
        max_wall: Option<f64>,
        /// Keep runs in <out>/runs that finished with the same settings.
        #[arg(long)]
        reuse: bool,
        /// No progress lines while a run integrates.
        #[arg(long)]
        quiet: bool,
    },
    /// Redraw one run's figures from its files (works on a run that stopped early).
    Plot {
        /// The run directory (as written by `cellsim run`).
        run_dir: PathBuf,
        /// Where to write the figures [default: <run_dir>/plots].
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Generate the mesh of a case and print its quality report.
    Mesh {
        /// The case file (RON).
        case: PathBuf,
        /// Also draw it as SVG.
        #[arg(long)]
        svg: Option<PathBuf>,
    },
    /// Check a case file and print it with every default filled in.
    Check {
        /// The case file (RON).
        case: PathBuf,
    },
    /// Print a markdown table of runs (outcome, cost, final values) from their summaries.
    Table {
        /// Run directories (each with a summary.json).
        #[arg(required = true)]
        run_dirs: Vec<PathBuf>,
    },
}

/// Loads a case; a bad case prints its located error and exits with status 2.
fn load_case(path: &Path) -> Result<Case, ExitCode> {
    Case::load(path).map_err(|e| {
        eprintln!("error: {e}");
        ExitCode::from(2)
    })
}

fn check_positive(name: &str, v: Option<f64>, upper: Option<f64>) -> Result<(), ExitCode> {
    if let Some(x) = v {
        let ok = x.is_finite() && x > 0.0 && upper.is_none_or(|u| x < u);
        if !ok {
            let range = match upper {
                Some(u) => format!("0 < {name} < {u}"),
                None => format!("{name} > 0"),
            };
            eprintln!("error: --{name} = {x} is out of range (must satisfy {range})");
            return Err(ExitCode::from(2));
        }
    }
    Ok(())
}

fn interrupt_flag() -> Arc<AtomicBool> {
    let flag = Arc::new(AtomicBool::new(false));
    let f = flag.clone();
    // A second Ctrl-C while stopping falls through to the default (exit).
    let _ = ctrlc::set_handler(move || {
        if f.swap(true, Ordering::SeqCst) {
            std::process::exit(130);
        }
        eprintln!(
            "\ninterrupted: finishing the current step and writing the summary (Ctrl-C again to quit now)"
        );
    });
    flag
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Run {
            case: path,
            out,
            integrator,
            rtol,
            atol,
            dt,
            linear_solver,
            dt_inertia,
            max_wall,
            quiet,
            vtu,
            gif,
        } => {
            let case = match load_case(&path) {
                Ok(c) => c,
                Err(code) => return code,
            };
            for (name, v, upper) in [
                ("rtol", rtol, Some(1.0)),
                ("atol", atol, None),
                ("dt", dt, None),
                ("dt-inertia", dt_inertia, None),
                ("max-wall", max_wall, None),
            ] {
                if let Err(code) = check_positive(name, v, upper) {
                    return code;
                }
            }
            let mut settings = RunSettings::from_case(&case);
            if let Some(i) = integrator {
                settings.integrator = match i {
                    IntegratorArg::Ida => case::Integrator::Ida,
                    IntegratorArg::Bdf2 => case::Integrator::Bdf2,
                };
            }
            settings.rtol = rtol.unwrap_or(settings.rtol);
            settings.atol = atol.unwrap_or(settings.atol);
            settings.dt = dt.unwrap_or(settings.dt);
            settings.linear_solver = linear_solver.unwrap_or(settings.linear_solver);
            settings.dt_inertia = dt_inertia;
            settings.max_wall_seconds = max_wall;
            let out = out.unwrap_or_else(|| PathBuf::from("runs").join(&case.name));
            let visible = !quiet && std::io::stderr().is_terminal();
            let opts = RunOptions {
                out: out.clone(),
                settings,
                progress: Progress::Bar(run::progress_bar(&case, visible)),
                interrupt: interrupt_flag(),
                snapshots: SnapshotOptions { vtu, gif },
            };
            match run::run(&case, &path.display().to_string(), &opts) {
                Ok(s) => {
                    let f = s.final_values.unwrap_or_default();
                    println!(
                        "{}: finished t = {} s in {:.1} s wall ({} steps, {} Jacobians, {} unknowns); contact radius {:.3} µm, uy(p_t) {:.4} µm, mean |E| nucleus {:.1} %, cytoplasm {:.1} %; outputs in {}",
                        s.case,
                        f.t,
                        s.wall_seconds,
                        s.stats.steps,
                        s.stats.jacobian_evals,
                        s.unknowns.total,
                        f.contact_radius,
                        f.uy_top,
                        100.0 * f.strain_nucleus,
                        100.0 * f.strain_cytoplasm,
                        out.display()
                    );
                    if let Some(t) = &s.timers {
                        print!("{}", t.table());
                    }
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    eprintln!("error: {e}");
                    if matches!(e, run::RunError::Scene(_)) {
                        ExitCode::from(2)
                    } else {
                        ExitCode::FAILURE
                    }
                }
            }
        }
        Command::Paper {
            out,
            jobs,
            cases,
            reuse,
            vtu,
            gif,
            quiet,
        } => {
            let jobs =
                jobs.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
            if jobs == 0 {
                eprintln!("error: --jobs must be at least 1");
                return ExitCode::from(2);
            }
            let opts = paper::PaperOptions {
                out: out.clone(),
                jobs,
                cases,
                reuse,
                snapshots: SnapshotOptions { vtu, gif },
                progress: !quiet,
                interrupt: interrupt_flag(),
            };
            match paper::run_paper(&opts) {
                Ok(report) => {
                    for p in &report.problems {
                        eprintln!("error: {p}");
                    }
                    for r in &report.runs {
                        if let Err(e) = &r.result {
                            eprintln!("error: {e}");
                        }
                    }
                    println!(
                        "{} files written in {} (comparison table: {})",
                        report.written.len(),
                        out.display(),
                        out.join("comparison.md").display()
                    );
                    if report.ok() {
                        ExitCode::SUCCESS
                    } else {
                        ExitCode::FAILURE
                    }
                }
                Err(e) => {
                    eprintln!("error: {e}");
                    ExitCode::from(2)
                }
            }
        }
        Command::Study {
            case: path,
            out,
            quantities,
            dt_max,
            rungs,
            rtols,
            ref_rtol,
            bdf2_rtol,
            dt_inertia,
            max_wall,
            reuse,
            quiet,
        } => {
            let case = match load_case(&path) {
                Ok(c) => c,
                Err(code) => return code,
            };
            let mut checks = vec![
                ("ref-rtol", Some(ref_rtol), Some(1.0)),
                ("bdf2-rtol", Some(bdf2_rtol), Some(1.0)),
                ("dt-max", dt_max, None),
                ("dt-inertia", dt_inertia, None),
                ("max-wall", max_wall, None),
            ];
            checks.extend(rtols.iter().map(|r| ("rtols", Some(*r), Some(1.0))));
            for (name, v, upper) in checks {
                if let Err(code) = check_positive(name, v, upper) {
                    return code;
                }
            }
            if rungs < 2 || rtols.is_empty() {
                eprintln!("error: --rungs must be at least 2 and --rtols not empty");
                return ExitCode::from(2);
            }
            let out = out.unwrap_or_else(|| PathBuf::from("runs/study").join(&case.name));
            let defaults = study::StudySettings::defaults(&case);
            let dt_max = dt_max.unwrap_or(defaults.dt_max);
            let settings = study::StudySettings {
                dt_max,
                rungs,
                rtols,
                ref_rtol,
                bdf2_rtol,
                dt_inertia: dt_inertia.or_else(|| study::default_dt_inertia(&case, dt_max)),
                max_wall,
                quantities: if quantities.is_empty() {
                    defaults.quantities
                } else {
                    quantities
                },
            };
            let opts = study::StudyOptions {
                out: out.clone(),
                settings,
                reuse,
                progress: !quiet,
                interrupt: interrupt_flag(),
            };
            match study::run_study(&case, &path.display().to_string(), &opts) {
                Ok(report) => {
                    print!("{}", study::summary_text(&report));
                    println!("study written in {}", out.display());
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    eprintln!("error: {e}");
                    ExitCode::FAILURE
                }
            }
        }
        Command::Plot { run_dir, out } => {
            let run = match RunData::load(&run_dir) {
                Ok(r) => r,
                Err(e) => {
                    eprintln!("error: {e}");
                    return ExitCode::from(2);
                }
            };
            for n in &run.notes {
                eprintln!("note: {n}");
            }
            let out = out.unwrap_or_else(|| run_dir.join("plots"));
            match output::figures::plot_run(&run, &out) {
                Ok(files) => {
                    for f in files {
                        println!("{}", f.display());
                    }
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    eprintln!("error: {e}");
                    ExitCode::FAILURE
                }
            }
        }
        Command::Mesh { case: path, svg } => {
            let case = match load_case(&path) {
                Ok(c) => c,
                Err(code) => return code,
            };
            match Mesh::generate(&scene::mesh_params(&case)) {
                Ok(mesh) => {
                    println!("{}", mesh.quality());
                    if let Some(p) = svg {
                        if let Err(e) = mesh.write_svg(&p) {
                            eprintln!("error: {e}");
                            return ExitCode::FAILURE;
                        }
                    }
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    eprintln!("error: {}: mesh: {e}", path.display());
                    ExitCode::from(2)
                }
            }
        }
        Command::Check { case: path } => match load_case(&path) {
            Ok(c) => match c.to_ron() {
                Ok(text) => {
                    println!("{text}");
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    eprintln!("error: {e}");
                    ExitCode::FAILURE
                }
            },
            Err(code) => code,
        },
        Command::Table { run_dirs } => {
            println!("{}", output::table::HEADER);
            let mut status = ExitCode::SUCCESS;
            for dir in run_dirs {
                match output::table::read_summary(&dir) {
                    Ok(s) => println!("{}", output::table::row(&s)),
                    Err(e) => {
                        eprintln!("error: {e}");
                        status = ExitCode::from(2);
                    }
                }
            }
            status
        }
    }
}
