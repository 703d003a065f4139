//! Heat conduction and the thermal shrink law, through the binary: the surface temperatures of
//! a slab heated by a flux or exchanging with hot air against Carslaw & Jaeger's series, the
//! curvature of a plate heated on one face against the linear-profile closed form, the ratchet
//! (cooling and reheating below the highest temperature change nothing), a moving source's
//! delivered heat and its path, the heated spoon scene, and bad temperature input.

mod common;

use common::{converged_frames, run_settings as run, run_status, shellsim};
use shellsim::math::Real;
use std::f64::consts::PI;
use std::path::Path;

/// Polypropylene as the `[temperature]` defaults assume it (W/(m·K), kg/m³, J/(kg·K)) and the
/// sheet's thickness (m).
const K: Real = 0.22;
const RHO: Real = 900.0;
const C: Real = 1900.0;
const H: Real = 1e-3;

/// A dynamic scene on a 1 cm square sheet of polypropylene, 1 mm thick, with `extra` appended.
fn scene(extra: &str) -> String {
    format!(
        "[material]\nyoung = 1.5e9\npoisson = 0.4\nthickness = {H}\ndensity = {RHO}\n\
         [solver]\nmode = \"dynamic\"\n[growth]\nlaw = \"thermal_shrink\"\n{extra}"
    )
}

/// The face-mean of a frame's face field.
fn mean(m: &shellsim::mesh::Mesh, field: &str) -> Real {
    let d = &m.face_fields[field].data;
    d.iter().sum::<Real>() / d.len() as Real
}

/// A slab `0 < x < l` insulated at 0 and heated by a flux F at `x = l` from T0
/// (Carslaw & Jaeger 1959, §3.3 (ii), Eq. 3): the temperature rise at `x`,
/// `F t/(ρ c l) + F l/k [(3x² − l²)/(6l²) − (2/π²) Σ (−1)ⁿ/n² exp(−κ n² π² t/l²) cos(nπx/l)]`.
fn flux_slab(x: Real, t: Real, f: Real) -> Real {
    let (l, kappa) = (H, K / (RHO * C));
    let series: Real = (1..4000)
        .map(|n| {
            let n = n as Real;
            (if n as i64 % 2 == 0 { 1.0 } else { -1.0 }) / (n * n)
                * (-kappa * n * n * PI * PI * t / (l * l)).exp()
                * (n * PI * x / l).cos()
        })
        .sum();
    f * t / (RHO * C * l)
        + f * l / K * ((3.0 * x * x - l * l) / (6.0 * l * l) - 2.0 / (PI * PI) * series)
}

/// The surface temperatures of a 1 mm sheet against Carslaw & Jaeger's series at the default
/// `[temperature]` resolution: heated on top by 1000 W/m² with the bottom insulated (§3.3), and
/// exchanging through both faces with air at 100 K above it, h = 440 W/(m²·K) (Biot number
/// h l/k = 1 on the half-thickness l; §3.11, the series of `diffusion::robin_slab_surface`).
/// Every frame's surface temperatures (every face alike) lie within 1e-3 of the rise of the
/// series (measured: 1.04e-4 and 5.9e-5 at most); the bar is 1%.
#[test]
fn heat_conduction_matches_carslaw_and_jaeger_with_flux_and_robin_conditions() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    shellsim(
        &[
            "mesh", "square", "--edge", "0.002", "--size", "0.01", "-o", "sq.vtk",
        ],
        d,
    );
    let t0 = 293.15;
    let flux = run(
        d,
        "flux",
        &scene(
            "shrink = [[293.15, 0, 0], [400, 0, 0]]\n[time]\ndt = 0.5\ndt_max = 1\nend = 10\n\
             output_interval = 1\n[temperature]\nenabled = true\n[[temperature.boundary]]\n\
             side = \"top\"\nkind = \"flux\"\nvalue = 1000\n",
        ),
        "sq.vtk",
    );
    let mut worst: Real = 0.0;
    for (i, m) in flux.iter().enumerate().skip(1) {
        let t = i as Real;
        let rise = flux_slab(H, t, 1000.0);
        for (field, x) in [("temperature_top", H), ("temperature_bottom", 0.0)] {
            let d = &m.face_fields[field].data;
            let spread = d.iter().fold(0.0, |a: Real, v| a.max((v - d[0]).abs()));
            assert!(
                spread < 1e-9 * t0,
                "{field} varies over the faces by {spread}"
            );
            let e = (d[0] - t0 - flux_slab(x, t, 1000.0)).abs() / rise;
            worst = worst.max(e);
        }
    }
    println!("flux: largest error of the surface temperatures {worst:.2e} of the rise");
    assert!(worst < 1e-3, "{worst}");
    // Robin on both faces, Bi = 1 on the half-thickness.
    let l = 0.5 * H;
    let h = K / l;
    let robin = run(
        d,
        "robin",
        &scene(&format!(
            "shrink = [[293.15, 0, 0], [400, 0, 0]]\n[time]\ndt = 0.1\ndt_max = 1\nend = 4\n\
             output_interval = 0.5\n[temperature]\nenabled = true\n\
             [[temperature.boundary]]\nside = \"top\"\nkind = \"robin\"\nh = {h}\nambient = 393.15\n\
             [[temperature.boundary]]\nside = \"bottom\"\nkind = \"robin\"\nh = {h}\nambient = 393.15\n"
        )),
        "sq.vtk",
    );
    let kappa = K / (RHO * C);
    let mut worst: Real = 0.0;
    for (i, m) in robin.iter().enumerate().skip(1) {
        let t = 0.5 * i as Real;
        let expect = t0 + 100.0 * shellsim::diffusion::robin_slab_surface(1.0, kappa * t / (l * l));
        for field in ["temperature_top", "temperature_bottom"] {
            worst = worst.max((mean(m, field) - expect).abs() / 100.0);
        }
    }
    println!("robin: largest error of the surface temperatures {worst:.2e} of the 100 K step");
    assert!(worst < 1e-3, "{worst}");
}

