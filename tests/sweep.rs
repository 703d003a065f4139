//! `shellsim sweep` and `shellsim collect` end to end: a 2×2 grid of a small static scene is
//! expanded, run by its own `run.sh` (GNU parallel when installed, else one run after another)
//! and collected into one CSV table; bad sweep files are named errors that write nothing.

mod common;
use common::run_status as run;

const SETTINGS: &str = "[material]\nyoung = 1.0e6\nthickness = 0.01\ndensity = 1000.0\n\
    [rest]\ntarget = \"uniform\"\n[loads]\ngravity = [0.0, 0.0, -9.81]\n\
    [constraints]\nfix_boxes = [{ min = [-1, -1, -1], max = [-0.45, 1, 1] }]\n";

#[test]
fn a_two_by_two_sweep_runs_and_collects() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    let (c, _, e) = run(
        &[
            "mesh",
            "rectangle",
            "--lx",
            "1",
            "--ly",
            "0.2",
            "--edge",
            "0.1",
            "-o",
            "m.vtk",
        ],
        p,
    );
    assert_eq!(c, 0, "{e}");
    std::fs::write(p.join("s.toml"), SETTINGS).unwrap();
    std::fs::write(
        p.join("sw.toml"),
        "settings = \"s.toml\"\nmesh = \"m.vtk\"\n\
         [grid]\n\"material.thickness\" = [0.01, 0.02]\nmaterial.young = [1.0e6, 4.0e6]\n",
    )
    .unwrap();
    let (c, _, e) = run(&["sweep", "sw.toml", "--run"], p);
    assert_eq!(c, 0, "{e}");
    assert!(e.contains("4 runs: 4 succeeded, 0 failed"), "{e}");
    let sw = p.join("sw");
    let jobs = std::fs::read_to_string(sw.join("jobs.txt")).unwrap();
    assert_eq!(jobs.lines().count(), 4, "{jobs}");
    let slurm = std::fs::read_to_string(sw.join("slurm.sh")).unwrap();
    assert!(slurm.contains("#SBATCH --array=0-3"), "{slurm}");
    // The first key varies slowest: run 1 is thickness 0.01, young 4e6.
    let s1 = std::fs::read_to_string(sw.join("run_0001/settings.toml")).unwrap();
    let s1: toml::Table = s1.parse().unwrap();
    assert_eq!(s1["material"]["thickness"].as_float(), Some(0.01));
    assert_eq!(s1["material"]["young"].as_float(), Some(4.0e6));
    let (c, table, e) = run(&["collect", "sw"], p);
    assert_eq!(c, 0, "{e}");
    let mut lines = table.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| {
        head.iter()
            .position(|h| *h == name)
            .unwrap_or_else(|| panic!("no column {name} in {head:?}"))
    };
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 4, "{table}");
    let (ct, cy, cs, ce) = (
        col("material.thickness"),
        col("material.young"),
        col("status"),
        col("energy.total"),
    );
    // What made each run, from its run.json.
    let (cv, cm) = (col("run.shellsim_version"), col("run.mesh_sha256"));
    let mut energies = Vec::new();
    for (i, r) in rows.iter().enumerate() {
        assert_eq!(r[cs], "done", "{table}");
        assert_eq!(r[cv], env!("CARGO_PKG_VERSION"), "{table}");
        assert_eq!(r[cm].len(), 64, "{table}");
        let t: f64 = r[ct].parse().unwrap();
        let y: f64 = r[cy].parse().unwrap();
        assert_eq!(
            (t, y),
            ([0.01, 0.02][i / 2], [1.0e6, 4.0e6][i % 2]),
            "row {i}"
        );
        // The table holds what the run's own summary says.
        let s: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(sw.join(format!("run_{i:04}/summary.json"))).unwrap(),
        )
        .unwrap();
        let e: f64 = r[ce].parse().unwrap();
        assert_eq!(e, s["energy"]["total"].as_f64().unwrap(), "row {i}");
        assert_eq!(r[col("converged")], "true", "{table}");
        energies.push(e);
    }
    // Each point ran its own physics: a cantilever under its weight, whose energy depends on
    // both the thickness and the stiffness.
    for i in 0..4 {
        for j in 0..i {
            assert!(
                (energies[i] - energies[j]).abs() > 1e-6 * energies[i].abs(),
                "{energies:?}"
            );
        }
    }
    // A second sweep into the same folder is refused without --overwrite.
    let (c, _, e) = run(&["sweep", "sw.toml"], p);
    assert_eq!(c, 2);
    assert!(e.contains("--overwrite"), "{e}");
}

