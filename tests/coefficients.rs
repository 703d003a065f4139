//! Per-face coefficients and softening, through the binary: swelling coefficients on regions
//! and from face fields reach exactly the faces they name, the thickness grows with the moisture
//! through `mu_through`, diffusivities on regions make each region follow its own slab series,
//! softening with temperature or moisture scales a cantilever's sag as the closed form says, and
//! bad coefficients are refused naming the key, field or face.

mod common;

use common::{finite_frames, run_settings as run, run_status, shellsim, summary};
use shellsim::math::Real;
use std::path::Path;

/// Writes `s.vtk`, a rectangle `lx` × 1 cm with edges `edge` (m), centred on the origin.
fn rectangle(dir: &Path, lx: Real, edge: Real) {
    let (lx, edge) = (lx.to_string(), edge.to_string());
    shellsim(
        &[
            "mesh",
            "rectangle",
            "--lx",
            &lx,
            "--ly",
            "0.01",
            "--edge",
            &edge,
            "-o",
            "s.vtk",
        ],
        dir,
    );
}

/// The face centroids' x of mesh `m`.
fn centroid_x(m: &shellsim::mesh::Mesh, f: usize) -> Real {
    m.faces[f].iter().map(|&v| m.positions[v].x).sum::<Real>() / 3.0
}

/// A flat 2 × 1 cm sheet swollen uniformly (m = 0.2 on both faces, μ = 0.05) with a region
/// (x < 0, a box) of μ = 0.1 and a face field `growth_mu` of 0.02 on the faces with x > 0.005:
/// each face's rest metric ā (the frames' `abar`, reference Cartesian) is (1 + μ m)² times its
/// reference one with its own μ, to 1e-6 (frames store single precision); the field, given on
/// every face (0.05 where it does not say 0.02), overrides the region, and without it the region
/// overrides the uniform value. With `mu_through = 0.5` every face's thickness is
/// h (1 + 0.5 × 0.2) = 1.1 h.
#[test]
fn swelling_coefficients_on_regions_and_face_fields_reach_their_faces() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    rectangle(d, 0.02, 0.002);
    let mut m = shellsim::mesh::io::read_mesh(&d.join("s.vtk")).unwrap();
    let mu_field: Vec<Real> = (0..m.faces.len())
        .map(|f| {
            if centroid_x(&m, f) > 0.005 {
                0.02
            } else {
                0.05
            }
        })
        .collect();
    m.face_fields.insert(
        "growth_mu".into(),
        shellsim::mesh::Field::scalar(mu_field.clone()),
    );
    shellsim::mesh::io::write_mesh(
        &d.join("f.vtk"),
        &m,
        shellsim::mesh::io::Format::VtkAscii,
        "fields",
    )
    .unwrap();
    let settings = "[material]\nyoung = 1e6\npoisson = 0.3\nthickness = 1e-4\n[growth]\n\
                    law = \"linear_swelling\"\nmu = 0.05\nmu_through = 0.5\nmoisture_top = 0.2\n\
                    moisture_bottom = 0.2\n[[growth.regions]]\n\
                    inside = { min = [-1, -1, -1], max = [0, 1, 1] }\nmu = 0.1\n";
    let frames = run(d, "regions", settings, "f.vtk");
    let last = frames.last().unwrap();
    let abar = &last.face_fields["abar"];
    let thick = &last.face_fields["thickness"].data;
    let (mut seen_region, mut seen_field) = (0, 0);
    for (f, thick_f) in thick.iter().enumerate() {
        // The face field wins over the region and the uniform value.
        let mu: Real = if centroid_x(&m, f) > 0.005 {
            seen_field += 1;
            0.02
        } else if centroid_x(&m, f) <= 0.0 {
            seen_region += 1;
            0.05
        } else {
            0.05
        };
        let s2 = (1.0 + mu * 0.2 as Real).powi(2);
        let a = abar.get(f);
        // A flat reference in the xy plane: ā's Cartesian form is s² I.
        assert!(
            (a[0] - s2).abs() < 1e-6 && a[1].abs() < 1e-6 && (a[2] - s2).abs() < 1e-6,
            "face {f}: abar {a:?} against {s2}"
        );
        assert!((thick_f / 1.1e-4 - 1.0).abs() < 1e-6, "face {f}: {thick_f}");
    }
    assert!(seen_region > 0 && seen_field > 0);
    // Without the field, the region's μ = 0.1 holds on x < 0.
    let frames = run(d, "region_only", settings, "s.vtk");
    let last = frames.last().unwrap();
    let abar = &last.face_fields["abar"];
    for f in 0..m.faces.len() {
        let mu: Real = if centroid_x(&m, f) <= 0.0 { 0.1 } else { 0.05 };
        let a = abar.get(f);
        let s2 = (1.0 + mu * 0.2 as Real).powi(2);
        assert!((a[0] - s2).abs() < 1e-6, "face {f}: {a:?} against {s2}");
    }
}