/// A free plate heated on its top by air at 393.15 K and cooled below by air at 293.15 K
/// (h = 10⁴ W/(m²·K) on both, so the steady profile is linear between surfaces a few kelvin
/// inside the air temperatures), with a shrink of 0.05% per 100 K: once steady it is a
/// spherical cap (κL²/h = 0.05) whose curvature is the linear profile's rest curvature
/// `s₀s₁/(s₀² + s₁²h²/12)`, `s₀ = 1 − (ε⁺ + ε⁻)/2`, `s₁ = −(ε⁺ − ε⁻)/h`, from the surfaces'
/// highest temperatures, concave on the hot side (measured: 1.0e-5 apart; the corners rise
/// as the sphere's to 1e-4). Cooling the top back to 293.15 K and
/// reheating it to 373.15 K (below the maximum) leave the shape: the reheated plate's frames are
/// the cooled plate's to 1e-9 (highest temperatures and curvature alike), and cooling moved the
/// curvature by less than 5e-4 of itself (the quadratic layers have no discrete maximum
/// principle: cooling overshoots the highest interior temperatures by about 0.01 K; measured
/// 2.3e-4).
#[test]
fn a_plate_heated_on_one_face_curves_as_the_linear_profile_says_and_reheating_changes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    shellsim(
        &[
            "mesh", "square", "--edge", "0.002", "--size", "0.01", "-o", "sq.vtk",
        ],
        d,
    );
    let air = |side: &str, t: Real, window: &str| {
        format!(
            "[[temperature.boundary]]\nside = \"{side}\"\nkind = \"robin\"\nh = 1e4\n\
             ambient = {t}\n{window}"
        )
    };
    let settings = scene(&format!(
        "shrink = [[293.15, 0, 0], [393.15, 0.0005, 0.0005]]\n[time]\ndt = 0.5\ndt_max = 2\n\
         end = 200\noutput_interval = 20\n[temperature]\nenabled = true\n{}{}{}{}",
        air("bottom", 293.15, ""),
        air("top", 393.15, "until = 60\n"),
        air("top", 293.15, "from = 60\nuntil = 120\n"),
        air("top", 373.15, "from = 120\n"),
    ));
    let frames = run(d, "plate", &settings, "sq.vtk");
    assert_eq!(frames.len(), 11);
    let kappa = |m: &shellsim::mesh::Mesh| mean(m, "mean_curvature");
    // Steady at t = 60 (frame 3): the closed form from the surfaces' highest temperatures.
    let hot = &frames[3];
    let eps = |t: Real| 0.0005 * (t - 293.15) / 100.0;
    let (et, eb) = (
        eps(mean(hot, "temperature_max_top")),
        eps(mean(hot, "temperature_max_bottom")),
    );
    let (s0, s1) = (1.0 - 0.5 * (et + eb), -(et - eb) / H);
    let expect = s0 * s1 / (s0 * s0 + s1 * s1 * H * H / 12.0);
    let got = kappa(hot);
    println!(
        "heated plate: surfaces {:.3} / {:.3} K, curvature {got:.6} 1/m, closed form {expect:.6}",
        mean(hot, "temperature_max_top"),
        mean(hot, "temperature_max_bottom")
    );
    assert!(
        (got - expect).abs() < 5e-4 * expect.abs(),
        "{got} against {expect}"
    );
    // Concave on the hot (top, +z) side: the corners rise above the middle as a sphere's,
    // by κ Δ(r²)/2.
    let mid = hot.positions.iter().sum::<shellsim::math::Vec3>() / hot.positions.len() as Real;
    let r = |p: &shellsim::math::Vec3| (p.x - mid.x).hypot(p.y - mid.y);
    let by_r = |far: bool| {
        let mut v: Vec<_> = hot.positions.iter().collect();
        v.sort_by(|a, b| r(a).total_cmp(&r(b)));
        if far {
            v.reverse();
        }
        v
    };
    // The four vertices nearest the middle and the four corners: symmetric sets, so a rigid
    // tilt cancels from their mean heights.
    let (near, far) = (&by_r(false)[..4], &by_r(true)[..4]);
    let avg = |v: &[&shellsim::math::Vec3], f: &dyn Fn(&shellsim::math::Vec3) -> Real| {
        v.iter().map(|p| f(p)).sum::<Real>() / 4.0
    };
    let rise = avg(far, &|p| p.z) - avg(near, &|p| p.z);
    let sphere = 0.5 * got.abs() * (avg(far, &|p| r(p).powi(2)) - avg(near, &|p| r(p).powi(2)));
    println!("the corners rise {rise:.4e} m above the middle, κ Δ(r²)/2 = {sphere:.4e} m");
    assert!(
        (rise - sphere).abs() < 1e-3 * sphere,
        "the corners rise by {rise} m"
    );
    // Cooled (frames 4–6) and reheated below the maximum (7–10).
    let cooled = &frames[6];
    let moved = (kappa(cooled) - got).abs() / got.abs();
    println!("cooling moved the curvature by {moved:.2e} of itself");
    assert!(moved < 5e-4, "{moved}");
    for m in &frames[7..] {
        for f in [
            "temperature_max_top",
            "temperature_max_bottom",
            "mean_curvature",
        ] {
            let (a, b) = (&m.face_fields[f].data, &cooled.face_fields[f].data);
            let e = a
                .iter()
                .zip(b)
                .fold(0.0, |w: Real, (x, y)| w.max((x - y).abs()));
            assert!(
                e <= 1e-9 * b[0].abs().max(1.0),
                "{f} changed by {e} on reheating"
            );
        }
    }
    let t_top = mean(&frames[10], "temperature_top");
    assert!(t_top > 360.0 && t_top < 373.15, "reheated top {t_top}");
}

