//! CLI tests: run the real binary in a temporary folder and check exit codes, messages and the
//! files written (or not written).

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_shellsim"))
}

struct Run {
    code: i32,
    stderr: String,
    stdout: String,
}

fn run(args: &[&str], dir: &Path) -> Run {
    let (code, stdout, stderr) = common::run_status(args, dir);
    Run {
        code,
        stderr,
        stdout,
    }
}

/// Writes a generated strip mesh `lx × ly` with target edge `edge` to `dir/name`.
fn strip_mesh(dir: &Path, lx: &str, ly: &str, edge: &str, name: &str) {
    let r = run(
        &[
            "mesh",
            "rectangle",
            "--lx",
            lx,
            "--ly",
            ly,
            "--edge",
            edge,
            "-o",
            name,
        ],
        dir,
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
}

fn tmp() -> tempfile::TempDir {
    tempfile::tempdir().unwrap()
}

/// A 2-triangle square with programmed cylinder forms, as MorphoShell writes it (legacy ASCII,
/// FIELD arrays, a free title line).
const TWO_TRIANGLES: &str = "# vtk DataFile Version 4.2
MorphoShell-style input dial_factor = 0
ASCII
DATASET UNSTRUCTURED_GRID
POINTS 4 double
0 0 0
1 0 0
1 1 0
0 1 0
CELLS 2 8
3 0 1 2
3 0 2 3
CELL_TYPES 2
5
5
CELL_DATA 2
FIELD FieldData 5
abar_info 3 2 double
1 0 1 1 0 1
bbar_info 3 2 double
0.5 0 0 0.5 0 0
ref_thicknesses 1 2 double
0.05 0.05
ref_shear_moduli 1 2 double
1000 1000
tri_tags 1 2 int
0 1
POINT_DATA 4
FIELD FieldData 2
constraint_indicators 1 4 int
0 0 0 0
node_tags 1 4 int
0 0 1 1
";

const STATIC: &str = "[rest]\ntarget = \"mesh\"\n[solver]\nmode = \"static\"\n";

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// Frames (`frame_NNNNN.vtu|vtk`, not their state files) in `dir`.
fn frames(dir: &Path) -> usize {
    std::fs::read_dir(dir)
        .map(|r| {
            r.filter(|e| {
                e.as_ref().is_ok_and(|e| {
                    let n = e.file_name().to_string_lossy().into_owned();
                    n.starts_with("frame_") && (n.ends_with(".vtu") || n.ends_with(".vtk"))
                })
            })
            .count()
        })
        .unwrap_or(0)
}

#[test]
fn two_triangles_static_run_writes_frames_series_log_and_summary() {
    let d = tmp();
    write(d.path(), "m.vtk", TWO_TRIANGLES);
    write(d.path(), "s.toml", STATIC);
    let r = run(&["s.toml", "m.vtk", "--out", "out"], d.path());
    assert_eq!(r.code, 0, "stderr: {}", r.stderr);
    let out = d.path().join("out");
    assert_eq!(frames(&out), 2);
    assert!(out.join("series.pvd").exists());
    let log = std::fs::read_to_string(out.join("log.csv")).unwrap();
    assert_eq!(log.lines().count(), 3, "{log}");
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    for key in [
        "converged",
        "final_frame",
        "wall_seconds",
        "steps",
        "newton_iterations",
        "vertices",
        "faces",
        "threads",
        "energy",
    ] {
        assert!(s.get(key).is_some(), "summary lacks {key}");
    }
    assert_eq!(s["converged"], true);
    assert_eq!(s["faces"], 2);
    assert!(out.join(s["final_frame"].as_str().unwrap()).exists());
}

#[test]
fn every_example_scene_runs_at_small_size() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let d = tmp();
    let mut n = 0;
    for entry in std::fs::read_dir(root.join("settings")).unwrap() {
        let p = entry.unwrap().path();
        if p.extension().and_then(|e| e.to_str()) != Some("toml") {
            continue;
        }
        let text = std::fs::read_to_string(&p).unwrap();
        // Each scene names its mesh on a line `# mesh: meshes/<file>`.
        let mesh = text
            .lines()
            .find_map(|l| l.strip_prefix("# mesh: "))
            .unwrap_or_else(|| panic!("{} names no mesh", p.display()));
        let out = d.path().join(p.file_stem().unwrap());
        let mesh = root.join(mesh.trim());
        let mut args = vec![
            p.to_str().unwrap(),
            mesh.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--set",
            "time.end=0.1",
        ];
        // A scene too long for the suite names its shortened run on `# test-set: KEY=VALUE`
        // lines (an explicit run to a looser equilibrium, say).
        for l in text.lines().filter_map(|l| l.strip_prefix("# test-set: ")) {
            args.extend(["--set", l.trim()]);
        }
        let r = run(&args, d.path());
        // … and the exit code of that shortened run on `# test-exit: CODE` (default 0).
        let code = text
            .lines()
            .find_map(|l| l.strip_prefix("# test-exit: "))
            .map_or(0, |c| c.trim().parse().unwrap());
        assert_eq!(r.code, code, "{}: {}", p.display(), r.stderr);
        assert!(frames(&out) >= 2);
        n += 1;
    }
    assert!(n >= 2, "expected example scenes in settings/");
}

fn expect_bad(args: &[&str], dir: &Path, needle: &str) {
    let r = run(args, dir);
    assert_eq!(
        r.code, 2,
        "expected exit 2 for {args:?}; stderr: {}",
        r.stderr
    );
    assert!(
        r.stderr.contains(needle),
        "stderr for {args:?} should mention '{needle}': {}",
        r.stderr
    );
    assert!(!r.stderr.contains("panicked"), "{}", r.stderr);
    assert!(!r.stderr.contains("stack backtrace"), "{}", r.stderr);
    assert_eq!(frames(&dir.join("out")), 0, "frames written for {args:?}");
}

#[test]
fn bad_meshes_are_rejected_with_exit_2_and_nothing_written() {
    let d = tmp();
    let p = d.path();
    write(p, "s.toml", STATIC);
    write(p, "garbage.vtk", "hello world\n");
    expect_bad(&["s.toml", "garbage.vtk"], p, "garbage.vtk");
    write(
        p,
        "trunc.vtk",
        &TWO_TRIANGLES[..TWO_TRIANGLES.find("CELL_TYPES").unwrap()],
    );
    expect_bad(&["s.toml", "trunc.vtk"], p, "trunc.vtk");
    write(p, "nan.vtk", &TWO_TRIANGLES.replace("1 1 0\n", "nan 1 0\n"));
    expect_bad(&["s.toml", "nan.vtk"], p, "line 8, POINTS: value");
    write(
        p,
        "zero.vtk",
        &TWO_TRIANGLES.replace("1 1 0\n0 1 0", "1 1 0\n2 2 0"),
    );
    expect_bad(&["s.toml", "zero.vtk"], p, "face 1");
    let wrong_len = TWO_TRIANGLES.replace(
        "ref_thicknesses 1 2 double\n0.05 0.05",
        "ref_thicknesses 1 3 double\n0.05 0.05 0.05",
    );
    write(p, "len.vtk", &wrong_len);
    expect_bad(&["s.toml", "len.vtk"], p, "ref_thicknesses");
    write(
        p,
        "neg.vtk",
        &TWO_TRIANGLES.replace("0.05 0.05", "0.05 -0.05"),
    );
    expect_bad(&["s.toml", "neg.vtk"], p, "face 1");
    write(
        p,
        "noabar.vtk",
        &TWO_TRIANGLES.replace("abar_info", "other_info"),
    );
    expect_bad(&["s.toml", "noabar.vtk"], p, "abar_info");
    // Inconsistent orientation: second triangle reversed.
    write(
        p,
        "orient.vtk",
        &TWO_TRIANGLES.replace("3 0 2 3", "3 0 3 2"),
    );
    expect_bad(&["s.toml", "orient.vtk"], p, "oriented");
    // Non-manifold edge: three triangles on edge (0, 2).
    let nm = "# vtk DataFile Version 3.0\nnm\nASCII\nDATASET POLYDATA\nPOINTS 5 double\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0.5 0.5 1\nPOLYGONS 3 12\n3 0 1 2\n3 0 2 3\n3 2 0 4\n";
    write(p, "nm.vtk", nm);
    write(p, "none.toml", "");
    expect_bad(&["none.toml", "nm.vtk"], p, "non-manifold");
    // Non-triangle cell.
    let quad = "# vtk DataFile Version 2.0\nq\nASCII\nDATASET POLYDATA\nPOINTS 4 double\n0 0 0 1 0 0 1 1 0 0 1 0\nPOLYGONS 1 5\n4 0 1 2 3\n";
    write(p, "quad.vtk", quad);
    expect_bad(&["none.toml", "quad.vtk"], p, "not a triangle");
    expect_bad(&["s.toml", "missing.vtk"], p, "missing.vtk");
}

#[test]
fn bad_settings_are_rejected_with_exit_2() {
    let d = tmp();
    let p = d.path();
    write(p, "m.vtk", TWO_TRIANGLES);
    let cases = [
        ("[material]\nyoungs = 1.0\n", "youngs"),
        ("[material]\nyoung = \"soft\"\n", "young"),
        ("[material]\nthickness = -0.1\n", "material.thickness"),
        ("[material]\nyoung = 0.0\n", "material.young"),
        ("[material]\ndensity = -1.0\n", "material.density"),
        ("[material]\npoisson = 0.6\n", "material.poisson"),
        ("[material]\npoisson = -1.0\n", "material.poisson"),
        ("[solver]\nmode = \"sideways\"\n", "mode"),
        ("[time]\ndt = 0.0\n", "time.dt"),
        (
            "[rest]\ntarget = \"uniform\"\nabar = [1.0, 2.0, 1.0]\n",
            "rest.abar",
        ),
        ("[material\n", "s.toml"),
    ];
    for (text, needle) in cases {
        write(p, "s.toml", text);
        expect_bad(&["s.toml", "m.vtk"], p, needle);
    }
    write(p, "s.toml", STATIC);
    expect_bad(
        &["s.toml", "m.vtk", "--set", "material.thikness=1"],
        p,
        "thikness",
    );
    expect_bad(&["s.toml", "m.vtk", "--set", "nokey"], p, "key=value");
}

#[test]
fn unwritable_output_folder_is_exit_2() {
    let d = tmp();
    let p = d.path();
    write(p, "m.vtk", TWO_TRIANGLES);
    write(p, "s.toml", STATIC);
    write(p, "afile", "x");
    let r = run(&["s.toml", "m.vtk", "--out", "afile/sub"], p);
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(r.stderr.contains("afile"), "{}", r.stderr);
}

