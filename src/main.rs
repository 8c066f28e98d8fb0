//! The `cellsim` command line: load a case → build the model → integrate → write outputs.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Parser, Subcommand, ValueEnum};

use cellsim::case::{Case, Override};
use cellsim::commands::paper;
use cellsim::commands::step_study;
use cellsim::commands::sweep;
use cellsim::fem::Mesh;
use cellsim::render::{self, RunData, SnapshotOptions};
use cellsim::run::{self, Progress, RunOptions};
use cellsim::scene;
use cellsim::solver::{self, Limits};
use cellsim::stop::{self, StopFlag};

const LONG_ABOUT: &str = "\
Finite-element simulation of a living cell that settles under gravity onto a flat or \
micropillared substrate, spreads by adhesion and contracts its actin, pulling its nucleus \
between the pillars: the model of Mondésert-Deveraux, Aubry & Allena (Biomech Model \
Mechanobiol 2019).

The cell (nucleus, cytoplasm, membrane) is a large-strain compressible Yeoh solid with \
Kelvin-Voigt viscosity and active strain, in one of three models (the case's \
geometry.model): PlaneStrain, the paper's half cell on six-node triangles; Axisymmetric, \
the same half mesh read as the meridian of a ball (flat substrate only); ThreeD, the quarter \
of the ball on ten-node tetrahedra meshed by gmsh, over a flat substrate or a lattice of \
pillars. Gravity, penalty contact, adhesion and the adhesion coefficient (an unknown field) \
make one implicit DAE F(t, y, y') = 0. It is integrated by SUNDIALS IDA (variable-order, variable-step BDF) with \
an exact sparse Jacobian, and verified by a fixed-step BDF2 on the same residual. A scene \
is a RON case file (cases/*.ron); every run writes its time series, states and summary as \
it goes.";

const EXIT_STATUSES: &str = "\
Exit status:
  0    success
  1    the integration failed, was stopped by its own limits (step limit, stall, \
wall-clock budget) or reached a state that left the scene (a node moved further than the \
cell's diameter plus its height above the substrate: not written); the outputs so far and \
summary.json (with the reason) are kept
  2    bad input: a case file, a value on the command line (--set, --rtol above 0.1, \
--atol above 0.01 µm, ...), a missing file, or a mesh too large for this machine's memory \
(refused before meshing, with the estimate): nothing is run
  129  stopped by SIGHUP, 130 by SIGINT (Ctrl-C), 143 by SIGTERM: the current step is \
finished, the outputs and summary.json are written, with the signal and time as reason";

/// Finite-element simulation of a cell settling, spreading and contracting on a flat or
/// micropillared substrate, integrated with SUNDIALS IDA or a fixed-step BDF2.
#[derive(Parser)]
#[command(
    name = "cellsim",
    version,
    about,
    long_about = LONG_ABOUT,
    after_help = EXIT_STATUSES,
    // `--rtol -1` must reach the range check, not be read as an option.
    allow_negative_numbers = true
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// A quantity of interest of a study.
#[derive(Clone, Copy, ValueEnum)]
enum QuantityArg {
    /// Final vertical displacement of the nucleus top.
    UyTop,
    /// Final contact radius.
    ContactRadius,
    /// Final mean strain norm over the nucleus.
    StrainNucleus,
    /// Final mean strain norm over the cytoplasm.
    StrainCytoplasm,
    /// The nucleus-top displacement over time (largest error in time).
    UyTopCurve,
}

impl From<QuantityArg> for step_study::Quantity {
    fn from(a: QuantityArg) -> Self {
        match a {
            QuantityArg::UyTop => step_study::Quantity::UyTop,
            QuantityArg::ContactRadius => step_study::Quantity::ContactRadius,
            QuantityArg::StrainNucleus => step_study::Quantity::StrainNucleus,
            QuantityArg::StrainCytoplasm => step_study::Quantity::StrainCytoplasm,
            QuantityArg::UyTopCurve => step_study::Quantity::UyTopCurve,
        }
    }
}

/// Writes a line to stdout; a closed pipe (`cellsim check CASE | head -1`) ends the
/// program quietly instead of panicking.
macro_rules! out {
    ($($arg:tt)*) => {{
        let mut o = std::io::stdout().lock();
        if let Err(e) = writeln!(o, $($arg)*).and_then(|_| o.flush()) {
            if e.kind() == std::io::ErrorKind::BrokenPipe {
                std::process::exit(0);
            }
        }
    }};
}

/// Writes a line to stderr, ignoring a closed stderr.
macro_rules! err {
    ($($arg:tt)*) => {{
        let _ = writeln!(std::io::stderr(), $($arg)*);
    }};
}

#[derive(Subcommand)]
enum Command {
    /// Run one scene: writes timeseries.csv, summary.json, mesh.json and state_<phase>.json
    /// as it goes (and state_stopped.json where a run stops early).
    Run(RunArgs),
    /// Run the five paper scenes (and the upside-down control) and write the paper's
    /// figures and comparison.md.
    Paper(PaperArgs),
    /// Time-step sensitivity and work-precision study of one scene: a tight IDA reference,
    /// a BDF2 dt ladder and an IDA rtol ladder; writes study.csv, study.json,
    /// work-precision.png, dt-sensitivity.png and each run in runs/<label>/.
    Study(StudyArgs),
    /// Run a sweep: many runs of one base case with fields changed (a Grid, Zip,
    /// OneAtATime or LatinHypercube design), in parallel and resumable, into
    /// DIR/points/<id>/; writes sweep.csv, sweep.json and figures. `sweep plot DIR`
    /// redraws the figures, `sweep collect DIR` assembles the shards of a Slurm array.
    Sweep(SweepArgs),
    /// The derivatives of a scene's measures with respect to case parameters, integrated
    /// by SUNDIALS IDAS with the solution (forward sensitivities): writes
    /// sensitivity.csv (per output time and parameter, ∂m/∂p of timeseries.csv's
    /// measures) and prints the final normalised sensitivities p/m ∂m/∂p. Through the
    /// inertia switch (restarted consistently) and with the μ_as unknowns in the system from
    /// the start; phases started by a condition are refused.
    Sensitivity {
        /// The case file (RON).
        case: PathBuf,
        /// A parameter: the dotted path of a number field of the case, e.g.
        /// materials.cytoplasm.e (repeatable).
        #[arg(long = "param", value_name = "PATH", required = true)]
        params: Vec<String>,
        /// Change a field of the case first (as `run --set`; repeatable).
        #[arg(long = "set", value_name = "PATH=VALUE", allow_hyphen_values = true)]
        set: Vec<Override>,
        /// Output directory [default: runs/<case name>-sensitivity].
        #[arg(long)]
        out: Option<PathBuf>,
        /// Include the sensitivities in the integrator's error test (their own accuracy
        /// controlled, at the price of more steps: 3.6× on push-pull-short-drag).
        #[arg(long)]
        error_control: bool,
    },
    /// Fit case parameters to measurements (FIT.ron: cases, parameters with bounds and
    /// scales, targets) by weighted least squares, Levenberg–Marquardt with bounds,
    /// gradients from the IDAS sensitivities (differences of whole runs for a case with a
    /// phase started by a condition): writes fit.json (values, standard errors,
    /// correlations, what the data cannot determine), history.csv, residuals.csv and
    /// fit-<case>-<measure>.png. With --make-data: writes the Series targets' data files
    /// from runs at --truth with --noise (a twin experiment).
    Fit(FitArgs),
    /// Redraw one run's figures from its files (works on a run that stopped early).
    Plot {
        /// The run directory (as written by `cellsim run`).
        run_dir: PathBuf,
        /// Where to write the figures [default: <run_dir>/plots].
        #[arg(long)]
        out: Option<PathBuf>,
        /// Other runs to draw beside this one in compare-*.png (contact radius,
        /// displacement, strain over time): a 3-D scene beside its 2-D run, say.
        #[arg(long = "with", value_name = "RUN_DIR")]
        with: Vec<PathBuf>,
    },
    /// Generate the mesh of a case and print its quality report.
    Mesh {
        /// The case file (RON).
        case: PathBuf,
        /// Also draw it as SVG.
        #[arg(long)]
        svg: Option<PathBuf>,
    },
    /// Check a case file (every rule a run would check before integrating) and print it
    /// with every default filled in.
    Check {
        /// The case file (RON).
        case: PathBuf,
        /// Change a field of the case before it is validated: a dotted path and a RON value,
        /// e.g. --set substrate.spacing=6.0 --set active.bottom.e=0.5 (repeatable; later ones
        /// win).
        #[arg(long = "set", value_name = "PATH=VALUE", allow_hyphen_values = true)]
        set: Vec<Override>,
    },
    /// Print a markdown table of runs (outcome, cost, final values) from their summaries.
    Table {
        /// Run directories (each with a summary.json).
        #[arg(required = true)]
        run_dirs: Vec<PathBuf>,
        /// The phases' table instead: when adhesion and the active strain started (on
        /// their conditions, MODEL.md §11, or at the case's times), the end, the cost and
        /// the final values.
        #[arg(long)]
        phases: bool,
        /// The measures a map reports instead: penetration depth and contact area (3-D),
        /// u_y of p_t and p_b, contact radius deformed and reference, mean and largest
        /// nucleus strain; after each run but the first, its relative difference from the
        /// first.
        #[arg(long, conflicts_with = "phases")]
        measures: bool,
    },
}

#[derive(clap::Args)]
#[command(allow_negative_numbers = true)]
struct RunArgs {
    /// The case file (RON), e.g. cases/flat.ron.
    case: PathBuf,
    /// Change a field of the case before it is validated: a dotted path and a RON value,
    /// e.g. --set substrate.spacing=6.0 --set active.bottom.e=0.5 (repeatable; later ones
    /// win).
    #[arg(long = "set", value_name = "PATH=VALUE", allow_hyphen_values = true)]
    set: Vec<Override>,
    /// Output directory [default: runs/<case name>].
    #[arg(long)]
    out: Option<PathBuf>,
    /// Integrator: ida (SUNDIALS IDA, variable-order BDF) or bdf2 (fixed-step BDF2); the
    /// same as --set solver.integrator=Ida or Bdf2 [default: the case's].
    #[arg(long, value_name = "NAME")]
    integrator: Option<String>,
    /// Relative tolerance, 0 < rtol <= 0.1: the same as --set solver.rtol=R, checked by the
    /// case's rule [default: the case's]. Looser tolerances let the error test pass
    /// nonsense; a state that leaves the scene anyway (a node moved further than the
    /// cell's diameter plus its height above the substrate) stops the run with exit
    /// status 1.
    #[arg(long, value_name = "R", allow_hyphen_values = true)]
    rtol: Option<String>,
    /// Absolute tolerance on displacements, µm, 0 < atol <= 0.01: the same as --set
    /// solver.atol=A [default: the case's].
    #[arg(long, value_name = "A", allow_hyphen_values = true)]
    atol: Option<String>,
    /// BDF2 time step, s, > 0: the same as --set solver.bdf2_dt=DT [default: the case's].
    #[arg(long, value_name = "DT", allow_hyphen_values = true)]
    dt: Option<String>,
    /// Sparse LU: faer, klu, faer-condensed (the velocities eliminated while inertia is
    /// on), klu-metis, umfpack, umfpack-nd (UMFPACK on METIS's nested dissection) or
    /// umfpack-condensed, or the case file's names (FaerCondensed, ...); the same as --set
    /// solver.linear_solver=FaerCondensed, ... [default: the case's].
    #[arg(long, value_name = "NAME")]
    linear_solver: Option<String>,
    /// BDF2 time step while the cell falls with inertia, s, when smaller than --dt
    /// [default: --dt throughout].
    #[arg(long, allow_hyphen_values = true)]
    dt_inertia: Option<f64>,
    /// Wall-clock budget of the integration, s: past it the run stops cleanly with its
    /// outputs so far and the reason in summary.json [default: none].
    #[arg(long, allow_hyphen_values = true)]
    max_wall: Option<f64>,
    /// No progress display (by default a progress bar on a terminal, a plain line every
    /// 10 s otherwise).
    #[arg(long)]
    quiet: bool,
    /// Also write a ParaView file per output time (vtu/<case>_NNNNN.vtu) and their
    /// collection <case>.pvd.
    #[arg(long)]
    vtu: bool,
    /// Also write the deformation as an animated GIF (<case>.gif).
    #[arg(long)]
    gif: bool,
}

#[derive(clap::Args)]
#[command(allow_negative_numbers = true)]
struct PaperArgs {
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
    /// No progress display.
    #[arg(long)]
    quiet: bool,
}

#[derive(clap::Args)]
#[command(allow_negative_numbers = true)]
struct StudyArgs {
    /// The case file (RON).
    case: PathBuf,
    /// Change a field of the case before it is validated: a dotted path and a RON value,
    /// e.g. --set substrate.spacing=6.0 --set active.bottom.e=0.5 (repeatable; later ones
    /// win).
    #[arg(long = "set", value_name = "PATH=VALUE", allow_hyphen_values = true)]
    set: Vec<Override>,
    /// Output directory [default: runs/study/<case name>].
    #[arg(long)]
    out: Option<PathBuf>,
    /// Quantities of interest shown in study.csv and the figures (comma-separated)
    /// [default: all].
    #[arg(long, value_enum, value_delimiter = ',')]
    quantities: Vec<QuantityArg>,
    /// Largest BDF2 time step, s [default: t_end / 100]; the ladder halves on past rungs
    /// that fail until --rungs rungs from the largest that converges down.
    #[arg(long, allow_hyphen_values = true)]
    dt_max: Option<f64>,
    /// BDF2 rungs (halvings of dt), at least 2. Six from t_end/100 reach the rungs where
    /// contact onsets are resolved and the order is visible.
    #[arg(long, default_value_t = step_study::DEFAULT_RUNGS)]
    rungs: usize,
    /// IDA's rtol ladder (comma-separated).
    #[arg(long, allow_hyphen_values = true, value_delimiter = ',', default_values_t = step_study::DEFAULT_RTOLS)]
    rtols: Vec<f64>,
    /// rtol of the reference (IDA); 10x looser if it fails, and said so.
    #[arg(long, allow_hyphen_values = true, default_value_t = step_study::DEFAULT_REF_RTOL)]
    ref_rtol: f64,
    /// rtol of BDF2's Newton convergence test.
    #[arg(long, allow_hyphen_values = true, default_value_t = step_study::DEFAULT_BDF2_RTOL)]
    bdf2_rtol: f64,
    /// BDF2 step during the fall (with inertia) on the largest rung, s, halved with dt
    /// [default: t_s/16 when the case has inertia OffAfter(t_s), else dt throughout].
    #[arg(long, allow_hyphen_values = true)]
    dt_inertia: Option<f64>,
    /// Wall-clock budget of each run, s [default: none].
    #[arg(long, allow_hyphen_values = true)]
    max_wall: Option<f64>,
    /// Keep runs in <out>/runs that finished with the same settings.
    #[arg(long)]
    reuse: bool,
    /// No progress display while a run integrates.
    #[arg(long)]
    quiet: bool,
}

#[derive(clap::Args)]
struct FitArgs {
    /// The fit file (RON), e.g. cases/fits/twin.ron.
    fit: PathBuf,
    /// Output directory [default: runs/fit/<fit name>].
    #[arg(long)]
    out: Option<PathBuf>,
    /// Runs at once (cases, difference runs).
    #[arg(long, default_value_t = 2)]
    jobs: usize,
    /// No line per evaluation on stderr.
    #[arg(long)]
    quiet: bool,
    /// Do not fit: write each Series target's data file from runs at --truth, with
    /// Gaussian noise of --noise (a twin experiment's data).
    #[arg(long)]
    make_data: bool,
    /// With --make-data: a parameter's true value, PATH=VALUE (repeatable; the others at
    /// their start).
    #[arg(long = "truth", value_name = "PATH=VALUE", allow_hyphen_values = true)]
    truth: Vec<String>,
    /// With --make-data: a measured column and its noise σ, COLUMN=SIGMA (repeatable).
    #[arg(long = "noise", value_name = "COLUMN=SIGMA")]
    noise: Vec<String>,
    /// With --make-data: the noise's seed.
    #[arg(long, default_value_t = 1)]
    seed: u64,
}

#[derive(clap::Args)]
#[command(
    args_conflicts_with_subcommands = true,
    subcommand_negates_reqs = true,
    allow_negative_numbers = true
)]
struct SweepArgs {
    #[command(subcommand)]
    action: Option<SweepAction>,
    /// The sweep file (RON), e.g. cases/sweeps/pillar-geometry.ron.
    #[arg(required = true)]
    sweep: Option<PathBuf>,
    /// Output directory [default: runs/sweep/<sweep name>].
    #[arg(long)]
    out: Option<PathBuf>,
    /// Runs at once [default: the number of cores].
    #[arg(long)]
    jobs: Option<usize>,
    /// Rerun the points that failed (by default a rerun skips finished and failed points
    /// whose case is unchanged, and reruns interrupted ones).
    #[arg(long)]
    retry_failed: bool,
    /// Run only shard i of K: the points k with k mod K = i (0 <= i < K).
    #[arg(long, value_name = "i/K")]
    shard: Option<String>,
    /// Wall-clock budget of each run, s [default: none].
    #[arg(long, allow_hyphen_values = true)]
    max_wall: Option<f64>,
    /// Override a case field of every point, PATH=VALUE (repeatable), after the sweep
    /// file's own `set` and before the design's values: the same map on another mesh,
    /// e.g. --set mesh.refine=1.5 (give it another --out).
    #[arg(long = "set", value_name = "PATH=VALUE")]
    set: Vec<String>,
    /// No progress display (by default a progress bar on a terminal, a line per finished
    /// point otherwise).
    #[arg(long)]
    quiet: bool,
    /// Do not run: write DIR/sweep.sbatch, a Slurm job array whose tasks run the shards.
    #[arg(long)]
    slurm: bool,
    /// Points per array task (with --slurm).
    #[arg(long, default_value_t = 1)]
    shard_size: usize,
    /// At most this many array tasks at once (with --slurm: --array=0-K%M).
    #[arg(long)]
    throttle: Option<usize>,
    /// An sbatch option for the script, e.g. --slurm-opt=--partition=short (repeatable).
    #[arg(long = "slurm-opt", value_name = "OPTION", allow_hyphen_values = true)]
    slurm_opt: Vec<String>,
    /// With --slurm: submit the script with sbatch and print the job id.
    #[arg(long)]
    submit: bool,
    /// Do not run: print each point (id, axis values, valid or the validation message).
    #[arg(long)]
    list: bool,
}

#[derive(Subcommand)]
enum SweepAction {
    /// Redraw a sweep's figures from DIR/sweep.csv.
    Plot {
        /// The sweep directory.
        dir: PathBuf,
        /// Column shown by the heat map, line or scatter plot [default: penetration_depth].
        #[arg(long)]
        quantity: Option<String>,
    },
    /// Assemble DIR/sweep.csv and the figures from the point directories (after the
    /// shards of a Slurm array have run); lists the points without a run.
    Collect {
        /// The sweep directory.
        dir: PathBuf,
    },
    /// Set a plane-strain sweep of the pillar geometry beside a 3-D one: the quantity
    /// against the spacing, one line per width, plane strain dashed, 3-D solid, the Gap
    /// lattice dotted (run from where the sweeps' base cases can be read).
    #[command(name = "plane-vs-3d")]
    PlaneVs3d {
        /// The plane-strain sweep directory (e.g. plots/sweeps/pillar-geometry).
        plane: PathBuf,
        /// The 3-D sweep directory (e.g. plots/sweeps/pillar-geometry-3d).
        three_d: PathBuf,
        /// The figure [default: THREE_D/plane-vs-3d-<quantity>.png].
        #[arg(long)]
        out: Option<PathBuf>,
        /// Column shown [default: penetration_depth].
        #[arg(long)]
        quantity: Option<String>,
    },
    /// The difference of a column between two sweeps over the same Grid of two axes (a map
    /// and the same map on a refined mesh): B − A point by point, as a heat map
    /// (diff-<quantity>.png) and a table (diff-<quantity>.csv); prints the largest.
    Diff {
        /// The first sweep directory (e.g. plots/sweeps/pillar-geometry-fine).
        a: PathBuf,
        /// The second (e.g. plots/sweeps/pillar-geometry-fine-refined).
        b: PathBuf,
        /// Where the figure and the table go [default: B].
        #[arg(long)]
        out: Option<PathBuf>,
        /// Column compared [default: penetration_depth].
        #[arg(long)]
        quantity: Option<String>,
    },
}

/// Loads a case with its `--set` overrides; a bad case prints its located error and exits
/// with status 2.
fn load_case(path: &Path, set: &[Override]) -> Result<Case, ExitCode> {
    Case::load_with_overrides(path, set).map_err(|e| {
        err!("error: {e}");
        ExitCode::from(2)
    })
}

fn check_positive(name: &str, v: Option<f64>, upper: Option<f64>) -> Result<(), ExitCode> {
    if let Some(x) = v {
        let ok = x.is_finite() && x > 0.0 && upper.is_none_or(|u| x <= u);
        if !ok {
            let range = match upper {
                Some(u) => format!("0 < {name} <= {u}"),
                None => format!("{name} > 0"),
            };
            err!("error: --{name} = {x} is out of range (must satisfy {range})");
            return Err(ExitCode::from(2));
        }
    }
    Ok(())
}

/// The case file's name of the variant of `T` that `typed` names by that name or by its
/// command-line alias (`umfpack-nd` → `UmfpackNd`); else `typed` itself, as a RON raw
/// identifier where it is not a plain one, for the case to refuse with its list of names.
fn variant_name<T: serde::Serialize + serde::de::DeserializeOwned>(typed: &str) -> String {
    let named = serde_json::from_value::<T>(serde_json::Value::String(typed.to_string()))
        .ok()
        .and_then(|v| serde_json::to_value(v).ok());
    match named {
        Some(serde_json::Value::String(name)) => name,
        _ if typed.contains('-') => format!("r#{typed}"),
        _ => typed.to_string(),
    }
}

/// The `--set` overrides that `cellsim run`'s solver flags stand for (`--rtol R` is
/// `--set solver.rtol=R`), each named in messages by the flag as typed, so that a bad value
/// gets the case's own check and message. Applied after the `--set` arguments: a flag wins.
fn flag_overrides(a: &RunArgs) -> Result<Vec<Override>, ExitCode> {
    let flags = [
        (
            "--integrator",
            "integrator",
            &a.integrator,
            variant_name::<solver::Integrator> as fn(&str) -> String,
        ),
        ("--rtol", "rtol", &a.rtol, str::to_string),
        ("--atol", "atol", &a.atol, str::to_string),
        ("--dt", "bdf2_dt", &a.dt, str::to_string),
        (
            "--linear-solver",
            "linear_solver",
            &a.linear_solver,
            variant_name::<solver::LinearSolver>,
        ),
    ];
    let mut set = Vec::new();
    for (flag, field, typed, value) in flags {
        let Some(typed) = typed else { continue };
        match Override::new(&format!("solver.{field}"), &value(typed)) {
            Ok(o) => set.push(o.from_source(format!("{flag} {typed}"))),
            Err(e) => {
                err!("error: {flag} {typed}: {e}");
                return Err(ExitCode::from(2));
            }
        }
    }
    Ok(set)
}

/// Installs the handler of SIGINT, SIGTERM and SIGHUP: the first asks the run to stop
/// cleanly (finish the step, write the outputs and the summary, exit 128 + signal); a
/// second one exits at once with that status.
fn stop_on_signals() -> StopFlag {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    let flag = StopFlag::new();
    let f = flag.clone();
    match signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP]) {
        Ok(mut signals) => {
            std::thread::spawn(move || {
                for sig in signals.forever() {
                    if f.request(sig) {
                        std::process::exit(128 + sig);
                    }
                    err!(
                        "\n{}: finishing the current step and writing the summary (again to quit now)",
                        stop::signal_name(sig)
                    );
                }
            });
        }
        Err(e) => err!("warning: cannot handle signals ({e}): a signal will end the run at once"),
    }
    flag
}