/// A 0.5 W spot (σ = 0.3 mm, on faces of 1 mm) crosses an insulated 2 cm sheet from x = −3 mm to
/// +3 mm in 10 s: the hottest face follows the path (at t = 5 s the hottest top face lies
/// within an edge of x = 0, at 10 s of x = +3 mm) and once the heat has spread the sheet is
/// uniformly `P τ/(ρ c V)` warmer (to 1e-5: the spot's power is integrated over sub-triangles,
/// and the steps end where the source switches off).
#[test]
fn a_moving_source_follows_its_path_and_delivers_its_heat() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    shellsim(
        &[
            "mesh", "square", "--edge", "0.001", "--size", "0.02", "-o", "sq.vtk",
        ],
        d,
    );
    let source = "[[temperature.source]]\nside = \"top\"\npower = 0.5\nradius = 0.0003\n\
                  path = [[0, -0.003, 0, 0], [10, 0.003, 0, 0]]\n";
    let head = "shrink = [[293.15, 0, 0], [400, 0, 0]]\n";
    let frames = run(
        d,
        "path",
        &scene(&format!(
            "{head}[time]\ndt = 0.25\ndt_max = 0.25\nend = 10\noutput_interval = 5\n\
             [temperature]\nenabled = true\nmax_change = 50\n{source}"
        )),
        "sq.vtk",
    );
    for (m, x) in [(&frames[1], 0.0), (&frames[2], 0.003)] {
        let top = &m.face_fields["temperature_top"].data;
        let hottest = (0..top.len())
            .max_by(|&a, &b| top[a].total_cmp(&top[b]))
            .unwrap();
        let c = m.faces[hottest]
            .iter()
            .map(|&v| m.positions[v])
            .sum::<shellsim::math::Vec3>()
            / 3.0;
        assert!(
            (c.x - x).abs() < 1e-3 && c.y.abs() < 1e-3,
            "hottest face at {c:?}, the spot at x = {x}"
        );
    }
    let frames = run(
        d,
        "spread",
        &scene(&format!(
            "{head}[time]\ndt = 0.5\ndt_max = 200\nend = 4000\noutput_interval = 4000\n\
             [temperature]\nenabled = true\nmax_change = 50\n{source}"
        )),
        "sq.vtk",
    );
    let last = frames.last().unwrap();
    let expect = 0.5 * 10.0 / (RHO * C * 0.02 * 0.02 * H);
    for f in ["temperature_top", "temperature_bottom"] {
        let rise = mean(last, f) - 293.15;
        println!("{f}: rise {rise:.6} K against P τ/(ρ c V) = {expect:.6} K");
        assert!(
            (rise / expect - 1.0).abs() < 1e-5,
            "{rise} against {expect}"
        );
    }
}

