//! Parameter sweeps: `shellsim sweep SWEEP.toml` expands a grid and a list of points of
//! `--set` overrides into one folder per run, each with its resolved settings, and writes a job
//! list that existing engines run (GNU parallel or a plain loop locally, a SLURM job array on a
//! cluster); `shellsim collect DIR…` gathers the runs' overrides and `summary.json` fields into
//! one CSV table.
//!
//! A sweep folder is self-contained: the mesh is copied into it, and every job runs from the
//! folder with relative paths, so it can be copied to a cluster as it is. The binary is
//! `$SHELLSIM` (default `shellsim` on the PATH), the threads per run `$SHELLSIM_THREADS`
//! (default 1, since the runs themselves are parallel). Every name in a job's command line is
//! shell-quoted; the mesh is copied as `mesh.EXT` with EXT one the readers know.
//!
//! ```toml
//! settings = "gcm_cone.toml"        # relative to this file
//! mesh = "cone.vtk"
//! out = "cone_sweep"                # default: the sweep file's name without .toml
//! args = ["--set", "solver.tolerance=1e-10"]   # added to every run (optional)
//!
//! [grid]                            # every combination, the first key varies slowest
//! "material.thickness" = [0.005, 0.01]
//! "material.poisson" = [0.3, 0.45]
//!
//! [[points]]                        # and single runs (optional)
//! "material.thickness" = 0.02
//!
//! [slurm]                           # slurm.sh (optional; these are the defaults)
//! time = "1:00:00"                  # per run; an array task's --time is this × its runs
//! mem = "4G"
//! cpus = 1
//! max_array = 1000                  # array tasks at most; each runs a chunk of the jobs
//! ```
//!
//! A folder is taken for a sweep folder when it holds `jobs.txt`, `run.sh` and `slurm.sh`;
//! `--overwrite` replaces one (see `clear`) and nothing else: a sweep is written only into a
//! new or empty folder or over a sweep.

use crate::settings::{apply_overrides, Settings};
use anyhow::{anyhow, bail, Context, Result};
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// The most runs a sweep may have: a sweep file is expanded only after its run count is
/// known to be at most this.
pub const MAX_RUNS: usize = 100_000;

/// The files every sweep folder holds (how a folder is recognised as one).
const SWEEP_FILES: [&str; 3] = ["jobs.txt", "run.sh", "slurm.sh"];

/// A sweep file.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
struct SweepFile {
    /// The settings every run starts from (relative to the sweep file).
    settings: PathBuf,
    /// The mesh (relative to the sweep file); copied into the sweep folder.
    mesh: PathBuf,
    /// The sweep folder (relative to the sweep file).
    out: Option<PathBuf>,
    /// Extra command-line arguments of every run.
    #[serde(default)]
    args: Vec<String>,
    /// Keys with lists of values: every combination is a run.
    #[serde(default)]
    grid: toml::Table,
    /// Single runs, each a table of keys and values.
    #[serde(default)]
    points: Vec<toml::Table>,
    /// The SLURM job array's resources.
    #[serde(default)]
    slurm: Slurm,
}

/// `[slurm]` of a sweep file: the resources of `slurm.sh`'s array tasks.
#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields, default)]
struct Slurm {
    /// Wall time of one run, `[D-]H:MM:SS`; an array task gets this times its runs.
    time: String,
    /// Memory of an array task (`--mem`): a whole number with an optional K, M, G or T.
    mem: String,
    /// CPUs of an array task (`--cpus-per-task`), the threads of each run.
    cpus: u32,
    /// Array tasks at most (SLURM's MaxArraySize is 1001 by default: indices 0–1000).
    max_array: usize,
}

impl Default for Slurm {
    fn default() -> Self {
        Slurm {
            time: "1:00:00".into(),
            mem: "4G".into(),
            cpus: 1,
            max_array: 1000,
        }
    }
}

/// Seconds of a SLURM time `[D-]H:MM:SS`, or `None` when it is not one (or is zero).
fn slurm_seconds(t: &str) -> Option<u64> {
    let (days, hms) = match t.split_once('-') {
        Some((d, rest)) => (d, rest),
        None => ("0", t),
    };
    // Whole numbers of at most `max` digits (exactly 2 for minutes and seconds).
    let num = |s: &str, min: usize, max: usize| -> Option<u64> {
        (s.len() >= min && s.len() <= max && s.bytes().all(|c| c.is_ascii_digit()))
            .then(|| s.parse().ok())
            .flatten()
    };
    let parts: Vec<&str> = hms.split(':').collect();
    let [h, m, s] = parts[..] else { return None };
    let (d, h, m, s) = (
        num(days, 1, 3)?,
        num(h, 1, 4)?,
        num(m, 2, 2)?,
        num(s, 2, 2)?,
    );
    if m >= 60 || s >= 60 {
        return None;
    }
    let total = ((d * 24 + h) * 60 + m) * 60 + s;
    (total > 0).then_some(total)
}

