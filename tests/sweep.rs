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
    let mut energies = Vec::new();
    for (i, r) in rows.iter().enumerate() {
        assert_eq!(r[cs], "done", "{table}");
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