#[test]
fn bad_sweep_files_are_named_and_write_nothing() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    std::fs::write(p.join("s.toml"), SETTINGS).unwrap();
    std::fs::write(p.join("m.vtk"), "not read before the settings are checked").unwrap();
    let cases = [
        // An unknown key in the sweep file.
        (
            "settings = \"s.toml\"\nmesh = \"m.vtk\"\n[grids]\n\"material.young\" = [1.0]\n",
            "grids",
        ),
        // An override that names no setting.
        (
            "settings = \"s.toml\"\nmesh = \"m.vtk\"\n[grid]\n\"material.thicknes\" = [0.01]\n",
            "thicknes",
        ),
        (
            "settings = \"s.toml\"\nmesh = \"m.vtk\"\n[[points]]\n\"solvr.tolerance\" = 1e-9\n",
            "solvr",
        ),
        // A grid key without a list.
        (
            "settings = \"s.toml\"\nmesh = \"m.vtk\"\n[grid]\n\"material.young\" = 1.0\n",
            "must list its values",
        ),
        // An invalid value.
        (
            "settings = \"s.toml\"\nmesh = \"m.vtk\"\n[grid]\n\"material.thickness\" = [-1.0]\n",
            "thickness",
        ),
        // No runs.
        ("settings = \"s.toml\"\nmesh = \"m.vtk\"\n", "no runs"),
    ];
    for (text, named) in cases {
        std::fs::write(p.join("bad.toml"), text).unwrap();
        let (c, _, e) = run(&["sweep", "bad.toml"], p);
        assert_eq!(c, 2, "{text}: {e}");
        assert!(e.contains(named) && e.contains("bad.toml"), "{text}: {e}");
        assert!(!e.contains("panicked"), "{e}");
        assert!(!p.join("bad").exists(), "{text}: a folder was written");
    }
    let (c, _, e) = run(&["collect", "nowhere"], p);
    assert_eq!(c, 2);
    assert!(e.contains("nowhere"), "{e}");
}

/// Every sweep file in `settings/sweeps/` expands: its settings, mesh and overrides are valid.
#[test]
fn the_example_sweeps_expand() {
    let root = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let mut n = 0;
    for entry in std::fs::read_dir(root.join("settings/sweeps")).unwrap() {
        let f = entry.unwrap().path();
        let d = tempfile::tempdir().unwrap();
        let (c, _, e) = run(&["sweep", f.to_str().unwrap(), "--out", "sweep"], d.path());
        assert_eq!(c, 0, "{}: {e}", f.display());
        assert!(d.path().join("sweep/jobs.txt").exists());
        n += 1;
    }
    assert!(n > 0, "no example sweep");
}

