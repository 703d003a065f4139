//! MorphoShell mode from the command line: the explicit damped dynamics (its time-step limit, the
//! Gauss–Codazzi–Mainardi cone against the implicit static solve), the liquid-crystal director
//! law against its closed-form cone, the dial order, bend stiffening in a run, and bad input.

mod common;
use common::shellsim;
use shellsim::math::{Real, Sym2, Vec3};
use std::path::{Path, PathBuf};

fn summary(out: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap()
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// Runs shellsim and returns (exit code, stderr).
fn run(args: &[&str], dir: &Path) -> (i32, String) {
    let (c, _, e) = common::run_status(args, dir);
    (c, e)
}

fn final_frame(out: &Path) -> shellsim::mesh::Mesh {
    let s = summary(out);
    shellsim::mesh::io::read_mesh(&out.join(s["final_frame"].as_str().unwrap())).unwrap()
}

/// The largest distance between two shapes of the same mesh after the best rigid alignment,
/// over the size of the second.
fn shape_distance(a: &[Vec3], b: &[Vec3]) -> Real {
    let al = shellsim::cases::align(a, b);
    let lo = b.iter().fold(Vec3::repeat(Real::INFINITY), |m, p| m.inf(p));
    let hi = b
        .iter()
        .fold(Vec3::repeat(-Real::INFINITY), |m, p| m.sup(p));
    let size = (hi - lo).norm();
    al.iter()
        .zip(b)
        .map(|(p, q)| (p - q).norm())
        .fold(0.0, Real::max)
        / size
}

/// The half-angle (degrees) of a cone through the vertices of reference radius in
/// `[r_min, 1]`: the axis is the normal of the rim's best-fit plane (through its centroid), and
/// the distance ρ from the axis is fitted as a linear function of the height h along it; the
/// slope is tan α, whatever the apex does.
fn cone_half_angle(reference: &[Vec3], x: &[Vec3], r_min: Real) -> Real {
    let rim: Vec<Vec3> = (0..x.len())
        .filter(|&v| reference[v].xy().norm() > 1.0 - 1e-9)
        .map(|v| x[v])
        .collect();
    let c = rim.iter().sum::<Vec3>() / rim.len() as Real;
    let mut cov = shellsim::math::Mat3::zeros();
    for p in &rim {
        cov += (p - c) * (p - c).transpose();
    }
    let eig = cov.symmetric_eigen();
    let k = (0..3)
        .min_by(|&i, &j| eig.eigenvalues[i].total_cmp(&eig.eigenvalues[j]))
        .unwrap();
    let axis: Vec3 = eig.eigenvectors.column(k).into();
    let (mut sh, mut sr, mut shh, mut shr, mut n) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for v in 0..x.len() {
        if reference[v].xy().norm() < r_min {
            continue;
        }
        let d = x[v] - c;
        let h = d.dot(&axis);
        let rho = (d - axis * h).norm();
        sh += h;
        sr += rho;
        shh += h * h;
        shr += h * rho;
        n += 1.0;
    }
    let slope = (n * shr - sh * sr) / (n * shh - sh * sh);
    slope.abs().atan().to_degrees()
}

/// The liquid-crystal director law on a disk with a circumferential director: the half-angle
/// and the rim's perimeter against the closed form `sin α = λ^(1+ν)`, `P = 2πλR`. The tolerance
/// is what this coarse mesh (edge R/12, ~900 faces) reaches: the half-angle converges under
/// refinement (docs/morphoshell.md), and the rim length is set by the metric alone.
#[test]
fn lce_disk_with_circumferential_director_becomes_the_closed_form_cone() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    shellsim(
        &[
            "mesh", "disk", "--radius", "1", "--edge", "0.083", "-o", "disk.vtk",
        ],
        d,
    );
    let (lambda, nu) = (0.9, 0.5);
    write(
        d,
        "lce.toml",
        &format!(
            "[material]\nyoung = 3.0\npoisson = 0.5\nthickness = 0.01\n\
             [rest]\ntarget = \"lce\"\n\
             [rest.lce]\ntheta = \"atan2(y, x) + pi/2\"\nlambda = {lambda}\nnu = {nu}\n"
        ),
    );
    shellsim(&["lce.toml", "disk.vtk", "--out", "o", "-q"], d);
    let reference = shellsim::mesh::io::read_mesh(&d.join("disk.vtk")).unwrap();
    let x = final_frame(&d.join("o")).positions;
    let exact = Real::powf(lambda, 1.0 + nu).asin().to_degrees();
    let alpha = cone_half_angle(&reference.positions, &x, 0.4);
    eprintln!("LCE cone: half-angle {alpha:.4}° (exact {exact:.4}°)");
    assert!(
        (alpha - exact).abs() < 0.5,
        "half-angle {alpha:.3}° vs asin(λ^(1+ν)) = {exact:.3}°"
    );
    // The rim: its vertices in angular order.
    let mut rim: Vec<usize> = (0..x.len())
        .filter(|&v| reference.positions[v].xy().norm() > 1.0 - 1e-9)
        .collect();
    rim.sort_by(|&a, &b| {
        let t = |v: usize| reference.positions[v].y.atan2(reference.positions[v].x);
        t(a).total_cmp(&t(b))
    });
    let per: Real = (0..rim.len())
        .map(|i| (x[rim[(i + 1) % rim.len()]] - x[rim[i]]).norm())
        .sum();
    let ref_per: Real = (0..rim.len())
        .map(|i| {
            (reference.positions[rim[(i + 1) % rim.len()]] - reference.positions[rim[i]]).norm()
        })
        .sum();
    let ratio = per / ref_per;
    eprintln!("LCE cone: rim perimeter ratio {ratio:.6} (exact {lambda})");
    assert!(
        (ratio - lambda).abs() < 2e-3,
        "rim perimeter / reference perimeter {ratio:.5}, exact λ = {lambda}"
    );
}

/// The director law's metric: at dial 0 the reference metric, at dial 1 the stretches λ along
/// the director and λ^(−ν) across it, in between the law at λ(s) = 1 + s(λ − 1).
#[test]
fn lce_metric_dials_the_stretch() {
    use shellsim::lce::LceFace;
    let t = shellsim::math::Mat2::new(0.3, -0.1, 0.05, 0.25);
    let (theta, lambda, nu) = (0.7, 0.8, 0.4);
    let l = LceFace::new(&t, theta, lambda, nu);
    let a0 = t.transpose() * t;
    let m0 = l.metric(0.0);
    assert!((m0 - Sym2::new(a0[(0, 0)], a0[(0, 1)], a0[(1, 1)])).amax() < 1e-15);
    for s in [0.5, 1.0] {
        let ls = 1.0 + s * (lambda - 1.0);
        let m = l.metric(s);
        // Push forward to Cartesian and read the stretches along d and d⊥.
        let ti = t.try_inverse().unwrap();
        let mm = shellsim::math::Mat2::new(m[0], m[1], m[1], m[2]);
        let c = ti.transpose() * mm * ti;
        let d = shellsim::math::Vec2::new(theta.cos(), theta.sin());
        let dp = shellsim::math::Vec2::new(-theta.sin(), theta.cos());
        assert!(((d.transpose() * c * d)[0] - ls * ls).abs() < 1e-14);
        assert!(((dp.transpose() * c * dp)[0] - ls.powf(-2.0 * nu)).abs() < 1e-14);
        assert!((d.transpose() * c * dp)[0].abs() < 1e-14);
    }
}

