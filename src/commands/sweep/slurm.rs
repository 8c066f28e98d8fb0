//! Running a sweep on a Slurm cluster: a job array over shards of points.
//!
//! `cellsim sweep SWEEP.ron --out DIR --slurm` writes `DIR/sweep.sbatch`, a batch script
//! whose array task `i` runs `cellsim sweep SWEEP.ron --out DIR --shard i/K` (the points
//! k with k mod K = i). K is the number of points divided by the shard size, rounded up;
//! `--array=0-(K-1)%M` lets at most M tasks run at once when a throttle is given. Every
//! `--slurm-opt` becomes an `#SBATCH` line (partition, time, memory, account...). Each
//! task's log goes to `DIR/slurm/<job>_<task>.out`. After the array,
//! `cellsim sweep collect DIR` assembles `sweep.csv` and the figures.
//!
//! Unless a `--slurm-opt` sets them, the script asks for the time and memory its largest
//! task is estimated to need ([`TaskEstimate`]): each point's cost from its case before
//! meshing ([`crate::scene::terms::run_cost`]), a task running its points `jobs` at a time.

use std::path::{Path, PathBuf};

use super::{Plan, SweepError};
use crate::scene::terms::{RunCost, run_cost};

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
    /// Pass `--set PATH=VALUE` to the tasks (the command line's, in order).
    pub set: Vec<String>,
}

/// Quotes `s` for a POSIX shell.
fn quote(s: &str) -> String {
    format!("'{}'", s.replace('\'', "'\\''"))
}

/// The time and memory asked for each array task, estimated for the largest task: its
/// points' estimated costs ([`run_cost`]) run `jobs` at a time, the wall time of the
/// longest lane of a greedy schedule and the memory of the `jobs` largest points at once.
/// Both carry a margin: time ×[`TIME_MARGIN`] plus [`TIME_ALLOWANCE`] (start, the mesh
/// generator on a cold cache, the outputs; a node slower than this project's), memory
/// ×[`MEMORY_MARGIN`] plus [`PROCESS_BYTES`] (the process itself, the figures).
#[derive(Debug, Clone, PartialEq)]
pub struct TaskEstimate {
    /// Estimated wall time of the longest task without the margin \[s\].
    pub seconds: f64,
    /// Estimated peak memory of the largest task without the margin \[bytes\].
    pub bytes: f64,
    /// The `--time` asked for, whole minutes.
    pub minutes: u64,
    /// The `--mem` asked for, MB (Slurm's unit).
    pub megabytes: u64,
    /// Points whose cost is estimated (valid cases with a mesh the generator accepts).
    pub estimated: usize,
    /// The largest point's cost: (id, seconds, bytes, dimension, elements).
    pub largest: Option<(String, f64, f64, usize, f64)>,
}

/// Time margin: the asked time is this many times the estimate, plus [`TIME_ALLOWANCE`].
pub const TIME_MARGIN: f64 = 2.0;
/// Time allowed on top of the margin \[s\].
pub const TIME_ALLOWANCE: f64 = 300.0;
/// Memory margin: the asked memory is this many times the estimate, plus [`PROCESS_BYTES`].
pub const MEMORY_MARGIN: f64 = 1.5;
/// The process's own memory (code, plots, buffers) \[bytes\].
pub const PROCESS_BYTES: f64 = 200e6;

/// The estimate for `plan` split into `k` shards run `jobs` points at a time each.
pub fn task_estimate(plan: &Plan, k: usize, jobs: usize) -> TaskEstimate {
    let jobs = jobs.max(1);
    let full: Vec<Option<RunCost>> = plan
        .points
        .iter()
        .map(|p| p.case.as_ref().ok().and_then(|(case, _)| run_cost(case)))
        .collect();
    let largest = plan
        .points
        .iter()
        .zip(&full)
        .filter_map(|(p, c)| c.map(|c| (p, c)))
        .max_by(|a, b| a.1.seconds.total_cmp(&b.1.seconds))
        .map(|(p, c)| (p.id.clone(), c.seconds, c.bytes, c.dimension, c.elements));
    let costs: Vec<Option<(f64, f64)>> = full
        .iter()
        .map(|c| c.map(|c| (c.seconds, c.bytes)))
        .collect();
    let (mut seconds, mut bytes) = (0.0f64, 0.0f64);
    for i in 0..k {
        // The points of shard i (k mod K = i), longest first onto the least loaded lane.
        let mut mine: Vec<(f64, f64)> = costs
            .iter()
            .enumerate()
            .filter(|(n, _)| n % k == i)
            .filter_map(|(_, c)| *c)
            .collect();
        mine.sort_by(|a, b| b.0.total_cmp(&a.0));
        let mut lanes = vec![0.0f64; jobs];
        for (s, _) in &mine {
            let lane = lanes
                .iter_mut()
                .min_by(|a, b| a.total_cmp(b))
                .expect("jobs >= 1");
            *lane += s;
        }
        seconds = seconds.max(lanes.iter().copied().fold(0.0, f64::max));
        mine.sort_by(|a, b| b.1.total_cmp(&a.1));
        bytes = bytes.max(mine.iter().take(jobs).map(|c| c.1).sum());
    }
    let minutes = ((seconds * TIME_MARGIN + TIME_ALLOWANCE) / 60.0).ceil() as u64;
    let megabytes = ((bytes * MEMORY_MARGIN + PROCESS_BYTES) / 1e6 / 100.0).ceil() as u64 * 100;
    TaskEstimate {
        seconds,
        bytes,
        minutes,
        megabytes,
        estimated: costs.iter().flatten().count(),
        largest,
    }
}