/// Runs the binary in `dir` with extra environment variables; exit code, stdout, stderr.
fn run_env(args: &[&str], dir: &std::path::Path, env: &[(&str, &str)]) -> (i32, String, String) {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_shellsim"))
        .args(args)
        .envs(env.iter().copied())
        .current_dir(dir)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Writes the small scene (`m.vtk`, `s.toml`) into `p`.
fn scene(p: &std::path::Path) {
    let args = [
        "mesh",
        "rectangle",
        "--lx",
        "1",
        "--ly",
        "0.2",
        "--edge",
        "0.1",
        "-o",
        "m.vtk",
    ];
    let (c, _, e) = run(&args, p);
    assert_eq!(c, 0, "{e}");
    std::fs::write(p.join("s.toml"), SETTINGS).unwrap();
}

/// A stand-in for the binary that records the run folder it is given (`calls.log` in the
/// folder it runs from), fails for `run_0001` and writes a converged summary for the others.
fn fake_binary(p: &std::path::Path) -> std::path::PathBuf {
    use std::os::unix::fs::PermissionsExt;
    let bin = p.join("bin");
    std::fs::create_dir_all(&bin).unwrap();
    let f = bin.join("shellsim");
    std::fs::write(
        &f,
        "#!/bin/sh\necho \"$4\" >> calls.log\ncase \"$4\" in run_0001) exit 1;; esac\n\
         echo '{\"converged\": true, \"reason\": \"\"}' > \"$4/summary.json\"\n",
    )
    .unwrap();
    std::fs::set_permissions(&f, std::fs::Permissions::from_mode(0o755)).unwrap();
    f
}

/// Every file and folder under `p`, relative to it.
fn tree(p: &std::path::Path) -> Vec<String> {
    let mut out = Vec::new();
    let mut stack = vec![p.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let q = e.unwrap().path();
            out.push(q.strip_prefix(p).unwrap().display().to_string());
            if q.is_dir() {
                stack.push(q);
            }
        }
    }
    out.sort();
    out
}

/// A grid's run count is computed, without expanding it, and bounded; its keys are checked
/// first. A 10⁹-run grid, 40 unknown keys of two values and 64 of them (2⁶⁴ runs) are errors
/// at once, and nothing is written.
#[test]
fn oversized_grids_are_refused_before_expanding() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    scene(p);
    let list = |a: f64, step: f64| {
        (0..1000)
            .map(|i| format!("{}", a + step * i as f64))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let big = format!(
        "settings = \"s.toml\"\nmesh = \"m.vtk\"\n[grid]\n\"material.young\" = [{}]\n\
         \"material.density\" = [{}]\n\"material.thickness\" = [{}]\n",
        list(1e6, 1.0),
        list(1000.0, 1.0),
        list(0.01, 1e-6)
    );
    let unknown = |n: usize| {
        let mut t = "settings = \"s.toml\"\nmesh = \"m.vtk\"\n[grid]\n".to_string();
        for i in 0..n {
            t += &format!("k{i} = [1, 2]\n");
        }
        t
    };
    for (text, named) in [
        (big, vec!["1000000000 runs", "limit of 100000"]),
        (unknown(40), vec!["k0"]),
        (unknown(64), vec!["k0"]),
    ] {
        std::fs::write(p.join("big.toml"), &text).unwrap();
        let t = std::time::Instant::now();
        let (c, _, e) = run(&["sweep", "big.toml"], p);
        assert_eq!(c, 2, "{e}");
        for n in named {
            assert!(e.contains(n) && e.contains("big.toml"), "{n}: {e}");
        }
        assert!(t.elapsed().as_secs_f64() < 5.0, "{:?}", t.elapsed());
        assert!(!p.join("big").exists(), "a folder was written");
    }
}