/// The exit status of a run, paper or study that did not succeed: 128 + signal when a
/// signal stopped it, `otherwise` else.
fn failure_status(stop: &StopFlag, otherwise: u8) -> ExitCode {
    ExitCode::from(stop.exit_status().unwrap_or(otherwise))
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Run(args) => run_command(args),
        Command::Paper(args) => paper_command(args),
        Command::Study(args) => study_command(args),
        Command::Sweep(args) => sweep_command(args),
        Command::Sensitivity {
            case,
            params,
            set,
            out,
            error_control,
        } => sensitivity_command(&case, params, &set, out, error_control),
        Command::Fit(args) => fit_command(args),
        Command::Plot { run_dir, out, with } => plot_command(&run_dir, out, &with),
        Command::Mesh { case, svg } => mesh_command(&case, svg.as_deref()),
        Command::Check { case, set } => check_command(&case, &set),
        Command::Table {
            run_dirs,
            phases,
            measures,
        } => table_command(&run_dirs, phases, measures),
    }
}

/// Returns early from a handler with the exit status of an `Err`.
macro_rules! tryc {
    ($e:expr) => {
        match $e {
            Ok(v) => v,
            Err(code) => return code,
        }
    };
}

fn run_command(a: RunArgs) -> ExitCode {
    let mut set = a.set.clone();
    set.extend(tryc!(flag_overrides(&a)));
    let case = tryc!(load_case(&a.case, &set));
    tryc!(check_positive("dt-inertia", a.dt_inertia, None));
    tryc!(check_positive("max-wall", a.max_wall, None));
    let out = a
        .out
        .unwrap_or_else(|| PathBuf::from("runs").join(&case.name));
    let stop = stop_on_signals();
    let opts = RunOptions {
        out: out.clone(),
        settings: case.solver.clone(),
        limits: Limits {
            dt_inertia: a.dt_inertia,
            max_wall_seconds: a.max_wall,
        },
        progress: Progress::for_stderr(&case, a.quiet),
        interrupt: stop.clone(),
        snapshots: SnapshotOptions {
            vtu: a.vtu,
            gif: a.gif,
        },
    };
    match run::run(&case, &a.case.display().to_string(), &opts) {
        Ok(s) => {
            let f = s.final_values.unwrap_or_default();
            out!(
                "{}: finished t = {} s in {:.1} s wall ({} steps, {} Jacobians, {} unknowns); contact radius {:.3} µm ({:.3} µm along the reference contour), uy(p_t) {:.4} µm (nucleus lowest {:.4} µm), mean |E| nucleus {:.1} %, cytoplasm with membrane {:.1} % (membrane {:.1} %); outputs in {}",
                s.case,
                f.t,
                s.wall_seconds,
                s.stats.steps,
                s.stats.jacobian_evals,
                s.unknowns.total,
                f.contact_radius,
                f.contact_radius_ref,
                f.uy_top,
                f.uy_nucleus_max,
                100.0 * f.strain_nucleus,
                100.0 * f.strain_cytoplasm,
                100.0 * f.strain_membrane,
                out.display()
            );
            if let Some(t) = &s.timers {
                out!("{}", t.table().trim_end());
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            err!("error: {e}");
            if matches!(e, run::RunError::Scene(_) | run::RunError::Mesh { .. }) {
                ExitCode::from(2)
            } else {
                failure_status(&stop, 1)
            }
        }
    }
}

fn paper_command(a: PaperArgs) -> ExitCode {
    let jobs = a
        .jobs
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    if jobs == 0 {
        err!("error: --jobs = 0 is out of range (must satisfy jobs >= 1)");
        return ExitCode::from(2);
    }
    let stop = stop_on_signals();
    let opts = paper::PaperOptions {
        out: a.out.clone(),
        jobs,
        cases: a.cases,
        reuse: a.reuse,
        snapshots: SnapshotOptions {
            vtu: a.vtu,
            gif: a.gif,
        },
        progress: !a.quiet,
        interrupt: stop.clone(),
    };
    match paper::run_paper(&opts) {
        Ok(report) => {
            for p in &report.problems {
                err!("error: {p}");
            }
            for r in &report.runs {
                if let Err(e) = &r.result {
                    err!("error: {e}");
                }
            }
            out!(
                "{} files written in {} (comparison table: {}); the runs took {:.1} s wall",
                report.written.len(),
                a.out.display(),
                a.out.join("comparison.md").display(),
                report.runs_seconds
            );
            if report.ok() {
                ExitCode::SUCCESS
            } else {
                failure_status(&stop, 1)
            }
        }
        Err(e) => {
            err!("error: {e}");
            ExitCode::from(2)
        }
    }
}

fn study_command(a: StudyArgs) -> ExitCode {
    let case = tryc!(load_case(&a.case, &a.set));
    let mut checks = vec![
        ("ref-rtol", Some(a.ref_rtol), Some(solver::MAX_RTOL)),
        ("bdf2-rtol", Some(a.bdf2_rtol), Some(solver::MAX_RTOL)),
        ("dt-max", a.dt_max, None),
        ("dt-inertia", a.dt_inertia, None),
        ("max-wall", a.max_wall, None),
    ];
    checks.extend(
        a.rtols
            .iter()
            .map(|r| ("rtols", Some(*r), Some(solver::MAX_RTOL))),
    );
    for (name, v, upper) in checks {
        tryc!(check_positive(name, v, upper));
    }
    if a.rungs < 2 || a.rtols.is_empty() {
        err!("error: --rungs must be at least 2 and --rtols not empty");
        return ExitCode::from(2);
    }
    let out = a
        .out
        .unwrap_or_else(|| PathBuf::from("runs/study").join(&case.name));
    let defaults = step_study::StudySettings::defaults(&case);
    let dt_max = a.dt_max.unwrap_or(defaults.dt_max);
    let settings = step_study::StudySettings {
        dt_max,
        rungs: a.rungs,
        rtols: a.rtols,
        ref_rtol: a.ref_rtol,
        bdf2_rtol: a.bdf2_rtol,
        dt_inertia: a
            .dt_inertia
            .or_else(|| step_study::default_dt_inertia(&case, dt_max)),
        max_wall: a.max_wall,
        quantities: if a.quantities.is_empty() {
            defaults.quantities
        } else {
            a.quantities.into_iter().map(Into::into).collect()
        },
    };
    let stop = stop_on_signals();
    let opts = step_study::StudyOptions {
        out: out.clone(),
        settings,
        reuse: a.reuse,
        progress: !a.quiet,
        interrupt: stop.clone(),
    };
    match step_study::run_study(&case, &a.case.display().to_string(), &opts) {
        Ok(report) => {
            out!("{}", step_study::summary_text(&report).trim_end());
            out!("study written in {}", out.display());
            match stop.exit_status() {
                Some(s) => ExitCode::from(s),
                None => ExitCode::SUCCESS,
            }
        }
        Err(e) => {
            err!("error: {e}");
            failure_status(&stop, 1)
        }
    }
}

fn sweep_error(e: &sweep::SweepError) -> ExitCode {
    err!("error: {e}");
    ExitCode::from(if e.is_input() { 2 } else { 1 })
}

/// `cellsim sweep`: checks the arguments and loads the plan, then lists its points, writes
/// its batch script or runs it.
fn sweep_command(a: SweepArgs) -> ExitCode {
    match &a.action {
        Some(SweepAction::Plot { dir, quantity }) => {
            return sweep_plot_command(dir, quantity.as_deref());
        }
        Some(SweepAction::Collect { dir }) => return sweep_collect_command(dir),
        Some(SweepAction::PlaneVs3d {
            plane,
            three_d,
            out,
            quantity,
        }) => {
            let q = quantity.as_deref();
            let out = out.clone().unwrap_or_else(|| {
                three_d.join(format!(
                    "plane-vs-3d-{}.png",
                    q.unwrap_or("penetration_depth")
                ))
            });
            return match sweep::plane_and_3d(plane, three_d, &out, q) {
                Ok(path) => {
                    out!("{}", path.display());
                    ExitCode::SUCCESS
                }
                Err(e) => sweep_error(&e),
            };
        }
        Some(SweepAction::Diff {
            a: da,
            b: db,
            out,
            quantity,
        }) => {
            let out = out.clone().unwrap_or_else(|| db.clone());
            return match sweep::difference(da, db, &out, quantity.as_deref()) {
                Ok(d) => {
                    for p in &d.written {
                        out!("{}", p.display());
                    }
                    let (n, all) = d.compared;
                    match d.largest {
                        Some((id, x, y)) => out!(
                            "{n} of {all} points finished in both; the largest difference \
                             at {id}: {y} − {x} = {} ({:+.2} %)",
                            y - x,
                            100.0 * (y - x) / x.abs()
                        ),
                        None => out!("{n} of {all} points finished in both"),
                    }
                    ExitCode::SUCCESS
                }
                Err(e) => sweep_error(&e),
            };
        }
        None => {}
    }
    let Some(file) = a.sweep.clone() else {
        err!("error: no sweep file given");
        return ExitCode::from(2);
    };
    let jobs = a
        .jobs
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    if jobs == 0 || a.shard_size == 0 || a.throttle == Some(0) {
        err!("error: --jobs, --shard-size and --throttle must be at least 1");
        return ExitCode::from(2);
    }
    tryc!(check_positive("max-wall", a.max_wall, None));
    let shard = match a.shard.as_deref().map(sweep::parse_shard).transpose() {
        Ok(s) => s,
        Err(m) => {
            err!("error: {m}");
            return ExitCode::from(2);
        }
    };
    let plan = match sweep::Plan::load_with(&file, &a.set) {
        Ok(p) => p,
        Err(e) => return sweep_error(&e),
    };
    if a.list {
        for line in plan.listing() {
            out!("{line}");
        }
        return ExitCode::SUCCESS;
    }
    let out = a
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("runs/sweep").join(&plan.name));
    if a.slurm || a.submit {
        return sweep_slurm_command(&a, &plan, &file, &out);
    }
    sweep_run_command(&a, &plan, out, jobs, shard)
}

