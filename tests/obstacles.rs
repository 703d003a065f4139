//! Rigid obstacles through the binary: a disk pressed by a sphere that moves down with the dial
//! onto a plane carries the same force on both (to 1e-6 of it), and its frames do not depend on
//! the thread count; a sheet lying on a plane obstacle carries its weight to 1e-6; a free sheet
//! in static mode that only a finite obstacle would hold is refused, and so are bad obstacles; a
//! sheet on a frictional incline slides by Coulomb's law or sticks, in dynamic and explicit mode.
//! Mesh obstacles: a plane mesh holds a sheet as the analytic plane does, a disk drapes over a
//! sphere mesh on its contact force without crossing it (checked by `scripts/contact_check.py`,
//! which needs VTK's Python package: `scripts/test.sh` provides it), a moving mesh presses a
//! disk onto a plane with its jumps checked, and bad mesh obstacles are refused.

mod common;

use common::{log_rows, run_status, shellsim};
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

/// Writes a disk of radius 0.5 m with target edge `edge` (m) to `d/file`.
fn disk(d: &Path, edge: &str, file: &str) {
    shellsim(
        &[
            "mesh", "disk", "--radius", "0.5", "--edge", edge, "-o", file,
        ],
        d,
    );
}

/// The weight ρ h A g (N) of the sheet `d/file`, A its area.
fn weight_of(d: &Path, file: &str, rho: f64, h: f64, g: f64) -> f64 {
    let mesh = shellsim::mesh::io::read_mesh(&d.join(file)).unwrap();
    let area: f64 = (0..mesh.faces.len()).map(|f| mesh.face_area(f)).sum();
    rho * h * area * g
}

/// The force `f` (N) carries `weight` upward with no sideways part, each to 1e-6 of the weight.
fn assert_carries(f: &[f64], weight: f64, label: &str) {
    assert!(
        (f[2] / weight - 1.0).abs() < 1e-6,
        "{label}: {f:?} vs {weight}"
    );
    assert!(
        f[0].abs() < 1e-6 * weight && f[1].abs() < 1e-6 * weight,
        "{label}: {f:?}"
    );
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
    disk(d, "0.05", "disk.vtk");
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
    disk(d, "0.05", "disk.vtk");
    let (rho, h, g) = (1000.0, 0.005, 9.81);
    let weight = weight_of(d, "disk.vtk", rho, h, g);
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
        assert_carries(&f, weight, tag);
    }
}