/// Names reach the job list shell-quoted: a mesh whose extension is a shell command is
/// refused (it is no mesh format), one with quotes and spaces in its name works, and `args`
/// with quotes, `$(…)` and `;` reach the run as they are. Nothing is created outside the run
/// folders by a shell.
#[test]
fn hostile_names_reach_no_shell() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    scene(p);
    std::fs::copy(p.join("m.vtk"), p.join("m.vtk;touch X;#")).unwrap();
    std::fs::write(
        p.join("a.toml"),
        "settings = \"s.toml\"\nmesh = \"m.vtk;touch X;#\"\n[grid]\n\"material.young\" = [1e6]\n",
    )
    .unwrap();
    let before = tree(p);
    let (c, _, e) = run(&["sweep", "a.toml", "--run"], p);
    assert_eq!(c, 2, "{e}");
    assert!(e.contains("touch X"), "{e}");
    assert_eq!(tree(p), before, "something was written");

    std::fs::copy(p.join("m.vtk"), p.join("my mesh's $(touch Y).vtk")).unwrap();
    let prefix = "f';touch X;'$(touch Y)`touch Z`";
    std::fs::write(
        p.join("b.toml"),
        format!(
            "settings = \"s.toml\"\nmesh = \"my mesh's $(touch Y).vtk\"\n\
             args = [\"--set\", \"output.prefix=\\\"{prefix}\\\"\"]\n[grid]\n\"material.young\" = [1e6]\n"
        ),
    )
    .unwrap();
    let (c, _, e) = run(&["sweep", "b.toml", "--run"], p);
    assert_eq!(c, 0, "{e}");
    assert!(p.join("b/mesh.vtk").is_file());
    assert!(
        p.join("b/run_0000")
            .join(format!("{prefix}_00000.vtu"))
            .is_file(),
        "{:?}",
        tree(&p.join("b"))
    );
    let made: Vec<String> = tree(p)
        .into_iter()
        .filter(|f| {
            ["X", "Y", "Z"]
                .iter()
                .any(|x| f.ends_with(&format!("/{x}")) || f == x)
        })
        .collect();
    assert!(made.is_empty(), "a shell ran a name: {made:?}");
}

/// A newline in the settings' file name stays inside the comment of the runs' settings: it
/// cannot add TOML lines.
#[test]
fn a_newline_in_a_path_injects_no_settings() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    scene(p);
    std::fs::copy(p.join("s.toml"), p.join("s\n[x]\ny = 1\n#.toml")).unwrap();
    std::fs::write(
        p.join("sw.toml"),
        "settings = \"s\\n[x]\\ny = 1\\n#.toml\"\nmesh = \"m.vtk\"\n\
         [grid]\n\"material.thickness\" = [0.02]\n",
    )
    .unwrap();
    let (c, _, e) = run(&["sweep", "sw.toml"], p);
    assert_eq!(c, 0, "{e}");
    let text = std::fs::read_to_string(p.join("sw/run_0000/settings.toml")).unwrap();
    let t: toml::Table = text.parse().unwrap();
    assert!(!t.contains_key("x"), "{text}");
    assert_eq!(t["material"]["thickness"].as_float(), Some(0.02), "{text}");
}