/// A 1 mm sheet exchanging moisture through both faces (Robin, k = 1e-6 m/s, ambient 0.3) whose
/// left half (a region) has 4× the through-thickness diffusivity: with the lateral diffusivity
/// negligible each half's surface moisture follows Crank's series at its own Biot number
/// `k l/D` and time `D t/l²` (l the half-thickness), within 1e-3 of the ambient at every frame;
/// the two halves differ by far more than that.
#[test]
fn diffusivities_on_regions_make_each_region_follow_its_own_series() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    rectangle(d, 0.02, 0.002);
    let (k, l, d_slow) = (1e-6, 5e-4, 1e-9);
    let settings = format!(
        "[material]\nyoung = 1e6\nthickness = 1e-3\n[growth]\nlaw = \"linear_swelling\"\n\
         mu = 0.0\n[moisture]\nenabled = true\ndiffusivity_along = 1e-16\n\
         diffusivity_across = 1e-16\ndiffusivity_through = {d_slow:e}\n\
         [[moisture.regions]]\ninside = {{ min = [-1, -1, -1], max = [0, 1, 1] }}\n\
         diffusivity_through = {:e}\n\
         [[moisture.boundary]]\nside = \"top\"\nkind = \"robin\"\nk = {k:e}\nambient = 0.3\n\
         [[moisture.boundary]]\nside = \"bottom\"\nkind = \"robin\"\nk = {k:e}\nambient = 0.3\n\
         [solver]\nmode = \"dynamic\"\n[time]\ndt = 1\ndt_max = 50\nend = 200\n\
         output_interval = 50\n",
        4.0 * d_slow
    );
    let frames = run(d, "slab", &settings, "s.vtk");
    let m = &frames[0];
    let mut worst: Real = 0.0;
    let mut apart: Real = 0.0;
    for (i, fr) in frames.iter().enumerate().skip(1) {
        let t = 50.0 * i as Real;
        let top = &fr.face_fields["moisture_top"].data;
        let mut means = [0.0; 2];
        for (f, &top_f) in top.iter().enumerate() {
            let fast = centroid_x(m, f) <= 0.0;
            // Faces on the border between the halves mix both; skip them.
            if centroid_x(m, f).abs() < 0.002 {
                continue;
            }
            let dd = if fast { 4.0 * d_slow } else { d_slow };
            let expect =
                0.3 * shellsim::diffusion::robin_slab_surface(k * l / dd, dd * t / (l * l));
            worst = worst.max((top_f - expect).abs() / 0.3);
            means[usize::from(fast)] = expect;
        }
        apart = apart.max((means[1] - means[0]).abs() / 0.3);
    }
    println!("regions: worst error {worst:.2e} of the ambient, the halves {apart:.2e} apart");
    assert!(worst < 1e-3 && apart > 20.0 * worst, "{worst} {apart}");
}

