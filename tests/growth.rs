//! The isotropic growth laws on curved shells, through the binary: uniform volumetric growth of
//! a spherical cap and of a cylindrical panel reaches the scaled copy (every edge × e^s, the
//! thickness × e^s) to round-off with zero energy; in-plane growth at fixed thickness leaves the
//! shell frustrated, more so the thicker it is. Bad growth settings are refused.

mod common;

use common::{run_status, shellsim};
use shellsim::math::{Real, Vec3};
use shellsim::mesh::io::{read_mesh, write_mesh, Format};
use std::path::{Path, PathBuf};

/// A curved shell from a flat mesh: the unit disk mapped onto a 60° cap of radius 1 (the disk
/// radius r becomes the polar angle r·π/3), or the rectangle [0, 1] × [0, 0.5] rolled into a
/// 90° panel of a cylinder of radius 2/π.
fn curved(dir: &Path, kind: &str) -> PathBuf {
    let flat = match kind {
        "cap" => vec!["disk", "--radius", "1", "--edge", "0.1"],
        _ => vec!["rectangle", "--lx", "1", "--ly", "0.5", "--edge", "0.08"],
    };
    let mut a = vec!["mesh"];
    a.extend(flat);
    a.extend(["-o", "flat.vtk"]);
    shellsim(&a, dir);
    let mut m = read_mesh(&dir.join("flat.vtk")).unwrap();
    for p in &mut m.positions {
        *p = match kind {
            "cap" => {
                let (r, phi) = (p.x.hypot(p.y), p.y.atan2(p.x));
                let t = r * std::f64::consts::FRAC_PI_3;
                Vec3::new(t.sin() * phi.cos(), t.sin() * phi.sin(), t.cos())
            }
            _ => {
                let rad = 2.0 / std::f64::consts::PI;
                let t = p.x / rad;
                Vec3::new(rad * t.sin(), p.y, rad * t.cos())
            }
        };
    }
    let path = dir.join(format!("{kind}.vtk"));
    write_mesh(&path, &m, Format::VtkAscii, kind).unwrap();
    path
}

/// Runs a static growth by `s` with `law` on `mesh` at thickness `h`: the final frame, the
/// reference and the summary's total energy (J).
fn grow(dir: &Path, mesh: &Path, law: &str, h: Real, tag: &str) -> (shellsim::mesh::Mesh, Real) {
    let s = (0.9f64).ln();
    grow_with(dir, mesh, &format!("law = \"{law}\"\ns = {s:?}\n"), h, tag)
}

/// Runs a static scene with the `[growth]` keys `growth` on `mesh` at thickness `h`: the final
/// frame and the summary's total energy (J).
fn grow_with(
    dir: &Path,
    mesh: &Path,
    growth: &str,
    h: Real,
    tag: &str,
) -> (shellsim::mesh::Mesh, Real) {
    let settings = dir.join(format!("{tag}.toml"));
    std::fs::write(
        &settings,
        format!("[material]\nyoung = 1e6\npoisson = 0.3\nthickness = {h}\n[growth]\n{growth}"),
    )
    .unwrap();
    let out = dir.join(tag);
    shellsim(
        &[
            settings.to_str().unwrap(),
            mesh.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "-q",
        ],
        dir,
    );
    let sum: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(sum["converged"], true, "{tag}");
    let last = out.join(sum["final_frame"].as_str().unwrap());
    let energy = sum["energy"]["total"].as_f64().unwrap();
    (read_mesh(&last).unwrap(), energy)
}

/// The smallest and largest ratio of an edge's length in `m` to its length in `reference`.
fn edge_ratios(reference: &shellsim::mesh::Mesh, m: &shellsim::mesh::Mesh) -> (Real, Real) {
    let (mut lo, mut hi) = (Real::INFINITY, 0.0 as Real);
    for f in &reference.faces {
        for k in 0..3 {
            let (i, j) = (f[k], f[(k + 1) % 3]);
            let r = (m.positions[i] - m.positions[j]).norm()
                / (reference.positions[i] - reference.positions[j]).norm();
            lo = lo.min(r);
            hi = hi.max(r);
        }
    }
    (lo, hi)
}