/// Slurm's `--time` form of a number of minutes: `D-HH:MM:00`, or `HH:MM:00` under a day.
pub fn time_limit(minutes: u64) -> String {
    let (d, h, m) = (minutes / 1440, minutes / 60 % 24, minutes % 60);
    if d > 0 {
        format!("{d}-{h:02}:{m:02}:00")
    } else {
        format!("{h:02}:{m:02}:00")
    }
}

/// The value of the sbatch option `long` (`--time`) or `short` (`-t`) among the user's,
/// in any of the forms `--time=V`, `--time V`, `-tV`, `-t V`.
fn user_value<'a>(options: &'a [String], long: &str, short: &str) -> Option<&'a str> {
    options.iter().find_map(|o| {
        let o = o.trim();
        if let Some(v) = o.strip_prefix(long) {
            v.strip_prefix('=')
                .or_else(|| v.strip_prefix(' '))
                .map(str::trim)
        } else {
            o.strip_prefix(short)
                .map(|v| v.trim_start_matches('=').trim())
        }
    })
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
    let cpus = user_value(&o.sbatch_options, "--cpus-per-task", "-c");
    if cpus.is_none() {
        s += &format!("#SBATCH --cpus-per-task={}\n", o.jobs.unwrap_or(1));
    }
    // Points at once in a task: --jobs, else the CPUs per task the script runs them on.
    let jobs = o
        .jobs
        .or_else(|| cpus.and_then(|c| c.parse().ok()))
        .unwrap_or(1);
    let e = task_estimate(plan, k, jobs);
    if let Some((id, secs, bytes, dim, elements)) = &e.largest {
        s += &format!(
            "# Estimated before meshing: the longest task {:.0} s and {:.0} MB with {jobs} \
             point(s) at once; the costliest point `{id}`, {dim}-D, about {elements:.0} \
             elements, {secs:.0} s and {:.0} MB. Asked: time x{TIME_MARGIN} + {:.0} min, \
             memory x{MEMORY_MARGIN} + {:.0} MB (a --slurm-opt=--time or --mem replaces them).\n",
            e.seconds,
            e.bytes / 1e6,
            bytes / 1e6,
            TIME_ALLOWANCE / 60.0,
            PROCESS_BYTES / 1e6,
        );
    }
    if user_value(&o.sbatch_options, "--time", "-t").is_none() {
        s += &format!("#SBATCH --time={}\n", time_limit(e.minutes));
    }
    if !o
        .sbatch_options
        .iter()
        .any(|x| x.starts_with("--mem") || x.starts_with("--mem-per-cpu"))
    {
        s += &format!("#SBATCH --mem={}M\n", e.megabytes);
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
    for set in &o.set {
        cmd += &format!(" --set {}", quote(set));
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn time_limits_in_slurm_form() {
        assert_eq!(time_limit(7), "00:07:00");
        assert_eq!(time_limit(61), "01:01:00");
        assert_eq!(time_limit(1440 + 125), "1-02:05:00");
    }

    #[test]
    fn user_values_in_every_form() {
        let o = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        assert_eq!(
            user_value(&o(&["--time=01:00:00"]), "--time", "-t"),
            Some("01:00:00")
        );
        assert_eq!(user_value(&o(&["--time 5"]), "--time", "-t"), Some("5"));
        assert_eq!(user_value(&o(&["-t5"]), "--time", "-t"), Some("5"));
        assert_eq!(
            user_value(&o(&["-c 4"]), "--cpus-per-task", "-c"),
            Some("4")
        );
        assert_eq!(user_value(&o(&["--partition=x"]), "--time", "-t"), None);
    }
}
