//! Parameter sweeps: `shellsim sweep SWEEP.toml` expands a grid and a list of points of
//! `--set` overrides into one folder per run, each with its resolved settings, and writes a job
//! list that existing engines run (GNU parallel or a plain loop locally, a SLURM job array on a
//! cluster); `shellsim collect DIR…` gathers the runs' overrides and `summary.json` fields into
//! one CSV table.
//!
//! A sweep folder is self-contained: the mesh is copied into it, and every job runs from the
//! folder with relative paths, so it can be copied to a cluster as it is. The binary is
//! `$SHELLSIM` (`run.sh` defaults it to the binary that wrote the sweep; `slurm.sh` to
//! `shellsim` on the PATH), the threads per run `$SHELLSIM_THREADS` (default 1, since the runs
//! themselves are parallel).
//!
//! ```toml
//! settings = "gcm_cone.toml"        # relative to this file
//! mesh = "cone.vtk"
//! out = "cone_sweep"                # default: the sweep file's name without .toml
//! args = ["--set", "solver.tolerance=1e-10"]   # added to every run (optional)
//!
//! [grid]                            # every combination, the first key varying slowest
//! "material.thickness" = [0.005, 0.01]
//! "material.poisson" = [0.3, 0.45]
//!
//! [[points]]                        # and single runs (optional)
//! "material.thickness" = 0.02
//! ```

use crate::settings::{apply_overrides, Settings};
use anyhow::{anyhow, bail, Context, Result};
use serde::Deserialize;
use std::path::{Path, PathBuf};

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

/// The runs of a sweep file: the grid's combinations (first key slowest), then the points.
fn expand(file: &SweepFile, name: &str) -> Result<Vec<Point>> {
    let mut axes = Vec::new();
    flatten("", &file.grid, &mut axes);
    let mut lists = Vec::new();
    for (k, v) in &axes {
        match v {
            toml::Value::Array(a) if !a.is_empty() => lists.push((k.clone(), a.clone())),
            _ => bail!("{name}: grid key '{k}' must list its values, e.g. {k} = [1, 2]"),
        }
    }
    let mut runs: Vec<Point> = Vec::new();
    if !lists.is_empty() {
        let total: usize = lists.iter().map(|(_, a)| a.len()).product();
        for i in 0..total {
            let mut rest = i;
            let mut p = vec![(String::new(), toml::Value::Integer(0)); lists.len()];
            for (j, (k, a)) in lists.iter().enumerate().rev() {
                p[j] = (k.clone(), a[rest % a.len()].clone());
                rest /= a.len();
            }
            runs.push(p);
        }
    }
    for t in &file.points {
        let mut p = Vec::new();
        flatten("", t, &mut p);
        runs.push(p);
    }
    if runs.is_empty() {
        bail!("{name}: no runs: give [grid] keys with lists of values, or [[points]]");
    }
    Ok(runs)
}

/// A `--set` argument for a key and a TOML value.
fn override_arg(k: &str, v: &toml::Value) -> String {
    format!("{k}={v}")
}

/// Shell-quotes an argument for the job list.
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

