//! Rigid obstacles through the binary: a disk pressed by a sphere that moves down with the dial
//! onto a plane carries the same force on both (to 1e-6 of it), and its frames do not depend on
//! the thread count; a sheet lying on a plane obstacle carries its weight to 1e-6; a free sheet
//! in static mode that only a finite obstacle would hold is refused, and so are bad obstacles.

mod common;

use common::{run_status, shellsim};
use std::collections::HashMap;
use std::path::Path;

fn last_log_row(out: &Path) -> HashMap<String, f64> {
    let text = std::fs::read_to_string(out.join("log.csv")).unwrap();
    let mut lines = text.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let last = lines.last().unwrap();
    head.iter()
        .zip(last.split(','))
        .filter_map(|(h, v)| v.parse().ok().map(|v| (h.to_string(), v)))
        .collect()
}

fn run(dir: &Path, settings: &str, mesh: &str, tag: &str, threads: &str) -> HashMap<String, f64> {
    std::fs::write(dir.join(format!("{tag}.toml")), settings).unwrap();
    let out = dir.join(tag);
    shellsim(
        &[
            &format!("{tag}.toml"),
            mesh,
            "--out",
            out.to_str().unwrap(),
            "-q",
            "--threads",
            threads,
        ],
        dir,
    );
    let sum: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(sum["converged"], true, "{tag}: {sum}");
    last_log_row(&out)
}

fn force(row: &HashMap<String, f64>, i: usize) -> [f64; 3] {
    ["x", "y", "z"].map(|k| row[&format!("obstacle{i}_force_{k}")])
}

/// A disk (radius 0.5 m, h = 5 mm) on a plane at z = −h/2, pressed 8 mm into it by a sphere
/// (radius 0.3) and by a box, each moving down with the dial: the plane pushes up with the
/// force the pressing obstacle pushes down, to 1e-6 of it (measured below 1e-9), the contact is
/// felt (more than 1 N), and the sphere's frames of 1 and 2 threads are identical to the bit.
/// (A frictionless sheet squeezed under a cylinder or capsule is squeezed out sideways, like a
/// seed between fingers: the static solve has no equilibrium to find without friction.)
#[test]
fn a_disk_pressed_onto_a_plane_balances_and_ignores_threads() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    shellsim(
        &[
            "mesh", "disk", "--radius", "0.5", "--edge", "0.05", "-o", "disk.vtk",
        ],
        d,
    );
    for (tag, press) in [
        (
            "sphere",
            "shape = \"sphere\"\ncenter = [0, 0, 0.3026]\nradius = 0.3",
        ),
        (
            "box",
            "shape = \"box\"\nmin = [-0.2, -0.2, 0.0026]\nmax = [0.2, 0.2, 0.5]",
        ),
    ] {
        let settings = format!(
            "[material]\nyoung = 1e6\npoisson = 0.3\nthickness = 0.005\n\
             [[obstacles]]\nshape = \"plane\"\npoint = [0, 0, -0.0025]\nnormal = [0, 0, 1]\n\
             [[obstacles]]\n{press}\ndisplacement = [0, 0, -0.008]\n\
             [output]\ncontinuation_frames = false\n"
        );
        let one = run(d, &settings, "disk.vtk", &format!("{tag}1"), "1");
        let (plane, pressing) = (force(&one, 0), force(&one, 1));
        println!("{tag}: plane pushes {plane:?} N, the {tag} pushes {pressing:?} N");
        assert!(pressing[2] < -1.0, "{tag}: {pressing:?}");
        let scale = pressing[2].abs();
        for k in 0..3 {
            assert!(
                (plane[k] + pressing[k]).abs() < 1e-6 * scale,
                "{tag}: {plane:?} {pressing:?}"
            );
        }
        if tag == "sphere" {
            let two = run(d, &settings, "disk.vtk", "sphere2", "2");
            for f in ["frame_00000.vtu", "frame_00001.vtu"] {
                let a = std::fs::read(d.join("sphere1").join(f)).unwrap();
                let b = std::fs::read(d.join("sphere2").join(f)).unwrap();
                assert!(a == b, "{f} differs between 1 and 2 threads");
            }
            assert_eq!(one.get("obstacle1_gap"), two.get("obstacle1_gap"));
        }
    }
}

