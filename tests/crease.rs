//! Crease relaxation, through the binary: a strip creased dry into a circular fold opens, when
//! wetted, to the blend of its creased and original angles, keeping its length; and a crease law
//! without its stored state, or with a bad moisture range, is refused naming the field or key.

mod common;

use common::{converged_frames, run_status};
use shellsim::math::{Real, Vec3};
use shellsim::mesh::{io, Field, Mesh};
use std::f64::consts::PI;
use std::path::Path;

/// Strip length, width, fold radius and fold angle (m, m, m, rad), and cells along the strip
/// and across it.
const L: Real = 0.03;
const W: Real = 0.005;
const R: Real = 0.001;
const THETA: Real = 2.0 * PI / 3.0;
const NU: usize = 120;
const NV: usize = 10;

/// The creased position of the strip's material point at arc length `u` along it: flat up to
/// the fold, a circular arc of radius R turning by θ about the y axis, then straight.
fn creased(u: Real, v: Real) -> Vec3 {
    let s = R * THETA;
    let u0 = 0.5 * (L - s);
    if u <= u0 {
        return Vec3::new(u, v, 0.0);
    }
    let phi = ((u - u0) / R).min(THETA);
    let p = Vec3::new(u0 + R * phi.sin(), v, R * (1.0 - phi.cos()));
    let rest = (u - u0 - s).max(0.0);
    p + Vec3::new(THETA.cos(), 0.0, THETA.sin()) * rest
}

/// Writes `crease.vtk` in `dir`: the creased strip (grid NU × NV, alternating diagonals, with a
/// row of vertices at both ends of the fold), with the flat strip as `original_positions`.
fn crease_mesh(dir: &Path, stored: bool) {
    let s = R * THETA;
    let u0 = 0.5 * (L - s);
    // Rows along u: uniform on each flat part and on the arc, meeting at the fold's ends.
    let arc = 8;
    let flat = (NU - arc) / 2;
    let mut us: Vec<Real> = (0..=flat).map(|i| u0 * i as Real / flat as Real).collect();
    us.extend((1..=arc).map(|i| u0 + s * i as Real / arc as Real));
    us.extend((1..=flat).map(|i| u0 + s + u0 * i as Real / flat as Real));
    // The flat strip with the same edge lengths: each row at the creased rows' cumulative chord
    // length (the arc's chords are 0.3% shorter than its arc), so that creasing is an isometry
    // of the mesh itself.
    let mut flat_u = vec![0.0];
    for w in us.windows(2) {
        let chord = (creased(w[1], 0.0) - creased(w[0], 0.0)).norm();
        flat_u.push(flat_u.last().unwrap() + chord);
    }
    let mut m = Mesh::default();
    let mut original = Vec::new();
    for (&u, &fu) in us.iter().zip(&flat_u) {
        for j in 0..=NV {
            let v = W * j as Real / NV as Real;
            m.positions.push(creased(u, v));
            original.extend([fu, v, 0.0]);
        }
    }
    let id = |i: usize, j: usize| i * (NV + 1) + j;
    for i in 0..us.len() - 1 {
        for j in 0..NV {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            if (i + j) % 2 == 0 {
                m.faces.extend([[a, b, c], [a, c, d]]);
            } else {
                m.faces.extend([[a, b, d], [b, c, d]]);
            }
        }
    }
    if stored {
        m.vertex_fields.insert(
            "original_positions".into(),
            Field {
                components: 3,
                data: original,
            },
        );
    }
    io::write_mesh(&dir.join("crease.vtk"), &m, io::Format::Vtk, "crease").unwrap();
}

/// The angle (rad) between the strip's directions along its first and last flat parts
/// (vertices 20% and 5% of the length from each end, on the centre line), and the centre line's
/// length.
fn fold(m: &Mesh, reference: &Mesh) -> (Real, Real) {
    let line: Vec<usize> = (0..m.positions.len())
        .filter(|&v| (reference.positions[v].y - 0.5 * W).abs() < 1e-9)
        .collect();
    let at = |frac: Real| {
        let v = *line
            .iter()
            .min_by(|&&a, &&b| {
                let da = (original_u(reference, a) - frac * L).abs();
                let db = (original_u(reference, b) - frac * L).abs();
                da.total_cmp(&db)
            })
            .unwrap();
        m.positions[v]
    };
    let d0 = (at(0.2) - at(0.05)).normalize();
    let d1 = (at(0.95) - at(0.8)).normalize();
    let mut length = 0.0;
    let mut sorted = line.clone();
    sorted.sort_by(|&a, &b| original_u(reference, a).total_cmp(&original_u(reference, b)));
    for w in sorted.windows(2) {
        length += (m.positions[w[1]] - m.positions[w[0]]).norm();
    }
    (d0.dot(&d1).clamp(-1.0, 1.0).acos(), length)
}

/// The arc length u of vertex `v` (from the stored flat strip).
fn original_u(reference: &Mesh, v: usize) -> Real {
    reference.vertex_fields["original_positions"].get(v)[0]
}