/// Uniform volumetric growth by s = ln 0.9 of a cap (h/R = 0.05) and of a cylindrical panel
/// (h/R = 0.08), run from the reference shape: every edge shrinks to 0.9 of its length (to
/// 1e-9, the solver's tolerance), the thickness field is 0.9 h on every face, and the energy is
/// below 1e-12 of E h R², the energy scale. The same holds for the thermal shrink law heated
/// uniformly to where its table shrinks every direction, the thickness included, by 10%. The
/// in-plane law at fixed thickness keeps an energy that grows with h/R on the same cap.
#[test]
fn volumetric_growth_of_curved_shells_is_a_scaled_copy() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let heated = "law = \"thermal_shrink\"\nshrink = [[300, 0, 0, 0], [400, 0.2, 0.2, 0.2]]\n\
                  temperature_top = 350\ntemperature_bottom = 350\n";
    for (kind, h, size, law) in [
        ("cap", 0.05, 1.0, "isotropic"),
        ("cylinder", 0.05, 2.0 / std::f64::consts::PI, "isotropic"),
        ("cap", 0.05, 1.0, "thermal_shrink"),
    ] {
        let mesh = curved(d, kind);
        let reference = read_mesh(&mesh).unwrap();
        let tag = format!("{kind}_{law}");
        let (m, e) = if law == "isotropic" {
            grow(d, &mesh, law, h, &tag)
        } else {
            grow_with(d, &mesh, heated, h, &tag)
        };
        let (lo, hi) = edge_ratios(&reference, &m);
        let thick = &m.face_fields["thickness"].data;
        let scale = 1e6 * h * size * size;
        println!(
            "{kind}, {law}: edge ratios {lo:.12}–{hi:.12}, thickness \
             {:.12}–{:.12}, energy {e:.3e} J ({:.1e} of E h R²)",
            thick.iter().copied().fold(Real::INFINITY, Real::min),
            thick.iter().copied().fold(0.0, Real::max),
            e / scale
        );
        assert!(
            (lo - 0.9).abs() < 1e-9 && (hi - 0.9).abs() < 1e-9,
            "{lo} {hi}"
        );
        // Frames store this field in single precision.
        assert!(
            thick.iter().all(|t| (t / (0.9 * h) - 1.0).abs() < 1e-7),
            "{thick:?}"
        );
        assert!(e.abs() < 1e-12 * scale, "{e}");
    }
    // The in-plane law on the cap: frustrated, the more so the thicker the shell.
    let mesh = curved(d, "cap");
    let reference = read_mesh(&mesh).unwrap();
    let mut last = 0.0;
    for h in [0.02, 0.05, 0.1] {
        let (m, e) = grow(d, &mesh, "isotropic_in_plane", h, &format!("in_plane_{h}"));
        let (lo, hi) = edge_ratios(&reference, &m);
        println!("cap, in-plane growth, h/R = {h}: edge ratios {lo:.5}–{hi:.5}, energy {e:.4e} J");
        assert!(m.face_fields["thickness"]
            .data
            .iter()
            .all(|&t| (t / h - 1.0).abs() < 1e-7));
        assert!(
            e > 1e-6 * 1e6 * h && e > 2.0 * last,
            "h {h}: energy {e} after {last}"
        );
        last = e;
    }
}