/// `cellsim sweep plot DIR`: redraws the figures and prints their paths.
fn sweep_plot_command(dir: &Path, quantity: Option<&str>) -> ExitCode {
    match sweep::plot(dir, quantity) {
        Ok(files) => {
            for f in files {
                out!("{}", f.display());
            }
            ExitCode::SUCCESS
        }
        Err(e) => sweep_error(&e),
    }
}

/// `cellsim sweep collect DIR`: assembles the table and figures and lists the points
/// without a run (then exit status 1).
fn sweep_collect_command(dir: &Path) -> ExitCode {
    match sweep::collect(dir) {
        Ok(c) => {
            out!("{}: {}", dir.display(), sweep::counts(&c.rows));
            for f in &c.written {
                out!("{}", f.display());
            }
            let missing = c.missing();
            if missing.is_empty() {
                ExitCode::SUCCESS
            } else {
                err!(
                    "{} points without a run: {}",
                    missing.len(),
                    missing.join(" ")
                );
                ExitCode::FAILURE
            }
        }
        Err(e) => sweep_error(&e),
    }
}

/// `cellsim sweep --slurm`: writes the batch script of the plan (and submits it with
/// `--submit`).
fn sweep_slurm_command(a: &SweepArgs, plan: &sweep::Plan, file: &Path, out: &Path) -> ExitCode {
    let o = sweep::slurm::SlurmOptions {
        shard_size: a.shard_size,
        throttle: a.throttle,
        sbatch_options: a.slurm_opt.clone(),
        jobs: a.jobs,
        retry_failed: a.retry_failed,
        max_wall: a.max_wall,
        set: a.set.clone(),
    };
    let path = match sweep::slurm::write_script(plan, file, out, &o) {
        Ok(p) => p,
        Err(e) => return sweep_error(&e),
    };
    out!(
        "{}: {} points in {} array tasks",
        path.display(),
        plan.points.len(),
        sweep::slurm::shards(plan.points.len(), a.shard_size)
    );
    if a.submit {
        match sweep::slurm::submit(&path) {
            Ok(id) => out!("submitted batch job {id}"),
            Err(e) => return sweep_error(&e),
        }
    }
    ExitCode::SUCCESS
}

