//! Hard numerical cases through the binary, at small sizes: large growth and shrinkage, extreme
//! thickness and stiffness, huge time steps, an inverted start and sliver triangles. Each run
//! must either converge (exit 0) with the right answer where one is known, or stop with exit 1
//! and a reason in `summary.json`. Never a panic (exit 101), never a non-finite value in a frame,
//! and never exit 0 with a wrong shape.

mod common;

use shellsim::mesh::io::{read_mesh, write_mesh, Format};
use shellsim::mesh::Mesh;
use std::path::Path;
use std::process::Command;

struct Outcome {
    code: i32,
    reason: String,
    last: Option<Mesh>,
}

/// Runs `shellsim settings mesh --out out` (plus `extra`) in `dir`, checks the exit code is 0
/// or 1, that summary.json exists with a reason on exit 1, and that every frame is finite.
fn run(dir: &Path, settings: &str, mesh: &str, out: &str, extra: &[&str]) -> Outcome {
    std::fs::write(dir.join(format!("{out}.toml")), settings).unwrap();
    let toml = format!("{out}.toml");
    let mut args = vec![toml.as_str(), mesh, "--out", out, "-q", "--overwrite"];
    args.extend_from_slice(extra);
    let o = Command::new(env!("CARGO_BIN_EXE_shellsim"))
        .args(&args)
        .current_dir(dir)
        .output()
        .unwrap();
    let code = o.status.code().unwrap_or(-1);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        code == 0 || code == 1,
        "{out}: exit {code} (0 or 1 expected): {stderr}"
    );
    let summary = std::fs::read_to_string(dir.join(out).join("summary.json")).unwrap();
    let json: serde_json::Value = serde_json::from_str(&summary).unwrap();
    let reason = json["reason"].as_str().unwrap_or("").to_string();
    assert_eq!(
        json["converged"].as_bool(),
        Some(code == 0),
        "{out}: {summary}"
    );
    if code == 1 {
        assert!(!reason.is_empty(), "{out}: exit 1 without a reason");
    }
    let last = common::finite_frames(&dir.join(out), "vtu", out).pop();
    println!("{out}: exit {code} {reason}");
    Outcome { code, reason, last }
}

fn square(dir: &Path, edge: &str, name: &str) {
    common::shellsim(&["mesh", "square", "--edge", edge, "-o", name], dir);
}

/// The largest distance between two vertices (the diagonal of a square).
fn diameter(m: &Mesh) -> f64 {
    let mut d: f64 = 0.0;
    for a in &m.positions {
        for b in &m.positions {
            d = d.max((a - b).norm());
        }
    }
    d
}

fn uniform(abar: f64, thickness: f64, extra: &str) -> String {
    format!(
        "[material]\nthickness = {thickness:e}\n{extra}\n[rest]\ntarget = \"uniform\"\n\
         abar = [{abar:e}, 0.0, {abar:e}]\nbbar = [0.0, 0.0, 0.0]\n"
    )
}

/// 4× growth and 4× shrinkage (ā = 16 I and I/16): the flat square scaled by 4 and by 1/4,
/// to 1e-6 of its size. Growth must converge. The shrinking sheet passes through compressed
/// states while the continuation dials ā down, and its symmetry-breaking perturbation lets it
/// wrinkle; it may stop with a reason (measured: a stalled line search at dial 0.93 with the
/// residual at 1e-6), but must not report a wrong size.
#[test]
fn large_growth_and_shrinkage() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    square(p, "0.25", "sq.vtk");
    let size = 2f64.sqrt();
    for (abar, scale, name) in [(16.0, 4.0, "grow"), (1.0 / 16.0, 0.25, "shrink")] {
        let o = run(p, &uniform(abar, 0.01, ""), "sq.vtk", name, &[]);
        if name == "grow" {
            assert_eq!(o.code, 0, "{name}: {}", o.reason);
        }
        if o.code != 0 {
            continue;
        }
        let got = diameter(o.last.as_ref().unwrap());
        assert!(
            (got / (scale * size) - 1.0).abs() < 1e-6,
            "{name}: diameter {got} vs {}",
            scale * size
        );
    }
}

/// A cylinder's curvature programmed on sheets of thickness 1e-6 and 0.5 of their size, and on
/// moduli 1 Pa and 1e12 Pa: each converges or stops with a reason; converged ones bend with
/// the programmed curvature's sign.
#[test]
fn extreme_thickness_and_stiffness() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    square(p, "0.25", "sq.vtk");
    let cyl = |h: f64, young: f64| {
        format!(
            "[material]\nthickness = {h:e}\nyoung = {young:e}\n[rest]\ntarget = \"uniform\"\n\
             abar = [1.0, 0.0, 1.0]\nbbar = [1.0, 0.0, 0.0]\n"
        )
    };
    for (h, young, name) in [
        (1e-6, 1e6, "thin"),
        (0.5, 1e6, "thick"),
        (0.01, 1.0, "soft"),
        (0.01, 1e12, "stiff"),
    ] {
        let o = run(p, &cyl(h, young), "sq.vtk", name, &[]);
        if o.code == 0 {
            let m = o.last.unwrap();
            let z: Vec<f64> = m.positions.iter().map(|q| q.z).collect();
            let span = z.iter().cloned().fold(f64::MIN, f64::max)
                - z.iter().cloned().fold(f64::MAX, f64::min);
            assert!(span > 0.05, "{name}: converged but flat (z span {span})");
        }
    }
}