/// A SLURM time `D-HH:MM:SS` of seconds.
fn slurm_time(s: u64) -> String {
    let (d, s) = (s / 86_400, s % 86_400);
    format!("{d}-{:02}:{:02}:{:02}", s / 3600, s / 60 % 60, s % 60)
}

impl Slurm {
    /// Checks every value, naming the key (they are written into `slurm.sh`).
    fn check(&self, name: &str) -> Result<()> {
        if slurm_seconds(&self.time).is_none() {
            bail!(
                "{name}: slurm.time = {:?}: expected a run's wall time as H:MM:SS or D-H:MM:SS, \
                 e.g. \"1:30:00\"",
                self.time
            );
        }
        let digits = self.mem.trim_end_matches(['K', 'M', 'G', 'T']);
        if digits.is_empty()
            || digits.len() > 9
            || self.mem.len() > digits.len() + 1
            || !digits.bytes().all(|c| c.is_ascii_digit())
            || digits.bytes().all(|c| c == b'0')
        {
            bail!(
                "{name}: slurm.mem = {:?}: expected a whole number with an optional K, M, G or \
                 T, e.g. \"4G\"",
                self.mem
            );
        }
        if !(1..=4096).contains(&self.cpus) {
            bail!("{name}: slurm.cpus = {}: expected 1 to 4096", self.cpus);
        }
        if !(1..=1_000_000).contains(&self.max_array) {
            bail!(
                "{name}: slurm.max_array = {}: expected 1 to 1000000",
                self.max_array
            );
        }
        Ok(())
    }
}

/// Flattens `a.b = v` tables into dotted keys, in the table's order.
fn flatten(prefix: &str, t: &toml::Table, out: &mut Vec<(String, toml::Value)>) {
    for (k, v) in t {
        let key = if prefix.is_empty() {
            k.clone()
        } else {
            format!("{prefix}.{k}")
        };
        match v {
            toml::Value::Table(sub) => flatten(&key, sub, out),
            v => out.push((key, v.clone())),
        }
    }
}

/// One run of a sweep: its overrides, in order.
type Point = Vec<(String, toml::Value)>;

/// The runs of a sweep file, not expanded: the grid's axes and the points. Run `i` is made
/// when it is asked for, so a sweep's size costs nothing until it is known to be allowed.
struct Plan {
    /// The grid's keys and their values, the first varying slowest.
    axes: Vec<(String, Vec<toml::Value>)>,
    /// The points.
    points: Vec<Point>,
}

impl Plan {
    /// Reads the grid's axes and the points (refused when there are none).
    fn new(file: &SweepFile, name: &str) -> Result<Plan> {
        let mut flat = Vec::new();
        flatten("", &file.grid, &mut flat);
        let mut axes = Vec::new();
        for (k, v) in flat {
            match v {
                toml::Value::Array(a) if !a.is_empty() => axes.push((k, a)),
                _ => bail!("{name}: grid key '{k}' must list its values, e.g. {k} = [1, 2]"),
            }
        }
        let mut points = Vec::new();
        for t in &file.points {
            let mut p = Vec::new();
            flatten("", t, &mut p);
            points.push(p);
        }
        for (k, v) in axes
            .iter()
            .flat_map(|(k, a)| a.iter().map(move |v| (k, v)))
            .chain(points.iter().flatten().map(|(k, v)| (k, v)))
        {
            if !finite(v) {
                bail!("{name}: '{k}': {v} is not a finite number");
            }
        }
        if axes.is_empty() && points.is_empty() {
            bail!("{name}: no runs: give [grid] keys with lists of values, or [[points]]");
        }
        Ok(Plan { axes, points })
    }

    /// The grid's runs (0 without a grid), `None` beyond u128 (a grid of 128 keys of pairs).
    fn grid(&self) -> Option<u128> {
        if self.axes.is_empty() {
            return Some(0);
        }
        self.axes
            .iter()
            .try_fold(1u128, |n, (_, a)| n.checked_mul(a.len() as u128))
    }