#[test]
fn set_overrides_reach_the_run() {
    let d = tmp();
    let p = d.path();
    write(p, "m.vtk", TWO_TRIANGLES);
    write(p, "s.toml", STATIC);
    let r = run(
        &[
            "s.toml",
            "m.vtk",
            "--out",
            "o",
            "--set",
            "output.format=\"vtk\"",
            "--set",
            "output.prefix=shape",
        ],
        p,
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(p.join("o/shape_00001.vtk").exists());
}

#[test]
fn non_convergence_exits_1_with_a_reason() {
    let d = tmp();
    let p = d.path();
    write(p, "m.vtk", TWO_TRIANGLES);
    write(p, "s.toml", "[rest]\ntarget = \"uniform\"\nabar = [9.0, 0.0, 9.0]\n[solver]\nmax_newton_iterations = 1\ncontinuation_step = 1.0\nmin_continuation_step = 0.5\n");
    let r = run(&["s.toml", "m.vtk", "--out", "o"], p);
    assert_eq!(r.code, 1, "{}", r.stderr);
    assert!(r.stderr.contains("did not converge"), "{}", r.stderr);
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(p.join("o/summary.json")).unwrap()).unwrap();
    assert_eq!(s["converged"], false);
    assert!(!s["reason"].as_str().unwrap().is_empty());
}

#[test]
fn results_do_not_depend_on_the_thread_count() {
    let d = tmp();
    let p = d.path();
    let r = run(
        &[
            "mesh",
            "square",
            "--edge",
            "0.1",
            "--jitter",
            "0.2",
            "--program",
            "spherical_cap",
            "-o",
            "m.vtk",
        ],
        p,
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    write(
        p,
        "s.toml",
        "[material]\nthickness = 0.05\n[rest]\ntarget = \"mesh\"\n",
    );
    for t in ["1", "2", "3"] {
        let r = run(
            &["s.toml", "m.vtk", "--out", &format!("o{t}"), "--threads", t],
            p,
        );
        assert_eq!(r.code, 0, "{}", r.stderr);
    }
    let a = std::fs::read(p.join("o1/frame_00001.vtu")).unwrap();
    let b = std::fs::read(p.join("o2/frame_00001.vtu")).unwrap();
    let c = std::fs::read(p.join("o3/frame_00001.vtu")).unwrap();
    assert!(a == b && b == c, "frames differ between thread counts");
    // The explicit driver, whose steps run on a team of spinning threads: every frame of a
    // run cut short after two long times (exit 1: no equilibrium yet).
    write(
        p,
        "e.toml",
        "[material]\nthickness = 0.05\nbending = \"patch_fit\"\n[rest]\ntarget = \"mesh\"\n\
         [solver]\nmode = \"explicit\"\n[explicit]\nmax_long_times = 2\n",
    );
    let frames = |t: &str| {
        let r = run(
            &["e.toml", "m.vtk", "--out", &format!("e{t}"), "--threads", t],
            p,
        );
        assert_eq!(r.code, 1, "{}", r.stderr);
        let mut names: Vec<_> = std::fs::read_dir(p.join(format!("e{t}")))
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|f| f.extension().is_some_and(|x| x == "vtu"))
            .collect();
        names.sort();
        assert!(names.len() > 10, "{names:?}");
        names
            .iter()
            .map(|f| std::fs::read(f).unwrap())
            .collect::<Vec<_>>()
    };
    let one = frames("1");
    assert!(
        frames("2") == one,
        "explicit frames differ between 1 and 2 threads"
    );
    assert!(
        frames("3") == one,
        "explicit frames differ between 1 and 3 threads"
    );
}

#[test]
fn mesh_generator_and_error_command() {
    let d = tmp();
    let p = d.path();
    for (shape, extra) in [
        ("square", vec!["--edge", "0.25"]),
        ("square", vec!["--edge", "0.1", "--delaunay", "--seed", "4"]),
        (
            "rectangle",
            vec![
                "--edge",
                "0.05",
                "--lx",
                "0.3",
                "--ly",
                "0.1",
                "--grading",
                "2",
            ],
        ),
        ("disk", vec!["--edge", "0.2", "--jitter", "0.25"]),
        (
            "annulus",
            vec!["--edge", "0.1", "--inner", "0.5", "--sweep", "300"],
        ),
        (
            "annulus",
            vec![
                "--edge",
                "0.1",
                "--inner",
                "0.5",
                "--sweep",
                "300",
                "--delaunay",
            ],
        ),
        (
            "annulus",
            vec!["--edge", "0.1", "--inner", "0.5", "--delaunay"],
        ),
    ] {
        let mut args = vec!["mesh", shape, "-o", "g.vtu"];
        args.extend(extra);
        let r = run(&args, p);
        assert_eq!(r.code, 0, "{shape}: {}", r.stderr);
        assert!(r.stdout.contains("faces"));
    }
    let r = run(&["mesh", "square", "--edge", "-1", "-o", "g.vtk"], p);
    assert_eq!(r.code, 2);
    let r = run(
        &[
            "mesh",
            "square",
            "--edge",
            "0.2",
            "--program",
            "teapot",
            "-o",
            "g.vtk",
        ],
        p,
    );
    assert_eq!(r.code, 2);
    assert!(r.stderr.contains("teapot"));
    let r = run(&["error", "cylinder", "nothere.vtu"], p);
    assert_eq!(r.code, 2);
}

#[test]
fn unused_vertices_warn_and_are_held_fixed() {
    let d = tmp();
    let p = d.path();
    let text = TWO_TRIANGLES
        .replace("POINTS 4 double\n", "POINTS 5 double\n")
        .replace("0 1 0\nCELLS", "0 1 0\n5 5 5\nCELLS")
        .replace("POINT_DATA 4\nFIELD FieldData 2\nconstraint_indicators 1 4 int\n0 0 0 0\nnode_tags 1 4 int\n0 0 1 1\n", "");
    write(p, "m.vtk", &text);
    write(p, "s.toml", STATIC);
    let r = run(&["s.toml", "m.vtk", "--out", "o"], p);
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(
        r.stderr.contains("warning") && r.stderr.contains("used by no face"),
        "{}",
        r.stderr
    );
}

#[test]
fn static_gravity_without_supports_is_bad_input() {
    let d = tmp();
    let p = d.path();
    write(p, "m.vtk", TWO_TRIANGLES);
    write(p, "s.toml", "[loads]\ngravity = [0, 0, -9.81]\n");
    expect_bad(&["s.toml", "m.vtk"], p, "fixed vertices");
}

#[test]
fn fixed_tags_hold_and_continuation_frames_are_written() {
    let d = tmp();
    let p = d.path();
    write(p, "m.vtk", TWO_TRIANGLES);
    write(
        p,
        "s.toml",
        "[rest]\ntarget = \"uniform\"\nabar = [1.2, 0.0, 1.2]\n[solver]\ncontinuation_step = 0.25\n\
         [constraints]\nfix_tags = [1]\n[output]\ncontinuation_frames = true\nformat = \"vtk_ascii\"\n",
    );
    let r = run(&["s.toml", "m.vtk", "--out", "o"], p);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let n = frames(&p.join("o"));
    assert!(n >= 3, "expected continuation frames, got {n}");
    let last = shellsim::mesh::io::read_mesh(&p.join(format!("o/frame_{:05}.vtk", n - 1))).unwrap();
    let fixed = &last.vertex_fields["constraint_indicators"].data;
    assert_eq!(fixed, &vec![0.0, 0.0, 1.0, 1.0]);
    let disp = &last.vertex_fields["displacement"];
    for v in [2, 3] {
        assert!(
            disp.get(v).iter().all(|c| *c == 0.0),
            "fixed vertex {v} moved"
        );
    }
    // The free vertices moved: ā = 1.2 I asks for edges √1.2 ≈ 9.5% longer.
    assert!(disp.get(0).iter().any(|c| c.abs() > 1e-3));
}

fn final_frame(dir: &Path, out: &str) -> String {
    format!(
        "{out}/{}",
        summary_of(dir, out)["final_frame"].as_str().unwrap()
    )
}

fn summary_of(dir: &Path, out: &str) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join(out).join("summary.json")).unwrap())
        .unwrap()
}