/// Dynamics with time steps far beyond any time scale of the sheet (Δt = 1e3 s for a sheet
/// whose bending period is milliseconds), under gravity with a clamped edge.
#[test]
fn huge_time_steps() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    square(p, "0.25", "sq.vtk");
    let s = "[material]\nthickness = 0.01\n[solver]\nmode = \"dynamic\"\n[time]\nend = 1e4\n\
             dt = 1e3\ndt_max = 1e4\noutput_interval = 5e3\n[loads]\ngravity = [0.0, 0.0, -9.81]\n\
             [constraints]\nfix_boxes = [{ min = [-1.0, -1.0, -1.0], max = [-0.49, 1.0, 1.0] }]\n";
    run(p, s, "sq.vtk", "huge_dt", &[]);
}

/// A start with inverted triangles: a restart frame whose interior vertex is pushed across
/// its neighbours (its incident faces flipped). The run recovers or stops with a reason.
#[test]
fn inverted_start() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    square(p, "0.25", "sq.vtk");
    let s = "[material]\nthickness = 0.01\n[solver]\nmode = \"dynamic\"\n[time]\nend = 0.2\n\
             dt = 0.01\noutput_interval = 0.1\n";
    let first = run(p, s, "sq.vtk", "first", &[]);
    assert_eq!(first.code, 0, "{}", first.reason);
    let mut frame = read_mesh(&p.join("first/frame_00000.vtu")).unwrap();
    let centre = frame
        .positions
        .iter()
        .enumerate()
        .min_by(|a, b| a.1.norm().partial_cmp(&b.1.norm()).unwrap())
        .unwrap()
        .0;
    frame.positions[centre].x += 0.4;
    write_mesh(&p.join("inverted.vtu"), &frame, Format::Vtu, "inverted").unwrap();
    run(p, s, "sq.vtk", "inverted", &["--restart", "inverted.vtu"]);
}

/// Sliver triangles: a column of needles of width 1e-4 and 1e-8 (aspect 4e-4 and 4e-8) in a
/// square, at rest (ā = I, b̄ = 0) statically and dynamically, and a growth on them. Converged
/// runs must have kept the square flat and its size.
#[test]
fn sliver_triangles() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    for (w, name) in [(1e-4, "s4.vtk"), (1e-8, "s8.vtk")] {
        let xs = [0.0, 0.25, 0.5, 0.5 + w, 0.75, 1.0];
        let ys = [0.0, 0.25, 0.5, 0.75, 1.0];
        let mut text = format!(
            "# vtk DataFile Version 3.0\nsliver\nASCII\nDATASET POLYDATA\nPOINTS {} double\n",
            xs.len() * ys.len()
        );
        for y in ys {
            for x in xs {
                text += &format!("{x:e} {y:e} 0\n");
            }
        }
        let nx = xs.len();
        let mut tris = Vec::new();
        for j in 0..ys.len() - 1 {
            for i in 0..nx - 1 {
                let (a, b, c) = (j * nx + i, j * nx + i + 1, (j + 1) * nx + i);
                tris.push([a, b, c + 1]);
                tris.push([a, c + 1, c]);
            }
        }
        text += &format!("POLYGONS {} {}\n", tris.len(), 4 * tris.len());
        for t in &tris {
            text += &format!("3 {} {} {}\n", t[0], t[1], t[2]);
        }
        std::fs::write(p.join(name), text).unwrap();
        let rest = uniform(1.0, 0.01, "");
        let dynamic = format!(
            "{rest}[solver]\nmode = \"dynamic\"\n[time]\nend = 0.1\ndt = 0.01\noutput_interval = 0.05\n"
        );
        let grow = uniform(1.21, 0.01, "");
        for (s, tag, scale) in [
            (&rest, "static", 1.0),
            (&dynamic, "dynamic", 1.0),
            (&grow, "grow", 1.1),
        ] {
            let out = format!("{}_{tag}", &name[..2]);
            let o = run(p, s, name, &out, &[]);
            if o.code == 0 {
                let m = o.last.unwrap();
                let got = diameter(&m);
                assert!(
                    (got / (scale * 2f64.sqrt()) - 1.0).abs() < 1e-3,
                    "{out}: converged with diameter {got}"
                );
            }
        }
    }
}