    /// The number of runs, refused when there are more than `MAX_RUNS` (computed without
    /// expanding the grid).
    fn count(&self, name: &str) -> Result<usize> {
        let total = self
            .grid()
            .and_then(|g| g.checked_add(self.points.len() as u128));
        if let Some(n) = total.filter(|&n| n <= MAX_RUNS as u128) {
            return Ok(n as usize);
        }
        let count = match total {
            Some(n) => n.to_string(),
            None => format!(
                "about {}",
                crate::math::human(
                    self.axes
                        .iter()
                        .map(|(_, a)| a.len() as f64)
                        .product::<f64>()
                )
            ),
        };
        let mut sizes: Vec<String> = self.axes.iter().map(|(_, a)| a.len().to_string()).collect();
        if sizes.len() > 8 {
            sizes.truncate(6);
            sizes.push("…".into());
        }
        let points = if self.points.is_empty() {
            String::new()
        } else {
            format!(" and {} points", self.points.len())
        };
        bail!(
            "{name}: {count} runs ({} grid keys of {} values{points}), more than the limit of \
             {MAX_RUNS} runs per sweep; split it into several sweeps",
            self.axes.len(),
            sizes.join(" × "),
        )
    }

    /// Run `i`'s overrides: the grid's combination `i` (mixed radix, the last key fastest),
    /// then the points.
    fn point(&self, i: usize) -> Point {
        let grid = self.grid().unwrap_or(u128::MAX);
        if i as u128 >= grid {
            return self.points[i - grid as usize].clone();
        }
        let mut rest = i;
        let mut p = vec![(String::new(), toml::Value::Integer(0)); self.axes.len()];
        for (j, (k, a)) in self.axes.iter().enumerate().rev() {
            p[j] = (k.clone(), a[rest % a.len()].clone());
            rest /= a.len();
        }
        p
    }
}

/// Whether a TOML value holds no NaN or infinity.
fn finite(v: &toml::Value) -> bool {
    match v {
        toml::Value::Float(x) => x.is_finite(),
        toml::Value::Array(a) => a.iter().all(finite),
        toml::Value::Table(t) => t.values().all(finite),
        _ => true,
    }
}

/// A TOML value as JSON (datetimes as their text); `None` for a non-finite float.
fn json(v: &toml::Value) -> Option<serde_json::Value> {
    use serde_json::Value as J;
    Some(match v {
        toml::Value::String(s) => J::String(s.clone()),
        toml::Value::Integer(n) => J::from(*n),
        toml::Value::Float(x) => J::Number(serde_json::Number::from_f64(*x)?),
        toml::Value::Boolean(b) => J::Bool(*b),
        toml::Value::Datetime(d) => J::String(d.to_string()),
        toml::Value::Array(a) => J::Array(a.iter().map(json).collect::<Option<_>>()?),
        toml::Value::Table(t) => J::Object(
            t.iter()
                .map(|(k, x)| Some((k.clone(), json(x)?)))
                .collect::<Option<_>>()?,
        ),
    })
}

/// A `--set` argument for a key and a TOML value.
fn override_arg(k: &str, v: &toml::Value) -> String {
    format!("{k}={v}")
}

/// Shell-quotes an argument for the job list (POSIX single quotes). Arguments with control
/// characters are refused before (a job is one line of `jobs.txt`).
fn quote(s: &str) -> String {
    if !s.is_empty()
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || "-_./=:,+".contains(c))
    {
        s.to_string()
    } else {
        format!("'{}'", s.replace('\'', "'\\''"))
    }
}

/// Lines of text as TOML comment lines: every line starts with `# `, and control characters
/// (a newline or carriage return in a file name or value) are escaped, so no text can end the
/// comment.
fn comment(lines: &[String]) -> String {
    let mut out = String::new();
    for l in lines {
        out.push_str("# ");
        for c in l.chars() {
            if c.is_control() {
                out.extend(c.escape_default());
            } else {
                out.push(c);
            }
        }
        out.push('\n');
    }
    out
}

/// The folder name of run `i` of `n`: `run_0000`, …, with as many digits as the last one
/// needs (at least 4), so that the names sort in run order.
pub fn run_name(i: usize, n: usize) -> String {
    let width = n.saturating_sub(1).to_string().len().max(4);
    format!("run_{i:0width$}")
}

/// Whether `name` is a run folder's name: `run_` and digits.
fn is_run_name(name: &str) -> bool {
    name.strip_prefix("run_")
        .is_some_and(|d| !d.is_empty() && d.bytes().all(|c| c.is_ascii_digit()))
}