/// Restart: a static run from the final frame of an earlier run reads the positions and edge
/// angles back and is converged at once, on the same shape; a dynamic restart resumes at the
/// frame's time. Edge angles that disagree between an edge's two faces, and a frame of another
/// mesh, are bad input.
#[test]
fn restart_carries_positions_edge_dofs_and_time() {
    let d = tmp();
    let p = d.path();
    let r = run(
        &[
            "mesh",
            "square",
            "--edge",
            "0.25",
            "--program",
            "cylinder",
            "-o",
            "m.vtk",
        ],
        p,
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    let settings = "[material]\nthickness = 0.05\nbending = \"midedge_sin\"\n[rest]\ntarget = \"mesh\"\n[output]\nformat = \"vtk_ascii\"\n";
    write(p, "s.toml", settings);
    let r = run(&["s.toml", "m.vtk", "--out", "a", "-q"], p);
    assert_eq!(r.code, 0, "{}", r.stderr);
    // `settings` run into `out`, restarted from `frame`.
    let restart = |settings: &str, out: &str, frame: &str| {
        run(
            &[settings, "m.vtk", "--out", out, "-q", "--restart", frame],
            p,
        )
    };
    let fa = final_frame(p, "a");
    let text = std::fs::read_to_string(p.join(&fa)).unwrap();
    assert!(text.contains("edge_angles"), "frames carry the edge DOFs");
    let r = restart("s.toml", "b", &fa);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let sb = summary_of(p, "b");
    assert!(sb["newton_iterations"].as_u64().unwrap() <= 1, "{sb}");
    let err = |frame: &str| -> f64 {
        let r = run(&["error", "cylinder", frame], p);
        let v: serde_json::Value = serde_json::from_str(&r.stdout).unwrap();
        v["max_error_rel"].as_f64().unwrap()
    };
    let (ea, eb) = (err(&fa), err(&final_frame(p, "b")));
    assert!(
        (ea - eb).abs() <= 1e-9,
        "restart moved the shape: {ea} vs {eb}"
    );

    // Tampered edge angles: the first face's three values no longer match its neighbours'.
    let i = text.find("edge_angles").unwrap();
    let line_start = i + text[i..].find('\n').unwrap() + 1;
    let line_end = line_start + text[line_start..].find('\n').unwrap();
    let mut vals: Vec<String> = text[line_start..line_end]
        .split_whitespace()
        .map(String::from)
        .collect();
    for (k, v) in vals.iter_mut().take(3).enumerate() {
        *v = format!("0.{}", 5 + k);
    }
    let bad = format!(
        "{}{}{}",
        &text[..line_start],
        vals.join(" "),
        &text[line_end..]
    );
    write(p, "bad.vtk", &bad);
    let r = restart("s.toml", "c", "bad.vtk");
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(r.stderr.contains("edge_angles"), "{}", r.stderr);
    // A frame of another mesh.
    let r = run(&["mesh", "square", "--edge", "0.5", "-o", "other.vtk"], p);
    assert_eq!(r.code, 0);
    let r = restart("s.toml", "c", "other.vtk");
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(r.stderr.contains("same mesh"), "{}", r.stderr);

    // Dynamic: 4 steps to t = 0.02 with frames every 0.01; restart from t = 0.01.
    let dynamic = "[material]\nthickness = 0.05\n[rest]\ntarget = \"mesh\"\n[solver]\nmode = \"dynamic\"\n[time]\nend = 0.02\ndt = 0.005\noutput_interval = 0.01\n";
    write(p, "dyn.toml", dynamic);
    let r = run(&["dyn.toml", "m.vtk", "--out", "d", "-q"], p);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let r = restart("dyn.toml", "e", "d/frame_00001.vtu");
    assert_eq!(r.code, 0, "{}", r.stderr);
    let se = summary_of(p, "e");
    assert!((se["time"].as_f64().unwrap() - 0.02).abs() < 1e-12, "{se}");
    let series = std::fs::read_to_string(p.join("e/series.pvd")).unwrap();
    assert!(series.contains("timestep=\"0.01\""), "{series}");
    // Same trajectory as the uninterrupted run (velocities and edge angles carried over).
    let (ed, ee) = (err(&final_frame(p, "d")), err(&final_frame(p, "e")));
    assert!((ed - ee).abs() <= 1e-12 * ed.abs(), "{ed} vs {ee}");
}

/// The membrane-continuation setting is validated.
#[test]
fn membrane_continuation_below_one_is_bad_input() {
    let d = tmp();
    let p = d.path();
    write(p, "m.vtk", TWO_TRIANGLES);
    write(
        p,
        "s.toml",
        &format!("{STATIC}membrane_continuation = 0.5\n"),
    );
    expect_bad(&["s.toml", "m.vtk"], p, "solver.membrane_continuation");
}

/// Growth laws end to end: a strip wetted on top (linear swelling) curls with its middle above
/// its ends (b̄ > 0 bulges toward the +z normal, i.e. away from the water), a dry top curls the
/// other way, equal moisture stays flat; bad growth input is exit 2 naming the face or key.
#[test]
fn growth_laws_curl_strips_and_reject_bad_input() {
    let d = tmp();
    let p = d.path();
    strip_mesh(p, "0.2", "0.02", "0.01", "s.vtk");
    let middle_minus_ends = |toml: &str, out: &str| -> f64 {
        write(p, "g.toml", toml);
        let r = run(&["g.toml", "s.vtk", "--out", out, "-q"], p);
        assert_eq!(r.code, 0, "{}", r.stderr);
        let frame = final_frame(p, out);
        let m = shellsim::mesh::io::read_mesh(&p.join(frame)).unwrap();
        let reference = shellsim::mesh::io::read_mesh(&p.join("s.vtk")).unwrap();
        let z = |pick: &dyn Fn(f64) -> bool| {
            let v: Vec<f64> = reference
                .positions
                .iter()
                .zip(&m.positions)
                .filter(|(r, _)| pick(r.x))
                .map(|(_, x)| x.z)
                .collect();
            v.iter().sum::<f64>() / v.len() as f64
        };
        z(&|x| x.abs() < 1e-9) - z(&|x| (x.abs() - 0.1).abs() < 1e-9)
    };
    let law = |top: f64, bottom: f64| {
        format!(
            "[material]\nthickness = 0.001\n[growth]\nlaw = \"linear_swelling\"\nmu = 0.01\nmoisture_top = {top}\nmoisture_bottom = {bottom}\n"
        )
    };
    let wet_top = middle_minus_ends(&law(0.1, 0.0), "a");
    let wet_bottom = middle_minus_ends(&law(0.0, 0.1), "b");
    let even = middle_minus_ends(&law(0.1, 0.1), "c");
    assert!(wet_top > 1e-4, "wet top: {wet_top}");
    assert!(wet_bottom < -1e-4, "wet bottom: {wet_bottom}");
    assert!(even.abs() < 1e-9, "even moisture: {even}");

    write(
        p,
        "neg.toml",
        &law(0.1, 0.0).replace("mu = 0.01", "mu = -20"),
    );
    expect_bad(&["neg.toml", "s.vtk"], p, "face 0");
    let md = "[material]\nthickness = 0.001\n[growth]\nlaw = \"machine_direction\"\nmu = 0.01\nmu_perp = 0.0\nmachine_direction = [0, 0, 1]\nmoisture_top = 0.1\n";
    write(p, "md.toml", md);
    expect_bad(&["md.toml", "s.vtk"], p, "machine_direction");
    write(
        p,
        "both.toml",
        "[rest]\ntarget = \"uniform\"\n[growth]\nlaw = \"isotropic\"\n",
    );
    expect_bad(&["both.toml", "s.vtk"], p, "growth.law");
    write(p, "nan.toml", "[growth]\nlaw = \"isotropic\"\ns = nan\n");
    expect_bad(&["nan.toml", "s.vtk"], p, "growth.s");
}

/// The moisture of a sheet exchanging with an ambient moisture through both faces (Robin,
/// Biot numbers Bi = k l / D of 0.1, 1 and 10, l the half-thickness), run end to end with the
/// default `[moisture]` layering, tolerance and step control: the surface moisture of every
/// frame from T = D t / l² = 0.05 to 2 lies within 1% of Crank's series (measured ≤ 0.1%).
/// Both faces swell alike, so the sheet stays flat and only the diffusion is tested.
#[test]
fn default_moisture_settings_resolve_the_surface_moisture() {
    let d = tmp();
    let p = d.path();
    strip_mesh(p, "0.004", "0.004", "0.002", "s.vtk");
    let (h, diff) = (1e-4, 1e-9);
    let l = 0.5 * h;
    let scale = l * l / diff; // s
    for bi in [0.1, 1.0, 10.0] {
        let k = bi * diff / l;
        let scene = format!(
            "[material]\nyoung = 3.0e9\ndensity = 800.0\nthickness = {h:e}\n[growth]\n\
             law = \"linear_swelling\"\nmu = 0.01\n[moisture]\nenabled = true\n\
             diffusivity_along = {diff:e}\ndiffusivity_across = {diff:e}\n\
             diffusivity_through = {diff:e}\n\
             [[moisture.boundary]]\nside = \"top\"\nkind = \"robin\"\nk = {k:e}\nambient = 0.3\n\
             [[moisture.boundary]]\nside = \"bottom\"\nkind = \"robin\"\nk = {k:e}\nambient = 0.3\n\
             [solver]\nmode = \"dynamic\"\n[time]\nend = {:e}\ndt = 1e-3\ndt_max = 0.5\n\
             output_interval = {:e}\n[output]\nformat = \"vtk_ascii\"\n",
            2.0 * scale,
            0.05 * scale
        );
        write(p, "r.toml", &scene);
        let out = format!("o{bi}");
        let r = run(&["r.toml", "s.vtk", "--out", &out, "-q"], p);
        assert_eq!(r.code, 0, "{}", r.stderr);
        let mut worst: f64 = 0.0;
        for frame in 1..=40 {
            let m = shellsim::mesh::io::read_mesh(&p.join(format!("{out}/frame_{frame:05}.vtk")))
                .unwrap();
            let t = 0.05 * frame as f64;
            let exact = 0.3 * shellsim::diffusion::robin_slab_surface(bi, t);
            for side in ["moisture_top", "moisture_bottom"] {
                for v in &m.face_fields[side].data {
                    worst = worst.max((v / exact - 1.0).abs());
                }
            }
        }
        println!("Bi {bi}: largest relative error of the surface moisture {worst:.2e}");
        assert!(worst < 0.01, "Bi {bi}: {worst:e}");
    }
}

/// Moisture coupling end to end: a strip wetted on top (prescribed moisture 0.2, bottom sealed)
/// curls away from the water while the moisture crosses the thickness, then flattens as it
/// evens out: the mean curvature rises, peaks and falls, with the right sign, and every frame
/// carries finite moisture fields. Contradictory regions and moisture in static mode are exit 2.
#[test]
fn wetted_strip_curls_then_flattens() {
    let d = tmp();
    let p = d.path();
    strip_mesh(p, "0.1", "0.02", "0.01", "s.vtk");
    let scene = "[material]\nyoung = 3.0e9\ndensity = 800.0\nthickness = 1.0e-4\n[growth]\nlaw = \"linear_swelling\"\nmu = 0.01\n[moisture]\nenabled = true\ndiffusivity_along = 1e-9\ndiffusivity_across = 1e-9\ndiffusivity_through = 1e-9\nlayers = 4\n[[moisture.boundary]]\nside = \"top\"\nkind = \"value\"\nvalue = 0.2\n[solver]\nmode = \"dynamic\"\n[time]\nend = 12.0\ndt = 0.01\ndt_max = 0.5\noutput_interval = 1.0\ndamping = 0.1\n[output]\nformat = \"vtk_ascii\"\n";
    write(p, "w.toml", scene);
    let r = run(&["w.toml", "s.vtk", "--out", "o", "-q"], p);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let mut curvature = Vec::new();
    for k in 0..=12 {
        let m = shellsim::mesh::io::read_mesh(&p.join(format!("o/frame_{k:05}.vtk"))).unwrap();
        let h = &m.face_fields["mean_curvature"].data;
        let top = &m.face_fields["moisture_top"].data;
        let bottom = &m.face_fields["moisture_bottom"].data;
        assert!(top
            .iter()
            .chain(bottom)
            .all(|v| v.is_finite() && *v >= -1e-12 && *v <= 0.2 + 1e-12));
        curvature.push(h.iter().sum::<f64>() / h.len() as f64);
    }
    println!("mean curvature per second: {curvature:.3?}");
    let (peak, at) =
        curvature.iter().enumerate().fold(
            (0.0f64, 0),
            |(m, i), (k, &c)| if c > m { (c, k) } else { (m, i) },
        );
    assert!(
        peak > 5.0,
        "the strip should curl away from the water: {curvature:?}"
    );
    assert!((1..=3).contains(&at), "peak at {at} s");
    assert!(
        curvature[12] < 0.2 * peak,
        "it should flatten as the moisture evens out"
    );

    let contradictory =
        format!("{scene}[[moisture.boundary]]\nside = \"top\"\nkind = \"flux\"\nvalue = 1e-6\n");
    write(p, "c.toml", &contradictory);
    expect_bad(&["c.toml", "s.vtk"], p, "face 0");
    write(
        p,
        "st.toml",
        &scene.replace("mode = \"dynamic\"", "mode = \"static\""),
    );
    expect_bad(&["st.toml", "s.vtk"], p, "moisture.enabled");
}

/// Moisture adds the water's mass (seed 000 §3): each face's density is ρ + (m⁺ + m⁻)/2 ρ_w. A
/// sealed sheet at uniform moisture 0.25 in free fall has kinetic energy ½ M (g t)² with
/// M = (ρ + 0.25 ρ_w) h A; `water_density = 0` keeps M = ρ h A.
#[test]
fn absorbed_water_adds_mass() {
    let d = tmp();
    let p = d.path();
    let r = run(&["mesh", "square", "--edge", "0.25", "-o", "s.vtk"], p);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let (rho, h, g, t) = (800.0, 1e-3, 9.81, 0.05);
    for rho_w in [1000.0, 0.0] {
        let scene = format!(
            "[material]\ndensity = {rho}\nthickness = {h}\n[growth]\nlaw = \"linear_swelling\"\nmu = 0.0\n\
             [moisture]\nenabled = true\ninitial = 0.25\nwater_density = {rho_w}\n[loads]\ngravity = [0.0, 0.0, -{g}]\n\
             [solver]\nmode = \"dynamic\"\nsymmetry_breaking = 0.0\n[time]\nend = {t}\ndt = 0.01\ndt_max = 0.01\noutput_interval = {t}\n"
        );
        write(p, "m.toml", &scene);
        let r = run(&["m.toml", "s.vtk", "--out", "o", "-q", "--overwrite"], p);
        assert_eq!(r.code, 0, "{}", r.stderr);
        let s = summary_of(p, "o");
        let kinetic = s["energy"]["kinetic"].as_f64().unwrap();
        let mass = (rho + 0.25 * rho_w) * h * 1.0;
        let expect = 0.5 * mass * (g * t) * (g * t);
        assert!(
            (kinetic / expect - 1.0).abs() < 1e-9,
            "ρ_w = {rho_w}: {kinetic} vs {expect}"
        );
    }
}

/// Bad growth and moisture input: per-face fields of the wrong length, NaN (the reader
/// names the line), a zero
/// machine direction, swelling that makes ā non-positive, a ground exchange without a ground,
/// a broken expression, a zero contact normal, a mesh that starts inside the ground. Each is
/// exit 2 naming the field, the face or the vertex.
#[test]
fn bad_growth_and_moisture_fields_are_rejected() {
    let d = tmp();
    let p = d.path();
    let with_fields = |fields: &str| {
        TWO_TRIANGLES.replace(
            "CELL_DATA 2\nFIELD FieldData 5\n",
            &format!(
                "CELL_DATA 2\nFIELD FieldData {}\n{fields}",
                5 + fields.matches(" double\n").count()
            ),
        )
    };
    let swell = "[growth]\nlaw = \"linear_swelling\"\nmu = 0.01\n";
    write(p, "swell.toml", swell);
    for (name, mesh, needle) in [
        (
            "len.vtk",
            with_fields("moisture_top 1 3 double\n0.1 0.1 0.1\n"),
            "moisture_top",
        ),
        (
            "nan.vtk",
            with_fields("moisture_top 1 2 double\n0.1 nan\n"),
            "line 19, CELL_DATA FIELD array 'moisture_top': value 1 of 2 is non-finite",
        ),
        (
            "nan2.vtk",
            with_fields("moisture_bottom 1 2 double\ninf 0.1\n"),
            "line 19, CELL_DATA FIELD array 'moisture_bottom': value 0 of 2 is non-finite",
        ),
        (
            "neg.vtk",
            with_fields("moisture_top 1 2 double\n0.1 -200\n"),
            "face 1",
        ),
    ] {
        write(p, name, &mesh);
        expect_bad(&["swell.toml", name], p, needle);
    }
    let md = "[growth]\nlaw = \"machine_direction\"\nmu = 0.01\nmu_perp = 0.03\n";
    write(p, "md.toml", md);
    for (name, field, needle) in [
        (
            "zero.vtk",
            "machine_direction 3 2 double\n1 0 0 0 0 0\n",
            "face 1",
        ),
        (
            "mdlen.vtk",
            "machine_direction 2 2 double\n1 0 1 0\n",
            "machine_direction",
        ),
        (
            "mdnan.vtk",
            "machine_direction 3 2 double\n1 0 0 nan 1 0\n",
            "line 19, CELL_DATA FIELD array 'machine_direction': value 3 of 6 is non-finite",
        ),
    ] {
        write(p, name, &with_fields(field));
        expect_bad(&["md.toml", name], p, needle);
    }
    write(
        p,
        "iso_len.vtk",
        &with_fields("growth_factor 1 1 double\n0.1\n"),
    );
    write(p, "iso.toml", "[growth]\nlaw = \"isotropic\"\n");
    expect_bad(&["iso.toml", "iso_len.vtk"], p, "growth_factor");
    write(p, "ok.vtk", TWO_TRIANGLES);
    let dynamic = "[solver]\nmode = \"dynamic\"\n[growth]\nlaw = \"linear_swelling\"\nmu = 0.01\n[moisture]\nenabled = true\n";
    write(
        p,
        "ground.toml",
        &format!("{dynamic}[moisture.ground]\nk = 1e-5\n"),
    );
    expect_bad(&["ground.toml", "ok.vtk"], p, "moisture.ground");
    write(
        p,
        "normal.toml",
        &format!("{dynamic}[contact]\nenabled = true\nnormal = [0, 0, 0]\n"),
    );
    expect_bad(&["normal.toml", "ok.vtk"], p, "contact.normal");
    write(
        p,
        "inside.toml",
        &format!("{dynamic}[contact]\nenabled = true\npoint = [0, 0, 0.01]\n"),
    );
    expect_bad(&["inside.toml", "ok.vtk"], p, "inside the ground");
    write(
        p,
        "expr.toml",
        "[growth]\nlaw = \"isotropic\"\ns = \"sqrt(x\"\n",
    );
    expect_bad(&["expr.toml", "ok.vtk"], p, "growth.s");
}

/// Tape (`moisture.boundary.tape`): a sealed side that does not swell. A strip wetted from below
/// with its top sealed evens out and flattens; with tape on top it stays curled once wet through,
/// away from the tape (the wet paper is the convex side: negative mean curvature with respect to
/// the top's normal), as a bilayer does.
#[test]
fn taped_side_does_not_swell() {
    let d = tmp();
    let p = d.path();
    strip_mesh(p, "0.06", "0.01", "0.005", "s.vtk");
    let mut end = Vec::new();
    for tape in [false, true] {
        let scene = format!(
            "[material]\nyoung = 4.0e9\ndensity = 800.0\nthickness = 1.0e-4\n[growth]\nlaw = \"linear_swelling\"\nmu = 0.04\n\
             [moisture]\nenabled = true\ndiffusivity_along = 1e-9\ndiffusivity_across = 1e-9\ndiffusivity_through = 1e-9\n\
             [[moisture.boundary]]\nside = \"bottom\"\nkind = \"value\"\nvalue = 0.3\n\
             [[moisture.boundary]]\nside = \"top\"\nkind = \"sealed\"\ntape = {tape}\n\
             [solver]\nmode = \"dynamic\"\n[time]\nend = 40.0\ndt = 0.01\ndt_max = 1.0\noutput_interval = 40.0\ndamping = 0.1\n\
             [output]\nformat = \"vtk_ascii\"\n"
        );
        write(p, "t.toml", &scene);
        let r = run(&["t.toml", "s.vtk", "--out", "o", "-q", "--overwrite"], p);
        assert_eq!(r.code, 0, "{}", r.stderr);
        let m = shellsim::mesh::io::read_mesh(&p.join("o/frame_00001.vtk")).unwrap();
        let top = &m.face_fields["moisture_top"].data;
        assert!(top.iter().all(|&v| v > 0.29), "wet through after 40 s");
        let h = &m.face_fields["mean_curvature"].data;
        end.push(h.iter().sum::<f64>() / h.len() as f64);
    }
    println!("mean curvature at 40 s, sealed / taped: {end:?}");
    // Without tape the moisture is uniform: flat to within 1 /m. With it, b̄ = −μ Δm/h ≈ −120 /m
    // asks for a curl of order 100 /m.
    assert!(end[0].abs() < 1.0, "{end:?}");
    assert!(end[1] < -30.0, "{end:?}");
    write(
        p,
        "bad.toml",
        "[solver]\nmode = \"dynamic\"\n[growth]\nlaw = \"linear_swelling\"\nmu = 0.01\n[moisture]\nenabled = true\n\
         [[moisture.boundary]]\nside = \"top\"\nkind = \"robin\"\nk = 1e-6\ntape = true\n",
    );
    expect_bad(&["bad.toml", "s.vtk"], p, "moisture.boundary[0].tape");
}

/// An output folder holds one run: a rerun is refused (exit 2, the folder untouched) unless
/// `--overwrite`, which leaves no file of the earlier run behind; a live run's lock refuses a
/// second run, a dead one's lock is taken over.
#[test]
fn output_folders_hold_one_run() {
    let d = tmp();
    let p = d.path();
    write(p, "m.vtk", TWO_TRIANGLES);
    let dynamic = |frames: u32| {
        format!(
            "[material]\nthickness = 0.05\n[solver]\nmode = \"dynamic\"\n[time]\nend = {e}\ndt = 0.01\ndt_max = 0.01\noutput_interval = 0.01\n",
            e = 0.01 * frames as f64
        )
    };
    write(p, "five.toml", &dynamic(5));
    write(p, "two.toml", &dynamic(2));
    let r = run(&["five.toml", "m.vtk", "--out", "o", "-q"], p);
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert_eq!(frames(&p.join("o")), 6);
    let before = std::fs::read(p.join("o/summary.json")).unwrap();
    let r = run(&["two.toml", "m.vtk", "--out", "o", "-q"], p);
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(
        r.stderr.contains("earlier run")
            && r.stderr.contains("--overwrite")
            && r.stderr.contains("6 frames"),
        "{}",
        r.stderr
    );
    assert_eq!(std::fs::read(p.join("o/summary.json")).unwrap(), before);
    assert_eq!(frames(&p.join("o")), 6, "a refused rerun touches nothing");
    let r = run(&["two.toml", "m.vtk", "--out", "o", "-q", "--overwrite"], p);
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert_eq!(
        frames(&p.join("o")),
        3,
        "no frame of the earlier run is left"
    );
    let series = std::fs::read_to_string(p.join("o/series.pvd")).unwrap();
    assert_eq!(series.matches("<DataSet").count(), 3, "{series}");
    let log = std::fs::read_to_string(p.join("o/log.csv")).unwrap();
    assert_eq!(log.lines().count(), 4, "{log}");
    assert!(
        !p.join("o/.shellsim.lock").exists(),
        "the lock goes with the run"
    );
    // A lock held by a live process (this test) refuses the run.
    std::fs::write(
        p.join("o/.shellsim.lock"),
        format!("{}\n", std::process::id()),
    )
    .unwrap();
    let r = run(&["two.toml", "m.vtk", "--out", "o", "-q", "--overwrite"], p);
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(
        r.stderr
            .contains(&format!("process {}", std::process::id())),
        "{}",
        r.stderr
    );
    // A lock whose process is gone is stale.
    std::fs::write(p.join("o/.shellsim.lock"), "4000000000\n").unwrap();
    let r = run(&["two.toml", "m.vtk", "--out", "o", "-q", "--overwrite"], p);
    assert_eq!(r.code, 0, "{}", r.stderr);
}

/// Restarts take their time or dial from `series.pvd`; a value that is not a number, or lies
/// outside the run, is bad input.
#[test]
fn restart_time_must_lie_inside_the_run() {
    let d = tmp();
    let p = d.path();
    write(p, "m.vtk", TWO_TRIANGLES);
    write(p, "s.toml", STATIC);
    let r = run(&["s.toml", "m.vtk", "--out", "a", "-q"], p);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let frame = final_frame(p, "a");
    let series = std::fs::read_to_string(p.join("a/series.pvd")).unwrap();
    let name = frame.rsplit('/').next().unwrap().to_string();
    for (value, needle) in [
        ("NaN", "dial not finite"),
        ("-5", "dial -5, outside"),
        ("1e300", "dial 1e300"),
        ("x", "'x'"),
    ] {
        let mut out = String::new();
        for l in series.lines() {
            if l.contains(&format!("file=\"{name}\"")) {
                let i = l.find("timestep=\"").unwrap() + 10;
                let j = i + l[i..].find('"').unwrap();
                out.push_str(&format!("{}{value}{}\n", &l[..i], &l[j..]));
            } else {
                out.push_str(l);
                out.push('\n');
            }
        }
        std::fs::write(p.join("a/series.pvd"), out).unwrap();
        let r = run(
            &["s.toml", "m.vtk", "--out", "b", "-q", "--restart", &frame],
            p,
        );
        assert_eq!(r.code, 2, "timestep {value}: {}", r.stderr);
        assert!(r.stderr.contains(needle), "timestep {value}: {}", r.stderr);
        assert_eq!(frames(&p.join("b")), 0);
    }
}

/// Sizes that would run on without limit are refused up front, naming the key; more threads
/// than cores is a warning, and the run goes on with the cores.
#[test]
fn unbounded_sizes_are_refused() {
    let d = tmp();
    let p = d.path();
    write(p, "m.vtk", TWO_TRIANGLES);
    write(p, "s.toml", STATIC);
    let dynamic = "[solver]\nmode = \"dynamic\"\n[material]\nthickness = 0.05\n";
    write(p, "d.toml", dynamic);
    for (set, needle) in [
        ("time.end=1e300", "time.end"),
        ("time.output_interval=1e-12", "time.output_interval"),
        ("time.output_interval=1e-7", "frames"),
    ] {
        expect_bad(&["d.toml", "m.vtk", "-q", "--set", set], p, needle);
    }
    // Values whose energies overflow are refused up front, naming the key or the face.
    expect_bad(
        &["s.toml", "m.vtk", "-q", "--set", "material.young=1e308"],
        p,
        "material.young",
    );
    write(
        p,
        "big.vtk",
        &TWO_TRIANGLES.replacen("1 0 1 1 0 1", "9.2e18 0 1 1 0 1", 1),
    );
    expect_bad(&["s.toml", "big.vtk", "-q"], p, "abar at face 0");
    write(
        p,
        "mu.vtk",
        &TWO_TRIANGLES.replacen("1000 1000", "1000 1e308", 1),
    );
    expect_bad(
        &["s.toml", "mu.vtk", "-q"],
        p,
        "'ref_shear_moduli' must lie in (0, 1e15], but face 1",
    );
    let wet = "[growth]\nlaw = \"linear_swelling\"\nmu = 0.01\n[moisture]\nenabled = true\nlayers = 100000\n[solver]\nmode = \"dynamic\"\n";
    write(p, "w.toml", wet);
    expect_bad(&["w.toml", "m.vtk", "-q"], p, "moisture.layers");
    let r = run(
        &["s.toml", "m.vtk", "--out", "t", "-q", "--threads", "100000"],
        p,
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(
        r.stderr.contains("warning: --threads 100000"),
        "{}",
        r.stderr
    );
}

/// A constraint selection that selects nothing is bad input naming the key and the value, as
/// a load's is: a tag no vertex carries, a box around no vertex. A prescribed displacement
/// beyond the coordinates' range (±1e30 m) is refused like such a coordinate.
#[test]
fn constraints_that_select_nothing_or_move_too_far_are_refused() {
    let d = tmp();
    let p = d.path();
    write(p, "m.vtk", TWO_TRIANGLES);
    for (text, needles) in [
        (
            "[constraints]\nfix_tags = [1, 99]\n",
            &["constraints.fix_tags[1] = 99", "selects no vertex"][..],
        ),
        (
            "[constraints]\nfix_boxes = [{ min = [5, 5, 5], max = [6, 6, 6] }]\n",
            &["constraints.fix_boxes[0]", "selects no vertex"],
        ),
        (
            "[[constraints.displacement]]\ndisplacement = [1e31, 0, 0]\ntags = [1]\n",
            &["constraints.displacement[0].displacement", "1e30"],
        ),
    ] {
        write(p, "s.toml", &format!("{STATIC}{text}"));
        for n in needles {
            expect_bad(&["s.toml", "m.vtk", "-q"], p, n);
        }
    }
    // A tag that does select vertices is fine.
    write(
        p,
        "s.toml",
        &format!("{STATIC}[constraints]\nfix_tags = [1]\n"),
    );
    let r = run(&["s.toml", "m.vtk", "--out", "ok", "-q"], p);
    assert_eq!(r.code, 0, "{}", r.stderr);
}

/// A restart frame whose faces have collapsed (all vertices at one point) is bad input, named
/// by face, before anything is written.
#[test]
fn collapsed_restart_frames_are_bad_input() {
    let d = tmp();
    let p = d.path();
    write(p, "m.vtk", TWO_TRIANGLES);
    let text = TWO_TRIANGLES.replacen(
        "0 0 0\n1 0 0\n1 1 0\n0 1 0\n",
        "0.5 0.5 0\n0.5 0.5 0\n0.5 0.5 0\n0.5 0.5 0\n",
        1,
    );
    assert_ne!(text, TWO_TRIANGLES);
    write(p, "c.vtk", &text);
    write(p, "s.toml", STATIC);
    let r = run(
        &["s.toml", "m.vtk", "--out", "o", "-q", "--restart", "c.vtk"],
        p,
    );
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(
        r.stderr.contains("face 0") && r.stderr.contains("collapsed"),
        "{}",
        r.stderr
    );
    assert_eq!(frames(&p.join("o")), 0);
}

/// SIGINT or SIGTERM ends a run cleanly: the step under way finishes, the state reached is the
/// last frame, the log and the series list every frame, `summary.json` says "interrupted", no
/// temporary file or lock is left, and the exit code is 128 + the signal. A second signal
/// exits at once.
#[test]
fn signals_stop_runs_cleanly() {
    let d = tmp();
    let p = d.path();
    strip_mesh(p, "1", "1", "0.05", "m.vtk");
    let long = "[material]\nthickness = 0.05\n[loads]\ngravity = [0.0, 0.0, -9.81]\n[constraints]\nfix_boxes = [{ min = [-1.0, -1.0, -1.0], max = [-0.45, 1.0, 1.0] }]\n\
                [solver]\nmode = \"dynamic\"\n[time]\nend = 1000.0\ndt = 0.001\ndt_max = 0.001\noutput_interval = 0.01\n";
    write(p, "long.toml", long);
    for (sig, code, twice) in [
        ("INT", 130, false),
        ("TERM", 143, false),
        ("TERM", 143, true),
    ] {
        let out = format!("o_{sig}_{twice}");
        let mut child = bin()
            .args(["long.toml", "m.vtk", "--out", &out, "-q"])
            .current_dir(p)
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        let dir = p.join(&out);
        let t0 = std::time::Instant::now();
        while frames(&dir) < 3 {
            assert!(t0.elapsed().as_secs() < 60, "no frames after 60 s");
            std::thread::sleep(std::time::Duration::from_millis(20));
        }
        let pid = child.id() as libc::pid_t;
        let kill = |s: &str| {
            let sig = if s == "INT" {
                libc::SIGINT
            } else {
                libc::SIGTERM
            };
            // SAFETY: a plain kill(2) of our own child process.
            assert_eq!(unsafe { libc::kill(pid, sig) }, 0);
        };
        kill(sig);
        if twice {
            kill(sig);
        }
        let status = child.wait().unwrap();
        assert_eq!(status.code(), Some(code), "SIG{sig} twice: {twice}");
        assert!(
            !dir.join(".shellsim.lock").exists() || twice,
            "the lock is released"
        );
        if twice {
            continue;
        }
        let s = summary_of(p, &out);
        assert_eq!(s["converged"], false);
        let reason = s["reason"].as_str().unwrap();
        assert!(
            reason.starts_with(&format!("interrupted by SIG{sig} at t ")),
            "{reason}"
        );
        let n = frames(&dir);
        let series = std::fs::read_to_string(dir.join("series.pvd")).unwrap();
        assert_eq!(
            series.matches("<DataSet").count(),
            n,
            "series and frames in step"
        );
        let log = std::fs::read_to_string(dir.join("log.csv")).unwrap();
        assert_eq!(log.lines().count(), n + 1, "log and frames in step");
        assert!(dir.join(s["final_frame"].as_str().unwrap()).exists());
        let tmp_left = std::fs::read_dir(&dir)
            .unwrap()
            .filter(|e| {
                e.as_ref()
                    .unwrap()
                    .file_name()
                    .to_string_lossy()
                    .ends_with(".tmp")
            })
            .count();
        assert_eq!(tmp_left, 0);
    }
}

/// `shellsim error` measures only finite frames: one with a NaN is bad input (exit 2).
#[test]
fn error_command_refuses_non_finite_frames() {
    let d = tmp();
    let p = d.path();
    let r = run(
        &[
            "mesh",
            "square",
            "--edge",
            "0.5",
            "--program",
            "cylinder",
            "-o",
            "m.vtk",
        ],
        p,
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    write(
        p,
        "s.toml",
        "[rest]\ntarget = \"mesh\"\n[output]\nformat = \"vtk_ascii\"\n",
    );
    let r = run(&["s.toml", "m.vtk", "--out", "a", "-q"], p);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let frame = final_frame(p, "a");
    let text = std::fs::read_to_string(p.join(&frame)).unwrap();
    let i = text.find("displacement 3").unwrap();
    let start = i + text[i..].find('\n').unwrap() + 1;
    let end = start + text[start..].find(' ').unwrap();
    let bad = format!("{}nan{}", &text[..start], &text[end..]);
    write(p, "bad.vtk", &bad);
    let r = run(&["error", "cylinder", "bad.vtk"], p);
    assert_eq!(r.code, 2, "{}", r.stdout);
    assert!(
        r.stderr.contains("displacement") && r.stderr.contains("non-finite"),
        "{}",
        r.stderr
    );
}

/// A reference mesh folded flat onto itself (two faces with opposite normals across an edge)
/// has no mid-edge normal there: bad input naming the faces.
#[test]
fn folded_reference_meshes_are_bad_input() {
    let d = tmp();
    let p = d.path();
    let folded = "# vtk DataFile Version 3.0\nfold\nASCII\nDATASET POLYDATA\nPOINTS 4 double\n0 0 0 1 0 0 0 1 0 0.5 0.2 0\nPOLYGONS 2 8\n3 0 1 2\n3 0 2 3\n";
    write(p, "f.vtk", folded);
    write(p, "s.toml", "[material]\nthickness = 0.01\n");
    expect_bad(&["s.toml", "f.vtk", "-q"], p, "faces 0 and 1 are folded");
}

/// Restart velocities whose kinetic energy overflows are bad input, naming the vertex.
#[test]
fn huge_restart_velocities_are_bad_input() {
    let d = tmp();
    let p = d.path();
    write(p, "m.vtk", TWO_TRIANGLES);
    let dynamic = "[material]\nthickness = 0.05\n[solver]\nmode = \"dynamic\"\n[time]\nend = 0.02\ndt = 0.01\noutput_interval = 0.01\n[output]\nformat = \"vtk_ascii\"\n";
    write(p, "d.toml", dynamic);
    let r = run(&["d.toml", "m.vtk", "--out", "a", "-q"], p);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let text = std::fs::read_to_string(p.join("a/frame_00001.vtk")).unwrap();
    let i = text.find("velocity 3").unwrap();
    let start = i + text[i..].find('\n').unwrap() + 1;
    let end = start + text[start..].find(' ').unwrap();
    write(
        p,
        "a/fast.vtk",
        &format!("{}1e300{}", &text[..start], &text[end..]),
    );
    let r = run(
        &[
            "d.toml",
            "m.vtk",
            "--out",
            "b",
            "-q",
            "--restart",
            "a/fast.vtk",
        ],
        p,
    );
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(
        r.stderr.contains("'velocity' at vertex 0 is 1e300"),
        "{}",
        r.stderr
    );
    assert_eq!(frames(&p.join("b")), 0);
}

/// The README's first screen: its example command (everything after `cargo run --release --`)
/// runs to convergence from the repository's files, the caption's `render` command draws its
/// frame, and its test command is the line `.ci/run` runs.
#[test]
fn readme_commands_work() {
    // The README's two commands, in its order, in a fresh clone: the example scene (with the
    // built binary for `cargo run --release --`), then its caption's `render`, then the test
    // command must be the one `.ci/run` runs and must exist. Everything runs inside the clone,
    // so an `out/` left in the working copy by the first command cannot change what is read.
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    assert!(
        root.join(".git").exists(),
        "this test clones the repository: run it in a git checkout"
    );
    let dir = tmp();
    let clone = dir.path().join("shellsim");
    let status = Command::new("git")
        .args(["clone", "--quiet", "--no-hardlinks"])
        .arg(&root)
        .arg(&clone)
        .status()
        .expect("git runs");
    assert!(status.success(), "git clone {}", root.display());
    let readme = std::fs::read_to_string(clone.join("README.md")).unwrap();
    let block = readme
        .split("```sh\n")
        .nth(1)
        .and_then(|b| b.split("```").next())
        .expect("README has a sh block");
    let lines: Vec<&str> = block
        .lines()
        .map(|l| l.split(" # ").next().unwrap().trim())
        .collect();
    assert_eq!(lines.len(), 2, "README's first block: {block}");
    let example = lines[0]
        .strip_prefix("cargo run --release -- ")
        .expect("the example is `cargo run --release -- …`");
    let args: Vec<&str> = example.split_whitespace().collect();
    let r = run(&args, &clone);
    assert_eq!(r.code, 0, "{example}: {}", r.stderr);
    let out = args[args.iter().position(|a| *a == "--out").unwrap() + 1];
    assert!(clone.join(out).join("series.pvd").exists());

    let caption = readme
        .split("`shellsim render ")
        .nth(1)
        .and_then(|c| c.split('`').next())
        .expect("the caption's render command");
    let mut render = vec!["render"];
    render.extend(caption.split_whitespace());
    render.extend(["-o", "picture.png"]);
    let r = run(&render, &clone);
    assert_eq!(r.code, 0, "render {caption}: {}", r.stderr);
    let png = std::fs::read(clone.join("picture.png")).unwrap();
    assert_eq!(&png[1..4], b"PNG");

    // The run command's output is ignored by git, so the test command still sees a clean tree.
    let status = Command::new("git")
        .args(["status", "--porcelain", "--untracked-files=all"])
        .current_dir(&clone)
        .output()
        .unwrap();
    let dirty: Vec<&str> = std::str::from_utf8(&status.stdout)
        .unwrap()
        .lines()
        .filter(|l| !l.ends_with("picture.png"))
        .collect();
    assert!(dirty.is_empty(), "the README's run leaves {dirty:?}");

    let test = lines[1];
    let script = test.split_whitespace().next().unwrap();
    assert!(clone.join(script).is_file(), "{script} is missing");
    let ci = std::fs::read_to_string(clone.join(".ci/run")).unwrap();
    assert!(
        ci.lines().any(|l| l.trim() == test),
        ".ci/run does not run the README's test command `{test}`"
    );
}

/// Positions and velocities of frame `k` in `dir`, exactly as written.
fn frame_state(dir: &Path, k: usize) -> (Vec<[f64; 3]>, Vec<f64>) {
    let m = shellsim::mesh::io::read_mesh(&dir.join(format!("frame_{k:05}.vtu")))
        .unwrap_or_else(|e| panic!("{}: frame {k}: {e:#}", dir.display()));
    let v = m
        .vertex_fields
        .get("velocity")
        .map(|f| f.data.clone())
        .unwrap_or_default();
    (m.positions.iter().map(|p| [p.x, p.y, p.z]).collect(), v)
}

/// A run of `scene` restarted from frame `k` of the uninterrupted run, and the same run stopped
/// at `stop` and continued in its folder with `--continue`, take the uninterrupted run's steps:
/// every later frame has the same positions and velocities to the bit, and the continued
/// series numbers its frames on, with `log.csv` and `run.json` extended.
fn restart_is_exact(scene: &str, mesh: &str, sets: &[&str], k: usize, stop: &str) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let d = tmp();
    let p = d.path();
    let settings = root.join("settings").join(scene).display().to_string();
    let mesh = root.join("meshes").join(mesh).display().to_string();
    let go = |out: &str, extra: &[&str]| {
        let mut args = vec![settings.as_str(), mesh.as_str(), "--out", out, "-q"];
        for s in sets {
            args.extend(["--set", s]);
        }
        args.extend(extra);
        let r = run(&args, p);
        assert_eq!(r.code, 0, "{scene} {extra:?}: {}", r.stderr);
    };
    go("full", &[]);
    let n = frames(&p.join("full"));
    assert!(n > k + 2, "{scene}: {n} frames");
    let from = format!("full/frame_{k:05}.vtu");
    go("re", &["--restart", &from]);
    for j in 1..n - k {
        assert!(
            frame_state(&p.join("full"), k + j) == frame_state(&p.join("re"), j),
            "{scene}: frame {} of the restart differs from frame {} of the whole run",
            j,
            k + j
        );
    }
    let end = format!("time.end={stop}");
    go("c", &["--set", &end]);
    let first = frames(&p.join("c"));
    assert!(
        first > 1 && first < n,
        "{scene}: stopped with {first} frames"
    );
    go("c", &["--continue"]);
    assert_eq!(frames(&p.join("c")), n, "{scene}: the continued series");
    for j in 0..n {
        assert!(
            frame_state(&p.join("full"), j) == frame_state(&p.join("c"), j),
            "{scene}: frame {j} of the continued series differs from the whole run's"
        );
    }
    let strip = |t: String| -> Vec<String> {
        t.lines()
            .map(|l| l.rsplit_once(',').map_or(l, |(a, _)| a).to_string())
            .collect()
    };
    let log = |o: &str| strip(std::fs::read_to_string(p.join(o).join("log.csv")).unwrap());
    assert_eq!(log("full"), log("c"), "{scene}: log.csv without wall times");
    let (sf, sc) = (summary_of(p, "full"), summary_of(p, "c"));
    for key in [
        "steps",
        "newton_iterations",
        "rejected_steps",
        "frames",
        "final_frame",
    ] {
        assert_eq!(sf[key], sc[key], "{scene}: summary {key}");
    }
    let runs: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(p.join("c/run.json")).unwrap()).unwrap();
    let runs = runs["runs"].as_array().unwrap();
    assert_eq!(runs.len(), 2);
    assert_eq!(runs[1]["frames"].as_u64().unwrap() as usize, n - first);
    assert!(runs[1]["restart"]["path"]
        .as_str()
        .unwrap()
        .ends_with(&format!("frame_{:05}.vtu", first - 1)));
}

#[test]
fn restart_follows_the_uninterrupted_dynamic_run_exactly() {
    // Adaptive implicit Euler with damping and a dial: the step control is carried over.
    restart_is_exact("dynamic_cylinder.toml", "strip.vtk", &[], 7, "0.5");
}

#[test]
fn restart_follows_the_uninterrupted_moisture_run_exactly() {
    // The diffusion's nodal moisture and its sub-step control are carried over.
    restart_is_exact(
        "paper_strip_md.toml",
        "paper_strip.vtk",
        &["time.end=0.6"],
        2,
        // The third output time, 3 × 0.1 in floating point: the stopped run's last step lands
        // where the uninterrupted run's does.
        "0.30000000000000004",
    );
}

#[test]
fn restart_follows_the_uninterrupted_heated_spoon_exactly() {
    // The conduction's nodal temperatures, the highest each has reached and its sub-step
    // control are carried over; the run crosses the end of the heat gun's window.
    restart_is_exact("spoon_heated.toml", "spoon.vtk", &["time.end=50"], 3, "25");
}

#[test]
fn restart_follows_the_uninterrupted_balloon_run_exactly() {
    // An enclosed gas with the prism element's tracked thickness, in dynamics.
    restart_is_exact(
        "balloon_teddy.toml",
        "balloon_teddy.vtk",
        &["time.end=0.4"],
        1,
        "0.2",
    );
}

/// The run folder says what made it: the command line, the overrides, the settings and mesh
/// with their SHA-256, the version and commit, the threads and times in `run.json`, and the
/// resolved settings, which run the same scene again.
#[test]
fn run_folders_record_what_made_them() {
    let d = tmp();
    let p = d.path();
    let mesh = write(p, "m.vtk", TWO_TRIANGLES);
    write(p, "s.toml", STATIC);
    let r = run(
        &[
            "s.toml",
            "m.vtk",
            "--out",
            "o",
            "--set",
            "material.thickness=0.02",
            "--threads",
            "1",
        ],
        p,
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    let runs: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(p.join("o/run.json")).unwrap()).unwrap();
    let run0 = &runs["runs"][0];
    assert_eq!(run0["overrides"][0], "material.thickness=0.02");
    assert_eq!(run0["threads"], 1);
    assert_eq!(run0["status"], "converged");
    assert_eq!(run0["exit_code"], 0);
    assert_eq!(run0["shellsim_version"], env!("CARGO_PKG_VERSION"));
    assert!(!run0["commit"].as_str().unwrap().is_empty());
    assert!(run0["command_line"]
        .as_array()
        .unwrap()
        .iter()
        .any(|a| a == "material.thickness=0.02"));
    let sha = shellsim::provenance::sha256_hex(&std::fs::read(&mesh).unwrap());
    assert_eq!(run0["mesh"]["sha256"], sha.as_str());
    assert_eq!(sha.len(), 64);
    for key in ["started", "ended"] {
        assert!(run0[key].as_str().unwrap().ends_with('Z'), "{key}: {run0}");
    }
    // The resolved settings carry the override and every default, and run the same scene.
    let resolved = std::fs::read_to_string(p.join("o/settings.resolved.toml")).unwrap();
    assert!(resolved.contains("thickness = 0.02"), "{resolved}");
    let r = run(
        &["o/settings.resolved.toml", "m.vtk", "--out", "again", "-q"],
        p,
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert_eq!(
        std::fs::read(p.join("o/frame_00001.vtu")).unwrap(),
        std::fs::read(p.join("again/frame_00001.vtu")).unwrap(),
        "the resolved settings give the same frame"
    );
    // ParaView names the tensor components.
    let raw = std::fs::read(p.join("o/frame_00001.vtu")).unwrap();
    let raw = String::from_utf8_lossy(&raw);
    assert!(
        raw.contains(
            "Name=\"abar\" NumberOfComponents=\"3\" ComponentName0=\"xx\" \
             ComponentName1=\"xy\" ComponentName2=\"yy\""
        ),
        "component names"
    );
    // --overwrite removes the provenance with the rest of the earlier run.
    let r = run(&["s.toml", "m.vtk", "--out", "o", "--overwrite", "-q"], p);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let runs: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(p.join("o/run.json")).unwrap()).unwrap();
    assert_eq!(runs["runs"].as_array().unwrap().len(), 1);
    assert_eq!(runs["runs"][0]["overrides"].as_array().unwrap().len(), 0);
}

/// Outside a terminal a run still says when it starts and how it ended, on stderr; `-q`
/// silences both; `-v` prints every step with its time or dial.
#[test]
fn runs_talk_outside_a_terminal() {
    let d = tmp();
    let p = d.path();
    write(p, "m.vtk", TWO_TRIANGLES);
    write(p, "s.toml", STATIC);
    let r = run(&["s.toml", "m.vtk", "--out", "o"], p);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let lines: Vec<&str> = r.stderr.lines().collect();
    assert!(
        lines
            .first()
            .is_some_and(|l| l.starts_with("shellsim: static run of s.toml on m.vtk")),
        "{}",
        r.stderr
    );
    assert!(
        lines
            .last()
            .is_some_and(|l| l.starts_with("shellsim: converged at dial 1 in ")
                && l.ends_with("2 frames in o")),
        "{}",
        r.stderr
    );
    let r = run(&["s.toml", "m.vtk", "--out", "q", "-q"], p);
    assert_eq!((r.code, r.stderr.as_str()), (0, ""));
    let r = run(&["s.toml", "m.vtk", "--out", "v", "-v"], p);
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(
        r.stderr
            .lines()
            .any(|l| l.starts_with("continuation  dial ")),
        "{}",
        r.stderr
    );
    assert!(r.stderr.contains("newton "), "{}", r.stderr);
}

/// A static run's progress is the dial: `log.csv` has no time column, `summary.json` no time,
/// and the series' times are the dials, the last frame of a failed run included.
#[test]
fn static_runs_report_the_dial() {
    let d = tmp();
    let p = d.path();
    write(p, "m.vtk", TWO_TRIANGLES);
    write(p, "s.toml", STATIC);
    let r = run(&["s.toml", "m.vtk", "--out", "o", "-q"], p);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let log = std::fs::read_to_string(p.join("o/log.csv")).unwrap();
    assert!(log.starts_with("frame,dial,"), "{log}");
    let s = summary_of(p, "o");
    assert!(s.get("time").is_none(), "{s}");
    assert_eq!(s["dial"], 1.0);
    // `plot` draws a static run against its dial.
    let r = run(&["plot", "o", "-o", "p.png"], p);
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(p.join("p.png").exists());
    // A run that fails part-way (two Newton iterations allowed per step, no membrane
    // continuation: it stops at dial 1/64 on the GCM cone): its last row, its last series
    // entry and the summary agree on the dial.
    let (settings, mesh) = gcm_cone_scene();
    let r = run(
        &[
            &settings,
            &mesh,
            "--out",
            "f",
            "-q",
            "--set",
            "solver.max_newton_iterations=2",
            "--set",
            "solver.membrane_continuation=1",
            "--set",
            "solver.min_continuation_step=0.01",
        ],
        p,
    );
    assert_eq!(r.code, 1, "{}", r.stderr);
    let s = summary_of(p, "f");
    let dial = s["dial"].as_f64().unwrap();
    assert!(dial > 0.0 && dial < 1.0, "{s}");
    let log = std::fs::read_to_string(p.join("f/log.csv")).unwrap();
    let last: f64 = log
        .lines()
        .last()
        .unwrap()
        .split(',')
        .nth(1)
        .unwrap()
        .parse()
        .unwrap();
    assert_eq!(last, dial, "{log}");
    let series = shellsim::output::series_entries(&p.join("f/series.pvd")).unwrap();
    assert_eq!(series.last().unwrap().0, dial);
}

/// The repository's GCM cone scene: its settings file and its jittered 842-face mesh.
fn gcm_cone_scene() -> (String, String) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let path = |rel: &str| root.join(rel).display().to_string();
    (
        path("settings/gcm_cone.toml"),
        path("meshes/gcm_cone_jittered.vtk"),
    )
}