/// `dial.order = "bbar_first"`: b̄ over the first half of the dial with ā at its start, then ā.
#[test]
fn bbar_first_dials_bbar_then_abar() {
    let a0 = Sym2::new(1.0, 0.0, 1.0);
    let a1 = Sym2::new(2.0, 0.1, 0.5);
    let b1 = Sym2::new(0.3, -0.2, 0.1);
    let mut r = shellsim::rest::RestForms {
        abar0: vec![a0],
        bbar0: vec![Sym2::zeros()],
        abar1: vec![a1],
        bbar1: vec![b1],
        order: shellsim::settings::DialOrder::BbarFirst,
        lce: Vec::new(),
    };
    let (a, b) = r.at(0, 0.25);
    assert_eq!(a, a0);
    assert!((b - b1 * 0.5).amax() < 1e-15);
    let (a, b) = r.at(0, 0.75);
    assert!((a - (a0 + a1) * 0.5).amax() < 1e-15);
    assert_eq!(b, b1);
    r.order = shellsim::settings::DialOrder::Together;
    let (a, b) = r.at(0, 0.25);
    assert!((a - (a0 * 0.75 + a1 * 0.25)).amax() < 1e-15);
    assert!((b - b1 * 0.25).amax() < 1e-15);
}

/// The Gauss–Codazzi–Mainardi cone's annular sector as `d/cone.vtk` at edge length `edge`.
fn gcm_cone_mesh(d: &Path, edge: &str) {
    let sweep = format!("{}", shellsim::cases::gcm_cone_sweep().to_degrees());
    shellsim(
        &[
            "mesh",
            "annulus",
            "--inner",
            "1",
            "--radius",
            "1.4",
            "--sweep",
            &sweep,
            "--edge",
            edge,
            "--program",
            "gcm_cone",
            "-o",
            "cone.vtk",
        ],
        d,
    );
}

const CONE_EXPLICIT: &str = "[material]\nyoung = 3.0\npoisson = 0.5\ndensity = 1.0\n\
    thickness = 0.01\nbending = \"patch_fit\"\n[rest]\ntarget = \"mesh\"\n\
    [solver]\nmode = \"explicit\"\n[explicit]\ntime_step_prefactor = 0.6\n\
    damping_prefactor_dial = 4.0\ndamping_prefactor_wait = 6.0\ndial_long_times = 0.25\n";

/// The explicit driver reaches the Gauss–Codazzi–Mainardi cone of the implicit static solve
/// (same mesh, same patch-fit energy): the default equilibrium test stops within 0.05% of its
/// shape (the bar; measured here 1e-5), and MorphoShell's own test stops farther.
#[test]
fn explicit_gcm_cone_stops_at_the_static_solution() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    gcm_cone_mesh(d, "0.17");
    write(d, "ex.toml", CONE_EXPLICIT);
    shellsim(&["ex.toml", "cone.vtk", "--out", "ex", "-q"], d);
    shellsim(
        &[
            "ex.toml",
            "cone.vtk",
            "--out",
            "st",
            "-q",
            "--set",
            "solver.mode=static",
        ],
        d,
    );
    let s = summary(&d.join("ex"));
    assert_eq!(s["converged"], true);
    assert!(s["explicit"]["stable_prefactor"].as_f64().unwrap() > 0.6);
    let xe = final_frame(&d.join("ex")).positions;
    let xs = final_frame(&d.join("st")).positions;
    let dist = shape_distance(&xe, &xs);
    eprintln!(
        "GCM cone explicit vs static: {dist:e}; summary {}",
        s["explicit"]
    );
    assert!(dist < 5e-4, "explicit vs static: {dist:e} of the size");
}

/// The measured stability limit p* of the time-step prefactor is the real one: undamped, a run
/// at 0.95 p* stays bounded and one at 1.05 p* blows up, stops with the reason, and writes no
/// frame of the unstable state.
#[test]
fn explicit_time_step_limit_is_measured() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    shellsim(
        &[
            "mesh", "disk", "--radius", "1", "--edge", "0.2", "-o", "disk.vtk",
        ],
        d,
    );
    // No programmed shape: the symmetry-breaking perturbation excites every mode.
    write(
        d,
        "free.toml",
        "[material]\nyoung = 3.0\npoisson = 0.3\ndensity = 1.0\nthickness = 0.05\n\
         bending = \"patch_fit\"\n[solver]\nmode = \"explicit\"\nsymmetry_breaking = 0.05\n\
         [explicit]\ndamping_prefactor_dial = 0\ndamping_prefactor_wait = 0\n\
         max_long_times = 0.2\n",
    );
    let (code, _) = run(&["free.toml", "disk.vtk", "--out", "probe", "-q"], d);
    assert_eq!(code, 1, "an undamped run does not reach equilibrium");
    let p = summary(&d.join("probe"))["explicit"]["stable_prefactor"]
        .as_f64()
        .unwrap();
    eprintln!("measured stability limit p* = {p}");
    let below = format!("explicit.time_step_prefactor={}", 0.95 * p);
    let (code, _) = run(
        &[
            "free.toml",
            "disk.vtk",
            "--out",
            "below",
            "-q",
            "--set",
            &below,
        ],
        d,
    );
    assert_eq!(code, 1);
    let sb = summary(&d.join("below"));
    let reason = sb["reason"].as_str().unwrap();
    assert!(reason.contains("no equilibrium"), "{reason}");
    let above = format!("explicit.time_step_prefactor={}", 1.05 * p);
    let (code, _) = run(
        &[
            "free.toml",
            "disk.vtk",
            "--out",
            "above",
            "-q",
            "--set",
            &above,
        ],
        d,
    );
    assert_eq!(code, 1);
    let sa = summary(&d.join("above"));
    let reason = sa["reason"].as_str().unwrap();
    assert!(reason.contains("unstable"), "{reason}");
    assert!(reason.contains("last good frame"), "{reason}");
    common::finite_frames(&d.join("above"), "vtu", "above");
}