/// Runs the plan's points (those of `shard`) into `out` and prints the outcome; exit
/// status 1 when a point failed.
fn sweep_run_command(
    a: &SweepArgs,
    plan: &sweep::Plan,
    out: PathBuf,
    jobs: usize,
    shard: Option<(usize, usize)>,
) -> ExitCode {
    let stop = stop_on_signals();
    let opts = sweep::SweepOptions {
        out: out.clone(),
        jobs,
        retry_failed: a.retry_failed,
        shard,
        max_wall: a.max_wall,
        progress: !a.quiet,
        interrupt: stop.clone(),
    };
    match sweep::run_sweep(plan, &opts) {
        Ok(report) => {
            for r in &report.rows {
                if r.status == sweep::Status::Invalid {
                    err!("invalid point {}: {}", r.id, r.reason);
                }
            }
            out!("{}", report.summary(&plan.name, &out));
            for f in &report.written {
                out!("{}", f.display());
            }
            if let Some((i, k)) = shard {
                out!(
                    "shard {i}/{k} done; when every shard is: cellsim sweep collect {}",
                    out.display()
                );
            }
            match stop.exit_status() {
                Some(s) => ExitCode::from(s),
                None if report.count(sweep::Status::Failed) > 0 => ExitCode::FAILURE,
                None => ExitCode::SUCCESS,
            }
        }
        Err(e) => {
            err!("error: {e}");
            if e.is_input() {
                ExitCode::from(2)
            } else {
                failure_status(&stop, 1)
            }
        }
    }
}