/// What [`sweep`] wrote.
pub struct Written {
    /// The sweep folder.
    pub dir: PathBuf,
    /// Runs (run folders and lines of `jobs.txt`).
    pub runs: usize,
    /// `slurm.sh`'s array tasks and the runs each runs (the last may run fewer).
    pub slurm_tasks: usize,
    /// Runs per array task.
    pub slurm_chunk: usize,
    /// Folders of the earlier sweep kept by `--overwrite` because they hold files shellsim did
    /// not write.
    pub kept: Vec<PathBuf>,
}

/// A sweep file parsed and its `[slurm]` and `args` checked, with the args' `--set` overrides.
fn parse(
    text: &str,
    name: &str,
    check_args: &dyn Fn(&[String]) -> Result<Vec<String>>,
) -> Result<(SweepFile, Vec<String>)> {
    let file: SweepFile = toml::from_str(text).map_err(|e| anyhow!("{name}: {e}"))?;
    file.slurm.check(name)?;
    for a in &file.args {
        if a.chars().any(char::is_control) {
            bail!("{name}: args: {a:?} holds a control character (a newline?)");
        }
    }
    let arg_sets = check_args(&file.args).map_err(|e| anyhow!("{name}: args: {e:#}"))?;
    Ok((file, arg_sets))
}

/// The runs of a sweep: its plan, on the settings every run starts from.
struct Runs<'a> {
    /// The sweep file's name, for messages.
    name: &'a str,
    /// The grid and the points.
    plan: Plan,
    /// The settings every run starts from.
    table: toml::Table,
    /// The `--set` overrides of the sweep's `args`, on top of every run's.
    arg_sets: Vec<String>,
    /// The number of runs.
    n: usize,
}

impl<'a> Runs<'a> {
    /// Reads the plan, then checks the keys on the first run (the grid's keys, or the first
    /// point's), then the size, then every run's settings.
    fn check(
        file: &SweepFile,
        name: &'a str,
        table: toml::Table,
        arg_sets: Vec<String>,
    ) -> Result<Runs<'a>> {
        let plan = Plan::new(file, name)?;
        let mut runs = Runs {
            name,
            plan,
            table,
            arg_sets,
            n: 0,
        };
        runs.resolve(0)?;
        runs.n = runs.plan.count(name)?;
        for i in 1..runs.n {
            runs.resolve(i)?;
        }
        Ok(runs)
    }

    /// Run i's overrides and resolved settings, checked with the args' overrides on top.
    fn resolve(&self, i: usize) -> Result<(Point, Vec<String>, String)> {
        let name = self.name;
        let p = self.plan.point(i);
        let sets: Vec<String> = p.iter().map(|(k, v)| override_arg(k, v)).collect();
        let mut t = self.table.clone();
        apply_overrides(&mut t, &sets).map_err(|e| anyhow!("{name}: run {i}: {e}"))?;
        let text = toml::to_string(&t).map_err(|e| anyhow!("{name}: run {i}: {e}"))?;
        let mut label = format!("{name}, run {i} ({})", sets.join(" "));
        if !self.arg_sets.is_empty() {
            label += &format!(" with args --set {}", self.arg_sets.join(" --set "));
        }
        Settings::from_str_with(&text, &label, &self.arg_sets).map_err(|e| anyhow!("{e}"))?;
        Ok((p, sets, text))
    }
}

/// The checks `shellsim sweep` makes of the text of a sweep file named `name`, on
/// `settings_text` in place of the settings file it names, without reading or writing any file
/// (the mesh is not read): the number of runs, or the first error.
pub fn check_text(
    text: &str,
    name: &str,
    settings_text: &str,
    check_args: &dyn Fn(&[String]) -> Result<Vec<String>>,
) -> Result<usize> {
    let (file, arg_sets) = parse(text, name, check_args)?;
    let table: toml::Table = settings_text.parse().map_err(|e| anyhow!("{name}: {e}"))?;
    Ok(Runs::check(&file, name, table, arg_sets)?.n)
}

