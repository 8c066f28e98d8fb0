//! Running a sweep on a Slurm cluster: a job array over shards of points.
//!
//! `cellsim sweep SWEEP.ron --out DIR --slurm` writes `DIR/sweep.sbatch`, a batch script
//! whose array task `i` runs `cellsim sweep SWEEP.ron --out DIR --shard i/K` (the points
//! k with k mod K = i). K is the number of points divided by the shard size, rounded up;
//! `--array=0-(K-1)%M` lets at most M tasks run at once when a throttle is given. Every
//! `--slurm-opt` becomes an `#SBATCH` line (partition, time, memory, account...). Each
//! task's log goes to `DIR/slurm/<job>_<task>.out`. After the array,
//! `cellsim sweep collect DIR` assembles `sweep.csv` and the figures.

use std::path::{Path, PathBuf};

use super::{Plan, SweepError};

/// Options of the batch script.
#[derive(Debug, Clone, Default)]
pub struct SlurmOptions {
    /// Points per array task (at least 1).
    pub shard_size: usize,
    /// At most this many tasks at once (`%M`), if given.
    pub throttle: Option<usize>,
    /// Extra sbatch options, one `#SBATCH` line each (e.g. `--partition=short`).
    pub sbatch_options: Vec<String>,
    /// Runs at once within a task [default: `$SLURM_CPUS_PER_TASK`, else 1].
    pub jobs: Option<usize>,
    /// Pass `--retry-failed` to the tasks.
    pub retry_failed: bool,
    /// Pass `--max-wall S` to the tasks.
    pub max_wall: Option<f64>,
}

/// Quotes `s` for a POSIX shell.
fn quote(s: &str) -> String {
    format!("'{}'", s.replace('\'', "'\\''"))
}

/// Number of shards (array tasks) for `points` points.
pub fn shards(points: usize, shard_size: usize) -> usize {
    points.div_ceil(shard_size.max(1)).max(1)
}

/// The batch script's text. `exe`, `sweep_file` and `out` should be absolute: the tasks
/// run wherever Slurm starts them.
pub fn script(plan: &Plan, exe: &Path, sweep_file: &Path, out: &Path, o: &SlurmOptions) -> String {
    let k = shards(plan.points.len(), o.shard_size);
    let throttle = o.throttle.map(|m| format!("%{m}")).unwrap_or_default();
    let mut s = String::from("#!/bin/bash\n");
    s += &format!(
        "# cellsim sweep `{}`: {} points in {k} array tasks of up to {} points\n\
         # (written by cellsim {}). Submit: sbatch {}\n\
         # When the array is done: cellsim sweep collect {}\n",
        plan.name,
        plan.points.len(),
        o.shard_size.max(1),
        env!("CARGO_PKG_VERSION"),
        out.join("sweep.sbatch").display(),
        out.display()
    );
    s += &format!("#SBATCH --job-name=cellsim-{}\n", plan.name);
    s += &format!("#SBATCH --array=0-{}{throttle}\n", k - 1);
    s += &format!(
        "#SBATCH --output={}\n",
        out.join("slurm").join("%A_%a.out").display()
    );
    let user_sets = |key: &str| o.sbatch_options.iter().any(|x| x.starts_with(key));
    if !user_sets("--cpus-per-task") && !user_sets("-c") {
        s += &format!("#SBATCH --cpus-per-task={}\n", o.jobs.unwrap_or(1));
    }
    for opt in &o.sbatch_options {
        s += &format!("#SBATCH {opt}\n");
    }
    s += "set -eu\n";
    let jobs = match o.jobs {
        Some(j) => j.to_string(),
        None => "\"${SLURM_CPUS_PER_TASK:-1}\"".into(),
    };
    let mut cmd = format!(
        "exec {} sweep {} --out {} --shard \"${{SLURM_ARRAY_TASK_ID}}/{k}\" --jobs {jobs}",
        quote(&exe.display().to_string()),
        quote(&sweep_file.display().to_string()),
        quote(&out.display().to_string()),
    );
    if o.retry_failed {
        cmd += " --retry-failed";
    }
    if let Some(w) = o.max_wall {
        cmd += &format!(" --max-wall {w}");
    }
    s += &cmd;
    s.push('\n');
    s
}

/// Writes `DIR/sweep.sbatch` (and creates `DIR/slurm/` for the logs); returns its path.
pub fn write_script(
    plan: &Plan,
    sweep_file: &Path,
    out: &Path,
    o: &SlurmOptions,
) -> Result<PathBuf, SweepError> {
    let abs = |p: &Path| std::path::absolute(p).map_err(SweepError::io(p));
    let (sweep_file, out) = (abs(sweep_file)?, abs(out)?);
    let exe = std::env::current_exe().map_err(SweepError::io(Path::new("cellsim")))?;
    let logs = out.join("slurm");
    std::fs::create_dir_all(&logs).map_err(SweepError::io(&logs))?;
    let path = out.join("sweep.sbatch");
    super::write_atomic(&path, &script(plan, &exe, &sweep_file, &out, o))?;
    Ok(path)
}

/// Runs `sbatch SCRIPT` and returns the job id it prints.
pub fn submit(script: &Path) -> Result<String, SweepError> {
    let out = std::process::Command::new("sbatch")
        .arg("--parsable")
        .arg(script)
        .output()
        .map_err(|e| {
            SweepError::Submit(format!("cannot run sbatch: {e} (is Slurm installed here?)"))
        })?;
    let stdout = String::from_utf8_lossy(&out.stdout);
    if !out.status.success() {
        return Err(SweepError::Submit(format!(
            "sbatch {} failed ({}): {}",
            script.display(),
            out.status,
            String::from_utf8_lossy(&out.stderr).trim()
        )));
    }
    // --parsable prints "jobid" or "jobid;cluster".
    let id = stdout.trim().split(';').next().unwrap_or("").to_string();
    if id.is_empty() {
        return Err(SweepError::Submit(format!(
            "sbatch printed no job id: {}",
            stdout.trim()
        )));
    }
    Ok(id)
}