/// Bad temperature input is exit 2 naming the key, with nothing run.
#[test]
fn bad_temperature_input_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    shellsim(
        &[
            "mesh", "square", "--edge", "0.002", "--size", "0.01", "-o", "sq.vtk",
        ],
        d,
    );
    let on = "[temperature]\nenabled = true\n";
    let table = "shrink = [[293.15, 0, 0], [400, 0.01, 0.01]]\n";
    for (what, extra, key) in [
        (
            "an initial temperature below 0 K",
            format!("{table}{on}initial = -20\n"),
            "temperature.initial",
        ),
        (
            "a Robin air temperature below 0 K",
            format!(
                "{table}{on}[[temperature.boundary]]\nkind = \"robin\"\nh = 10\nambient = -5\n"
            ),
            "temperature.boundary[0].ambient",
        ),
        (
            "temperatures that do not increase",
            format!("shrink = [[293.15, 0, 0], [400, 0.01, 0.01], [380, 0.02, 0.02]]\n{on}"),
            "growth.shrink[2]",
        ),
        (
            "a shrink that reverses",
            format!("shrink = [[293.15, 0, 0], [400, 0.02, 0.02], [420, 0.01, 0.02]]\n{on}"),
            "growth.shrink[2]",
        ),
        (
            "rows of different lengths",
            format!("shrink = [[293.15, 0, 0], [400, 0.02, 0.02, 0.01]]\n{on}"),
            "growth.shrink[1]",
        ),
        ("no table", on.to_string(), "growth.shrink"),
        (
            "a window on a prescribed temperature",
            format!(
                "{table}{on}[[temperature.boundary]]\nkind = \"value\"\nvalue = 300\nuntil = 5\n"
            ),
            "temperature.boundary[0].from",
        ),
        (
            "a source path that goes back in time",
            format!(
                "{table}{on}[[temperature.source]]\npower = 1\nradius = 0.001\n\
                 path = [[1, 0, 0, 0], [0.5, 0, 0, 0]]\n"
            ),
            "temperature.source[0].path[1]",
        ),
    ] {
        let s = scene(&format!("{extra}[time]\nend = 1\n"));
        std::fs::write(d.join("bad.toml"), &s).unwrap();
        let (code, _, err) = run_status(&["bad.toml", "sq.vtk", "--out", "bad", "-q"], d);
        assert_eq!(code, 2, "{what}: {err}");
        assert!(err.contains(key), "{what}: {err}");
        assert!(!d.join("bad").exists(), "{what}: wrote output");
    }
    // Two air temperatures on one side at once (windows that overlap).
    let s = scene(&format!(
        "{table}{on}[[temperature.boundary]]\nkind = \"robin\"\nh = 10\nambient = 300\n\
         until = 3\n[[temperature.boundary]]\nkind = \"robin\"\nh = 10\nambient = 350\n\
         from = 2\n[time]\nend = 1\n"
    ));
    std::fs::write(d.join("bad.toml"), &s).unwrap();
    let (code, _, err) = run_status(&["bad.toml", "sq.vtk", "--out", "bad", "-q"], d);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("temperature.boundary[0] and temperature.boundary[1]") && err.contains("face"),
        "{err}"
    );
    assert!(!d.join("bad").exists());
}