/// Bad obstacles: exit 2 naming the obstacle and key, or the vertex inside, nothing written.
#[test]
fn bad_obstacles_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    disk(d, "0.2", "d.vtk");
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
            "shape = \"plane\"\npoint = [0, 0, -1]\nnormal = [0, 0, 1]\npush = [0, 0, 1]",
            &["line 5", "push"][..],
        ),
        (
            "shape = \"sphere\"\ncenter = [0, 0, 1]\nradius = 0.5\nforce = [0, 0, 0]",
            &["obstacles[0].force", "non-zero"][..],
        ),
        (
            "shape = \"sphere\"\ncenter = [0, 0, 1]\nradius = 0.5\nforce = [0, 0, -1]\n\
             [solver]\nmode = \"dynamic\"",
            &["obstacles[0].mass", "required", "dynamic"][..],
        ),
        (
            "shape = \"sphere\"\ncenter = [0, 0, 1]\nradius = 0.5\nforce = [0, 0, -1]\n\
             displacement = [0, 0, -0.1]",
            &["obstacles[0].displacement", "force"][..],
        ),
        (
            "shape = \"sphere\"\ncenter = [0, 0, 1]\nradius = 0.5\nforce = [0, 0, -1]\n\
             mass = 1\n[solver]\nmode = \"explicit\"\n[material]\nbending = \"patch_fit\"",
            &["obstacles[0].force", "explicit"][..],
        ),
        (
            "shape = \"sphere\"\ncenter = [0, 0, 1]\nradius = 0.5\nmass = 1",
            &["obstacles[0].mass", "force"][..],
        ),
        (
            "shape = \"sphere\"\ncenter = [0, 0, 1]\nradius = 0.5\nforce = [0, 0, -1]\n\
             mass = -1\n[solver]\nmode = \"dynamic\"",
            &["obstacles[0].mass", "> 0"][..],
        ),
        (
            "shape = \"plane\"\npoint = [0, 0, -1]\nnormal = [0, 0, 1]\nfriction = -0.1",
            &["obstacles[0].friction", "≥ 0"][..],
        ),
        (
            "shape = \"plane\"\npoint = [0, 0, -1]\nnormal = [0, 0, 1]\nfriction = 0.5",
            &["obstacles[0].friction", "static", "dynamic"][..],
        ),
        (
            "shape = \"plane\"\npoint = [0, 0, -1]\nnormal = [0, 0, 1]\nfriction = 0.5\n\
             displacement = [0, 0, 0.1]\n[solver]\nmode = \"explicit\"\n\
             [material]\nbending = \"patch_fit\"",
            &["obstacles[0].friction", "moving", "dynamic"][..],
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

/// The last frame of `out` (the last row of its log) and that row.
fn last_frame(out: &Path) -> (shellsim::mesh::Mesh, HashMap<String, f64>) {
    let row = last_log_row(out);
    let frame = out.join(format!("frame_{:05}.vtu", row["frame"] as usize));
    (shellsim::mesh::io::read_mesh(&frame).unwrap(), row)
}

/// Mean velocity and displacement of the vertices in the last frame of `out` (m/s, m), and its
/// time (s).
fn last_frame_motion(out: &Path) -> ([f64; 3], [f64; 3], f64) {
    let (m, row) = last_frame(out);
    let n = m.positions.len() as f64;
    let mean = |name: &str| {
        let f = &m.vertex_fields[name];
        let mut s = [0.0; 3];
        for i in 0..m.positions.len() {
            for (k, sk) in s.iter_mut().enumerate() {
                *sk += f.get(i)[k] / n;
            }
        }
        s
    };
    (mean("velocity"), mean("displacement"), row["time"])
}

/// A square sheet (10 cm, h = 2 mm, 25 vertices) lying on a plane obstacle, with gravity tilted
/// by θ = 30° from the plane's normal (an incline): with μ = 0.3 < tan θ it slides at
/// `a = g (sin θ − μ cos θ)`: its mean velocity down the slope is `a t` to 1e-4, once the
/// momentum of its bounce on the penalty is counted (`v_x + μ v_z`; measured 7e-6 in dynamic
/// mode, where implicit Euler damps the bounce, and 2e-7 in explicit mode without drag, where
/// v_z is still 1% of v_x), and across the slope it does not move; with μ = 0.8 > tan θ it sticks,
/// creeping at most at the slip speed (dynamic mode, 1e-5 m/s), or held still at equilibrium
/// after slipping less than 1 mm while it bounces on the penalty (explicit). The explicit sliding run never
/// reaches equilibrium, so it ends unconverged (exit 1) at its time limit. The same in explicit
/// mode on a plane mesh of two triangles, through the sheet's contact pairs, their dashpot and
/// their stick/slip: it slides at `a t` to 1e-12 (the dashpot stops the bounce, v_z 6e-15),
/// and with μ = 0.8 slips 0.43 µm and holds.
#[test]
fn a_sheet_on_an_incline_slides_or_sticks_by_coulomb() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    shellsim(
        &[
            "mesh", "square", "--size", "0.1", "--edge", "0.025", "-o", "sq.vtk",
        ],
        d,
    );
    let (g, theta) = (9.81_f64, 30_f64.to_radians());
    let gravity = format!("[{}, 0, {}]", g * theta.sin(), -g * theta.cos());
    plane_obj(d, "plane.obj", -0.001);
    for kind in ["dynamic", "explicit", "explicit_mesh"] {
        let mode = if kind == "dynamic" {
            "dynamic"
        } else {
            "explicit"
        };
        let obstacle = if kind == "explicit_mesh" {
            "shape = \"mesh\"\nfile = \"plane.obj\"\n"
        } else {
            "shape = \"plane\"\npoint = [0, 0, -0.001]\nnormal = [0, 0, 1]\n"
        };
        for mu in [0.3, 0.8] {
            let tag = format!("{kind}_{}", (mu * 10.0) as i32);
            let timing = if mode == "dynamic" {
                "[time]\nend = 0.2\ndt = 1e-3\ndt_max = 0.01\noutput_interval = 0.05\n"
            } else if mu < 0.5 {
                "[explicit]\ndamping_prefactor_dial = 0\ndamping_prefactor_wait = 0\n\
                 max_long_times = 0.2\nframes_per_long_time = 20\n"
            } else {
                "[explicit]\nmax_long_times = 20\n"
            };
            let bending = if mode == "explicit" {
                "bending = \"patch_fit\"\n"
            } else {
                ""
            };
            let settings = format!(
                "[material]\nyoung = 1e6\npoisson = 0.3\nthickness = 0.002\ndensity = 1000\n{bending}\
                 [solver]\nmode = \"{mode}\"\nsymmetry_breaking = 0\n{timing}[loads]\ngravity = {gravity}\n\
                 [[obstacles]]\n{obstacle}friction = {mu}\n"
            );
            std::fs::write(d.join(format!("{tag}.toml")), settings).unwrap();
            let out = d.join(&tag);
            let (code, _, err) =
                run_status(&[&format!("{tag}.toml"), "sq.vtk", "--out", &tag, "-q"], d);
            let sliding_explicit = mode == "explicit" && mu < 0.5;
            assert_eq!(code, if sliding_explicit { 1 } else { 0 }, "{tag}: {err}");
            let (v, u, t) = last_frame_motion(&out);
            let a = g * (theta.sin() - mu * theta.cos());
            println!(
                "{tag}: t {t} s, mean velocity {v:?} m/s, displacement {u:?} m, a t = {}",
                a * t
            );
            assert!(v[1].abs() < 1e-6 * a.abs() * t, "{tag}: {v:?} {u:?}");
            if mu < theta.tan() {
                assert!(t > 0.05, "{tag}: t = {t}");
                // The momentum the normal force put into the sheet's bounce is μ m v_z: the
                // friction impulse is μ ∫N dt = μ m (g cos θ t + v_z).
                let slide = v[0] + mu * v[2];
                assert!(
                    (slide / (a * t) - 1.0).abs() < 1e-4,
                    "{tag}: {v:?} vs {}",
                    a * t
                );
            } else if mode == "dynamic" {
                assert!(
                    v[0].abs() <= 1e-5 && u[0].abs() <= 1e-5 * t,
                    "{tag}: {v:?} {u:?}"
                );
            } else if kind == "explicit" {
                // Undamped by the integrator, the sheet bounces on the penalty at first and
                // slips while the normal force is low (measured 0.27 mm); then it holds.
                assert!(v[0] == 0.0 && u[0].abs() < 1e-3, "{tag}: {v:?} {u:?}");
            } else {
                // The contact pairs' dashpot stops the bounce: it slips 0.43 µm, then holds.
                assert!(
                    v[0].abs() < 1e-12 && u[0].abs() < 1e-5,
                    "{tag}: {v:?} {u:?}"
                );
            }
        }
    }
}

/// The frame state file's global DOFs and their velocities (a force-controlled obstacle's
/// offset, m, and speed, m/s).
fn frame_globals(out: &Path, frame: usize) -> (Vec<f64>, Vec<f64>) {
    let text = std::fs::read_to_string(out.join(format!("frame_{frame:05}.state.json"))).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    let list = |k: &str| -> Vec<f64> {
        v[k].as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect()
    };
    (list("globals"), list("global_velocities"))
}