/// `--overwrite` removes what the earlier sweep and its runs wrote (a larger sweep's extra run
/// folders included), keeps a run folder holding a user's file, and is refused for a folder
/// that is not a sweep's or in which a run is under way.
#[test]
fn overwrite_replaces_the_earlier_sweep_only() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    scene(p);
    let sweep = |values: &str| {
        format!(
            "settings = \"s.toml\"\nmesh = \"m.vtk\"\n[grid]\n\"material.thickness\" = [{values}]\n"
        )
    };
    std::fs::write(p.join("sw.toml"), sweep("0.01, 0.02, 0.03, 0.04, 0.05")).unwrap();
    let (c, _, e) = run(&["sweep", "sw.toml"], p);
    assert_eq!(c, 0, "{e}");
    let sw = p.join("sw");
    for i in 0..5 {
        std::fs::write(
            sw.join(format!("run_{i:04}/summary.json")),
            "{\"converged\": true, \"energy\": {\"total\": 1.0}}",
        )
        .unwrap();
        std::fs::write(sw.join(format!("run_{i:04}/frame_00000.vtu")), "").unwrap();
        std::fs::write(sw.join(format!("slurm-7_{i}.out")), "").unwrap();
    }
    std::fs::write(sw.join("joblog.tsv"), "").unwrap();
    std::fs::write(sw.join("run_0003/notes.txt"), "mine").unwrap();
    // A link named like a run folder goes, not what it points to.
    let elsewhere = p.join("elsewhere");
    std::fs::create_dir(&elsewhere).unwrap();
    std::fs::write(elsewhere.join("summary.json"), "{}").unwrap();
    std::fs::remove_dir_all(sw.join("run_0001")).unwrap();
    std::os::unix::fs::symlink(&elsewhere, sw.join("run_0001")).unwrap();

    // A run under way in the folder (a live lock: this process) stops the replacement.
    let lock = sw.join("run_0004/.shellsim.lock");
    std::fs::write(&lock, format!("{}\n", std::process::id())).unwrap();
    let before = tree(p);
    let (c, _, e) = run(&["sweep", "sw.toml", "--overwrite"], p);
    assert_eq!(c, 2, "{e}");
    assert!(e.contains("run_0004") && e.contains("under way"), "{e}");
    assert_eq!(tree(p), before);
    std::fs::remove_file(&lock).unwrap();

    std::fs::write(p.join("sw.toml"), sweep("0.06, 0.07")).unwrap();
    let (c, _, e) = run(&["sweep", "sw.toml", "--overwrite"], p);
    assert_eq!(c, 0, "{e}");
    assert!(e.contains("run_0003") && e.contains("kept"), "{e}");
    let mut left = tree(&sw);
    left.retain(|f| !f.starts_with("run_0000/") && !f.starts_with("run_0001/"));
    assert_eq!(
        left,
        [
            "jobs.txt",
            "mesh.vtk",
            "run.sh",
            "run_0000",
            "run_0001",
            "run_0003",
            "run_0003/notes.txt",
            "slurm.sh"
        ],
        "{:?}",
        tree(&sw)
    );
    assert_eq!(
        tree(&sw.join("run_0000")),
        ["settings.toml", "sweep_point.json"]
    );
    assert_eq!(tree(&elsewhere), ["summary.json"]);
    let (c, table, e) = run(&["collect", "sw"], p);
    assert_eq!(c, 0, "{e}");
    assert_eq!(table.lines().count(), 3, "{table}");
    assert!(
        table.contains(",0.06") && table.contains(",0.07"),
        "{table}"
    );
    assert!(!table.contains("done"), "{table}");

    // A folder that is not a sweep's is never written into nor cleared.
    let other = p.join("other");
    std::fs::create_dir(&other).unwrap();
    std::fs::write(other.join("run.sh"), "mine").unwrap();
    std::fs::create_dir(other.join("run_0000")).unwrap();
    let before = tree(p);
    for extra in [&[][..], &["--overwrite"][..]] {
        let mut args = vec!["sweep", "sw.toml", "--out", "other"];
        args.extend(extra);
        let (c, _, e) = run(&args, p);
        assert_eq!(c, 2, "{e}");
        assert!(
            e.contains("other") && e.contains("not a sweep folder"),
            "{e}"
        );
        assert_eq!(tree(p), before);
    }
}

/// A sweep's `args` are parsed as a run's command line is, and their `--set` overrides
/// checked with every run's settings, when the sweep is written.
#[test]
fn bad_run_args_are_named_when_the_sweep_is_written() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    scene(p);
    for (args, named) in [
        ("[\"--bogus\"]", "--bogus"),
        ("[\"--set\", \"material.thicknes=0.1\"]", "thicknes"),
        ("[\"--set\", \"material.thickness=-1\"]", "thickness"),
        ("[\"--threads\", \"2\"]", "--threads"),
        ("[\"extra.vtk\"]", "extra.vtk"),
        ("[\"--help\"]", "--help"),
        ("[\"--restart\", \"a\\nb\"]", "a\\nb"),
    ] {
        std::fs::write(
            p.join("bad.toml"),
            format!(
                "settings = \"s.toml\"\nmesh = \"m.vtk\"\nargs = {args}\n\
                 [grid]\n\"material.young\" = [1e6]\n"
            ),
        )
        .unwrap();
        let (c, _, e) = run(&["sweep", "bad.toml"], p);
        assert_eq!(c, 2, "{args}: {e}");
        assert!(e.contains(named) && e.contains("args"), "{args}: {e}");
        assert!(!p.join("bad").exists(), "{args}: a folder was written");
    }
}