/// `shellsim sweep`: checks every run's settings, then writes the sweep folder.
/// `check_args(args)` parses the sweep's `args` as a run's command line does and returns their
/// `--set` overrides (which every run's settings are checked with).
pub fn sweep(
    path: &Path,
    out: Option<&Path>,
    overwrite: bool,
    check_args: &dyn Fn(&[String]) -> Result<Vec<String>>,
) -> Result<Written> {
    let name = path.display().to_string();
    let text = std::fs::read_to_string(path).with_context(|| name.clone())?;
    let (file, arg_sets) = parse(&text, &name, check_args)?;
    let base = path.parent().unwrap_or(Path::new(""));
    let settings_path = base.join(&file.settings);
    let mesh_path = base.join(&file.mesh);
    let settings_name = settings_path.display().to_string();
    let settings_text = std::fs::read_to_string(&settings_path)
        .map_err(|e| anyhow!("{name}: settings '{settings_name}': {e}"))?;
    let table: toml::Table = settings_text
        .parse()
        .map_err(|e| anyhow!("{settings_name}: {e}"))?;
    if !mesh_path.is_file() {
        bail!("{name}: mesh '{}' is not a file", mesh_path.display());
    }
    // Every run's settings are checked before anything is written (not kept: a sweep of many
    // runs is resolved again while it is written).
    let runs = Runs::check(&file, &name, table, arg_sets)?;
    let n = runs.n;
    // The mesh is read (the format from its extension, which names the copy).
    crate::mesh::io::read_mesh(&mesh_path).map_err(|e| anyhow!("{name}: mesh: {e}"))?;
    let ext = mesh_path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .filter(|e| ["vtk", "vtu", "vtp", "off", "obj", "ply", "stl"].contains(&e.as_str()))
        .ok_or_else(|| anyhow!("{name}: mesh '{}': unknown extension", mesh_path.display()))?;
    let mesh_name = format!("mesh.{ext}");
    let dir = match out {
        Some(o) => o.to_path_buf(),
        None => match &file.out {
            Some(o) => base.join(o),
            None => base.join(path.file_stem().unwrap_or_default()),
        },
    };
    let kept = prepare(&dir, overwrite)?;
    std::fs::create_dir_all(&dir).with_context(|| dir.display().to_string())?;
    std::fs::copy(&mesh_path, dir.join(&mesh_name))
        .with_context(|| format!("copying {} into {}", mesh_path.display(), dir.display()))?;
    let extra: String = file.args.iter().map(|a| format!(" {}", quote(a))).collect();
    let mut jobs = String::new();
    for i in 0..n {
        let (point, sets, text) = runs.resolve(i)?;
        let run = run_name(i, n);
        let rd = dir.join(&run);
        std::fs::create_dir_all(&rd).with_context(|| rd.display().to_string())?;
        let mut lines = vec![format!("Run {i} of the sweep {name}: {settings_name} with")];
        lines.extend(sets.iter().map(|s| format!("  {s}")));
        crate::mesh::io::write_atomic(
            &rd.join("settings.toml"),
            (comment(&lines) + &text).as_bytes(),
        )
        .with_context(|| rd.display().to_string())?;
        let point: serde_json::Map<String, serde_json::Value> = point
            .iter()
            .map(|(k, v)| {
                Ok((
                    k.clone(),
                    json(v).ok_or_else(|| anyhow!("{name}: '{k}': {v} is not finite"))?,
                ))
            })
            .collect::<Result<_>>()?;
        let json = serde_json::to_string_pretty(&point)?;
        crate::mesh::io::write_atomic(&rd.join("sweep_point.json"), json.as_bytes())
            .with_context(|| rd.display().to_string())?;
        let (r, m) = (quote(&run), quote(&mesh_name));
        jobs.push_str(&format!(
            "\"$SHELLSIM\" {r}/settings.toml {m} --out {r} --overwrite -q --threads \
             \"${{SHELLSIM_THREADS:-1}}\"{extra}\n"
        ));
    }
    let run_sh = "#!/bin/sh\n\
         # Written by shellsim sweep: runs this sweep's jobs (jobs.txt, one shellsim run per line)\n\
         # from this folder, on every core with GNU parallel when it is installed, else one after\n\
         # another. Exit status 0 when every run converged. SHELLSIM names the binary (default:\n\
         # shellsim on the PATH), SHELLSIM_THREADS the threads per run (default 1).\n\
         cd \"$(dirname \"$0\")\" || exit 2\n\
         SHELLSIM=\"${SHELLSIM:-shellsim}\"\n\
         export SHELLSIM\n\
         if ! command -v \"$SHELLSIM\" >/dev/null 2>&1; then\n\
         \x20 echo \"run.sh: no binary '$SHELLSIM': put shellsim on the PATH or set SHELLSIM=/path/to/shellsim\" >&2\n\
         \x20 exit 2\n\
         fi\n\
         if command -v parallel >/dev/null 2>&1; then\n\
         \x20 exec parallel --will-cite --joblog joblog.tsv < jobs.txt\n\
         fi\n\
         status=0\n\
         while IFS= read -r job; do\n\
         \x20 sh -c \"$job\" </dev/null || status=1\n\
         done < jobs.txt\n\
         exit $status\n";
    let s = &file.slurm;
    let tasks = n.min(s.max_array);
    let chunk = n.div_ceil(tasks);
    let tasks = n.div_ceil(chunk);
    let task_time = slurm_time(slurm_seconds(&s.time).unwrap_or(3600) * chunk as u64);
    let slurm = format!(
        "#!/bin/bash\n\
         #SBATCH --job-name=shellsim-sweep\n\
         #SBATCH --array=0-{last}\n\
         #SBATCH --cpus-per-task={cpus}\n\
         #SBATCH --time={task_time}\n\
         #SBATCH --mem={mem}\n\
         #SBATCH --output=slurm-%A_%a.out\n\
         # Written by shellsim sweep. Submit from this folder: sbatch slurm.sh (options given to\n\
         # sbatch override these). {tasks} array tasks of up to {chunk} runs (jobs.txt has {n}): task k\n\
         # runs lines {chunk}·k + 1 to {chunk}·(k + 1), one after another, each with --cpus-per-task\n\
         # threads; --time is {time} per run. SHELLSIM names the binary (default: shellsim on the\n\
         # PATH).\n\
         : \"${{SLURM_ARRAY_TASK_ID:?submit this script with sbatch slurm.sh}}\"\n\
         cd \"${{SLURM_SUBMIT_DIR:-.}}\" || exit 2\n\
         export SHELLSIM=\"${{SHELLSIM:-shellsim}}\"\n\
         export SHELLSIM_THREADS=\"${{SLURM_CPUS_PER_TASK:-1}}\"\n\
         first=$((SLURM_ARRAY_TASK_ID * {chunk} + 1))\n\
         last=$((first + {chunk} - 1))\n\
         status=0\n\
         while IFS= read -r job; do\n\
         \x20 sh -c \"$job\" </dev/null || status=1\n\
         done < <(sed -n \"${{first}},${{last}}p\" jobs.txt)\n\
         exit $status\n",
        last = tasks - 1,
        cpus = s.cpus,
        mem = s.mem,
        time = s.time,
    );
    for (f, body, exec) in [
        ("jobs.txt", jobs.as_str(), false),
        ("run.sh", run_sh, true),
        ("slurm.sh", slurm.as_str(), true),
    ] {
        let p = dir.join(f);
        crate::mesh::io::write_atomic(&p, body.as_bytes())
            .with_context(|| p.display().to_string())?;
        if exec {
            use std::os::unix::fs::PermissionsExt;
            std::fs::set_permissions(&p, std::fs::Permissions::from_mode(0o755))
                .with_context(|| p.display().to_string())?;
        }
    }
    Ok(Written {
        dir,
        runs: n,
        slurm_tasks: tasks,
        slurm_chunk: chunk,
        kept,
    })
}