/// A disk (radius 0.5 m, h = 5 mm) on a plane obstacle, pressed by a sphere (radius 0.3 m)
/// under a prescribed force of 20 N, its height a global DOF of the solve:
/// * statics (the force dialled in): the sphere's push on the disk is the force and the plane
///   carries it, each to 1e-6 (measured 1e-12 and 6e-10); the sphere sinks 1.5 mm; the frames
///   of 1 and 2 threads are identical to the bit;
/// * dynamics (mass 0.5 kg, starting 1 cm above the disk): in free flight the sphere's speed is
///   `F t / M` to round-off (implicit Euler's velocity is exact under a constant force), and once
///   it rests on the disk its push balances the force to 1e-4 (measured 9e-9 at t = 0.5 s);
///   a restart from a frame in the middle ends on the same bits as the uninterrupted run.
#[test]
fn a_force_controlled_sphere_presses_with_its_force() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    disk(d, "0.05", "disk.vtk");
    let base = "[material]\nyoung = 1e6\npoisson = 0.3\nthickness = 0.005\n\
                [[obstacles]]\nshape = \"plane\"\npoint = [0, 0, -0.0025]\nnormal = [0, 0, 1]\n";
    let statics = format!(
        "{base}[[obstacles]]\nshape = \"sphere\"\ncenter = [0, 0, 0.3025]\nradius = 0.3\n\
         force = [0, 0, -20]\n[output]\ncontinuation_frames = false\n"
    );
    let one = run(d, &statics, "disk.vtk", "press1", "1");
    let two = run(d, &statics, "disk.vtk", "press2", "2");
    for (k, v) in &one {
        assert!(
            k == "wall_seconds" || two[k].to_bits() == v.to_bits(),
            "{k} differs between 1 and 2 threads"
        );
    }
    let (plane, sphere) = (force(&one, 0), force(&one, 1));
    println!(
        "statics: plane {plane:?} N, sphere {sphere:?} N, offset {} m",
        one["obstacle1_offset"]
    );
    assert!((sphere[2] / -20.0 - 1.0).abs() < 1e-6, "{sphere:?}");
    assert!((plane[2] / 20.0 - 1.0).abs() < 1e-6, "{plane:?}");
    assert!(one["obstacle1_offset"] > 0.0005, "{one:?}");
    let a = std::fs::read(d.join("press1/frame_00001.vtu")).unwrap();
    let b = std::fs::read(d.join("press2/frame_00001.vtu")).unwrap();
    assert!(a == b, "frames differ between 1 and 2 threads");

    let (f, m) = (20.0, 0.5);
    let dynamics = format!(
        "{base}[solver]\nmode = \"dynamic\"\n[time]\nend = 0.5\ndt = 1e-3\ndt_max = 0.05\n\
         output_interval = 0.02\ndamping = 0.1\n[[obstacles]]\nshape = \"sphere\"\n\
         center = [0, 0, 0.3125]\nradius = 0.3\nforce = [0, 0, -{f}]\nmass = {m}\n"
    );
    let row = run(d, &dynamics, "disk.vtk", "drop", "2");
    let (q, w) = frame_globals(&d.join("drop"), 1);
    println!("free flight at 0.02 s: offset {q:?} m, speed {w:?} m/s");
    assert!((w[0] / (f / m * 0.02) - 1.0).abs() < 1e-12, "{w:?}");
    let sphere = force(&row, 1);
    println!(
        "at rest: sphere {sphere:?} N, offset {}",
        row["obstacle1_offset"]
    );
    assert!((sphere[2] / -f - 1.0).abs() < 1e-4, "{sphere:?}");
    // Restart from t = 0.1 s: the same last frame, bit for bit.
    let (code, _, err) = run_status(
        &[
            "drop.toml",
            "disk.vtk",
            "--out",
            "again",
            "-q",
            "--restart",
            "drop/frame_00005.vtu",
        ],
        d,
    );
    assert_eq!(code, 0, "{err}");
    let (x, y) = (
        last_frame(&d.join("drop")).0,
        last_frame(&d.join("again")).0,
    );
    assert_eq!(x.positions, y.positions, "a restart changed the positions");
    assert_eq!(
        frame_globals(&d.join("drop"), 25).0,
        frame_globals(&d.join("again"), 20).0,
        "a restart changed the sphere's offset"
    );
}

/// A disk (radius 0.5 m, h = 5 mm, 347 vertices) dropped onto a sphere (radius 0.3 m) under
/// gravity, with friction μ = 0.5 (frictionless, its symmetric drape is unstable and it slides
/// off): it drapes over the sphere and comes to rest, where the sphere's normal and friction
/// forces together carry its weight ρ h A g to 1e-6 (measured 3e-8), with no sideways force
/// left (1e-6 of the weight; measured 3e-8). The friction matters: the wrapped disk squeezes the
/// sphere with 47.3 N against its 38.5 N weight, and friction holds its bending spring-back
/// with 8.9 N (downward). The frames report the friction of the accepted step's own lag.
#[test]
fn a_sheet_draped_over_a_sphere_rests_on_its_contact_force() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    disk(d, "0.05", "disk.vtk");
    let (rho, h, g) = (1000.0, 0.005, 9.81);
    let weight = weight_of(d, "disk.vtk", rho, h, g);
    let settings = format!(
        "[material]\nyoung = 1e6\npoisson = 0.3\nthickness = {h}\ndensity = {rho}\n\
         [solver]\nmode = \"dynamic\"\n[time]\nend = 4\ndt = 1e-3\ndt_max = 0.05\n\
         output_interval = 1\ndamping = 0.05\n[loads]\ngravity = [0, 0, -{g}]\n\
         [[obstacles]]\nshape = \"sphere\"\ncenter = [0, 0, -0.3026]\nradius = 0.3\n\
         friction = 0.5\n"
    );
    let row = run(d, &settings, "disk.vtk", "drape", "2");
    let normal = force(&row, 0);
    let friction = ["x", "y", "z"].map(|k| row[&format!("obstacle0_friction_{k}")]);
    let total: Vec<f64> = (0..3).map(|k| normal[k] + friction[k]).collect();
    println!(
        "normal {normal:?} N, friction {friction:?} N, total {total:?} N, weight {weight} N, \
         kinetic {} J",
        row["energy_kinetic"]
    );
    assert_carries(&total, weight, "drape");
    let f = friction.iter().map(|c| c * c).sum::<f64>().sqrt();
    assert!(f > 1e-2 * weight, "no friction acts: {friction:?}");
}