/// The bowl's length, width and depth (m) in frame `m`: the extent of the vertices `bowl`.
fn bowl_size(m: &shellsim::mesh::Mesh, bowl: &[usize]) -> [Real; 3] {
    std::array::from_fn(|k| {
        let v = bowl.iter().map(|&i| m.positions[i][k]);
        v.clone().fold(Real::NEG_INFINITY, Real::max) - v.fold(Real::INFINITY, Real::min)
    })
}

/// `settings/spoon_heated.toml` at its size (632 faces): a heat gun at 160 °C into the bowl for
/// 30 s shrinks the bowl by 3–6% in length and width and thickens its wall, for good: 60 s of
/// cooling and 30 s of reheating at 120 °C move no vertex by more than 0.1% of the bowl's
/// length (measured 1.0e-5 m: a few faces at the bowl's edge, which the first heating left barely
/// above the shrink's onset, are conducted 1.2 K past it), and the bowl's hottest faces keep
/// their highest temperature. With the anisotropic table (twice the shrink along the flow, the
/// handle) the bowl shortens more than it narrows.
#[test]
fn the_heated_spoon_shrinks_its_bowl_for_good() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let settings = root.join("settings/spoon_heated.toml");
    let mesh = root.join("meshes/spoon.vtk");
    let go = |out: &str, sets: &[&str]| {
        converged_frames(
            d,
            settings.to_str().unwrap(),
            mesh.to_str().unwrap(),
            out,
            sets,
        )
    };
    let iso = go("iso", &[]);
    let reference = &iso[0];
    let bowl: Vec<usize> = (0..reference.positions.len())
        .filter(|&i| reference.positions[i].x < 0.045)
        .collect();
    let at = |t: usize| &iso[t / 5];
    let [l0, w0, _] = bowl_size(reference, &bowl);
    let [l1, w1, depth] = bowl_size(at(90), &bowl);
    let (sl, sw) = (1.0 - l1 / l0, 1.0 - w1 / w0);
    let h = &at(90).face_fields["thickness"].data;
    let thickest = h.iter().copied().fold(0.0, Real::max);
    println!(
        "isotropic: bowl length −{:.2}%, width −{:.2}%, depth {:.3} mm, wall up to {:.3} mm",
        100.0 * sl,
        100.0 * sw,
        1e3 * depth,
        1e3 * thickest
    );
    assert!(
        (0.03..0.06).contains(&sl) && (0.03..0.06).contains(&sw),
        "{sl} {sw}"
    );
    assert!(thickest > 1.25e-3, "{thickest}");
    // Cooled (t = 90 s) against reheated and cooled again (180 s).
    let moved = at(90)
        .positions
        .iter()
        .zip(&at(180).positions)
        .fold(0.0, |m: Real, (a, b)| m.max((a - b).norm()));
    println!("reheating at 120 °C moved the spoon by {moved:.2e} m at most");
    assert!(moved < 1e-3 * l0, "{moved}");
    let (t90, t180) = (
        &at(90).face_fields["temperature_max_top"].data,
        &at(180).face_fields["temperature_max_top"].data,
    );
    let hottest = (0..t90.len())
        .max_by(|&a, &b| t90[a].total_cmp(&t90[b]))
        .unwrap();
    assert!(
        t90[hottest] > 410.0 && t90[hottest] == t180[hottest],
        "{}",
        t90[hottest]
    );
    let reheated = at(120).face_fields["temperature_top"].data[hottest];
    assert!(reheated > 380.0 && reheated < t90[hottest], "{reheated}");
    // Anisotropic: along the flow (x) twice the shrink across.
    let md = go(
        "md",
        &[
            "growth.shrink=[[293.15,0,0,0],[343.15,0,0,0],[373.15,0.015,0.0075,-0.0227],\
             [403.15,0.05,0.025,-0.0782],[433.15,0.08,0.04,-0.1382]]",
            "growth.machine_direction=[1,0,0]",
            "time.end=60",
        ],
    );
    let [l2, w2, _] = bowl_size(md.last().unwrap(), &bowl);
    let (al, aw) = (1.0 - l2 / l0, 1.0 - w2 / w0);
    println!(
        "anisotropic: bowl length −{:.2}%, width −{:.2}%",
        100.0 * al,
        100.0 * aw
    );
    assert!(al > 1.5 * aw && al > sl, "{al} {aw}");
}