/// Makes `dir` ready for a sweep: a missing or empty folder is used as it is; a sweep folder
/// (one holding `jobs.txt`, `run.sh` and `slurm.sh`) is refused unless `overwrite`, which
/// [`clear`]s it; any other folder is refused. Returns the folders `clear` kept.
fn prepare(dir: &Path, overwrite: bool) -> Result<Vec<PathBuf>> {
    let shown = dir.display();
    if !dir.exists() {
        return Ok(Vec::new());
    }
    if !dir.is_dir() {
        bail!("{shown} is not a folder");
    }
    let empty = std::fs::read_dir(dir)
        .with_context(|| shown.to_string())?
        .next()
        .is_none();
    if empty {
        return Ok(Vec::new());
    }
    if !SWEEP_FILES.iter().all(|f| dir.join(f).is_file()) {
        bail!(
            "{shown} holds files and is not a sweep folder (it lacks {}): a sweep is written \
             into a new or empty folder, or over an earlier sweep with --overwrite",
            SWEEP_FILES
                .iter()
                .filter(|f| !dir.join(f).is_file())
                .copied()
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    if !overwrite {
        bail!("{shown} holds a sweep already (jobs.txt); pass --overwrite to replace it");
    }
    clear(dir)
}

/// Removes what an earlier sweep and its runs wrote in the sweep folder `dir`: `jobs.txt`,
/// `run.sh`, `slurm.sh`, `joblog.tsv`, SLURM's `slurm-*.out`, the mesh copy `mesh.*`, and in
/// each run folder `run_N…` its `settings.toml`, `sweep_point.json` and its run's output (the
/// summary, series, log, frames and snapshots that `--overwrite` of a run removes), then the run
/// folder when that leaves it empty. A run folder holding other files is kept (returned) and
/// has no `sweep_point.json` or `summary.json` left, so `collect` skips it. A run under way
/// in the folder (a live `.shellsim.lock`) is refused before anything is removed.
fn clear(dir: &Path) -> Result<Vec<PathBuf>> {
    let ctx = |p: &Path| p.display().to_string();
    let mut files = Vec::new();
    let mut runs = Vec::new();
    for e in std::fs::read_dir(dir).with_context(|| ctx(dir))? {
        let e = e.with_context(|| ctx(dir))?;
        // Not followed: a link named like a run folder is removed, never what it points to.
        let kind = e.file_type().with_context(|| ctx(&e.path()))?;
        let p = e.path();
        let Some(name) = p.file_name().and_then(|n| n.to_str()) else {
            continue;
        };
        let ours = SWEEP_FILES.contains(&name)
            || name == "joblog.tsv"
            || (name.starts_with("slurm-") && name.ends_with(".out"))
            || name.starts_with("mesh.")
            || is_run_name(name)
            || (name.starts_with('.') && name.ends_with(".tmp"));
        if kind.is_dir() && is_run_name(name) {
            if let Some(pid) = crate::output::lock_owner(&p) {
                bail!(
                    "{}: a run is under way in it (process {pid}); not replacing the sweep",
                    p.display()
                );
            }
            runs.push(p);
        } else if ours && !kind.is_dir() {
            files.push(p);
        }
    }
    let mut kept = Vec::new();
    for rd in runs {
        // The frames' prefix is the run's own setting.
        let prefix = std::fs::read_to_string(rd.join("settings.toml"))
            .ok()
            .and_then(|t| t.parse::<toml::Table>().ok())
            .and_then(|t| t.get("output")?.get("prefix")?.as_str().map(String::from))
            .unwrap_or_else(|| "frame".into());
        let mut gone = crate::output::previous_outputs(&rd, &prefix).with_context(|| ctx(&rd))?;
        for f in ["settings.toml", "sweep_point.json", ".shellsim.lock"] {
            if rd.join(f).is_file() {
                gone.push(rd.join(f));
            }
        }
        for f in &gone {
            std::fs::remove_file(f).with_context(|| ctx(f))?;
        }
        if std::fs::remove_dir(&rd).is_err() {
            kept.push(rd);
        }
    }
    for f in &files {
        std::fs::remove_file(f).with_context(|| ctx(f))?;
    }
    Ok(kept)
}

/// How run `i` of a sweep of `n` in `dir` ended: `None` when it converged (its
/// `summary.json` says so), else why not.
pub fn failure(dir: &Path, i: usize, n: usize) -> Option<String> {
    let p = dir.join(run_name(i, n)).join("summary.json");
    let Ok(text) = std::fs::read_to_string(&p) else {
        return Some("no summary.json".into());
    };
    match serde_json::from_str::<serde_json::Value>(&text) {
        Ok(s) if s["converged"] == serde_json::Value::Bool(true) => None,
        Ok(s) => Some(format!(
            "not converged: {}",
            s["reason"].as_str().unwrap_or("no reason given")
        )),
        Err(e) => Some(format!("unreadable summary.json: {e}")),
    }
}

/// Flattens a JSON value into `key → CSV cell` pairs (nested objects with dotted keys; arrays
/// as their JSON text).
fn cells(prefix: &str, v: &serde_json::Value, out: &mut Vec<(String, String)>) {
    match v {
        serde_json::Value::Object(m) => {
            for (k, x) in m {
                let key = if prefix.is_empty() {
                    k.clone()
                } else {
                    format!("{prefix}.{k}")
                };
                cells(&key, x, out);
            }
        }
        serde_json::Value::String(s) => out.push((prefix.into(), s.clone())),
        serde_json::Value::Null => out.push((prefix.into(), String::new())),
        x => out.push((prefix.into(), x.to_string())),
    }
}

/// CSV-quotes a cell when it needs it.
fn csv(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// `shellsim collect`: one CSV row per run folder under `dirs` (a folder with `summary.json` or
/// `sweep_point.json`, or each sub-folder of one that has either, in name order):
/// `run`, `status` (`done`, or `no summary.json` for a run that has not finished), the sweep's
/// overrides, then every `summary.json` field (nested ones with dotted names).
pub fn collect(dirs: &[PathBuf]) -> Result<String> {
    let mut folders = Vec::new();
    for d in dirs {
        if !d.is_dir() {
            bail!("{}: not a folder", d.display());
        }
        if d.join("summary.json").is_file() || d.join("sweep_point.json").is_file() {
            folders.push(d.clone());
            continue;
        }
        let mut subs: Vec<PathBuf> = std::fs::read_dir(d)
            .with_context(|| d.display().to_string())?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.join("summary.json").is_file() || p.join("sweep_point.json").is_file())
            .collect();
        if subs.is_empty() {
            bail!(
                "{}: no runs (no summary.json in it or in its sub-folders)",
                d.display()
            );
        }
        subs.sort();
        folders.extend(subs);
    }
    let mut columns: Vec<String> = vec!["run".into(), "status".into()];
    let mut rows = Vec::new();
    for f in &folders {
        let mut row = vec![
            ("run".to_string(), f.display().to_string()),
            ("status".to_string(), String::new()),
        ];
        let read = |name: &str| -> Result<Option<serde_json::Value>> {
            let p = f.join(name);
            if !p.is_file() {
                return Ok(None);
            }
            let text = std::fs::read_to_string(&p).with_context(|| p.display().to_string())?;
            serde_json::from_str(&text)
                .map(Some)
                .map_err(|e| anyhow!("{}: {e}", p.display()))
        };
        if let Some(p) = read("sweep_point.json")? {
            cells("", &p, &mut row);
        }
        // What made the run (its latest invocation in run.json).
        if let Some(prov) = read("run.json")? {
            if let Some(last) = prov["runs"].as_array().and_then(|r| r.last()) {
                let overrides: Vec<&str> = last["overrides"]
                    .as_array()
                    .map(|o| o.iter().filter_map(|v| v.as_str()).collect())
                    .unwrap_or_default();
                let made = serde_json::json!({
                    "shellsim_version": last["shellsim_version"],
                    "commit": last["commit"],
                    "overrides": overrides.join(" "),
                    "mesh_sha256": last["mesh"]["sha256"],
                    "started": last["started"],
                });
                cells("run", &made, &mut row);
            }
        }
        match read("summary.json")? {
            Some(s) => {
                row[1].1 = "done".into();
                cells("", &s, &mut row);
            }
            None => row[1].1 = "no summary.json".into(),
        }
        for (k, _) in &row {
            if !columns.contains(k) {
                columns.push(k.clone());
            }
        }
        rows.push(row);
    }
    let mut out = columns.iter().map(|c| csv(c)).collect::<Vec<_>>().join(",");
    out.push('\n');
    for row in rows {
        let line: Vec<String> = columns
            .iter()
            .map(|c| {
                row.iter()
                    .find(|(k, _)| k == c)
                    .map(|(_, v)| csv(v))
                    .unwrap_or_default()
            })
            .collect();
        out.push_str(&line.join(","));
        out.push('\n');
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plan(text: &str) -> Plan {
        let file: SweepFile = toml::from_str(text).unwrap();
        Plan::new(&file, "f").unwrap()
    }

    /// Grids are counted without expanding them: up to the limit exactly, beyond it (and beyond
    /// u64 and u128) refused with the count.
    #[test]
    fn runs_are_counted_without_expanding() {
        let grid = |keys: usize, values: &str| {
            let mut t = "settings = \"s\"\nmesh = \"m\"\n[grid]\n".to_string();
            for i in 0..keys {
                t += &format!("k{i} = [{values}]\n");
            }
            t
        };
        let ten = "0, 1, 2, 3, 4, 5, 6, 7, 8, 9";
        assert_eq!(plan(&grid(5, ten)).count("f").unwrap(), MAX_RUNS);
        let with_point = grid(5, ten).replace("[grid]", "[[points]]\nk0 = 1\n[grid]");
        let e = plan(&with_point).count("f").unwrap_err().to_string();
        assert!(e.contains("100001 runs") && e.contains("1 points"), "{e}");
        let e = plan(&grid(64, "1, 2")).count("f").unwrap_err().to_string();
        assert!(e.contains("18446744073709551616 runs"), "{e}");
        let e = plan(&grid(130, "1, 2")).count("f").unwrap_err().to_string();
        assert!(e.contains("about 1.361e39 runs"), "{e}");
        // Run i is the grid's combination i, the last key fastest.
        let p = plan(&grid(64, "1, 2"));
        let last = p.point(1);
        assert_eq!(last[63].1, toml::Value::Integer(2));
        assert_eq!(last[62].1, toml::Value::Integer(1));
    }
}