/// A strip clamped at one end (two rows of vertices) sags under gravity; at a uniform temperature of 350 K with the
/// softening table [[300 K, 1], [400 K, 0.5]] (factor 0.75), and at a uniform moisture of 0.1
/// with [[0, 1], [0.2, 0.5]] (factor 0.75), its tip sags 1/0.75 times as far as at 300 K, and
/// 1.1/0.75 times as far as when dry (the water's mass, 1000 kg/m³ × 0.1, adds 10%): small
/// deflections, linear in weight/E, to 1e-3 (measured 1.3e-4).
#[test]
fn softening_scales_a_cantilevers_sag_as_its_modulus() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    rectangle(d, 0.1, 0.005);
    let head = common::SAGGING_CANTILEVER;
    let sag = |name: &str, extra: &str| -> Real {
        let frames = run(d, name, &format!("{head}{extra}"), "s.vtk");
        let last = frames.last().unwrap();
        -last
            .positions
            .iter()
            .map(|p| p.z)
            .fold(Real::INFINITY, Real::min)
    };
    let heat = |t: Real| {
        format!(
            "[growth]\nlaw = \"thermal_shrink\"\nshrink = [[300, 0, 0], [400, 0, 0]]\n\
             [temperature]\nenabled = true\ninitial = {t}\n\
             softening = [[300, 1], [400, 0.5]]\n"
        )
    };
    let wet = |m: Real| {
        format!(
            "[growth]\nlaw = \"linear_swelling\"\nmu = 0\n[moisture]\nenabled = true\n\
             initial = {m}\nsoftening = [[0, 1], [0.2, 0.5]]\n"
        )
    };
    // The absorbed water (1000 kg/m³ × 0.1) makes the wet strip 10% heavier, too.
    for (what, cold, warm, expect) in [
        (
            "temperature",
            sag("cold", &heat(300.0)),
            sag("warm", &heat(350.0)),
            1.0 / 0.75,
        ),
        (
            "moisture",
            sag("dry", &wet(0.0)),
            sag("wet", &wet(0.1)),
            1.1 / 0.75,
        ),
    ] {
        let ratio = warm / cold;
        println!("{what}: tip sag {cold:.6e} → {warm:.6e} m, ratio {ratio:.6} against {expect:.6}");
        assert!(cold > 1e-4 && cold < 2e-3, "{what}: sag {cold}");
        assert!((ratio / expect - 1.0).abs() < 1e-3, "{what}: {ratio}");
    }
}

/// Bad per-face coefficients and softening tables are exit 2 naming the key, field or face.
#[test]
fn bad_coefficients_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    rectangle(d, 0.02, 0.005);
    let mut m = shellsim::mesh::io::read_mesh(&d.join("s.vtk")).unwrap();
    for (name, v) in [("inf.vtk", Real::INFINITY), ("big.vtk", 1e6)] {
        let mut bad = vec![0.01; m.faces.len()];
        bad[3] = v;
        m.face_fields
            .insert("growth_mu".into(), shellsim::mesh::Field::scalar(bad));
        shellsim::mesh::io::write_mesh(
            &d.join(name),
            &m,
            shellsim::mesh::io::Format::VtkAscii,
            "bad",
        )
        .unwrap();
    }
    let swell = "[material]\nthickness = 1e-3\n[growth]\nlaw = \"linear_swelling\"\nmu = 0.01\n";
    let moist = "[solver]\nmode = \"dynamic\"\n[moisture]\nenabled = true\n";
    for (what, settings, mesh, needle) in [
        // The reader refuses it, naming the line and the field.
        (
            "a non-finite face field",
            swell.to_string(),
            "inf.vtk",
            "'growth_mu'",
        ),
        (
            "a face field out of range",
            swell.to_string(),
            "big.vtk",
            "at face 3",
        ),
        (
            "a region without tags or a box",
            format!("{swell}[[growth.regions]]\nmu = 0.1\n"),
            "s.vtk",
            "growth.regions[0]",
        ),
        (
            "a non-finite region coefficient",
            format!("{swell}[[growth.regions]]\ntags = [1]\nmu = inf\n"),
            "s.vtk",
            "growth.regions[0].mu",
        ),
        (
            "a negative diffusivity on a region",
            format!(
                "{swell}{moist}[[moisture.regions]]\ntags = [1]\ndiffusivity_through = -1e-9\n"
            ),
            "s.vtk",
            "moisture.regions[0].diffusivity_through",
        ),
        (
            "a softening table that goes back",
            format!("{swell}{moist}softening = [[0, 1], [0.2, 0.5], [0.1, 0.4]]\n"),
            "s.vtk",
            "moisture.softening[2]",
        ),
        (
            "a softening factor of zero",
            format!("{swell}{moist}softening = [[0, 1], [0.2, 0]]\n"),
            "s.vtk",
            "moisture.softening[1]",
        ),
    ] {
        std::fs::write(d.join("b.toml"), &settings).unwrap();
        let (code, _, err) = run_status(&["b.toml", mesh, "--out", "o", "-q"], d);
        assert_eq!(code, 2, "{what}: {err}");
        assert!(err.contains(needle), "{what}: {err}");
        assert!(!d.join("o").exists(), "{what}: wrote output");
    }
}