/// The independent check `scripts/contact_check.py` run in `d` with `args` (VTK's readers,
/// brute force over every pair of a sheet face and an obstacle face): its JSON summary,
/// written to `d/json`.
fn contact_check(d: &Path, json: &str, args: &[&str]) -> serde_json::Value {
    let python = std::env::var("SHELLSIM_PYTHON").unwrap_or_else(|_| "python3".into());
    let res = std::process::Command::new(&python)
        .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/contact_check.py"))
        .args(args)
        .arg("--json")
        .arg(json)
        .current_dir(d)
        .output()
        .unwrap_or_else(|e| panic!("{python}: {e}"));
    let text = std::fs::read_to_string(d.join(json)).unwrap_or_else(|_| {
        panic!(
            "contact_check.py failed (is VTK in {python}? run the tests with scripts/test.sh):\n{}",
            String::from_utf8_lossy(&res.stderr)
        )
    });
    serde_json::from_str(&text).unwrap()
}

/// The independent check `c` found no crossing and the smallest distance `logged` (m, the
/// log's smallest gap plus the offset) to 1e-9, and its `control` (the obstacle moved into the
/// sheet) found crossings: the check can fail.
fn agrees_with_the_log(c: &serde_json::Value, logged: f64, control: &serde_json::Value) {
    println!("independent check: {c}");
    assert_eq!(c["crossing_pairs"], 0, "{c}");
    let dmin = c["min_distance"].as_f64().unwrap();
    assert!(
        (dmin - logged).abs() < 1e-9,
        "the check's smallest distance {dmin} against the log's {logged}"
    );
    assert!(control["crossing_pairs"].as_u64().unwrap() > 0, "{control}");
}

/// The smallest value of the gap column `column` (m) over the frames of the run `out`,
/// asserting that no frame has a pair closer than a tenth of its offset h/2 (gap ≥ −0.9 h/2).
fn smallest_gap(out: &Path, column: &str, h: f64) -> f64 {
    log_rows(out).iter().fold(f64::INFINITY, |smallest, row| {
        let gap = row[column];
        assert!(
            gap >= -0.9 * h / 2.0,
            "a pair within a tenth of its offset: {gap}"
        );
        smallest.min(gap)
    })
}

/// A plane of two triangles as an OBJ file, `z` its height (m), spanning ±1 m.
fn plane_obj(d: &Path, file: &str, z: f64) {
    std::fs::write(
        d.join(file),
        format!("v -1 -1 {z}\nv 1 -1 {z}\nv 1 1 {z}\nv -1 1 {z}\nf 1 2 3\nf 1 3 4\n"),
    )
    .unwrap();
}

/// A mesh obstacle goes through the sheet's contact pairs, one-sided: a free disk (h = 5 mm)
/// resting under gravity on a plane of two triangles (an OBJ file, its path relative to the
/// settings file) reaches the same equilibrium as on the analytic plane, whose law is the
/// same `k A_v ψ(h/2 − d)` on every vertex: contact energy, force and smallest gap agree to
/// 1e-9 (measured: 2e-16 on the energy), the force carries the weight ρ h A g to 1e-6, and
/// the frames of 1 and 2 threads are identical to the bit. With the barrier law the disk stops
/// outside its offset at the barrier's closed-form gap.
#[test]
fn a_mesh_plane_holds_a_sheet_as_the_analytic_plane_does() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    disk(d, "0.05", "disk.vtk");
    std::fs::create_dir(d.join("shapes")).unwrap();
    plane_obj(&d.join("shapes"), "plane.obj", -0.0026);
    let (rho, h, g) = (1000.0, 0.005, 9.81);
    let weight = weight_of(d, "disk.vtk", rho, h, g);
    let base = format!(
        "[material]\nyoung = 1e6\npoisson = 0.3\nthickness = {h}\ndensity = {rho}\n\
         [loads]\ngravity = [0, 0, -{g}]\n[[obstacles]]\n"
    );
    let analytic = run(
        d,
        &format!("{base}shape = \"plane\"\npoint = [0, 0, -0.0026]\nnormal = [0, 0, 1]\n"),
        "disk.vtk",
        "analytic",
        "2",
    );
    std::fs::create_dir(d.join("cases")).unwrap();
    let mesh_settings = format!("{base}shape = \"mesh\"\nfile = \"../shapes/plane.obj\"\n");
    let mesh = run(
        d,
        &mesh_settings.replace("../shapes", "shapes"),
        "disk.vtk",
        "mesh",
        "2",
    );
    // The same scene from a settings file in another folder: the file is found relative to it.
    std::fs::write(d.join("cases").join("mesh1.toml"), &mesh_settings).unwrap();
    shellsim(
        &[
            "cases/mesh1.toml",
            "disk.vtk",
            "--out",
            "mesh1",
            "-q",
            "--threads",
            "1",
        ],
        d,
    );
    let close = |a: f64, b: f64, what: &str| {
        assert!(
            (a - b).abs() <= 1e-9 * a.abs().max(b.abs()),
            "{what}: analytic {a}, mesh {b}"
        );
    };
    close(
        analytic["energy_obstacles"],
        mesh["energy_mesh_obstacles"],
        "contact energy",
    );
    close(
        analytic["obstacle0_gap"],
        mesh["obstacle0_gap"],
        "smallest gap",
    );
    let (fa, fm) = (force(&analytic, 0), force(&mesh, 0));
    println!("analytic {fa:?} N, mesh {fm:?} N, weight {weight} N");
    close(fa[2], fm[2], "force");
    assert_carries(&fm, weight, "mesh plane");
    for f in ["frame_00000.vtu", "frame_00001.vtu"] {
        let a = std::fs::read(d.join("mesh").join(f)).unwrap();
        let b = std::fs::read(d.join("mesh1").join(f)).unwrap();
        assert!(a == b, "{f} differs between 1 and 2 threads");
    }
    // IPC's log barrier (`self_contact.law`, which the mesh's pairs follow): every vertex
    // stops at the gap g outside the offset where −k b′(g) = σ = ρ h g (ĝ = h/100; bisection),
    // 48.0 µm; measured equal to 1e-12 (a flat, uniform contact), asserted to 1e-6.
    let barrier = run(
        d,
        &format!(
            "{}[self_contact]\nlaw = \"barrier\"\n",
            mesh_settings.replace("../shapes", "shapes")
        ),
        "disk.vtk",
        "barrier",
        "2",
    );
    let exact = common::barrier_gap(rho * h * g, 1e6 / h, h / 100.0);
    let gap = barrier["obstacle0_gap"];
    println!("barrier: gap {gap:e} m, closed form {exact:e} m");
    assert!((gap - exact).abs() < 1e-6 * exact, "{gap} vs {exact}");
    assert_carries(&force(&barrier, 0), weight, "mesh plane, barrier");
}