/// `slurm.sh` runs the jobs in chunks, at most `max_array` array tasks (1000 by default, under
/// SLURM's default MaxArraySize), with `--time` (a run's time × the runs of a task), `--mem`
/// and `--cpus-per-task` from `[slurm]`; every run is run once, in order.
#[test]
fn slurm_arrays_are_chunked_with_time_and_memory() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    scene(p);
    let fake = fake_binary(p);
    std::fs::write(
        p.join("sw.toml"),
        "settings = \"s.toml\"\nmesh = \"m.vtk\"\n\
         [grid]\n\"material.thickness\" = [0.01, 0.02, 0.03, 0.04, 0.05, 0.06, 0.07]\n\
         [slurm]\ntime = \"0:10:00\"\nmem = \"1G\"\ncpus = 2\nmax_array = 3\n",
    )
    .unwrap();
    let (c, _, e) = run(&["sweep", "sw.toml"], p);
    assert_eq!(c, 0, "{e}");
    let sw = p.join("sw");
    let slurm = std::fs::read_to_string(sw.join("slurm.sh")).unwrap();
    for line in [
        "#SBATCH --array=0-2\n",
        "#SBATCH --time=0-00:30:00\n",
        "#SBATCH --mem=1G\n",
        "#SBATCH --cpus-per-task=2\n",
    ] {
        assert!(slurm.contains(line), "{line}: {slurm}");
    }
    for task in 0..3 {
        let out = std::process::Command::new("bash")
            .arg(sw.join("slurm.sh"))
            .env("SLURM_ARRAY_TASK_ID", task.to_string())
            .env("SLURM_SUBMIT_DIR", &sw)
            .env("SLURM_CPUS_PER_TASK", "2")
            .env("SHELLSIM", &fake)
            .output()
            .unwrap();
        // Task 0 holds run_0001, which the stand-in fails.
        assert_eq!(out.status.success(), task != 0, "task {task}: {out:?}");
    }
    let calls = std::fs::read_to_string(sw.join("calls.log")).unwrap();
    let want: Vec<String> = (0..7).map(|i| format!("run_{i:04}")).collect();
    assert_eq!(calls.lines().collect::<Vec<_>>(), want);

    // 1200 runs: 600 tasks of 2 (a task per run would exceed MaxArraySize).
    std::fs::write(
        p.join("sw.toml"),
        format!(
            "settings = \"s.toml\"\nmesh = \"m.vtk\"\n[grid]\n\"material.young\" = [{}]\n\
             \"material.thickness\" = [{}]\n",
            (1..=40)
                .map(|i| format!("{i}e6"))
                .collect::<Vec<_>>()
                .join(", "),
            (1..=30)
                .map(|i| format!("{i}e-3"))
                .collect::<Vec<_>>()
                .join(", ")
        ),
    )
    .unwrap();
    let (c, _, e) = run(&["sweep", "sw.toml", "--overwrite"], p);
    assert_eq!(c, 0, "{e}");
    let slurm = std::fs::read_to_string(sw.join("slurm.sh")).unwrap();
    assert!(slurm.contains("#SBATCH --array=0-599\n"), "{slurm}");
    assert!(slurm.contains("#SBATCH --time=0-02:00:00\n"), "{slurm}");
    assert!(slurm.contains("#SBATCH --mem=4G\n"), "{slurm}");
    let jobs = std::fs::read_to_string(sw.join("jobs.txt")).unwrap();
    assert_eq!(jobs.lines().count(), 1200);

    // Values written into slurm.sh are checked.
    for (slurm, named) in [
        ("mem = \"1G\\n#SBATCH --x\"", "slurm.mem"),
        ("mem = \"0\"", "slurm.mem"),
        ("time = \"1h\"", "slurm.time"),
        ("time = \"1:60:00\"", "slurm.time"),
        ("cpus = 0", "slurm.cpus"),
        ("max_array = 0", "slurm.max_array"),
        ("partition = \"x\"", "partition"),
    ] {
        std::fs::write(
            p.join("bad.toml"),
            format!(
                "settings = \"s.toml\"\nmesh = \"m.vtk\"\n[grid]\n\"material.young\" = [1e6]\n\
                 [slurm]\n{slurm}\n"
            ),
        )
        .unwrap();
        let (c, _, e) = run(&["sweep", "bad.toml"], p);
        assert_eq!(c, 2, "{slurm}: {e}");
        assert!(e.contains(named) && e.contains("bad.toml"), "{slurm}: {e}");
        assert!(!p.join("bad").exists());
    }
}