/// The membrane continuation goes straight to the true stretching weight once a raised weight
/// needed no Newton iteration (the membrane is at its rest metric: the programmed cone is
/// isometric to the flat sheet), and the cone it ends on is the exact one to the mesh's error.
#[test]
fn membrane_continuation_ends_after_a_raise_that_needs_no_iteration() {
    let d = tmp();
    let p = d.path();
    let (settings, mesh) = gcm_cone_scene();
    let r = run(&[&settings, &mesh, "--out", "o", "-v"], p);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let lines: Vec<&str> = r.stderr.lines().collect();
    let steps: Vec<usize> = (0..lines.len())
        .filter(|&i| lines[i].starts_with("continuation"))
        .collect();
    // The first continuation step at dial 1 whose solve converged at its first evaluation.
    let free = steps
        .iter()
        .position(|&i| i > 0 && lines[i - 1].starts_with("newton   0:"))
        .unwrap_or_else(|| panic!("no raise without iterations: {}", r.stderr));
    assert_eq!(free + 2, steps.len(), "{}", r.stderr);
    let e = run(&["error", "gcm_cone", "o/frame_00001.vtu"], p);
    assert_eq!(e.code, 0, "{}", e.stderr);
    let v: serde_json::Value = serde_json::from_str(&e.stdout).unwrap();
    let rel = v["rms_error_rel"].as_f64().unwrap();
    assert!(rel < 2e-4, "{v}");
}