/// Bad input exits 2 naming the key: a time-step prefactor ≤ 0, λ ≤ 0, a missing director,
/// an edge-DOF bending model in explicit mode, holds out of order.
#[test]
fn morphoshell_mode_bad_input_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    shellsim(
        &[
            "mesh", "disk", "--radius", "1", "--edge", "0.3", "-o", "disk.vtk",
        ],
        d,
    );
    let base = "[material]\nbending = \"patch_fit\"\n[solver]\nmode = \"explicit\"\n";
    for (extra, needle) in [
        (
            "[explicit]\ntime_step_prefactor = 0\n",
            "explicit.time_step_prefactor",
        ),
        (
            "[rest]\ntarget = \"lce\"\n[rest.lce]\ntheta = 0\nlambda = -1\n",
            "rest.lce.lambda",
        ),
        ("[rest]\ntarget = \"lce\"\n", "abar_info"),
        (
            "[rest]\ntarget = \"lce\"\n[rest.lce]\ntheta = 0\nlambda = \"x - 2\"\n",
            "λ = -",
        ),
        ("[dial]\nholds = [0.5, 0.2]\n", "dial.holds[1]"),
        // Work bounds: ~1e13 steps to the time limit; a window the time limit never reaches.
        (
            "[explicit]\ntime_step_prefactor = 1e-6\n",
            "explicit.time_step_prefactor = 0.000001) is",
        ),
        (
            "[explicit]\nwindow_long_times = 10\nmax_long_times = 3\n",
            "explicit.window_long_times",
        ),
        (
            "[explicit]\nwindow_long_times = 1e308\n",
            "explicit.window_long_times",
        ),
        // A drag that overflows, or that symplectic Euler cannot take (c Δt ≥ 2).
        (
            "[explicit]\ndamping_prefactor_wait = 1e308\n",
            "explicit.damping_prefactor_wait",
        ),
        (
            "[explicit]\ndamping_prefactor_dial = 1e6\n",
            "explicit.damping_prefactor_dial",
        ),
        (
            "[constraints]\nfix_boxes = [{ min = [-2, -2, -2], max = [2, 2, 2] }]\n",
            "nothing to move",
        ),
    ] {
        write(d, "bad.toml", &format!("{base}{extra}"));
        let (code, err) = run(&["bad.toml", "disk.vtk", "--out", "o", "-q"], d);
        assert_eq!(code, 2, "{extra}: {err}");
        assert!(err.contains(needle), "{extra}: {err}");
        assert!(!d.join("o").join("summary.json").exists());
    }
    // A thickness of 1e-30 (an imported MorphoShell file can give one) makes the long time,
    // the slowest bending mode's period, ~1e30 steps.
    write(
        d,
        "bad.toml",
        &base.replace("[material]\n", "[material]\nthickness = 1e-30\n"),
    );
    let (code, err) = run(&["bad.toml", "disk.vtk", "--out", "o", "-q"], d);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("thinnest thickness 1e-30 m"), "{err}");
    assert!(err.contains("more than 1e9"), "{err}");
    write(
        d,
        "bad.toml",
        "[material]\nbending = \"midedge_sin\"\n[solver]\nmode = \"explicit\"\n",
    );
    let (code, err) = run(&["bad.toml", "disk.vtk", "--out", "o", "-q"], d);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("material.bending"), "{err}");
}

/// A short explicit run that stops at its time limit writes a finite `log.csv` (the residual
/// of every frame is the window test's force measure at that frame's state) and a
/// `summary.json` without `null`; a window almost as long as the limit does not carry the run
/// past it (the limit is checked every step).
#[test]
fn explicit_run_stops_at_its_limit_with_finite_output() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    shellsim(
        &[
            "mesh", "disk", "--radius", "1", "--edge", "0.3", "-o", "disk.vtk",
        ],
        d,
    );
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let scene = root.join("settings/cone_squeezed.toml");
    let (code, err) = run(
        &[
            scene.to_str().unwrap(),
            "disk.vtk",
            "--out",
            "o",
            "-q",
            "--set",
            "explicit.max_long_times=0.2",
            "--set",
            "explicit.window_long_times=0.15",
        ],
        d,
    );
    assert_eq!(code, 1, "{err}");
    let out = d.join("o");
    let log = std::fs::read_to_string(out.join("log.csv")).unwrap();
    let mut lines = log.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let mut rows = 0;
    for line in lines {
        for (name, cell) in head.iter().zip(line.split(',')) {
            let v: Real = cell
                .parse()
                .unwrap_or_else(|_| panic!("{name}: '{cell}' in {line}"));
            assert!(v.is_finite(), "{name}: {cell} in {line}");
        }
        rows += 1;
    }
    assert!(rows >= 3, "{log}");
    let residuals = log_column(&out, "residual");
    assert!(
        residuals[1..].iter().all(|&r| r > 0.0),
        "a moving sheet has a residual: {residuals:?}"
    );
    let text = std::fs::read_to_string(out.join("summary.json")).unwrap();
    assert!(!text.contains("null"), "{text}");
    let s = summary(&out);
    let reason = s["reason"].as_str().unwrap();
    assert!(reason.contains("explicit.max_long_times"), "{reason}");
    let (t, long) = (
        s["time"].as_f64().unwrap(),
        s["explicit"]["long_time"].as_f64().unwrap(),
    );
    let dt = s["explicit"]["time_step"].as_f64().unwrap();
    assert!(
        t >= 0.2 * long && t < 0.2 * long + 1.5 * dt,
        "stopped at {} long times",
        t / long
    );
}

/// A flat sheet pressed by a force-controlled slide onto the lower slide carries the force:
/// the contact is a penalty on the mid-surface, so the upper plane goes below the lower one by
/// the penalty's give 2F/(n k) and every vertex is pushed from both sides. At the equilibrium
/// test both slides carry the prescribed 2 mN: the test includes the slide's balance,
/// |F − F_up| ≤ force_tolerance × E h ℓ (1e-7 × 3 × 0.02 × 0.25 = 1.5e-9 N, 1e-6 of the load),
/// and the sheet's forces below the same tolerance per vertex bound the lower slide's to
/// n × that (64 vertices: 5e-5 of the load).
#[test]
fn force_controlled_slide_on_a_flat_sheet_carries_the_load() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    shellsim(
        &[
            "mesh", "disk", "--radius", "1", "--edge", "0.25", "-o", "disk.vtk",
        ],
        d,
    );
    write(
        d,
        "flat.toml",
        "[material]\nyoung = 3.0\npoisson = 0.5\ndensity = 1.0\nthickness = 0.02\n\
         bending = \"patch_fit\"\n[solver]\nmode = \"explicit\"\n[explicit]\n\
         time_step_prefactor = 0.6\ndial_long_times = 0.5\ndamping_prefactor_dial = 2\n\
         damping_prefactor_wait = 2\n[slides]\nenabled = true\nlower = -0.03\nupper = 0.03\n\
         control = \"force\"\nforce = 0.002\n",
    );
    let (code, err) = run(&["flat.toml", "disk.vtk", "--out", "o", "-q"], d);
    let out = d.join("o");
    let s = summary(&out);
    assert_eq!(code, 0, "{err} {}", s["reason"]);
    let col = |n: &str| *log_column(&out, n).last().unwrap();
    let (up, down, gap) = (
        col("slide_upper_force"),
        col("slide_lower_force"),
        col("slide_gap"),
    );
    eprintln!("flat sheet pressed: forces {up:e} / {down:e} N, gap {gap:e}");
    assert!((up - 0.002).abs() < 1e-6 * 0.002, "upper force {up}");
    assert!((down - 0.002).abs() < 5e-5 * 0.002, "lower force {down}");
    assert!(gap < 0.0, "the planes overlap by the penalty's give: {gap}");
}