/// `shellsim sweep`: checks every run's settings, then writes the sweep folder. Returns the
/// folder and the number of runs.
pub fn sweep(path: &Path, out: Option<&Path>, overwrite: bool) -> Result<(PathBuf, usize)> {
    let name = path.display().to_string();
    let text = std::fs::read_to_string(path).with_context(|| name.clone())?;
    let file: SweepFile = toml::from_str(&text).map_err(|e| anyhow!("{name}: {e}"))?;
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
    let runs = expand(&file, &name)?;
    // Every run's settings, resolved and validated before anything is written.
    let mut resolved = Vec::with_capacity(runs.len());
    for (i, p) in runs.iter().enumerate() {
        let mut t = table.clone();
        let sets: Vec<String> = p.iter().map(|(k, v)| override_arg(k, v)).collect();
        apply_overrides(&mut t, &sets).map_err(|e| anyhow!("{name}: run {i}: {e}"))?;
        let text = toml::to_string(&t).map_err(|e| anyhow!("{name}: run {i}: {e}"))?;
        Settings::from_str_with(&text, &format!("{name}, run {i} ({})", sets.join(" ")), &[])
            .map_err(|e| anyhow!("{e}"))?;
        resolved.push((sets, text));
    }
    let dir = match out {
        Some(o) => o.to_path_buf(),
        None => match &file.out {
            Some(o) => base.join(o),
            None => base.join(path.file_stem().unwrap_or_default()),
        },
    };
    if dir.join("jobs.txt").exists() && !overwrite {
        bail!(
            "{} holds a sweep already (jobs.txt); pass --overwrite to replace it",
            dir.display()
        );
    }
    std::fs::create_dir_all(&dir).with_context(|| dir.display().to_string())?;
    let ext = mesh_path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("vtk");
    let mesh_name = format!("mesh.{ext}");
    std::fs::copy(&mesh_path, dir.join(&mesh_name))
        .with_context(|| format!("copying {} into {}", mesh_path.display(), dir.display()))?;
    let extra: Vec<String> = file.args.iter().map(|a| quote(a)).collect();
    let mut jobs = String::new();
    for (i, (sets, text)) in resolved.iter().enumerate() {
        let run = format!("run_{i:04}");
        let rd = dir.join(&run);
        std::fs::create_dir_all(&rd).with_context(|| rd.display().to_string())?;
        let header = format!(
            "# Run {i} of the sweep {name}: {settings_name} with\n#   {}\n",
            sets.join("\n#   ")
        );
        crate::mesh::io::write_atomic(&rd.join("settings.toml"), (header + text).as_bytes())
            .with_context(|| rd.display().to_string())?;
        let point: serde_json::Map<String, serde_json::Value> = runs[i]
            .iter()
            .map(|(k, v)| {
                (
                    k.clone(),
                    serde_json::to_value(v).unwrap_or(serde_json::Value::Null),
                )
            })
            .collect();
        let json = serde_json::to_string_pretty(&point)?;
        crate::mesh::io::write_atomic(&rd.join("sweep_point.json"), json.as_bytes())
            .with_context(|| rd.display().to_string())?;
        jobs.push_str(&format!(
            "\"$SHELLSIM\" {run}/settings.toml {mesh_name} --out {run} --overwrite -q --threads \
             \"${{SHELLSIM_THREADS:-1}}\"{}{}\n",
            if extra.is_empty() { "" } else { " " },
            extra.join(" ")
        ));
    }
    let exe = std::env::current_exe()
        .ok()
        .map(|p| p.display().to_string())
        .unwrap_or_else(|| "shellsim".into());
    let run_sh = format!(
        "#!/bin/sh\n\
         # Runs this sweep's jobs (jobs.txt, one shellsim run per line) from this folder: on every\n\
         # core with GNU parallel when it is installed, else one after another. Exit status 0 when\n\
         # every run converged. SHELLSIM overrides the binary, SHELLSIM_THREADS the threads per run.\n\
         cd \"$(dirname \"$0\")\" || exit 2\n\
         : \"${{SHELLSIM:={exe}}}\"\n\
         [ -x \"$SHELLSIM\" ] || SHELLSIM=shellsim\n\
         export SHELLSIM\n\
         if command -v parallel >/dev/null 2>&1; then\n\
         \x20 exec parallel --will-cite --joblog joblog.tsv < jobs.txt\n\
         fi\n\
         status=0\n\
         while IFS= read -r job; do\n\
         \x20 sh -c \"$job\" || status=1\n\
         done < jobs.txt\n\
         exit $status\n",
        exe = exe.replace('"', "\\\"")
    );
    let slurm = format!(
        "#!/bin/bash\n\
         #SBATCH --job-name=shellsim-sweep\n\
         #SBATCH --array=0-{last}\n\
         #SBATCH --cpus-per-task=1\n\
         #SBATCH --output=slurm-%A_%a.out\n\
         # Submit from this folder: sbatch slurm.sh. Array task k runs line k + 1 of jobs.txt with\n\
         # --cpus-per-task threads. SHELLSIM names the binary (default: shellsim on the PATH).\n\
         cd \"${{SLURM_SUBMIT_DIR:-.}}\" || exit 2\n\
         export SHELLSIM=\"${{SHELLSIM:-shellsim}}\"\n\
         export SHELLSIM_THREADS=\"${{SLURM_CPUS_PER_TASK:-1}}\"\n\
         job=$(sed -n \"$((SLURM_ARRAY_TASK_ID + 1))p\" jobs.txt)\n\
         exec sh -c \"$job\"\n",
        last = resolved.len() - 1
    );
    for (f, body, exec) in [
        ("jobs.txt", jobs.as_str(), false),
        ("run.sh", run_sh.as_str(), true),
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
    Ok((dir, resolved.len()))
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
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// `shellsim collect`: one CSV row per run folder under `dirs` (a folder with `summary.json`, or
/// each sub-folder of one that has `sweep_point.json` or `summary.json`, in name order):
/// `run`, `status` (`done`, or `no summary.json` for a run that has not finished), the sweep's
/// overrides, then every `summary.json` field (nested ones with dotted names).
pub fn collect(dirs: &[PathBuf]) -> Result<String> {
    let mut folders = Vec::new();
    for d in dirs {
        if !d.is_dir() {
            bail!("{}: not a folder", d.display());
        }
        if d.join("summary.json").is_file() {
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