/// The scaled copy itself, evaluated in-process at dial 1 for every bending model: under uniform
/// volumetric growth its energy and gradient vanish to round-off (energy below 1e-24 of
/// E h R², every gradient entry below 1e-12 of E h R); under in-plane growth at fixed thickness
/// and under seed 000's printed law they do not.
#[test]
fn the_scaled_copy_is_the_rest_state_of_volumetric_growth_only() {
    use shellsim::assembly::{Pattern, Want};
    use shellsim::energy::Potential;
    use shellsim::model::Scene;
    use shellsim::settings::Settings;
    let dir = tempfile::tempdir().unwrap();
    let mesh = curved(dir.path(), "cap");
    let h = 0.05;
    let s = (0.9f64).ln();
    for bending in ["midedge_sin", "midedge_tan", "midedge_average", "none"] {
        for law in ["isotropic", "isotropic_in_plane", "isotropic_metric_only"] {
            let text = format!(
                "[material]\nyoung = 1e6\nthickness = {h}\nbending = \"{bending}\"\n\
                 [growth]\nlaw = \"{law}\"\ns = {s:?}\n"
            );
            let settings = Settings::from_str_with(&text, "growth", &[]).unwrap();
            let scene = Scene::build(read_mesh(&mesh).unwrap(), settings).unwrap();
            let pattern = Pattern::for_scene(&scene);
            let pot = Potential {
                dial: 1.0,
                ..Potential::new(&scene, &pattern)
            };
            let x: Vec<Vec3> = scene.body.mesh.positions.iter().map(|p| p * 0.9).collect();
            let phi = vec![0.0; scene.body.num_edge_dofs()];
            let mut g = vec![0.0; pattern.n];
            let e = pot.eval(&x, &phi, Want::Gradient, &mut g, &mut []);
            let gmax = g.iter().fold(0.0 as Real, |m, v| m.max(v.abs()));
            let (escale, gscale) = (1e6 * h, 1e6 * h);
            println!("{bending}, {law}: energy {e:.3e} J, largest gradient entry {gmax:.3e}");
            if law == "isotropic" {
                assert!(e.abs() < 1e-24 * escale, "{bending}: {e}");
                assert!(gmax < 1e-12 * gscale, "{bending}: {gmax}");
            } else if bending != "none" {
                assert!(e > 1e-9 * escale, "{bending} {law}: {e}");
            }
        }
    }
}

/// A growth law without its field, or with a key of another law's or out of range, is refused
/// (exit 2, the key named, nothing written).
#[test]
fn growth_laws_need_their_fields() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    shellsim(
        &[
            "mesh", "disk", "--radius", "1", "--edge", "0.3", "-o", "d.vtk",
        ],
        d,
    );
    for (text, needles) in [
        ("law = \"isotropic\"", &["growth.s", "growth_factor"][..]),
        ("law = \"isotropic_in_plane\"", &["growth.s"][..]),
        ("law = \"isotropic_metric_only\"", &["growth.s"][..]),
        (
            "law = \"linear_swelling\"\nmoisture_top = 0.1",
            &["growth.mu", "linear_swelling"][..],
        ),
        (
            "law = \"bilayer\"\nmu_top = 0.1",
            &["growth.mu_bottom", "bilayer"][..],
        ),
        (
            "law = \"machine_direction\"\nmu = 0.1",
            &["growth.mu_perp", "machine_direction"][..],
        ),
        // A layer's coefficient across the machine direction belongs to the bilayer, and not
        // to layers that grow through their thickness too.
        (
            "law = \"machine_direction\"\nmu = 0.1\nmu_perp = 0.1\nmu_top_perp = 0.1",
            &["growth.mu_top_perp", "bilayer"][..],
        ),
        (
            "law = \"bilayer\"\nmu_top = 0.1\nmu_bottom = 0.0\nmu_bottom_perp = 0.1\n\
             isotropic_layers = true",
            &["growth.mu_bottom_perp", "isotropic_layers"][..],
        ),
        (
            "law = \"bilayer\"\nmu_top = 0.1\nmu_bottom = 0.0\nmu_top_perp = inf",
            &["growth.mu_top_perp"][..],
        ),
    ] {
        std::fs::write(d.join("g.toml"), format!("[growth]\n{text}\n")).unwrap();
        let (code, _, err) = run_status(&["g.toml", "d.vtk", "--out", "o", "-q"], d);
        assert_eq!(code, 2, "{text}: {err}");
        for n in needles {
            assert!(err.contains(n), "{text}: {err}");
        }
        assert!(!d.join("o").exists(), "{text}: wrote output");
    }
}