/// Frames keep the input's corner order even where the scene starts a sliver at a wider
/// corner, with the per-corner `edge_angles` in that order too, and a restart reads them back.
#[test]
fn frames_keep_the_input_corner_order() {
    let d = tmp();
    let p = d.path();
    let r = run(
        &[
            "mesh",
            "disk",
            "--radius",
            "1",
            "--edge",
            "0.15",
            "--jitter",
            "0.3",
            "--seed",
            "3",
            "--program",
            "spherical_cap",
            "-o",
            "disk.vtk",
        ],
        p,
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    let input = shellsim::mesh::io::read_mesh(&p.join("disk.vtk")).unwrap();
    let mut anchored = input.clone();
    let shifted = anchored
        .anchor_faces_at_wide_angles()
        .iter()
        .filter(|&&k| k != 0)
        .count();
    assert!(
        shifted > 0,
        "the jittered disk needs some faces started elsewhere"
    );
    write(
        p,
        "s.toml",
        "[material]\nthickness = 0.01\n[rest]\ntarget = \"mesh\"\n",
    );
    let r = run(&["s.toml", "disk.vtk", "--out", "o", "-q"], p);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let last = final_frame(p, "o");
    let frame = shellsim::mesh::io::read_mesh(&p.join(&last)).unwrap();
    assert_eq!(
        frame.faces, input.faces,
        "{shifted} faces start at another corner"
    );
    // Each edge's angle appears in both its faces at the slots of the input's order.
    let topo = shellsim::mesh::Topology::build(&input).unwrap();
    let ea = &frame.face_fields["edge_angles"];
    assert!(
        ea.data.iter().any(|&v| v.abs() > 1e-6),
        "a curved cap has edge angles to compare"
    );
    for (f, fe) in topo.face_edges.iter().enumerate() {
        for (i, &e) in fe.iter().enumerate() {
            let other = topo.edge_faces[e]
                .iter()
                .copied()
                .find(|&g| g != f && g < input.faces.len());
            if let Some(g) = other {
                let j = topo.face_edges[g].iter().position(|&x| x == e).unwrap();
                assert_eq!(ea.get(f)[i], ea.get(g)[j], "edge {e} at faces {f} and {g}");
            }
        }
    }
    let r = run(
        &[
            "s.toml",
            "disk.vtk",
            "--out",
            "re",
            "-q",
            "--restart",
            &last,
        ],
        p,
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
}

/// `shellsim mesh` with arguments that would make an impossible mesh (a tiny, zero, negative,
/// NaN or infinite edge, a huge shape, a count beyond the 10⁷-face bound) is exit 2 naming the
/// argument, for every shape, planar and Delaunay: never a panic or an abort on allocation, and
/// nothing written.
#[test]
fn mesh_arguments_beyond_the_bound_are_refused() {
    let d = tmp();
    let p = d.path();
    let shapes: &[(&str, &[&str], &str)] = &[
        ("square", &[], "--size"),
        ("square", &["--delaunay"], "--size"),
        ("rectangle", &[], "--lx"),
        ("rectangle", &["--delaunay"], "--lx"),
        ("disk", &[], "--radius"),
        ("annulus", &[], "--radius"),
        ("annulus", &["--delaunay"], "--radius"),
        ("annulus", &["--delaunay", "--sweep", "90"], "--radius"),
        ("sphere", &[], "--radius"),
        ("capsule", &[], "--radius"),
        ("peanut", &[], "--radius"),
        ("teddy", &[], "--radius"),
        ("torus", &[], "--radius"),
    ];
    for &(shape, extra, size) in shapes {
        let cases: Vec<(Vec<&str>, &str)> = vec![
            (vec!["--edge", "1e-300"], "--edge"),
            (vec!["--edge", "1e-5"], "more than the 1e7"),
            (vec!["--edge", "0"], "--edge"),
            (vec!["--edge", "-1"], "--edge"),
            (vec!["--edge", "NaN"], "--edge"),
            (vec!["--edge", "inf"], "--edge"),
            (vec!["--edge", "0.1", size, "1e300"], size),
            (vec!["--edge", "0.1", size, "1e12"], size),
            (vec!["--edge", "0.1", size, "inf"], size),
        ];
        for (args, needle) in cases {
            let mut a = vec!["mesh", shape, "-o", "m.vtk"];
            a.extend_from_slice(extra);
            a.extend_from_slice(&args);
            let r = run(&a, p);
            let what = format!("{}: {}", a.join(" "), r.stderr);
            assert_eq!(r.code, 2, "{what}");
            assert!(r.stderr.contains(needle), "{needle} not named: {what}");
            assert!(!r.stderr.contains("panicked"), "{what}");
            assert!(!p.join("m.vtk").exists(), "written: {what}");
        }
    }
    // The bound's message gives the count.
    let r = run(&["mesh", "square", "--edge", "1e-300", "-o", "m.vtk"], p);
    assert!(
        r.stderr.contains(
            "--edge and --size would make uncountably many (beyond floating point) faces"
        ),
        "{}",
        r.stderr
    );
    let r = run(&["mesh", "square", "--edge", "1e-5", "-o", "m.vtk"], p);
    assert!(
        r.stderr
            .contains("--edge and --size would make about 2e10 faces, more than the 1e7"),
        "{}",
        r.stderr
    );
}

/// A mesh field shellsim does not read (a misspelt name) is warned about, one line per field,
/// naming it and the fields that are read; the run goes on. The fields of shellsim's own frames
/// are not warned about, whether a frame is the mesh or the restart.
#[test]
fn unknown_mesh_fields_warn() {
    let d = tmp();
    let p = d.path();
    let text = TWO_TRIANGLES
        .replace("FIELD FieldData 5", "FIELD FieldData 6")
        .replace(
            "tri_tags 1 2 int\n0 1\n",
            "tri_tags 1 2 int\n0 1\nref_thicknes 1 2 double\n0.1 0.1\n",
        )
        .replace("FIELD FieldData 2\n", "FIELD FieldData 3\n")
        .replace(
            "node_tags 1 4 int\n0 0 1 1\n",
            "node_tags 1 4 int\n0 0 1 1\nconstraint_indicator 1 4 int\n1 1 0 0\n",
        );
    write(p, "m.vtk", &text);
    write(
        p,
        "s.toml",
        &format!("{STATIC}[output]\nmorphoshell_fields = true\n"),
    );
    let r = run(&["s.toml", "m.vtk", "--out", "o", "-q"], p);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let lines: Vec<&str> = r
        .stderr
        .lines()
        .filter(|l| l.contains("is not one shellsim reads"))
        .collect();
    assert_eq!(lines.len(), 2, "{}", r.stderr);
    assert!(
        lines[0].starts_with("warning: m.vtk: face field 'ref_thicknes'")
            && lines[0].contains("ref_thicknesses, ref_shear_moduli"),
        "{}",
        lines[0]
    );
    assert!(
        lines[1].starts_with("warning: m.vtk: vertex field 'constraint_indicator'")
            && lines[1].contains("constraint_indicators, node_tags"),
        "{}",
        lines[1]
    );
    // A frame as the mesh, and as the restart (static and dynamic frames).
    let frame = final_frame(p, "o");
    write(p, "plain.toml", "[solver]\nmode = \"static\"\n");
    let r = run(&["plain.toml", &frame, "--out", "f", "-q"], p);
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(!r.stderr.contains("warning"), "{}", r.stderr);
    write(p, "dyn.toml", "[solver]\nmode = \"dynamic\"\n[time]\nend = 0.001\ndt = 0.001\n[output]\nmorphoshell_fields = true\n");
    let r = run(&["dyn.toml", "m.vtk", "--out", "g", "-q"], p);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let frame = final_frame(p, "g");
    for args in [
        vec!["dyn.toml", &frame, "--out", "h", "-q"],
        vec!["dyn.toml", "m.vtk", "--out", "i", "-q", "--restart", &frame],
    ] {
        let r = run(&args, p);
        assert_eq!(r.code, 0, "{}", r.stderr);
        let unknown = r
            .stderr
            .lines()
            .filter(|l| l.contains("is not one shellsim reads"));
        // The restart's mesh is m.vtk, whose two fields warn as before; the frame adds none.
        let expected = if args.contains(&"--restart") { 2 } else { 0 };
        assert_eq!(unknown.count(), expected, "{}", r.stderr);
    }
}

/// An explicit run with a pressed glass slide, restarted from one of its frames, takes the
/// uninterrupted run's steps: its time, dial, equilibrium windows, frame times and the slide's
/// height and speed come back from the frame's state, and every later frame is the same to the
/// bit.
#[test]
fn restart_follows_the_uninterrupted_explicit_run_exactly() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let d = tmp();
    let p = d.path();
    let settings = root
        .join("settings/cone_squeezed.toml")
        .display()
        .to_string();
    let mesh = root.join("meshes/squeeze_disk.vtk").display().to_string();
    let r = run(&[&settings, &mesh, "--out", "full", "-q"], p);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let n = frames(&p.join("full"));
    assert!(n > 6, "{n} frames");
    let k = n / 2;
    let from = format!("full/frame_{k:05}.vtu");
    let r = run(
        &[&settings, &mesh, "--out", "re", "-q", "--restart", &from],
        p,
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert_eq!(frames(&p.join("re")), n - k);
    for j in 1..n - k {
        assert!(
            frame_state(&p.join("full"), k + j) == frame_state(&p.join("re"), j),
            "frame {j} of the restart differs from frame {} of the whole run",
            k + j
        );
    }
    let log = |o: &str| std::fs::read_to_string(p.join(o).join("log.csv")).unwrap();
    let slide = |o: &str| -> Vec<String> {
        let text = log(o);
        let mut lines = text.lines();
        let head: Vec<&str> = lines.next().unwrap().split(',').collect();
        let c = head.iter().position(|h| *h == "slide_upper_z").unwrap();
        lines
            .map(|l| l.split(',').nth(c).unwrap().to_string())
            .collect()
    };
    assert_eq!(slide("full")[k..], slide("re")[..], "the slide's height");
}

/// A frame that cannot be written (here its temporary file's name is taken by a folder, as a
/// full disk would refuse it) stops the run with the frames, the series and the log in step
/// and a summary saying why; `--overwrite` then removes every file of that run, frames it wrote
/// under another `output.prefix` included.
#[test]
fn a_failed_write_leaves_the_folder_in_step() {
    let d = tmp();
    let p = d.path();
    write(p, "m.vtk", TWO_TRIANGLES);
    let dynamic = "[material]\nthickness = 0.05\n[solver]\nmode = \"dynamic\"\n[time]\nend = 0.1\ndt = 0.01\ndt_max = 0.01\noutput_interval = 0.01\n[output]\nprefix = \"step\"\n";
    write(p, "dyn.toml", dynamic);
    std::fs::create_dir_all(p.join("o/.step_00003.vtu.tmp")).unwrap();
    let r = run(&["dyn.toml", "m.vtk", "--out", "o", "-q"], p);
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(r.stderr.contains("step_00003.vtu"), "{}", r.stderr);
    let o = p.join("o");
    let listed = shellsim::output::series_entries(&o.join("series.pvd")).unwrap();
    assert_eq!(listed.len(), 3, "{listed:?}");
    for (k, (_, f)) in listed.iter().enumerate() {
        assert_eq!(f, &format!("step_{k:05}.vtu"));
        assert!(o.join(f).exists());
    }
    assert!(!o.join("step_00003.vtu").exists());
    assert!(!o.join("step_00003.state.json").exists());
    let log = std::fs::read_to_string(o.join("log.csv")).unwrap();
    assert_eq!(log.lines().count(), 4, "{log}");
    let s = summary_of(p, "o");
    assert_eq!(s["converged"], false);
    assert!(
        s["reason"].as_str().unwrap().starts_with("output failed"),
        "{s}"
    );
    assert!(!o.join(".shellsim.reserve").exists());
    // The default prefix now: --overwrite removes the `step_*` frames too.
    std::fs::remove_dir(o.join(".step_00003.vtu.tmp")).unwrap();
    let plain = dynamic.replace("[output]\nprefix = \"step\"\n", "");
    write(p, "plain.toml", &plain);
    let r = run(
        &["plain.toml", "m.vtk", "--out", "o", "-q", "--overwrite"],
        p,
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    let left: Vec<String> = std::fs::read_dir(&o)
        .unwrap()
        .filter_map(|e| e.ok()?.file_name().to_str().map(String::from))
        .filter(|n| n.starts_with("step_"))
        .collect();
    assert!(left.is_empty(), "{left:?}");
}

/// Every registered membrane material × bending model, and every registered rest-form law (each
/// with its own example keys), restarts exactly: a dynamic run of a strip clamped at one end
/// under gravity, restarted from its first frame, ends on the bits of the uninterrupted run,
/// positions and edge angles alike. A new material, bending model or law is checked without
/// being listed here.
#[test]
fn every_registered_model_and_law_restarts_exactly() {
    use shellsim::energy::registry::{BENDINGS, MATERIALS};
    use shellsim::rest::laws::LAWS;
    let d = tmp();
    let p = d.path();
    let r = run(
        &[
            "mesh",
            "rectangle",
            "--lx",
            "1",
            "--ly",
            "0.3",
            "--edge",
            "0.1",
            "-o",
            "m.vtk",
        ],
        p,
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    // A law that relaxes toward a stored shape reads it from `original_positions`: here a
    // copy of the mesh raised by 1 mm (its forms equal the mesh's; other laws ignore the field).
    let mut m = shellsim::mesh::io::read_mesh(&p.join("m.vtk")).unwrap();
    let stored: Vec<f64> = m
        .positions
        .iter()
        .flat_map(|x| [x.x, x.y, x.z + 1e-3])
        .collect();
    m.vertex_fields.insert(
        "original_positions".into(),
        shellsim::mesh::Field {
            data: stored,
            components: 3,
        },
    );
    shellsim::mesh::io::write_mesh(&p.join("m.vtk"), &m, shellsim::mesh::io::Format::Vtk, "m")
        .unwrap();
    let mut cases: Vec<(String, String)> = Vec::new();
    for m in MATERIALS {
        for (_, bend) in BENDINGS {
            cases.push((
                format!("{:?} {bend}", m.model),
                format!("[material]\n{}\n{bend}\n", m.example),
            ));
        }
    }
    for e in LAWS {
        cases.push((
            e.law.name().to_string(),
            format!(
                "[material]\nyoung = 1e6\n[growth]\nlaw = \"{}\"\n{}\n",
                e.law.name(),
                e.example
            ),
        ));
    }
    for (k, (label, head)) in cases.iter().enumerate() {
        let settings = format!(
            "{head}[solver]\nmode = \"dynamic\"\n[time]\nend = 0.03\ndt = 0.005\n\
             output_interval = 0.01\n[loads]\ngravity = [0, 0, -9.81]\n[constraints]\n\
             fix_boxes = [{{ min = [-1, -1, -1], max = [0.01, 1, 1] }}]\n"
        )
        .replacen("[material]\n", "[material]\nthickness = 0.02\n", 1);
        let name = format!("c{k}.toml");
        write(p, &name, &settings);
        let (a, b) = (format!("a{k}"), format!("b{k}"));
        let r = run(&[&name, "m.vtk", "--out", &a, "-q"], p);
        assert_eq!(r.code, 0, "{label}: {}", r.stderr);
        let frame = format!("{a}/frame_00001.vtu");
        let r = run(&[&name, "m.vtk", "--out", &b, "-q", "--restart", &frame], p);
        assert_eq!(r.code, 0, "{label}: {}", r.stderr);
        let read = |f: String| shellsim::mesh::io::read_mesh(&p.join(f)).unwrap();
        let (x, y) = (
            read(format!("{a}/frame_00003.vtu")),
            read(format!("{b}/frame_00002.vtu")),
        );
        assert!(
            x.positions != read(format!("{a}/frame_00000.vtu")).positions,
            "{label}: nothing moved"
        );
        assert_eq!(
            x.positions, y.positions,
            "{label}: the restart moved the positions"
        );
        if let Some(e) = x.face_fields.get("edge_angles") {
            assert_eq!(
                Some(&e.data),
                y.face_fields.get("edge_angles").map(|f| &f.data),
                "{label}: the restart changed the edge angles"
            );
        }
    }
}

/// The help of `error CASE` and of `mesh --program` names every analytic case the commands
/// accept.
#[test]
fn help_lists_every_analytic_case() {
    let d = tmp();
    for args in [&["error", "--help"][..], &["mesh", "--help"][..]] {
        let r = run(args, d.path());
        assert_eq!(r.code, 0, "{}", r.stderr);
        for c in shellsim::cases::Case::ALL {
            assert!(r.stdout.contains(c.name()), "{args:?} omits {}", c.name());
        }
    }
}