/// A liquid-crystal cone squashed between fixed glass slides with friction (explicit mode):
/// it reaches equilibrium inside the gap (penetrations of the penalty's order only), the slides'
/// forces balance, and `log.csv` carries their heights, gap and forces. Slides that start
/// intersecting the sheet, an upper slide below the lower one, and friction in an implicit
/// mode are exit 2 naming the cause.
#[test]
fn slides_squeeze_a_cone_and_bad_slides_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    shellsim(
        &[
            "mesh", "disk", "--radius", "1", "--edge", "0.15", "-o", "disk.vtk",
        ],
        d,
    );
    write(
        d,
        "sl.toml",
        "[material]\nyoung = 3.0\npoisson = 0.5\ndensity = 1.0\nthickness = 0.02\n\
         bending = \"patch_fit\"\n[rest]\ntarget = \"lce\"\n[rest.lce]\n\
         theta = \"atan2(y, x) + pi/2\"\nlambda = 0.9\nnu = 0.5\n[solver]\nmode = \"explicit\"\n\
         [explicit]\ntime_step_prefactor = 0.6\ndial_long_times = 0.5\n\
         damping_prefactor_dial = 2\ndamping_prefactor_wait = 2\n\
         [slides]\nenabled = true\nlower = -0.1\nupper = 0.1\nfriction = 0.3\n",
    );
    shellsim(&["sl.toml", "disk.vtk", "--out", "o", "-q"], d);
    let s = summary(&d.join("o"));
    assert_eq!(s["converged"], true, "{}", s["reason"]);
    let x = final_frame(&d.join("o")).positions;
    // Free, the cone would be ~0.5 high; squashed, every vertex stays within the gap up to
    // the penalty's give (force / k with k = 100 μ t = 2 N/m and forces ~1e-3 N).
    let (lo, hi) = x
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
            (a.min(p.z), b.max(p.z))
        });
    assert!(lo > -0.1 - 2e-3 && hi < 0.1 + 2e-3, "z range {lo} … {hi}");
    assert!(hi - lo > 0.19, "the cone fills the gap: {lo} … {hi}");
    let col = |n: &str| *log_column(&d.join("o"), n).last().unwrap();
    assert_eq!(col("slide_gap"), 0.2);
    let (up, down) = (col("slide_upper_force"), col("slide_lower_force"));
    assert!(
        up > 0.0 && (up - down).abs() < 1e-3 * up,
        "forces {up} vs {down}"
    );
    for (extra, needle) in [
        ("upper = 0.1\nlower = 0.05\n", "vertex"),
        ("upper = -0.1\nlower = 0.1\n", "slides.upper"),
    ] {
        write(
            d,
            "bad.toml",
            &format!("[material]\nbending = \"patch_fit\"\n[solver]\nmode = \"explicit\"\n[slides]\nenabled = true\n{extra}"),
        );
        let (code, err) = run(&["bad.toml", "disk.vtk", "--out", "b", "-q"], d);
        assert_eq!(code, 2, "{extra}: {err}");
        assert!(err.contains(needle), "{extra}: {err}");
    }
    write(
        d,
        "bad.toml",
        "[slides]\nenabled = true\nlower = -1\nupper = 1\nfriction = 0.2\n",
    );
    let (code, err) = run(&["bad.toml", "disk.vtk", "--out", "b", "-q"], d);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("slides.friction"), "{err}");
    for (mode, damping) in [("static", "1"), ("explicit", "-0.5")] {
        write(
            d,
            "bad.toml",
            &format!(
                "[solver]\nmode = \"{mode}\"\n[material]\nbending = \"patch_fit\"\n\
                 [slides]\nenabled = true\nlower = -1\nupper = 1\ncontact_damping = {damping}\n"
            ),
        );
        let (code, err) = run(&["bad.toml", "disk.vtk", "--out", "b", "-q"], d);
        assert_eq!(code, 2, "{mode}: {err}");
        assert!(err.contains("slides.contact_damping"), "{mode}: {err}");
    }
}

/// A settings file in MorphoShell's own format: its 23 entries in the order of its
/// `read_settings.cpp`, with `//` comments on their own lines and after values, blank lines and
/// uneven spacing.
const MORPHOSHELL_SETTINGS: &str = "// Settings for a test run.

// Frames per long time.
outputs_per_char_long_time  = 400.0;

// Negative: the mesh's ref_thicknesses.
ref_thickness_if_uniform = 0.01;
timestep_prefactor = 0.3;
dialling_from_ansatz_rather_than_ref_state = true;
dial_factors_to_hold_at_spacing = 0.5;
dial_phase_time_prefactor = 0.25;

time_between_equil_checks_prefactor = 0.01;
damping_prefactor_1 = 4.0;
damping_prefactor_2 = 6.0;
num_steps_to_use_gradient_descent_dynamics_for_before_switching_to_newtonian_dynamics = 7;
force_to_char_force_ratio_equil_threshold = 0.000001;
speed_to_char_speed_ratio_equil_threshold = 0.00001;
def_poisson_ratio = 0.5; // a decimal, not 1/2
ref_shear_modulus_if_uniform = 1.0;
ref_density = 1.0;
bend_stiffening_scale_factor = 100000000000000000.0;
patch_mat_dimless_conditioning_thresh = 10.0;
slide_stiffness_prefactor = 0.0;
slide_friction_coefficent = 0.0;
slide_speed_prefactor = 0.0;
using_initial_glass_slide_z_coords_from_settings_file = false;
initial_upper_slide_z_coord = 12345.0;
initial_lower_slide_z_coord = 12345.0;


";

