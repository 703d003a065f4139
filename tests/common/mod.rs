//! Helpers shared by the integration-test crates.

use std::path::Path;
use std::process::Command;

/// Runs the binary in `dir`, asserts success (with its stderr in the message) and returns its
/// stdout.
#[allow(dead_code)] // not every test crate runs the binary this way
pub fn shellsim(args: &[&str], dir: &Path) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_shellsim"))
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "shellsim {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// Runs the binary in `dir` and returns its exit code (−1 when killed by a signal), stdout and
/// stderr, whatever the outcome.
#[allow(dead_code)] // not every test crate checks failures
pub fn run_status(args: &[&str], dir: &Path) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_shellsim"))
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Reads `frame_00000.EXT`, `frame_00001.EXT`, … from the run folder `out` until one is
/// missing, asserting that every position and face field is finite (`label` names the run in
/// the messages).
#[allow(dead_code)] // not every test crate reads frames
pub fn finite_frames(out: &Path, ext: &str, label: &str) -> Vec<shellsim::mesh::Mesh> {
    let mut frames = Vec::new();
    for k in 0.. {
        let p = out.join(format!("frame_{k:05}.{ext}"));
        if !p.exists() {
            break;
        }
        let m = shellsim::mesh::io::read_mesh(&p)
            .unwrap_or_else(|e| panic!("{label}: frame {k}: {e:#}"));
        assert!(
            m.positions.iter().all(|p| p.iter().all(|v| v.is_finite())),
            "{label}: non-finite position in frame {k}"
        );
        for (name, f) in &m.face_fields {
            assert!(
                f.data.iter().all(|v| v.is_finite()),
                "{label}: non-finite {name} in frame {k}"
            );
        }
        frames.push(m);
    }
    frames
}

/// Writes `dir/name`: a cylinder patch of radius `r` about the y axis, angle `θ ∈ [t.0, t.1]`
/// (from +z towards +x) and `y ∈ [y.0, y.1]`, on an n × m grid of quads split along alternating
/// diagonals (mirror-symmetric about the grid's middle lines when n and m are even), points
/// `(r sin θ, y, r cos θ − drop)`, as legacy ASCII VTK.
#[allow(dead_code)] // not every test crate builds shells
pub fn cylinder_patch(
    dir: &Path,
    name: &str,
    r: f64,
    t: (f64, f64),
    y: (f64, f64),
    (n, m): (usize, usize),
    drop: f64,
) {
    graded_cylinder_patch(dir, name, r, t, y, (n, m), drop, 1.0);
}

/// As [`cylinder_patch`], the grid graded toward `(t.0, y.0)` when `gamma` is not 1: θ and y
/// vary as the `gamma`-th power of the grid coordinate.
#[allow(clippy::too_many_arguments, dead_code)]
pub fn graded_cylinder_patch(
    dir: &Path,
    name: &str,
    r: f64,
    t: (f64, f64),
    y: (f64, f64),
    (n, m): (usize, usize),
    drop: f64,
    gamma: f64,
) {
    let mut s = format!(
        "# vtk DataFile Version 3.0\npatch\nASCII\nDATASET POLYDATA\nPOINTS {} double\n",
        (n + 1) * (m + 1)
    );
    let at = |k: usize, of: usize| {
        let u = k as f64 / of as f64;
        if gamma == 1.0 {
            u
        } else {
            u.powf(gamma)
        }
    };
    for j in 0..=m {
        for i in 0..=n {
            let th = t.0 + (t.1 - t.0) * at(i, n);
            let yy = y.0 + (y.1 - y.0) * at(j, m);
            s += &format!("{} {} {}\n", r * th.sin(), yy, r * th.cos() - drop);
        }
    }
    s += &format!("POLYGONS {} {}\n", 2 * n * m, 8 * n * m);
    for j in 0..m {
        for i in 0..n {
            let a = j * (n + 1) + i;
            let (b, c, d) = (a + 1, a + n + 1, a + n + 2);
            if (i + j) % 2 == 0 {
                s += &format!("3 {a} {b} {d}\n3 {a} {d} {c}\n");
            } else {
                s += &format!("3 {a} {b} {c}\n3 {b} {d} {c}\n");
            }
        }
    }
    std::fs::write(dir.join(name), s).unwrap();
}

/// `out/summary.json`, parsed.
#[allow(dead_code)] // not every test crate reads summaries
pub fn summary(out: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(out.join("summary.json"))
        .unwrap_or_else(|e| panic!("{}: summary.json: {e}", out.display()));
    serde_json::from_str(&text).unwrap()
}