/// A disk (radius 0.5 m, h = 5 mm) on a plane, pressed by a plate of two triangles (an OBJ
/// file, 0.1 mm above it) under a prescribed force of 2000 N, the plate's offset along the
/// force a global DOF of the solve, against the analytic plane pressed the same way, whose law
/// on every vertex is the same `k A_v ψ(h/2 − d)`:
/// * statics (the force dialled in): the plate's push balances the force and the plane carries
///   it, to 1e-6; the plate's offset agrees with the analytic plane's to 1e-6, and its gap with
///   the closed form `−√(2δσ/k)` of a uniform squeeze (σ = F/A below kδ/2) to 1e-4; the frames
///   of 1 and 2 threads are identical to the bit;
/// * dynamics (20 N, mass 0.5 kg, starting 1 cm above the disk): in free flight the plate's speed is
///   `F t / M` to round-off, and once it rests on the disk its push balances the force to 1e-4;
///   no frame has a pair within a tenth of its offset.
#[test]
fn a_force_controlled_mesh_presses_as_the_analytic_plane_does() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    disk(d, "0.05", "disk.vtk");
    let (h, f, e) = (0.005, 2000.0, 1e6);
    // The plate faces down: its normal, from the winding, points away from the disk.
    std::fs::write(
        d.join("plate.obj"),
        "v -1 -1 0.0026\nv -1 1 0.0026\nv 1 1 0.0026\nv 1 -1 0.0026\nf 1 2 3\nf 1 3 4\n",
    )
    .unwrap();
    let base = format!(
        "[material]\nyoung = {e}\npoisson = 0.3\nthickness = {h}\n\
         [[obstacles]]\nshape = \"plane\"\npoint = [0, 0, -0.0025]\nnormal = [0, 0, 1]\n"
    );
    let plane = "shape = \"plane\"\npoint = [0, 0, 0.0026]\nnormal = [0, 0, -1]\n";
    let plate = "shape = \"mesh\"\nfile = \"plate.obj\"\n";
    let statics = |top: &str| {
        format!(
            "{base}[[obstacles]]\n{top}force = [0, 0, -{f}]\n\
             [output]\ncontinuation_frames = false\n"
        )
    };
    let analytic = run(d, &statics(plane), "disk.vtk", "analytic", "2");
    let one = run(d, &statics(plate), "disk.vtk", "plate1", "1");
    let two = run(d, &statics(plate), "disk.vtk", "plate2", "2");
    for (k, v) in &one {
        assert!(
            k.ends_with("_seconds") || two[k].to_bits() == v.to_bits(),
            "{k} differs between 1 and 2 threads"
        );
    }
    let a = std::fs::read(d.join("plate1/frame_00001.vtu")).unwrap();
    let b = std::fs::read(d.join("plate2/frame_00001.vtu")).unwrap();
    assert!(a == b, "frames differ between 1 and 2 threads");
    let (below, above) = (force(&one, 0), force(&one, 1));
    let (qa, qm) = (analytic["obstacle1_offset"], one["obstacle1_offset"]);
    // The squeeze's closed form: every vertex sinks p into both sides, ψ′(p) = σ/k.
    let area = weight_of(d, "disk.vtk", 1.0, 1.0, 1.0);
    let (k, delta) = (e / h, h / 100.0);
    let sigma = f / area;
    assert!(sigma < k * delta / 2.0);
    let p = (2.0 * delta * sigma / k).sqrt();
    println!(
        "statics: plane {below:?} N, plate {above:?} N, offset {qm} m (analytic plane {qa} m), \
         gap {} m (closed form {})",
        one["obstacle1_gap"], -p
    );
    assert!((above[2] / -f - 1.0).abs() < 1e-6, "{above:?}");
    assert!((below[2] / f - 1.0).abs() < 1e-6, "{below:?}");
    assert!((qm - qa).abs() < 1e-6 * qa.abs(), "{qm} vs {qa}");
    assert!(
        (one["obstacle1_gap"] + p).abs() < 1e-4 * p,
        "{} vs {}",
        one["obstacle1_gap"],
        -p
    );

    let (f, m) = (20.0, 0.5);
    let dynamics = format!(
        "{base}[solver]\nmode = \"dynamic\"\n[time]\nend = 0.5\ndt = 1e-3\ndt_max = 0.05\n\
         output_interval = 0.02\ndamping = 0.1\n[[obstacles]]\n{}force = [0, 0, -{f}]\n\
         mass = {m}\n",
        plate.to_string() + "translate = [0, 0, 0.01]\n"
    );
    let row = run(d, &dynamics, "disk.vtk", "drop", "2");
    let (q, w) = frame_globals(&d.join("drop"), 1);
    println!("free flight at 0.02 s: offset {q:?} m, speed {w:?} m/s");
    assert!((w[0] / (f / m * 0.02) - 1.0).abs() < 1e-12, "{w:?}");
    let above = force(&row, 1);
    println!(
        "at rest: plate {above:?} N, offset {}, smallest gap {}",
        row["obstacle1_offset"],
        smallest_gap(&d.join("drop"), "obstacle1_gap", h)
    );
    assert!((above[2] / -f - 1.0).abs() < 1e-4, "{above:?}");
}