/// A settings file in MorphoShell's order converts into a shellsim file that shellsim accepts,
/// with the physics carried over (so does one in the gravity layout); a file with too few
/// entries, a non-numeric value, a switch neither true nor false or an entry out of order is
/// exit 2 naming the line and entry, with nothing written.
#[test]
fn import_morphoshell_settings() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let text = MORPHOSHELL_SETTINGS;
    write(d, "ms.txt", text);
    shellsim(&["import-morphoshell", "ms.txt", "-o", "ms.toml"], d);
    let s = shellsim::settings::Settings::load(&d.join("ms.toml"), &[]).unwrap();
    assert_eq!(s.solver.mode, shellsim::settings::Mode::Explicit);
    assert_eq!(
        s.material.stretch_convention,
        shellsim::energy::material::StretchConvention::Morphoshell
    );
    assert_eq!(
        s.material.bending,
        shellsim::settings::BendingModel::PatchFit
    );
    assert!((s.material.young - 3.0).abs() < 1e-15, "E = 2μ(1+ν)");
    assert_eq!(s.material.thickness, 0.01);
    assert!(!s.material.use_mesh_thickness && !s.material.use_mesh_shear_modulus);
    assert_eq!(s.explicit.time_step_prefactor, 0.3);
    assert_eq!(s.explicit.damping_prefactor_dial, 4.0);
    assert_eq!(s.explicit.damping_prefactor_wait, 6.0);
    assert_eq!(s.explicit.gradient_descent_steps, 7);
    assert_eq!(s.explicit.dial_long_times, 0.5, "0.25 per phase, 2 phases");
    assert_eq!(s.dial.holds, vec![0.5]);
    assert_eq!(s.material.bend_stiffening, Some(1e17));
    assert_eq!(s.dial.from, shellsim::settings::DialFrom::Start);
    // A negative uniform value: per face from the mesh.
    write(
        d,
        "mesh.txt",
        &text.replace(
            "ref_thickness_if_uniform = 0.01",
            "ref_thickness_if_uniform = -1.0",
        ),
    );
    shellsim(&["import-morphoshell", "mesh.txt", "-o", "mesh.toml"], d);
    let s = shellsim::settings::Settings::load(&d.join("mesh.toml"), &[]).unwrap();
    assert!(s.material.use_mesh_thickness && !s.material.use_mesh_shear_modulus);

    // The gravity layout: 24 entries, its second entry the dialling switch.
    let names = shellsim::morphoshell::GRAVITY_ENTRIES;
    let value = |n: &str| match n {
        "grav_field_strength" => "9.81".to_string(),
        _ => text
            .lines()
            .find_map(|l| l.strip_prefix(n)?.trim().strip_prefix('='))
            .map(|v| v.split(';').next().unwrap().trim().to_string())
            .unwrap(),
    };
    let gravity: String = names
        .iter()
        .map(|n| format!("{n} = {};\n", value(n)))
        .collect();
    write(d, "grav.txt", &gravity);
    shellsim(&["import-morphoshell", "grav.txt", "-o", "grav.toml"], d);
    let s = shellsim::settings::Settings::load(&d.join("grav.toml"), &[]).unwrap();
    assert_eq!(s.explicit.gradient_descent_steps, 7);
    assert!((s.material.young - 3.0).abs() < 1e-15);
    assert_eq!(
        std::fs::read_to_string(d.join("grav.toml"))
            .unwrap()
            .matches("gravity = [0.0, 0.0, -9.81]")
            .count(),
        1
    );

    // Bad files.
    let lines: Vec<&str> = text.lines().collect();
    for (bad, needle) in [
        (lines[..27].join("\n"), "missing 'initial_upper_slide_z_coord'"),
        (
            text.replace("ref_density = 1.0", "ref_density = one"),
            ":21: ref_density = 'one' is not a number",
        ),
        (
            text.replace("= true;", "= 1;"),
            ":9: dialling_from_ansatz_rather_than_ref_state = '1' is neither true nor false",
        ),
        (
            text.replace("= 7;", "= 7.5;"),
            ":16: num_steps_to_use_gradient_descent_dynamics_for_before_switching_to_newtonian_dynamics \
             = '7.5' is not an integer",
        ),
        (
            text.replace("ref_density", "density"),
            "expects 'ref_density' here",
        ),
        (
            format!("{text}grav_field_strength = 9.81;\n"),
            "unknown entry 'grav_field_strength' after the 23",
        ),
        (
            gravity.replace("grav_field_strength = 9.81;\n", ""),
            "expects 'grav_field_strength' here",
        ),
    ] {
        write(d, "bad.txt", &bad);
        let (code, err) = run(&["import-morphoshell", "bad.txt", "-o", "bad.toml"], d);
        assert_eq!(code, 2, "{err}");
        assert!(err.contains(needle), "{needle}: {err}");
        assert!(!d.join("bad.toml").exists());
    }
}

/// A flat 3 × 3-node square (8 triangles) written as MorphoShell's meshing scripts write a
/// mesh: `%.15e` values, the per-face fields as one FIELD block, ā = I, b̄ = 0, and
/// `ref_thicknesses` / `ref_shear_moduli` given per face.
fn morphoshell_mesh(thickness: &[Real; 8], shear: &[Real; 8]) -> String {
    let mut t = String::from(
        "# vtk DataFile Version 2.0\nsquare\nASCII\nDATASET POLYDATA\nPOINTS 9 double\n",
    );
    for j in 0..3 {
        for i in 0..3 {
            t += &format!(
                "{:.15e} {:.15e} {:.15e}\n",
                i as Real * 0.5,
                j as Real * 0.5,
                0.0
            );
        }
    }
    t += "POLYGONS 8 32\n";
    for j in 0..2 {
        for i in 0..2 {
            let v = 3 * j + i;
            t += &format!("3 {} {} {}\n3 {} {} {}\n", v, v + 1, v + 4, v, v + 4, v + 3);
        }
    }
    t += "CELL_DATA 8\nFIELD tri_quantities 5\nabar_info 3 8 double\n";
    t += &"1.000000000000000e+00 0.000000000000000e+00 1.000000000000000e+00\n".repeat(8);
    t += "bbar_info 3 8 double\n";
    t += &"0.000000000000000e+00 0.000000000000000e+00 0.000000000000000e+00\n".repeat(8);
    for (name, v) in [("ref_thicknesses", thickness), ("ref_shear_moduli", shear)] {
        t += &format!("{name} 1 8 double\n");
        for x in v {
            t += &format!("{x:.15e}\n");
        }
    }
    t += "tri_tags 1 8 int\n";
    t += &"0\n".repeat(8);
    t += "POINT_DATA 9\nFIELD node_quantities 2\nconstraint_indicators 1 9 int\n";
    t += &"0\n".repeat(9);
    t += "node_tags 1 9 int\n";
    t += &"0\n".repeat(9);
    t
}

/// MorphoShell's meshes carry −1234 in `ref_thicknesses` and `ref_shear_moduli` where its
/// settings' uniform value is used: such a mesh runs with the uniform values (the settings
/// `import-morphoshell` writes, or `use_mesh_* = false`), and a per-face value that would be
/// used and is the placeholder, or not positive, is exit 2 naming the field and the face.
#[test]
fn morphoshell_mesh_placeholders() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let settings = MORPHOSHELL_SETTINGS.replace("= true;", "= false;");
    write(d, "ms.txt", &settings);
    shellsim(&["import-morphoshell", "ms.txt", "-o", "ms.toml"], d);
    write(
        d,
        "placeholder.vtk",
        &morphoshell_mesh(&[-1234.0; 8], &[-1234.0; 8]),
    );
    let static_run = |mesh: &str, out: &str, extra: &[&str]| {
        let mut a = vec!["ms.toml", mesh, "--out", out, "-q"];
        for s in ["solver.mode=\"static\"", "material.bending=\"midedge_sin\""] {
            a.extend_from_slice(&["--set", s]);
        }
        a.extend_from_slice(extra);
        run(&a, d)
    };
    let (code, err) = static_run("placeholder.vtk", "ok", &[]);
    assert_eq!(code, 0, "{err}");
    let thickness = |out: &str| {
        final_frame(&d.join(out)).face_fields["thickness"]
            .data
            .clone()
    };
    // Frames write the thickness in Float32.
    let near = |h: &[Real], want: Real| h.len() == 8 && h.iter().all(|x| (x - want).abs() < 1e-8);
    assert!(near(&thickness("ok"), 0.01), "{:?}", thickness("ok"));

    // The per-face values used: the placeholder, or a value that is not positive, is named.
    let mut thick = [0.02; 8];
    thick[5] = 0.0;
    write(d, "mixed.vtk", &morphoshell_mesh(&thick, &[-1234.0; 8]));
    for (mesh, key, needle) in [
        (
            "placeholder.vtk",
            "material.use_mesh_thickness=true",
            "'ref_thicknesses' must lie in (0, 1e30], but face 0 has -1234 (MorphoShell's \
             placeholder",
        ),
        (
            "placeholder.vtk",
            "material.use_mesh_shear_modulus=true",
            "'ref_shear_moduli' must lie in (0, 1e15], but face 0 has -1234 (MorphoShell's \
             placeholder for the settings' uniform value; to use one, set \
             material.use_mesh_shear_modulus = false)",
        ),
        (
            "mixed.vtk",
            "material.use_mesh_thickness=true",
            "'ref_thicknesses' must lie in (0, 1e30], but face 5 has 0",
        ),
    ] {
        let (code, err) = static_run(mesh, "bad", &["--set", key]);
        assert_eq!(code, 2, "{key}: {err}");
        assert!(
            err.contains(mesh) && err.contains(needle),
            "{needle}: {err}"
        );
        assert!(!d.join("bad").exists(), "nothing written");
    }
    // The per-face thicknesses are used where valid.
    write(d, "thick.vtk", &morphoshell_mesh(&[0.02; 8], &[-1234.0; 8]));
    let (code, err) = static_run(
        "thick.vtk",
        "thick",
        &["--set", "material.use_mesh_thickness=true"],
    );
    assert_eq!(code, 0, "{err}");
    assert!(near(&thickness("thick"), 0.02), "{:?}", thickness("thick"));
}