/// A bilayer strip whose layers swell only along a machine direction at 30° to its length,
/// the top by `ε` and the bottom by `−ε`, coils into a helix: the rest forms are exactly
/// `ā = I + ((g⁺ + g⁻)/2 − 1) d dᵀ` and `b̄ = 3(g⁺ − g⁻)/(4h) d dᵀ` (`g± = (1 ± ε)²`, equal
/// layers), a curvature along `d` alone that the flat metric admits up to `O(ε²)`, so the strip
/// wraps onto a cylinder of radius `ā_dd/b̄_dd` with `d` around it, away from the swelling top.
/// On a 2 × 0.2 strip (h = 0.01, ε = 0.01: radius 1/3, 0.8 turn) the equilibrium is that helix
/// to 3.0e-3 of the strip's size at edge 0.1 (80 faces) and 7.1e-4 at edge 0.05 (320 faces):
/// second order, the discrete bending's error. The test asks for 1e-3 on the finer strip and an
/// error ratio above 3. The same strip with the layers along x lands 14% away (a ring, not a
/// helix).
#[test]
fn anisotropic_bilayer_strip_coils_into_its_helix() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (h, eps): (Real, Real) = (0.01, 0.01);
    let (gp, gm) = ((1.0 + eps).powi(2), (1.0 - eps).powi(2));
    let (add, bdd) = ((gp + gm) / 2.0, 3.0 * (gp - gm) / (4.0 * h));
    let radius = add / bdd;
    let angle = 30f64.to_radians();
    let mut off = Vec::new();
    for (edge, dir3) in [
        ("0.1", "[0.8660254037844386, 0.5, 0]"),
        ("0.05", "[0.8660254037844386, 0.5, 0]"),
        ("0.1", "[1, 0, 0]"),
    ] {
        let name = format!("strip_{edge}.vtk");
        shellsim(
            &[
                "mesh",
                "rectangle",
                "--lx",
                "2",
                "--ly",
                "0.2",
                "--edge",
                edge,
                "-o",
                &name,
            ],
            d,
        );
        let mesh = read_mesh(&d.join(&name)).unwrap();
        // The helix: each vertex's coordinate along d stretched by √ā_dd and wrapped.
        let helix: Vec<Vec3> = mesh
            .positions
            .iter()
            .map(|p| {
                let u = (p.x * angle.cos() + p.y * angle.sin()) * add.sqrt();
                let v = -p.x * angle.sin() + p.y * angle.cos();
                Vec3::new(
                    radius * (u / radius).sin(),
                    v,
                    -radius * (1.0 - (u / radius).cos()),
                )
            })
            .collect();
        let growth = format!(
            "law = \"bilayer\"\nmu_top = {eps}\nmu_top_perp = 0.0\nmu_bottom = {}\n\
             mu_bottom_perp = 0.0\nmoisture_top = 1.0\nmoisture_bottom = 1.0\n\
             machine_direction = {dir3}\n[solver]\nmode = \"static\"\n",
            -eps
        );
        let (m, _) = grow_with(d, &d.join(&name), &growth, h, &format!("run{}", off.len()));
        let pts = shellsim::design::objective::Points::new(&mesh, helix, true);
        off.push(shellsim::design::objective::Points::relative_rms(
            pts.eval(&m.positions).value,
        ));
    }
    println!(
        "helix at edge 0.1, 0.05: {:.3e}, {:.3e}; layers along x: {:.3e}",
        off[0], off[1], off[2]
    );
    assert!(off[1] < 1e-3 && off[0] / off[1] > 3.0, "{off:?}");
    assert!(off[2] > 0.1, "{off:?}");
}