/// A disk (radius 0.5 m, h = 5 mm, held sideways) on a plane, pressed with 200 N by a sphere
/// mesh (radius 0.3 m, edges about 5 cm) that starts 1 cm above it: in statics the offset
/// crosses the gap by Newton steps that CCD bounds as the ball's vertices move along the
/// force, comes to rest where the ball's push balances the force and the plane carries it, to
/// 1e-6, and no continuation step's frame has a pair within a tenth of its offset.
#[test]
fn a_force_controlled_sphere_mesh_comes_down_onto_a_disk() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    disk(d, "0.05", "disk.vtk");
    shellsim(
        &[
            "mesh", "sphere", "--radius", "0.3", "--edge", "0.05", "-o", "ball.vtk",
        ],
        d,
    );
    let (h, f) = (0.005, 200.0);
    // Frictionless, a free disk squeezed by a faceted ball slides sideways off its facets.
    let settings = format!(
        "[material]\nyoung = 1e6\npoisson = 0.3\nthickness = {h}\n\
         [[constraints.support]]\ncomponents = [\"x\", \"y\"]\n\
         inside = {{ min = [-1, -1, -1], max = [1, 1, 1] }}\n\
         [[obstacles]]\nshape = \"plane\"\npoint = [0, 0, -0.0025]\nnormal = [0, 0, 1]\n\
         [[obstacles]]\nshape = \"mesh\"\nfile = \"ball.vtk\"\ntranslate = [0, 0, 0.3125]\n\
         force = [0, 0, -{f}]\n[output]\ncontinuation_frames = true\n"
    );
    let row = run(d, &settings, "disk.vtk", "ball", "2");
    let (plane, ball) = (force(&row, 0), force(&row, 1));
    let gap = smallest_gap(&d.join("ball"), "obstacle1_gap", h);
    println!(
        "plane {plane:?} N, ball {ball:?} N, offset {} m, smallest gap {gap} m",
        row["obstacle1_offset"]
    );
    assert!((ball[2] / -f - 1.0).abs() < 1e-6, "{ball:?}");
    assert!((plane[2] / f - 1.0).abs() < 1e-6, "{plane:?}");
    assert!(row["obstacle1_offset"] > 0.01, "{row:?}");
    // The independent check, the ball moved in each frame by its logged offset along the
    // force: no crossing, and the smallest distance the log reports; the last frame against
    // the ball pushed 5 mm further crosses it (the control).
    let check = |z: &str, last: bool| {
        let mut args = vec!["disk.vtk", "ball", "--obstacle", "ball.vtk"];
        args.extend(["--translate", "0", "0", z]);
        args.extend(["--push", "obstacle1_offset", "0", "0", "-1"]);
        args.extend(last.then_some("--last"));
        contact_check(d, &format!("check{z}.json"), &args)
    };
    agrees_with_the_log(
        &check("0.3125", false),
        h / 2.0 + gap,
        &check("0.3075", true),
    );
}

/// A disk (radius 0.5 m, h = 5 mm) dropped with friction μ = 0.5 onto a geodesic sphere mesh
/// (radius 0.3 m, 980 faces, edges about 5 cm, the disk's own size) placed by `translate`:
/// it drapes and comes to rest, the mesh's normal and friction forces together carrying the
/// weight to 1e-6 (measured 1e-7), and no pair ever comes closer than the guaranteed tenth of
/// its offset: the sheet's mid-surface stays 1.70 mm from the faceted ball (h/2 = 2.5 mm; the
/// ball's ridges between the sheet's vertices enter the offset, as edge pairs press only
/// inside half of it), which the independent script confirms, with no crossing.
#[test]
fn a_sheet_draped_over_a_sphere_mesh_rests_on_its_contact_force() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    disk(d, "0.05", "disk.vtk");
    shellsim(
        &[
            "mesh", "sphere", "--radius", "0.3", "--edge", "0.05", "-o", "ball.vtk",
        ],
        d,
    );
    let (rho, h, g) = (1000.0, 0.005, 9.81);
    let weight = weight_of(d, "disk.vtk", rho, h, g);
    let settings = format!(
        "[material]\nyoung = 1e6\npoisson = 0.3\nthickness = {h}\ndensity = {rho}\n\
         [solver]\nmode = \"dynamic\"\n[time]\nend = 4\ndt = 1e-3\ndt_max = 0.05\n\
         output_interval = 1\ndamping = 0.05\n[loads]\ngravity = [0, 0, -{g}]\n\
         [[obstacles]]\nshape = \"mesh\"\nfile = \"ball.vtk\"\ntranslate = [0, 0, -0.3026]\n\
         friction = 0.5\n"
    );
    let row = run(d, &settings, "disk.vtk", "drape", "2");
    let f = force(&row, 0);
    println!(
        "force {f:?} N (normal and friction), weight {weight} N, kinetic {} J, gap {} m, \
         pairs {}",
        row["energy_kinetic"], row["obstacle0_gap"], row["mesh_obstacles_pairs"]
    );
    assert_carries(&f, weight, "drape on a mesh");
    assert!(row["mesh_obstacles_friction"] > 1e-2 * weight, "{row:?}");
    let out = d.join("drape");
    let smallest = smallest_gap(&out, "obstacle0_gap", h);
    // The independent check (VTK's readers, brute force over every pair of a sheet face and a
    // ball face): no crossing, and the smallest distance the log reports; the last frame
    // against the ball moved 5 mm up crosses it (the control: the check can fail).
    let check = |z: &str, last: bool| {
        let mut args = vec!["disk.vtk", "drape", "--obstacle", "ball.vtk"];
        args.extend(["--translate", "0", "0", z]);
        args.extend(last.then_some("--last"));
        contact_check(d, &format!("check{z}.json"), &args)
    };
    agrees_with_the_log(
        &check("-0.3026", false),
        h / 2.0 + smallest,
        &check("-0.2976", true),
    );
}