/// The column `name` of a run's `log.csv` (one row per frame).
fn log_column(out: &Path, name: &str) -> Vec<Real> {
    let text = std::fs::read_to_string(out.join("log.csv")).unwrap();
    let mut lines = text.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let k = head.iter().position(|h| *h == name).unwrap();
    lines
        .map(|l| l.split(',').nth(k).unwrap().parse().unwrap())
        .collect()
}

/// The dial's rows of `log.csv`.
fn logged_dials(out: &Path) -> Vec<Real> {
    log_column(out, "dial")
}

/// Hold points in the implicit drivers: the static continuation lands on each hold, solves it to
/// full accuracy and writes a frame, and still reaches the shape of a run without holds; the
/// dynamic dial stops at a hold until the equilibrium test passes, then goes on.
#[test]
fn holds_in_the_implicit_drivers() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    gcm_cone_mesh(d, "0.25");
    write(d, "ex.toml", CONE_EXPLICIT);
    let st = |out: &str, extra: &[&str]| {
        let mut a = vec!["ex.toml", "cone.vtk", "--out", out, "-q"];
        // Tight: at the default 1e-9 the two solves differ by 8e-6 of the size along the soft
        // modes the residual does not see; at 1e-12 by 4e-16 (both end on the same Newton solution).
        a.extend_from_slice(&["--set", "solver.mode=static"]);
        a.extend_from_slice(&["--set", "solver.tolerance=1e-12"]);
        a.extend_from_slice(extra);
        shellsim(&a, d);
    };
    st("plain", &[]);
    st("held", &["--set", "dial.holds=[0.3, 0.6]"]);
    let s = summary(&d.join("held"));
    assert_eq!(s["converged"], true);
    assert_eq!(s["holds_reached"], 2);
    let dials = logged_dials(&d.join("held"));
    assert!(dials.contains(&0.3) && dials.contains(&0.6), "{dials:?}");
    let dist = shape_distance(
        &final_frame(&d.join("held")).positions,
        &final_frame(&d.join("plain")).positions,
    );
    assert!(dist < 1e-9, "held vs plain static: {dist:e}");
    eprintln!("held vs plain static: {dist:e}");

    // Dynamics: the damped strip curling into a cylinder (its dial takes 0.5 s), held at 0.5.
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    shellsim(
        &[
            root.join("settings/dynamic_cylinder.toml")
                .to_str()
                .unwrap(),
            root.join("meshes/strip.vtk").to_str().unwrap(),
            "--out",
            d.join("dyn").to_str().unwrap(),
            "-q",
            "--set",
            "dial.holds=[0.5]",
            "--set",
            "time.end=20",
            "--set",
            "time.dt_max=0.5",
            "--set",
            "time.output_interval=1",
            "--set",
            "time.stop_at_equilibrium=true",
        ],
        d,
    );
    let s = summary(&d.join("dyn"));
    assert_eq!(s["converged"], true, "{s}");
    assert_eq!(s["holds_reached"], 1, "{s}");
    assert_eq!(s["dial"], 1.0);
    let dials = logged_dials(&d.join("dyn"));
    let at_hold = dials.iter().filter(|&&x| x == 0.5).count();
    assert!(at_hold >= 2, "the dial waited at 0.5: {dials:?}");
    assert!(
        dials.windows(2).all(|w| w[1] >= w[0]),
        "the dial never goes back: {dials:?}"
    );
}

/// Writes `x` as MorphoShell writes a frame (its ansatz format): legacy ASCII polydata whose
/// title carries the dial factor.
fn write_ansatz(path: &Path, dial: &str, x: &[Vec3], faces: &[[usize; 3]]) {
    let mut t = format!(
        "# vtk DataFile Version 4.2\ndial_factor = {dial}, stepcount = 1234\nASCII\n\
         DATASET POLYDATA\nPOINTS {} double\n",
        x.len()
    );
    for p in x {
        t += &format!("{:.14e} {:.14e} {:.14e}\n", p.x, p.y, p.z);
    }
    t += &format!("POLYGONS {} {}\n", faces.len(), 4 * faces.len());
    for f in faces {
        t += &format!("3 {} {} {}\n", f[0], f[1], f[2]);
    }
    // Then its face and vertex data (not read back).
    t += &format!("CELL_DATA {}\n", faces.len());
    t += &format!(
        "POINT_DATA {}\nSCALARS angleDeficit double 1\nLOOKUP_TABLE default\n",
        x.len()
    );
    t += &format!("{:.14e}\n", 0.0).repeat(x.len());
    std::fs::write(path, t).unwrap();
}