/// `run.sh` runs `$SHELLSIM`, by default `shellsim` on the PATH (no path of the binary that
/// wrote it); without one it says so.
#[test]
fn run_sh_takes_shellsim_from_the_path() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    scene(p);
    let fake = fake_binary(p);
    std::fs::write(
        p.join("sw.toml"),
        "settings = \"s.toml\"\nmesh = \"m.vtk\"\n[grid]\n\"material.thickness\" = [0.01, 0.02]\n",
    )
    .unwrap();
    let (c, _, e) = run(&["sweep", "sw.toml"], p);
    assert_eq!(c, 0, "{e}");
    let sw = p.join("sw");
    let run_sh = std::fs::read_to_string(sw.join("run.sh")).unwrap();
    assert!(!run_sh.contains(env!("CARGO_BIN_EXE_shellsim")), "{run_sh}");
    let sh = |path: String| {
        std::process::Command::new("sh")
            .arg(sw.join("run.sh"))
            .env_remove("SHELLSIM")
            .env("PATH", path)
            .output()
            .unwrap()
    };
    let out = sh("/usr/bin:/bin".into());
    assert_eq!(out.status.code(), Some(2), "{out:?}");
    assert!(String::from_utf8_lossy(&out.stderr).contains("SHELLSIM"));
    let out = sh(format!(
        "{}:/usr/bin:/bin",
        fake.parent().unwrap().display()
    ));
    assert_eq!(out.status.code(), Some(1), "run_0001 fails: {out:?}");
    let calls = std::fs::read_to_string(sw.join("calls.log")).unwrap();
    assert_eq!(calls, "run_0000\nrun_0001\n");
}

/// `sweep --run` tallies the runs, names the failed ones and exits 1; `collect` reports a run
/// without a summary, given in its sweep or on its own.
#[test]
fn sweep_run_tallies_and_collect_reports_unfinished_runs() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    scene(p);
    let fake = fake_binary(p);
    std::fs::write(
        p.join("sw.toml"),
        "settings = \"s.toml\"\nmesh = \"m.vtk\"\n\
         [grid]\n\"material.thickness\" = [0.01, 0.02, 0.03]\n",
    )
    .unwrap();
    let (c, _, e) = run_env(
        &["sweep", "sw.toml", "--run"],
        p,
        &[("SHELLSIM", fake.to_str().unwrap())],
    );
    assert_eq!(c, 1, "{e}");
    assert!(e.contains("2 succeeded, 1 failed"), "{e}");
    assert!(e.contains("sw/run_0001: no summary.json"), "{e}");
    assert!(!e.contains("run them with"), "{e}");
    for dirs in [&["sw"][..], &["sw/run_0001", "sw/run_0002"][..]] {
        let mut args = vec!["collect"];
        args.extend(dirs);
        let (c, table, e) = run(&args, p);
        assert_eq!(c, 0, "{e}");
        let row = table.lines().find(|l| l.contains("run_0001")).unwrap();
        assert!(row.contains(",no summary.json,"), "{table}");
        let rows = if dirs.len() == 1 { 3 } else { dirs.len() };
        assert_eq!(table.lines().count(), rows + 1, "{table}");
    }
}