fn plot_command(run_dir: &Path, out: Option<PathBuf>, with: &[PathBuf]) -> ExitCode {
    let mut runs = Vec::new();
    for dir in std::iter::once(run_dir).chain(with.iter().map(PathBuf::as_path)) {
        match RunData::load(dir) {
            Ok(r) => runs.push(r),
            Err(e) => {
                err!("error: {e}");
                return ExitCode::from(2);
            }
        }
    }
    for n in runs.iter().flat_map(|r| &r.notes) {
        err!("note: {n}");
    }
    let run = &runs[0];
    let out = out.unwrap_or_else(|| run_dir.join("plots"));
    let figures = render::figures::plot_run(run, &out).and_then(|mut files| {
        if runs.len() > 1 {
            let all: Vec<&RunData> = runs.iter().collect();
            files.extend(render::figures::compare_runs(&all, &out)?);
        }
        Ok(files)
    });
    match figures {
        Ok(files) => {
            for f in files {
                out!("{}", f.display());
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            err!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn mesh_command(path: &Path, svg: Option<&Path>) -> ExitCode {
    let case = tryc!(load_case(path, &[]));
    if scene::is_3d(&case) {
        if svg.is_some() {
            err!("error: {}: --svg draws 2-D meshes only", path.display());
            return ExitCode::from(2);
        }
        let cache = cellsim::fem::mesh::quarter_cell::cache_root();
        let made = cellsim::fem::TetMesh::generate_with(
            &scene::tet_mesh_params(&case),
            Path::new("gmsh"),
            &cache,
        );
        return match made {
            Ok(g) => {
                out!("{}", g.mesh.quality());
                if g.from_cache {
                    out!("mesh file {} (from the cache)", g.file.display());
                } else {
                    out!(
                        "mesh file {} (made by gmsh in {:.1} s)",
                        g.file.display(),
                        g.gmsh_seconds
                    );
                }
                ExitCode::SUCCESS
            }
            Err(e) => {
                err!("error: {}: mesh: {e}", path.display());
                ExitCode::from(2)
            }
        };
    }
    match Mesh::generate(&scene::mesh_params(&case)) {
        Ok(mesh) => {
            out!("{}", mesh.quality());
            if let Some(p) = svg {
                if let Err(e) = mesh.write_svg(p) {
                    err!("error: {e}");
                    return ExitCode::FAILURE;
                }
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            err!("error: {}: mesh: {e}", path.display());
            ExitCode::from(2)
        }
    }
}

fn sensitivity_command(
    path: &Path,
    params: Vec<String>,
    set: &[Override],
    out: Option<PathBuf>,
    error_control: bool,
) -> ExitCode {
    use cellsim::run::sensitivity::{SensitivityError, SensitivityRequest, sensitivities};
    let case = tryc!(load_case(path, set));
    let out =
        out.unwrap_or_else(|| PathBuf::from("runs").join(format!("{}-sensitivity", case.name)));
    let req = SensitivityRequest {
        case,
        file: path.display().to_string(),
        params,
        out: out.clone(),
        error_control,
        progress: std::io::IsTerminal::is_terminal(&std::io::stderr()),
    };
    match sensitivities(&req) {
        Ok(report) => {
            let columns = &cellsim::model::observables::COLUMNS[1..];
            out!(
                "{}: sensitivities of {} parameters to t = {} s in {:.1} s wall ({} steps); \
                 final p/m ∂m/∂p:",
                req.case.name,
                report.params.len(),
                report.rows.last().map_or(0.0, |r| r.t),
                report.wall_seconds,
                report.steps
            );
            out!("| parameter | value | {} |", columns.join(" | "));
            out!("|---|---:|{}", "---:|".repeat(columns.len()));
            for ((name, v), row) in report.params.iter().zip(report.final_normalised()) {
                let cells: Vec<String> = row.iter().map(|x| format!("{x:.4}")).collect();
                out!("| {name} | {v} | {} |", cells.join(" | "));
            }
            out!("sensitivity.csv in {}", out.display());
            ExitCode::SUCCESS
        }
        Err(e) => {
            err!("error: {e}");
            match e {
                SensitivityError::Input(_) => ExitCode::from(2),
                SensitivityError::Run(run::RunError::Scene(_) | run::RunError::Mesh { .. }) => {
                    ExitCode::from(2)
                }
                _ => ExitCode::from(1),
            }
        }
    }
}

/// `NAME=NUMBER` of `--truth` and `--noise`.
fn name_number(flag: &str, arg: &str) -> Result<(String, f64), ExitCode> {
    let parsed = arg.split_once('=').and_then(|(n, v)| {
        let v: f64 = v.trim().parse().ok()?;
        (v.is_finite() && !n.trim().is_empty()).then(|| (n.trim().to_string(), v))
    });
    parsed.ok_or_else(|| {
        err!("error: --{flag} {arg:?}: expected NAME=NUMBER");
        ExitCode::from(2)
    })
}

fn fit_command(args: FitArgs) -> ExitCode {
    use cellsim::fit;
    if args.jobs == 0 {
        err!("error: --jobs = 0 is out of range (must be at least 1)");
        return ExitCode::from(2);
    }
    let spec = match fit::spec::load(&args.fit, !args.make_data) {
        Ok(s) => s,
        Err(e) => {
            err!("error: {e}");
            return ExitCode::from(2);
        }
    };
    let out = args
        .out
        .unwrap_or_else(|| PathBuf::from("runs").join("fit").join(&spec.name));
    if args.make_data {
        let truth = tryc!(
            args.truth
                .iter()
                .map(|a| name_number("truth", a))
                .collect::<Result<Vec<_>, _>>()
        );
        let noise = tryc!(
            args.noise
                .iter()
                .map(|a| name_number("noise", a))
                .collect::<Result<Vec<_>, _>>()
        );
        return match fit::make_data(&spec, &truth, &noise, args.seed, &out) {
            Ok(files) => {
                for f in files {
                    out!("wrote {}", f.display());
                }
                ExitCode::SUCCESS
            }
            Err(e) => {
                err!("error: {e}");
                ExitCode::from(1)
            }
        };
    }
    if !args.truth.is_empty() || !args.noise.is_empty() {
        err!("error: --truth and --noise go with --make-data");
        return ExitCode::from(2);
    }
    let opts = fit::FitOptions {
        out: out.clone(),
        jobs: args.jobs,
        quiet: args.quiet,
    };
    match fit::run_fit(&spec, &opts) {
        Ok(r) => {
            out!(
                "{}: {} ({} iterations, {} evaluations, {:.1} s); χ² {:.4e} -> {:.4e} \
                 ({} data, {} degrees of freedom, reduced χ² {:.3})",
                r.name,
                r.termination,
                r.iterations,
                r.evaluations,
                r.wall_seconds,
                r.chi2_start,
                r.chi2,
                r.data_points,
                r.degrees_of_freedom,
                r.reduced_chi2
            );
            out!("| parameter | start | fitted | standard error | bounds |");
            out!("|---|---:|---:|---:|---|");
            for p in &r.parameters {
                out!(
                    "| {} | {:.6e} | {:.6e} | {:.3e}{} | [{}, {}] |",
                    p.path,
                    p.start,
                    p.value,
                    p.standard_error,
                    if p.at_bound { " (at a bound)" } else { "" },
                    p.lower,
                    p.upper
                );
            }
            for d in &r.undetermined {
                let c: Vec<String> = d
                    .combination
                    .iter()
                    .map(|(n, w)| format!("{w:+.3} {n}"))
                    .collect();
                out!(
                    "not determined by the data: {} (standard error {:.3} in z)",
                    c.join(" "),
                    d.standard_error
                );
            }
            out!(
                "fit.json, history.csv, residuals.csv and figures in {}",
                out.display()
            );
            ExitCode::SUCCESS
        }
        Err(e) => {
            err!("error: {}: {e}", args.fit.display());
            ExitCode::from(1)
        }
    }
}

fn check_command(path: &Path, set: &[Override]) -> ExitCode {
    let case = tryc!(load_case(path, set));
    match case.to_ron() {
        Ok(text) => {
            out!("{text}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            err!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn table_command(run_dirs: &[PathBuf], phases: bool, measures: bool) -> ExitCode {
    if phases {
        out!("{}", render::table::PHASES_HEADER);
    } else if measures {
        out!("{}", render::table::MEASURES_HEADER);
    } else {
        out!("{}", render::table::HEADER);
    }
    let mut status = ExitCode::SUCCESS;
    let mut first: Option<[Option<f64>; 8]> = None;
    for (k, dir) in run_dirs.iter().enumerate() {
        let row = if measures {
            cellsim::run_files::read::read_summary(dir)
                .map(|s| {
                    let against = if k == 0 {
                        first = render::table::measures(&s);
                        None
                    } else {
                        first.as_ref()
                    };
                    render::table::measures_rows(&s, against)
                })
                .map_err(|e| e.to_string())
        } else if phases {
            cellsim::run_files::read::RunData::load(dir)
                .map(|run| render::table::phases_row(&run))
                .map_err(|e| e.to_string())
        } else {
            cellsim::run_files::read::read_summary(dir)
                .map(|s| render::table::row(&s))
                .map_err(|e| e.to_string())
        };
        match row {
            Ok(r) => out!("{r}"),
            Err(e) => {
                err!("error: {e}");
                status = ExitCode::from(2);
            }
        }
    }
    status
}