/// MorphoShell's ansatz files: a run restarts at the dial factor of the title from the
/// positions, and reaches the same equilibrium as a run from the start; `dial.from = "start"`
/// dials from the ansatz's own forms (from dial 0); bad ansatz files are named by line.
#[test]
fn morphoshell_ansatz_files() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    gcm_cone_mesh(d, "0.25");
    write(d, "ex.toml", CONE_EXPLICIT);
    let st = |out: &str, extra: &[&str]| {
        let mut a = vec!["ex.toml", "cone.vtk", "--out", out, "-q"];
        a.extend_from_slice(&["--set", "solver.mode=static"]);
        a.extend_from_slice(&["--set", "solver.tolerance=1e-12"]);
        a.extend_from_slice(extra);
        shellsim(&a, d);
    };
    st("plain", &[]);
    st("held", &["--set", "dial.holds=[0.5]"]);
    // The frame at the hold, written as a MorphoShell ansatz at dial 0.5.
    let row = logged_dials(&d.join("held")).iter().position(|&s| s == 0.5);
    let k = log_column(&d.join("held"), "frame")[row.unwrap()] as usize;
    let half = shellsim::mesh::io::read_mesh(&d.join(format!("held/frame_{k:05}.vtu"))).unwrap();
    write_ansatz(&d.join("half.vtk"), "0.5", &half.positions, &half.faces);
    st("resumed", &["--restart", "half.vtk"]);
    let dials = logged_dials(&d.join("resumed"));
    assert_eq!(
        dials[0], 0.5,
        "the run starts at the ansatz's dial: {dials:?}"
    );
    let plain = final_frame(&d.join("plain")).positions;
    let dist = shape_distance(&final_frame(&d.join("resumed")).positions, &plain);
    assert!(dist < 1e-9, "resumed from the ansatz vs plain: {dist:e}");

    // Dialling from the ansatz: from the final cone, the forms go from the cone's own (a, b),
    // in which it is stress-free, to the targets, so the run ends on the same equilibrium. From
    // the same positions at dial 0 of the reference forms (a flat disk's) it is far from
    // stress-free.
    write_ansatz(&d.join("cone1.vtk"), "1", &plain, &half.faces);
    write_ansatz(&d.join("cone0.vtk"), "0", &plain, &half.faces);
    st("from_reference", &["--restart", "cone0.vtk"]);
    st(
        "from_start",
        &["--restart", "cone1.vtk", "--set", "dial.from=\"start\""],
    );
    let dials = logged_dials(&d.join("from_start"));
    assert_eq!(
        dials[0], 0.0,
        "dialling from the ansatz starts at 0: {dials:?}"
    );
    let first_energy = |out: &str| log_column(&d.join(out), "energy_total")[0];
    let (e_start, e_ref) = (first_energy("from_start"), first_energy("from_reference"));
    assert!(
        e_start.abs() < 1e-12 * e_ref.abs(),
        "energy at dial 0: {e_start:e} from the ansatz's forms, {e_ref:e} from the reference's"
    );
    let dist = shape_distance(&final_frame(&d.join("from_start")).positions, &plain);
    assert!(dist < 1e-9, "dialled from the cone's own forms: {dist:e}");
    eprintln!("dial.from = start, from the cone: {dist:e}");

    // Bad ansatz files name the file and line.
    let bad = |name: &str, text: &str, what: &str| {
        write(d, name, text);
        let (code, err) = run(
            &[
                "ex.toml",
                "cone.vtk",
                "--restart",
                name,
                "--out",
                name,
                "-q",
            ],
            d,
        );
        assert_eq!(code, 2, "{name}: {err}");
        assert!(err.contains(name) && err.contains(what), "{name}: {err}");
    };
    let head = "# vtk DataFile Version 4.2\n";
    bad(
        "dial.vtk",
        &format!("{head}dial_factor = 1.5, stepcount = 1\nASCII\nDATASET POLYDATA\nPOINTS 1 double\n0 0 0\n"),
        "dial.vtk:2",
    );
    bad(
        "title.vtk",
        &format!("{head}dial_factor is half\nASCII\n"),
        "title.vtk:2",
    );
    let n = plain.len();
    bad(
        "count.vtk",
        &format!(
            "{head}dial_factor = 0.5, stepcount = 1\nASCII\nDATASET POLYDATA\nPOINTS {} double\n",
            n + 1
        ),
        "count.vtk:5",
    );
    bad(
        "coord.vtk",
        &format!("{head}dial_factor = 0.5, stepcount = 1\nASCII\nDATASET POLYDATA\nPOINTS {n} double\n0 0 zero\n"),
        "coord.vtk:6",
    );
    // Files cut short: inside the last coordinate (no final newline), after the points, among
    // the polygons; and a coordinate too many.
    write_ansatz(&d.join("whole.vtk"), "0.5", &half.positions, &half.faces);
    let whole = std::fs::read_to_string(d.join("whole.vtk")).unwrap();
    let poly = whole.find("POLYGONS").unwrap();
    // Up to the first digit of the last coordinate (5.0e-03 cut to 5).
    let start = whole[..poly - 1].rfind(' ').unwrap() + 1;
    let last_coordinate = start + whole[start..].find(|c: char| c.is_ascii_digit()).unwrap() + 1;
    let point_lines = whole[..poly].lines().count();
    bad(
        "cut.vtk",
        &whole[..last_coordinate],
        &format!(
            "cut.vtk:{point_lines}: the file ends inside the number '{}', without a final newline",
            &whole[last_coordinate - 1..last_coordinate]
        ),
    );
    bad(
        "nopoly.vtk",
        &whole[..poly],
        &format!("the file ends after the {n} points, without the POLYGONS block"),
    );
    let third = poly + whole[poly..].match_indices('\n').nth(3).unwrap().0 + 1;
    bad(
        "halfpoly.vtk",
        &whole[..third],
        &format!("the file ends after 3 of the {} polygons", half.faces.len()),
    );
    bad(
        "extra.vtk",
        &whole.replacen("\nPOLYGONS", " 0\nPOLYGONS", 1),
        &format!(
            "extra.vtk:{point_lines}: '0' is more than the {} point coordinates",
            3 * n
        ),
    );
    bad(
        "short.vtk",
        &format!("{head}dial_factor = 0.5, stepcount = 1\nASCII\nDATASET POLYDATA\nPOINTS {n} double\n0 0 0\n"),
        "of",
    );
}