/// `out/log.csv` as rows of named columns (a cell that is not a number reads as NaN).
#[allow(dead_code)] // not every test crate reads logs
pub fn log_rows(out: &Path) -> Vec<std::collections::HashMap<String, f64>> {
    let text = std::fs::read_to_string(out.join("log.csv")).unwrap();
    let mut lines = text.lines();
    let head: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    lines
        .map(|l| {
            head.iter()
                .cloned()
                .zip(l.split(',').map(|v| v.parse::<f64>().unwrap_or(f64::NAN)))
                .collect()
        })
        .collect()
}

/// The gap `g ∈ (0, ĝ)` (m) at which IPC's log barrier of stiffness `k` (Pa/m) and activation
/// distance `g_hat` (m) carries the pressure `sigma` (Pa): `−k b′(g) = σ`, by bisection (`b′`
/// increases on the interval, [`shellsim::contact::barrier`]); the closed form of a flat
/// contact under the barrier law.
#[allow(dead_code)] // only the contact tests use it
pub fn barrier_gap(sigma: f64, k: f64, g_hat: f64) -> f64 {
    let (mut lo, mut hi) = (0.0, g_hat);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if -k * shellsim::contact::barrier(mid, g_hat).1 > sigma {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Runs `settings` on `mesh` (paths, or file names in `dir`) into `dir/out` with the `--set`
/// overrides `sets`, asserts that it converged, and returns its frames (checked finite).
#[allow(dead_code)] // not every test crate runs scenes this way
pub fn converged_frames(
    dir: &Path,
    settings: &str,
    mesh: &str,
    out: &str,
    sets: &[&str],
) -> Vec<shellsim::mesh::Mesh> {
    let mut args = vec![settings, mesh, "--out", out, "-q"];
    for s in sets {
        args.extend(["--set", s]);
    }
    shellsim(&args, dir);
    assert_eq!(summary(&dir.join(out))["converged"], true, "{out}");
    finite_frames(&dir.join(out), "vtu", out)
}

/// Writes `settings` (TOML text) as `dir/name.toml` and runs it on `mesh` into `dir/name`
/// ([`converged_frames`]).
#[allow(dead_code)] // not every test crate runs scenes this way
pub fn run_settings(
    dir: &Path,
    name: &str,
    settings: &str,
    mesh: &str,
) -> Vec<shellsim::mesh::Mesh> {
    let file = format!("{name}.toml");
    std::fs::write(dir.join(&file), settings).unwrap();
    converged_frames(dir, &file, mesh, name, &[])
}

/// Writes `dir/name`: `shellsim mesh rectangle` `lx` × `ly` (m) with edges `edge`, centred on the
/// origin, with the further arguments `extra`.
#[allow(dead_code)] // not every test crate meshes rectangles
pub fn rectangle(dir: &Path, lx: f64, ly: f64, edge: f64, extra: &[&str], name: &str) {
    let (lx, ly, edge) = (lx.to_string(), ly.to_string(), edge.to_string());
    let mut args = vec![
        "mesh",
        "rectangle",
        "--lx",
        &lx,
        "--ly",
        &ly,
        "--edge",
        &edge,
        "-o",
        name,
    ];
    args.extend_from_slice(extra);
    shellsim(&args, dir);
}

/// Settings of a 10 × 1 cm strip (`rectangle(dir, 0.1, 0.01, 0.005, ..)`) clamped by its first
/// two rows of vertices (x < −0.0449), sagging under gravity to rest: E = 1 GPa, ν = 0.3,
/// h = 1 mm, ρ = 1000 kg/m³, damped dynamics stopped at equilibrium. Small deflections, linear in
/// weight / (E h³).
#[allow(dead_code)] // not every test crate sags a cantilever
pub const SAGGING_CANTILEVER: &str = "[material]\nyoung = 1e9\npoisson = 0.3\nthickness = 1e-3\n\
    density = 1000\n[solver]\nmode = \"dynamic\"\n[time]\ndt = 0.01\ndt_max = 0.5\nend = 40\n\
    output_interval = 40\ndamping = 0.05\nstop_at_equilibrium = true\n\
    [loads]\ngravity = [0, 0, -9.81]\n[constraints]\n\
    fix_boxes = [{ min = [-1, -1, -1], max = [-0.0449, 1, 1] }]\n";