/// Bad mesh obstacles: exit 2 naming the key or the obstacle's file and what is wrong, nothing
/// written.
#[test]
fn bad_mesh_obstacles_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    disk(d, "0.2", "d.vtk");
    plane_obj(d, "low.obj", -0.01);
    plane_obj(d, "near.obj", -0.001);
    std::fs::write(
        d.join("flat.obj"),
        "v 0 0 -1\nv 1 0 -1\nv 2 0 -1\nf 1 2 3\n",
    )
    .unwrap();
    std::fs::write(
        d.join("index.obj"),
        "v 0 0 -1\nv 1 0 -1\nv 0 1 -1\nf 1 2 7\n",
    )
    .unwrap();
    std::fs::write(
        d.join("junk.stl"),
        "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0\n",
    )
    .unwrap();
    // A tilted plane through the disk.
    std::fs::write(
        d.join("through.obj"),
        "v -1 -1 -1\nv 1 -1 1\nv 1 1 1\nv -1 1 -1\nf 1 2 3\nf 1 3 4\n",
    )
    .unwrap();
    let mesh = |f: &str| format!("shape = \"mesh\"\nfile = \"{f}\"");
    for (text, needles) in [
        (
            mesh("missing.obj"),
            &["missing.obj", "obstacles[0].file"][..],
        ),
        (
            mesh("junk.stl"),
            &["junk.stl", "obstacles[0].file", "line"][..],
        ),
        (
            mesh("flat.obj"),
            &["flat.obj", "obstacles[0].file", "face 0"][..],
        ),
        (
            mesh("index.obj"),
            &["index.obj", "obstacles[0].file", "out of range"][..],
        ),
        (
            mesh("through.obj"),
            &["through.obj", "obstacles[0]", "passes through", "face"][..],
        ),
        (
            mesh("near.obj"),
            &["near.obj", "obstacles[0]", "vertex", "within"][..],
        ),
        (
            "shape = \"mesh\"".into(),
            &["obstacles[0].file", "required"][..],
        ),
        (
            format!("{}\nradius = 1", mesh("low.obj")),
            &["obstacles[0].radius", "not a key"][..],
        ),
        (
            format!(
                "{}\ndisplacement = [0, 0, 0.02]\n[solver]\nmode = \"dynamic\"",
                mesh("low.obj")
            ),
            &["rest.dial_time", "dial 1", "mesh obstacle"][..],
        ),
        (
            format!("{}\nscale = 0", mesh("low.obj")),
            &["obstacles[0].scale", "> 0"][..],
        ),
        (
            format!(
                "{}\ndisplacement = [0, 0, 0.1]\n[solver]\ncontinuation = \"arc_length\"",
                mesh("low.obj")
            ),
            &["obstacles[0].shape", "arc_length"][..],
        ),
        (
            format!(
                "{}\nforce = [0, 0, 1]\n[solver]\nmode = \"explicit\"\n[material]\nbending = \"patch_fit\"",
                mesh("low.obj")
            ),
            &["obstacles[0].force", "explicit"][..],
        ),
        (
            format!(
                "{}\nforce = [0, 0, 1]\nmass = 1\nfriction = 0.3\n[solver]\nmode = \"dynamic\"",
                mesh("low.obj")
            ),
            &["obstacles[0].friction", "force-controlled"][..],
        ),
        (
            format!("{}\nforce = [0, 0, 1]\n[solver]\nmode = \"dynamic\"", mesh("low.obj")),
            &["obstacles[0].mass", "required"][..],
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

/// A disk (h = 5 mm) on a plane, pressed 2 mm into it by a sphere mesh (radius 0.3, edges
/// about 5 cm) that moves down with the dial, in one dial step: the first jump would carry the
/// mesh through the disk, and the collision check over the jump cuts the step instead. The
/// plane pushes up with the force the mesh pushes down, to 1e-6 of it, and no pair ever comes
/// closer than a tenth of its offset (the smallest gap over the frames, ≥ −0.9 h/2).
#[test]
fn a_mesh_moving_with_the_dial_presses_a_disk_onto_a_plane() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    disk(d, "0.05", "disk.vtk");
    shellsim(
        &[
            "mesh", "sphere", "--radius", "0.3", "--edge", "0.05", "-o", "ball.vtk",
        ],
        d,
    );
    let h = 0.005;
    let settings = format!(
        "[material]\nyoung = 1e6\npoisson = 0.3\nthickness = {h}\n\
         [solver]\ncontinuation_step = 1\n\
         [[obstacles]]\nshape = \"plane\"\npoint = [0, 0, -0.0025]\nnormal = [0, 0, 1]\n\
         [[obstacles]]\nshape = \"mesh\"\nfile = \"ball.vtk\"\ntranslate = [0, 0, 0.3026]\n\
         displacement = [0, 0, -0.002]\n[output]\ncontinuation_frames = true\n"
    );
    let row = run(d, &settings, "disk.vtk", "press", "2");
    let (plane, pressing) = (force(&row, 0), force(&row, 1));
    println!("plane pushes {plane:?} N, the mesh pushes {pressing:?} N");
    assert!(pressing[2] < -1.0, "{pressing:?}");
    let scale = pressing[2].abs();
    for k in 0..3 {
        assert!(
            (plane[k] + pressing[k]).abs() < 1e-6 * scale,
            "{plane:?} {pressing:?}"
        );
    }
    let out = d.join("press");
    let sum: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    println!("steps {} rejected {}", sum["steps"], sum["rejected_steps"]);
    assert!(sum["rejected_steps"].as_u64().unwrap() > 0, "{sum}");
    smallest_gap(&out, "obstacle1_gap", h);
}

/// Explicit mode: a plane mesh driven 6.8 mm down toward another 7 mm below it, a 5 mm disk
/// between them, asks for more than the guarantee allows: the two surfaces would come within
/// 0.2 mm, where each side keeps a tenth of the sheet's offset (0.25 mm) from its mid-surface.
/// The run stops (exit 1) naming the moving obstacle, and no frame, checked independently
/// against both meshes (the moving one at each frame's dial), has a crossing or a pair below
/// its floor.
#[test]
fn a_mesh_driven_through_a_sheet_in_explicit_mode_stops() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    disk(d, "0.1", "disk.vtk");
    plane_obj(d, "top.obj", 0.0035);
    plane_obj(d, "bottom.obj", -0.0035);
    let h = 0.005;
    let settings = "[material]\nyoung = 1e6\npoisson = 0.3\nthickness = 0.005\n\
         bending = \"patch_fit\"\n[solver]\nmode = \"explicit\"\n\
         [[obstacles]]\nshape = \"mesh\"\nfile = \"bottom.obj\"\n\
         [[obstacles]]\nshape = \"mesh\"\nfile = \"top.obj\"\ndisplacement = [0, 0, -0.0068]\n";
    std::fs::write(d.join("over.toml"), settings).unwrap();
    let (code, _, err) = run_status(&["over.toml", "disk.vtk", "--out", "over", "-q"], d);
    println!("{err}");
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("obstacles[1]") && err.contains("min_separation"),
        "{err}"
    );
    let out = d.join("over");
    for k in 0..2 {
        println!(
            "obstacle {k}: smallest gap {}",
            smallest_gap(&out, &format!("obstacle{k}_gap"), h)
        );
    }
    let bottom = contact_check(
        d,
        "bottom.json",
        &["disk.vtk", "over", "--obstacle", "bottom.obj"],
    );
    let top = contact_check(
        d,
        "top.json",
        &[
            "disk.vtk",
            "over",
            "--obstacle",
            "top.obj",
            "--push",
            "dial",
            "0",
            "0",
            "-0.0068",
        ],
    );
    println!("independent checks: bottom {bottom}, top {top}");
    for c in [&bottom, &top] {
        assert_eq!(c["crossing_pairs"], 0, "{c}");
        assert!(
            c["min_distance"].as_f64().unwrap() >= 0.1 * h / 2.0 * (1.0 - 1e-9),
            "{c}"
        );
    }
}