/// A wet sheet (moisture 0.5, a leaf's water by volume) drying through both faces into dry air
/// loses mass: `log.csv`'s `mass` column falls every frame and equals the dry mass plus the
/// water the frame's surface moistures hold, `ρ V + ρ_w Σ A h (m⁺ + m⁻)/2` (the lumped masses'
/// own sum), to 1e-6 (frames store single precision).
#[test]
fn a_drying_sheet_loses_mass_and_the_log_reports_it() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    rectangle(d, 0.02, 0.002);
    let (h, rho) = (2e-4, 500.0);
    let settings = format!(
        "[material]\nyoung = 1e7\nthickness = {h}\ndensity = {rho}\n[growth]\n\
         law = \"linear_swelling\"\nmu = 0.02\n[moisture]\nenabled = true\ninitial = 0.5\n\
         diffusivity_through = 1e-10\n\
         [[moisture.boundary]]\nside = \"top\"\nkind = \"robin\"\nk = 1e-6\nambient = 0\n\
         [[moisture.boundary]]\nside = \"bottom\"\nkind = \"robin\"\nk = 1e-6\nambient = 0\n\
         [solver]\nmode = \"dynamic\"\n[time]\ndt = 0.1\ndt_max = 20\nend = 200\n\
         output_interval = 50\ndamping = 0.1\n"
    );
    let frames = run(d, "dry", &settings, "s.vtk");
    let rows = common::log_rows(&d.join("dry"));
    assert_eq!(rows.len(), frames.len());
    let m0 = &frames[0];
    let area: Vec<Real> = (0..m0.faces.len()).map(|f| m0.face_area(f)).collect();
    let dry = rho * h * area.iter().sum::<Real>();
    let mut last = Real::INFINITY;
    for (row, fr) in rows.iter().zip(&frames) {
        let (top, bottom) = (
            &fr.face_fields["moisture_top"].data,
            &fr.face_fields["moisture_bottom"].data,
        );
        let water: Real = (0..area.len())
            .map(|f| 1000.0 * area[f] * h * 0.5 * (top[f] + bottom[f]))
            .sum();
        let mass = row["mass"];
        println!(
            "t {:6.1} s: mass {mass:.6e} kg, dry {dry:.6e} + water {water:.6e}",
            row["time"]
        );
        assert!(
            (mass / (dry + water) - 1.0).abs() < 1e-6,
            "{mass} against {}",
            dry + water
        );
        assert!(
            mass < last || row["time"] == 0.0,
            "mass {mass} after {last}"
        );
        last = mass;
    }
    assert!(last < dry + 0.9 * 1000.0 * 0.5 * h * area.iter().sum::<Real>());
}

/// Losing more water than the material holds is diagnosed: an initial moisture that leaves the
/// sheet without mass is exit 2 naming the key, with nothing written, and a sheet dried past it
/// stops with exit 1, the reason naming the vertex, and finite frames up to there.
#[test]
fn water_loss_past_the_dry_mass_is_diagnosed() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    rectangle(d, 0.02, 0.005);
    let scene = |initial: Real, ambient: Real| {
        format!(
            "[material]\nyoung = 1e7\nthickness = 2e-4\ndensity = 500\n[growth]\n\
             law = \"linear_swelling\"\nmu = 0.01\n[moisture]\nenabled = true\n\
             initial = {initial}\ndiffusivity_through = 1e-10\n\
             [[moisture.boundary]]\nside = \"top\"\nkind = \"robin\"\nk = 1e-5\n\
             ambient = {ambient}\n[solver]\nmode = \"dynamic\"\n[time]\ndt = 0.1\n\
             dt_max = 10\nend = 400\noutput_interval = 50\n"
        )
    };
    std::fs::write(d.join("a.toml"), scene(-0.6, 0.0)).unwrap();
    let (code, _, err) = run_status(&["a.toml", "s.vtk", "--out", "a", "-q"], d);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("moisture.initial") && err.contains("mass"),
        "{err}"
    );
    assert!(!d.join("a").exists(), "wrote output");
    std::fs::write(d.join("b.toml"), scene(0.0, -2.0)).unwrap();
    let (code, _, err) = run_status(&["b.toml", "s.vtk", "--out", "b", "-q"], d);
    assert_eq!(code, 1, "{err}");
    let reason = summary(&d.join("b"))["reason"]
        .as_str()
        .unwrap()
        .to_string();
    assert!(
        reason.contains("vertex") && reason.contains("mass"),
        "{reason}"
    );
    finite_frames(&d.join("b"), "vtu", "dried past");
}