/// A free disk under gravity on a plane obstacle, fixed and lifting it by 1 cm with the dial
/// (statics): the obstacle's force balances the weight ρ h A g to 1e-6 (measured 3.5e-10).
#[test]
fn sheets_resting_on_obstacles_carry_their_weight() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    shellsim(
        &[
            "mesh", "disk", "--radius", "0.5", "--edge", "0.05", "-o", "disk.vtk",
        ],
        d,
    );
    let mesh = shellsim::mesh::io::read_mesh(&d.join("disk.vtk")).unwrap();
    let area: f64 = (0..mesh.faces.len()).map(|f| mesh.face_area(f)).sum();
    let (rho, h, g) = (1000.0, 0.005, 9.81);
    let weight = rho * h * area * g;
    for (tag, obstacle) in [
        (
            "plane",
            "shape = \"plane\"\npoint = [0, 0, -0.0026]\nnormal = [0, 0, 1]",
        ),
        (
            "lifting_plane",
            "shape = \"plane\"\npoint = [0, 0, -0.0026]\nnormal = [0, 0, 1]\n\
             displacement = [0, 0, 0.01]",
        ),
    ] {
        let settings = format!(
            "[material]\nyoung = 1e6\npoisson = 0.3\nthickness = {h}\ndensity = {rho}\n\
             [loads]\ngravity = [0, 0, -{g}]\n[[obstacles]]\n{obstacle}\n"
        );
        let row = run(d, &settings, "disk.vtk", tag, "2");
        let f = force(&row, 0);
        println!("{tag}: obstacle force {f:?} N, weight {weight} N");
        assert!(
            (f[2] / weight - 1.0).abs() < 1e-6,
            "{tag}: {f:?} vs {weight}"
        );
        assert!(
            f[0].abs() < 1e-6 * weight && f[1].abs() < 1e-6 * weight,
            "{f:?}"
        );
    }
}

/// Bad obstacles: exit 2 naming the obstacle and key, or the vertex inside, nothing written.
#[test]
fn bad_obstacles_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    shellsim(
        &[
            "mesh", "disk", "--radius", "0.5", "--edge", "0.2", "-o", "d.vtk",
        ],
        d,
    );
    for (text, needles) in [
        (
            "shape = \"sphere\"\ncenter = [0, 0, 0.1]\nradius = 0.2",
            &["obstacles[0]", "starts inside the sheet", "vertex"][..],
        ),
        (
            "shape = \"sphere\"\ncenter = [0, 0, 1]\nradius = 0",
            &["obstacles[0].radius", "must be > 0"][..],
        ),
        (
            "shape = \"plane\"\npoint = [0, 0, -1]\nnormal = [0, 0, 0]",
            &["obstacles[0].normal", "non-zero"][..],
        ),
        (
            "shape = \"cylinder\"\npoint = [0, 0, -1]\naxis = [1, 0, 0]",
            &["obstacles[0].radius", "required"][..],
        ),
        ("shape = \"cone\"", &["line 2", "cone"][..]),
        (
            "shape = \"box\"\nmin = [0, 0, -1]\nmax = [1, 1, -1]",
            &["obstacles[0].max", "exceed min"][..],
        ),
        (
            "shape = \"sphere\"\ncenter = [0, 0, -0.5]\nradius = 0.4\n[loads]\ngravity = [0, 0, -9.8]",
            &["obstacles", "static", "plane", "dynamic"][..],
        ),
        (
            "shape = \"plane\"\npoint = [0, 0, -1]\nnormal = [0, 0, 1]\nforce = [0, 0, 1]",
            &["line 5", "force"][..],
        ),
    ] {
        std::fs::write(d.join("o.toml"), format!("[[obstacles]]\n{text}\n")).unwrap();
        let (code, _, err) = run_status(&["o.toml", "d.vtk", "--out", "o", "-q"], d);
        assert_eq!(code, 2, "{text}: {err}");
        for n in needles {
            assert!(err.contains(n), "{text}: {err}");
        }
        assert!(!d.join("o").exists(), "{text}: wrote output");
    }
}