/// Explicit mode: a disk (h = 5 mm, 157 faces) squeezed 0.5 mm between an analytic plane and a
/// plane mesh (two triangles, 1 mm above its top surface), once with the plane moving 1.5 mm up
/// with the dial and the mesh fixed, once with the mesh moving 1.5 mm down and the plane fixed.
/// The moving mesh's move is bounded as the sheet's vertices are (its room from where the pairs
/// were gathered, the pairs gathered again before it is used up), and the contact dashpot
/// measures the approach against its own velocity. At equilibrium the mesh and the plane push
/// with the same force, to 1e-6 of it, and the two equal penalties (E/h) share the squeeze,
/// each side sinking 0.25 mm into its offset to 1e-6 (measured: 19090.806 N on both at edges of
/// 5 cm, 4747.958 N at 10 cm, either way). The contact dashpot acts on the approach the step
/// would reach by backward Euler: one that stopped that approach outright held the disk where
/// the mesh first touched it (132 N against the plane's 39 kN, a false equilibrium).
#[test]
fn a_disk_squeezed_between_a_plane_and_a_plane_mesh_in_explicit_mode_balances_its_load() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    disk(d, "0.1", "disk.vtk");
    plane_obj(d, "top.obj", 0.0035);
    for (tag, plane_moves, mesh_moves) in [
        ("squeeze", "displacement = [0, 0, 0.0015]\n", ""),
        ("press", "", "displacement = [0, 0, -0.0015]\n"),
    ] {
        let settings = format!(
            "[material]\nyoung = 1e6\npoisson = 0.3\nthickness = 0.005\n\
             bending = \"patch_fit\"\n[solver]\nmode = \"explicit\"\n\
             [[obstacles]]\nshape = \"plane\"\npoint = [0, 0, -0.0025]\nnormal = [0, 0, 1]\n\
             {plane_moves}[[obstacles]]\nshape = \"mesh\"\nfile = \"top.obj\"\n{mesh_moves}"
        );
        let row = run(d, &settings, "disk.vtk", tag, "2");
        let (plane, mesh) = (force(&row, 0), force(&row, 1));
        println!(
            "{tag}: plane pushes {plane:?} N, the mesh {mesh:?} N; gaps {} and {} m",
            row["obstacle0_gap"], row["obstacle1_gap"]
        );
        assert!(plane[2] > 1000.0, "{tag}: {plane:?}");
        assert!(
            (plane[2] + mesh[2]).abs() < 1e-6 * plane[2],
            "{tag}: {plane:?} {mesh:?}"
        );
        for k in 0..2 {
            let gap = row[&format!("obstacle{k}_gap")];
            assert!(
                (gap + 2.5e-4).abs() < 1e-6 * 2.5e-4,
                "{tag}: obstacle {k}: {gap}"
            );
        }
        smallest_gap(&d.join(tag), "obstacle1_gap", 0.005);
    }
}