/// A 30 × 5 mm paper strip (h = 0.2 mm) creased dry into a 120° fold of radius 1 mm (five
/// thicknesses), stress-free when dry, wetted uniformly so that the crease is half relaxed
/// (mean moisture 0.3 in `relax_moisture = [0.1, 0.5]`), and 90% relaxed (0.46). A free fold
/// takes its rest angle: the blend of the rest forms scales the arc's curvature by 1 − w, so
/// the fold opens to (1 − w) 120° in the continuum: 60° and 12°. The discrete model blends
/// each edge's `sin` of its half-angle, 15° per edge on this mesh, which differs from the
/// angles' blend by 0.22% of the fold (1 − w)(θ_e/2)²·w/6 summed; the bound is 0.5% of the fold
/// and 1e-3 rad flat. The creased mesh is an isometry of the stored one (its rows at the same
/// chord lengths), so the centre line keeps its length to 1e-6 at every moisture.
#[test]
fn a_wetted_crease_opens_to_its_blended_angle() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    crease_mesh(d, true);
    let reference = io::read_mesh(&d.join("crease.vtk")).unwrap();
    let (dry, dry_length) = fold(&reference, &reference);
    assert!((dry - THETA).abs() < 1e-9, "creased {dry}");
    for (m, want) in [(0.0, THETA), (0.3, 0.5 * THETA), (0.46, 0.1 * THETA)] {
        let name = format!("w{}", (m * 10.0) as i32);
        let settings = format!(
            "[material]\nyoung = 3e9\npoisson = 0.3\nthickness = 2e-4\n\
             [growth]\nlaw = \"crease_relaxation\"\nrelax_moisture = [0.1, 0.5]\n\
             moisture_top = {m}\nmoisture_bottom = {m}\n"
        );
        std::fs::write(d.join(format!("{name}.toml")), settings).unwrap();
        let frames = converged_frames(d, &format!("{name}.toml"), "crease.vtk", &name, &[]);
        let (angle, length) = fold(frames.last().unwrap(), &reference);
        println!(
            "moisture {m}: fold {:.4}° (want {:.4}°), centre line {:.8} m (dry {:.8})",
            angle.to_degrees(),
            want.to_degrees(),
            length,
            dry_length
        );
        assert!(
            (angle - want).abs() < 0.005 * want + 1e-3,
            "moisture {m}: fold {angle} rad, want {want}"
        );
        assert!(
            (length / dry_length - 1.0).abs() < 1e-6,
            "length {length} vs {dry_length}"
        );
    }
}

/// A crease law without its stored state, or with a bad moisture range, or the range with
/// another law: exit 2 naming the field or key, nothing written.
#[test]
fn a_crease_law_without_its_stored_state_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    crease_mesh(d, false);
    let law = "[growth]\nlaw = \"crease_relaxation\"\n";
    for (text, key) in [
        (
            format!("{law}relax_moisture = [0.1, 0.5]\n"),
            "original_positions",
        ),
        (law.to_string(), "growth.relax_moisture"),
        (
            format!("{law}relax_moisture = [0.5, 0.5]\n"),
            "growth.relax_moisture",
        ),
        (
            format!("{law}relax_moisture = [0.1, nan]\n"),
            "growth.relax_moisture",
        ),
        (
            "[growth]\nlaw = \"linear_swelling\"\nmu = 0.1\nrelax_moisture = [0, 1]\n".into(),
            "growth.relax_moisture",
        ),
    ] {
        std::fs::write(d.join("bad.toml"), &text).unwrap();
        let (code, _, err) = run_status(&["bad.toml", "crease.vtk", "--out", "bad"], d);
        assert_eq!(code, 2, "{text}: {err}");
        assert!(err.contains(key), "{text}: {err}");
        assert!(!d.join("bad").exists(), "{text}: wrote output");
    }
}

#[test]
fn a_wrapper_with_folds_tighter_than_its_thickness_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let base = [
        "mesh", "wrapper", "--lx", "0.012", "--edge", "4e-4", "-o", "w.vtk",
    ];
    for (extra, needle) in [
        (&["--radius", "0.0025"][..], "--thickness"),
        (
            &["--thickness", "1e-4", "--radius", "0.0025"][..],
            "twice the thickness",
        ),
        (
            &[
                "--thickness",
                "5e-5",
                "--bunching",
                "1.2",
                "--radius",
                "0.0025",
            ][..],
            "--bunching",
        ),
        (
            &["--thickness", "5e-5", "--folds", "0", "--radius", "0.0025"][..],
            "--folds",
        ),
        (
            &[
                "--thickness",
                "5e-5",
                "--strip-angle",
                "10",
                "--radius",
                "0.0025",
            ][..],
            "--strip-angle",
        ),
        (
            &[
                "--thickness",
                "5e-5",
                "--folds",
                "2",
                "--bunching",
                "4",
                "--radius",
                "1e-4",
            ][..],
            "--radius",
        ),
    ] {
        let mut args = base.to_vec();
        args.extend_from_slice(extra);
        let (code, _, err) = run_status(&args, d);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(err.contains(needle), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{err}");
        assert!(!d.join("w.vtk").exists(), "{args:?}: wrote a mesh");
    }
    // The rectangle's flags do not take the wrapper's.
    let (code, _, err) = run_status(
        &[
            "mesh",
            "rectangle",
            "--edge",
            "0.1",
            "--folds",
            "3",
            "-o",
            "r.vtk",
        ],
        d,
    );
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--folds"), "{err}");
}