/// MorphoShell's output fields against closed forms. A square clamped on its rim with the rest
/// metric ā = q I shrunk is flat and uniformly strained: both principal Cauchy stresses are
/// E t (1 − q) / (2 q (1 − ν)) (St Venant–Kirchhoff, plane stress, at a = I) and the strain
/// measure is (1 − q)/2. On a sphere the angle deficits sum to 4π (discrete Gauss–Bonnet,
/// exact) and their Gauss curvature is 1/R² to the barycentric cell's accuracy. The frames are
/// written in double: the checks are far below Float32's 6e-8.
#[test]
fn morphoshell_output_fields() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    shellsim(
        &[
            "mesh", "square", "--size", "1", "--edge", "0.1", "--jitter", "0.2", "-o", "sq.vtk",
        ],
        d,
    );
    let (e, nu, t, q) = (1000.0, 0.3, 0.01, 0.81);
    write(
        d,
        "flat.toml",
        &format!(
            "[material]\nyoung = {e:?}\npoisson = {nu:?}\nthickness = {t:?}\n\
             [rest]\ntarget = \"uniform\"\nabar = [{q:?}, 0.0, {q:?}]\n\
             [constraints]\nfix_boxes = [{{ min = [-1, -1, -1], max = [-0.45, 1, 1] }}, \
             {{ min = [0.45, -1, -1], max = [1, 1, 1] }}, {{ min = [-1, -1, -1], max = [1, -0.45, 1] }}, \
             {{ min = [-1, 0.45, -1], max = [1, 1, 1] }}]\n\
             [output]\nmorphoshell_fields = true\nprecision = \"double\"\n"
        ),
    );
    shellsim(&["flat.toml", "sq.vtk", "--out", "flat", "-q"], d);
    let m = final_frame(&d.join("flat"));
    let sigma = e * t * (1.0 - q) / (2.0 * q * (1.0 - nu));
    let mu_t = e / (2.0 * (1.0 + nu)) * t;
    let field = |name: &str| m.face_fields[name].data.clone();
    for name in ["cauchy_stress_eigval_1", "cauchy_stress_eigval_2"] {
        for (f, s) in field(name).iter().enumerate() {
            assert!(
                (s - sigma).abs() < 1e-8 * sigma,
                "{name} at face {f}: {s} vs {sigma}"
            );
        }
    }
    for (f, s) in field("dimless_cauchy_stress_eigval_1").iter().enumerate() {
        assert!(
            (s - sigma / mu_t).abs() < 1e-8 * sigma / mu_t,
            "face {f}: {s}"
        );
    }
    for (f, s) in field("strain_measure").iter().enumerate() {
        assert!(
            (s - 0.5 * (1.0 - q)).abs() < 1e-9,
            "strain at face {f}: {s}"
        );
    }
    let dirs = &m.face_fields["cauchy_stress_eigvec_1"];
    assert_eq!(dirs.components, 3);
    assert!(dirs
        .data
        .chunks(3)
        .all(|u| (Vec3::from_column_slice(u).norm() - 1.0).abs() < 1e-12));
    let deficit = &m.vertex_fields["angle_deficit"].data;
    let total: Real = deficit.iter().sum();
    assert!(
        (total - 2.0 * std::f64::consts::PI).abs() < 1e-12,
        "disk: Σ = {total}"
    );

    shellsim(
        &[
            "mesh", "sphere", "--radius", "1", "--edge", "0.2", "-o", "sph.vtk",
        ],
        d,
    );
    write(
        d,
        "sph.toml",
        "[material]\nyoung = 1000.0\nthickness = 0.01\n[output]\nmorphoshell_fields = true\n\
         precision = \"double\"\n",
    );
    shellsim(&["sph.toml", "sph.vtk", "--out", "sph", "-q"], d);
    let m = final_frame(&d.join("sph"));
    let total: Real = m.vertex_fields["angle_deficit"].data.iter().sum();
    assert!(
        (total - 4.0 * std::f64::consts::PI).abs() < 1e-11,
        "sphere: Σ = {total}"
    );
    let mut k = m.vertex_fields["angle_deficit_gauss_curvature"]
        .data
        .clone();
    k.sort_by(Real::total_cmp);
    // At 362 vertices the barycentric cell gives K R² in [1.004, 1.149] (worst next to the 12
    // valence-5 vertices); the median is within 1%.
    let median = k[k.len() / 2];
    assert!((median - 1.0).abs() < 0.01, "median K R² = {median}");
    assert!(
        k[0] > 0.95 && k[k.len() - 1] < 1.2,
        "K R² in [{}, {}]",
        k[0],
        k[k.len() - 1]
    );
}

/// Runs `settings/cone_squeezed.toml` on a unit disk of edge `edge` with `sets` overrides;
/// returns the run's final (upper force, lower force, gap) after asserting it converged.
fn squeeze_cone(edge: &str, sets: &[&str]) -> (Real, Real, Real) {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    shellsim(
        &[
            "mesh", "disk", "--radius", "1", "--edge", edge, "-o", "disk.vtk",
        ],
        d,
    );
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let scene = root.join("settings/cone_squeezed.toml");
    let mut args = vec![scene.to_str().unwrap(), "disk.vtk", "--out", "o", "-q"];
    for s in sets {
        args.extend(["--set", s]);
    }
    shellsim(&args, d);
    let s = summary(&d.join("o"));
    assert_eq!(s["converged"], true, "{}", s["reason"]);
    let col = |n: &str| *log_column(&d.join("o"), n).last().unwrap();
    (
        col("slide_upper_force"),
        col("slide_lower_force"),
        col("slide_gap"),
    )
}

/// A cone pressed by a force-controlled slide (frictionless, after the dial) settles where the
/// sheet carries the load: at the default equilibrium test both slides carry the applied force
/// (the upper slide's backward-Euler update balances it exactly; the lower one through the
/// sheet), and the cone is squashed below its free height.
#[test]
fn force_controlled_slide_squashes_a_cone_to_the_load() {
    let (up, down, gap) = squeeze_cone("0.25", &[]);
    eprintln!("squeezed cone: forces {up:e} / {down:e} N, gap {gap}");
    // At the test's force residual (1e-7 of E h × edge per node) the forces balance to ~1e-6.
    assert!((up - 0.002).abs() < 1e-5 * 0.002, "upper force {up}");
    assert!((down - 0.002).abs() < 1e-4 * 0.002, "lower force {down}");
    assert!(
        gap > 0.0 && gap < 0.3,
        "squashed below the free cone's ~0.55: gap {gap}"
    );
}

/// A cone driven down to a gap of 0.11 by a speed-controlled slide with friction 0.3 (157
/// faces) comes to rest: the default contact damping removes the vertices' bouncing on the
/// penalty springs, which without it keeps the sheet chattering past 4 long times (kinetic
/// energy ~1e-12 J, residual ~7e-4, the slide forces 0.4% apart; measured). At rest the two
/// slides carry the same force (the sheet is in equilibrium between them).
#[test]
fn slide_with_friction_squashing_a_cone_comes_to_rest() {
    let (up, down, gap) = squeeze_cone(
        "0.2",
        &[
            "slides.control=\"speed\"",
            "slides.speed=0.005",
            "slides.travel=0.70",
            "slides.friction=0.3",
            "explicit.max_long_times=4",
        ],
    );
    assert!((gap - 0.11).abs() < 1e-12, "the slide stopped at gap {gap}");
    // At the test's force residual the vertical forces balance to ~1e-6 of the load.
    assert!(
        up > 0.0 && (up - down).abs() < 1e-5 * up,
        "forces {up} vs {down}"
    );
}

/// The bilayer strip under the explicit dynamics (patch fit, 80 faces) stops by the default
/// test (the target is compatible: Φ relaxes to round-off, so the energy test is relative to
/// the target's starting energy) on the shape of the static solve of the same energy.
#[test]
fn explicit_bilayer_strip_stops_at_the_static_solution() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    shellsim(
        &[
            "mesh",
            "rectangle",
            "--lx",
            "1",
            "--ly",
            "0.1",
            "--edge",
            "0.05",
            "--program",
            "bilayer_strip",
            "-o",
            "strip.vtk",
        ],
        d,
    );
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let scene = root.join("settings/bilayer_strip_explicit.toml");
    let scene = scene.to_str().unwrap();
    shellsim(&[scene, "strip.vtk", "--out", "ex", "-q"], d);
    shellsim(
        &[
            scene,
            "strip.vtk",
            "--out",
            "st",
            "-q",
            "--set",
            "solver.mode=static",
        ],
        d,
    );
    let s = summary(&d.join("ex"));
    assert_eq!(s["converged"], true, "{}", s["reason"]);
    let dist = shape_distance(
        &final_frame(&d.join("ex")).positions,
        &final_frame(&d.join("st")).positions,
    );
    eprintln!("bilayer strip explicit vs static: {dist:e}");
    assert!(dist < 5e-4, "explicit vs static: {dist:e} of the size");
}
