//! Self-contact from the command line: a strip rolled by an end moment past a full turn winds
//! onto itself with its layers a thickness apart, in the spiral of the planar elastica with
//! self-contact (`scripts/elastica_roll.py`); a stack of sheets sinks into its offset by
//! the penalty's closed form; a sheet dropped onto another lands without crossing it; a sheet
//! on an inclined sheet slides or sticks by Coulomb's law; random thrusts on a folded sheet
//! never carry one layer through the other; a bunched straw wrapper wetted at one end unfolds
//! into its tube without crossing itself; bad input is named. Frames
//! are checked by an independent script (`scripts/contact_check.py`: VTK's readers and a
//! brute-force numpy search over every pair of faces, none of shellsim's code) for crossing
//! faces and for the smallest distance between mid-surfaces; the rolled strip without
//! self-contact is the control that the check can fail, and its frames are bitwise identical
//! on 1, 2 and 3 threads.
//!
//! Needs VTK's Python package: `scripts/test.sh` makes the project's `.venv/` with it and names
//! its interpreter in `SHELLSIM_PYTHON` (without that variable, `python3` is used).

use std::path::Path;
use std::process::Command;

mod common;
use common::{log_rows, shellsim};

/// The strip: L = 1, b = 0.04, h = 0.01, E = 1e7, ν = 0, clamped at x = −0.5, end moment
/// 1.5 × the full-circle moment 2πD/L (per unit width) at x = 0.5, 20 load steps.
const ROLL: &str = "[material]\nyoung = 1e7\npoisson = 0.0\nthickness = 0.01\n\
    [solver]\nsymmetry_breaking = 0.0\ncontinuation_step = 0.05\n\
    [output]\ncontinuation_frames = true\n\
    [[constraints.clamp]]\ninside = { min = [-1, -1, -1], max = [-0.499, 1, 1] }\n\
    [[loads.moment]]\nmoment = 7.853981633974483\n\
    inside = { min = [0.499, -1, -1], max = [1, 1, 1] }\n\
    [self_contact]\nenabled = true\n";

/// Runs `scripts/<script>` with `args` and `--json dir/<json>` in the project's Python (the
/// variable `SHELLSIM_PYTHON`, else `python3`); returns the JSON it wrote.
fn python_json(
    dir: &Path,
    script: &str,
    args: &[&std::ffi::OsStr],
    json: &str,
) -> serde_json::Value {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let python = std::env::var("SHELLSIM_PYTHON").unwrap_or_else(|_| "python3".into());
    let json = dir.join(json);
    let res = Command::new(&python)
        .arg(root.join("scripts").join(script))
        .args(args)
        .arg("--json")
        .arg(&json)
        .output()
        .unwrap_or_else(|e| panic!("{python}: {e}"));
    let text = std::fs::read_to_string(&json).unwrap_or_else(|_| {
        panic!(
            "{script} failed (is VTK in {python}? run the tests with scripts/test.sh):\n{}{}",
            String::from_utf8_lossy(&res.stdout),
            String::from_utf8_lossy(&res.stderr)
        )
    });
    serde_json::from_str(&text).unwrap()
}

/// Runs `scripts/contact_check.py` on the run `out` (reference mesh `mesh`) with exclusion
/// radius `r`; returns its JSON summary.
fn check(dir: &Path, mesh: &str, out: &str, r: f64) -> serde_json::Value {
    let (mesh, out, r) = (dir.join(mesh), dir.join(out), r.to_string());
    let args = [
        mesh.as_os_str(),
        out.as_os_str(),
        "--exclusion".as_ref(),
        r.as_ref(),
    ];
    let name = format!("{}.check.json", out.file_name().unwrap().to_string_lossy());
    python_json(dir, "contact_check.py", &args, &name)
}

/// Runs `scripts/elastica_roll.py` on the rolled strip's run `out` (the strip of [`ROLL`]);
/// returns its JSON comparison.
fn elastica(dir: &Path, out: &str, mesh: &str) -> serde_json::Value {
    let (run, mesh) = (dir.join(out), dir.join(mesh));
    let mut args = vec![run.as_os_str(), mesh.as_os_str()];
    for a in [
        "--length",
        "1",
        "--thickness",
        "0.01",
        "--young",
        "1e7",
        "--poisson",
        "0",
        "--moment",
        "7.853981633974483",
        "--segments",
        "150",
    ] {
        args.push(a.as_ref());
    }
    python_json(
        dir,
        "elastica_roll.py",
        &args,
        &format!("{out}.elastica.json"),
    )
}

/// A gallery scene that folds or rolls onto itself, checked at small size: copies
/// `settings/<scene>.toml` into `dir`, writes `shellsim mesh <mesh>` as `sheet.vtk`, and runs
/// it with the overrides `sets` into `on`, then without self-contact into `off`. Asserts that
/// the run with it converges, that its pairs press, that the independent script finds no
/// crossing face in any frame and no two mid-surfaces closer than the minimum separation (a
/// tenth of the offset, thickness `h`), and that the control crosses itself. Returns the most
/// pairs pressing at once.
fn presses_without_crossing(dir: &Path, scene: &str, mesh: &[&str], sets: &[&str], h: f64) -> f64 {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    std::fs::copy(
        root.join(format!("settings/{scene}.toml")),
        dir.join("scene.toml"),
    )
    .unwrap();
    let mut args = vec!["mesh"];
    args.extend_from_slice(mesh);
    args.extend_from_slice(&["-o", "sheet.vtk"]);
    shellsim(&args, dir);
    let run = |out: &str, extra: &[&str]| {
        let mut args = vec!["scene.toml", "sheet.vtk", "--out", out, "-q"];
        for s in sets.iter().chain(extra) {
            args.extend_from_slice(&["--set", s]);
        }
        shellsim(&args, dir);
    };
    run("on", &[]);
    let s: serde_json::Value = common::summary(&dir.join("on"));
    assert_eq!(s["converged"], true, "{scene}: {s}");
    let pressing = log_rows(&dir.join("on"))
        .iter()
        .map(|r| r["self_contact_pairs"])
        .fold(0.0, f64::max);
    let r = 2.0 * (h + h / 100.0);
    let c = check(dir, "sheet.vtk", "on", r);
    println!("{scene}: {pressing} pairs at most: {c}");
    assert!(pressing > 0.0, "{scene}: the sheet presses on itself");
    assert_eq!(c["crossing_pairs"], 0, "{scene}: {c}");
    let dmin = c["min_distance"].as_f64().unwrap();
    assert!(dmin >= 0.1 * h && dmin < h, "{scene}: {dmin}");
    run("off", &["self_contact.enabled=false"]);
    let c = check(dir, "sheet.vtk", "off", r);
    println!("{scene} without self-contact: {c}");
    assert!(c["crossing_pairs"].as_u64().unwrap() > 0, "{scene}: {c}");
    pressing
}

#[test]
fn a_strip_rolled_past_a_full_turn_winds_onto_itself_a_thickness_apart() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    shellsim(
        &[
            "mesh",
            "rectangle",
            "--lx",
            "1",
            "--ly",
            "0.04",
            "--edge",
            "0.02",
            "-o",
            "strip.vtk",
        ],
        dir,
    );
    std::fs::write(dir.join("roll.toml"), ROLL).unwrap();
    shellsim(&["roll.toml", "strip.vtk", "--out", "on", "-q"], dir);
    let s: serde_json::Value = common::summary(&dir.join("on"));
    assert_eq!(s["converged"], true, "{s}");
    assert!(s["energy"]["self_contact"].as_f64().unwrap() > 0.0, "{s}");
    // The tip turned through one and a half turns.
    let last = log_rows(&dir.join("on")).pop().unwrap();
    let turn = last["moment_rotation"] / (2.0 * std::f64::consts::PI);
    assert!((turn - 1.5).abs() < 0.02, "{turn} turns");
    // Exclusion radius 2 (ξ + δ) with ξ = h = 0.01, δ = h/100.
    let h = 0.01;
    let r = 2.0 * (h + h / 100.0);
    let c = check(dir, "strip.vtk", "on", r);
    println!("with self-contact: {c}");
    assert_eq!(c["crossing_pairs"], 0, "{c}");
    // The layers touch: the smallest mid-surface distance is the offset less the penalty's
    // penetration (about 4e-5 here; the closed form's σ/k + δ/2 at the contact pressure).
    let dmin = c["min_distance"].as_f64().unwrap();
    assert!(dmin > 0.99 * h && dmin < 1.001 * h, "{dmin}");
    // The spiral against the planar elastica with self-contact, solved independently by
    // `scripts/elastica_roll.py`. The tip winds inside the first turn: the turns' radii r_0 (the
    // tip's) and r_1 (the first's) are within 1% of the elastica's (measured −0.6% and −0.4% on
    // this mesh, −0.25% and −0.2% at edges of h/2), and where the tip's turn lies over the first
    // the layers are h apart to 1% of the radius: r_1 = r_0 + h at every angle they share
    // (measured 0.998 h to 1.064 h; the elastica: 0.992 h to 1.063 h).
    let e = elastica(dir, "on", "strip.vtk");
    println!("against the elastica: {e}");
    for k in ["r0", "r1"] {
        let shell = e["shell"][k].as_f64().unwrap();
        let reference = e["elastica"][k].as_f64().unwrap();
        assert!(
            (shell / reference - 1.0).abs() < 0.01,
            "{k}: {shell} against {reference}"
        );
    }
    let r0 = e["elastica"]["r0"].as_f64().unwrap();
    let gap = &e["shell"]["gap"];
    assert!(gap[0].as_f64().unwrap() > 0.99 * h, "{gap}");
    assert!(gap[2].as_f64().unwrap() < h + 0.01 * r0, "{gap}");
    // The control: without self-contact the strip passes through itself, and the check sees it.
    shellsim(
        &[
            "roll.toml",
            "strip.vtk",
            "--out",
            "off",
            "-q",
            "--set",
            "self_contact.enabled=false",
        ],
        dir,
    );
    let c = check(dir, "strip.vtk", "off", r);
    assert!(c["crossing_pairs"].as_u64().unwrap() > 0, "{c}");
    // Bitwise identical on 1 and 3 threads (the default is 2).
    for t in ["1", "3"] {
        let out = format!("t{t}");
        shellsim(
            &[
                "roll.toml",
                "strip.vtk",
                "--out",
                &out,
                "-q",
                "--threads",
                t,
            ],
            dir,
        );
        for k in [10, 20] {
            let f = format!("frame_{k:05}.vtu");
            let a = std::fs::read(dir.join("on").join(&f)).unwrap();
            let b = std::fs::read(dir.join(&out).join(&f)).unwrap();
            assert!(a == b, "{f} differs on {t} threads");
        }
    }
}

/// Squares of side `side` (edges about `edge`, jittered, each its own seed) with their corners
/// at `corners`, flat, written as one mesh `name` in `dir`.
fn sheets_mesh(dir: &Path, name: &str, side: f64, edge: f64, corners: &[(f64, f64, f64)]) {
    use shellsim::mesh::generate::{rectangle, Spacing};
    let mut mesh = shellsim::mesh::Mesh::default();
    for (k, &(x0, y0, z0)) in corners.iter().enumerate() {
        let m = rectangle(
            x0,
            y0,
            side,
            side,
            edge,
            Spacing {
                jitter: 0.2,
                seed: 5 + k as u64,
                ..Default::default()
            },
        );
        let base = mesh.positions.len();
        mesh.positions.extend(
            m.positions
                .iter()
                .map(|p| shellsim::math::Vec3::new(p.x, p.y, z0)),
        );
        mesh.faces.extend(
            m.faces
                .iter()
                .map(|f| [f[0] + base, f[1] + base, f[2] + base]),
        );
    }
    shellsim::mesh::io::write_mesh(
        &dir.join(name),
        &mesh,
        shellsim::mesh::io::Format::Vtk,
        name,
    )
    .unwrap();
}

/// The force (N, along z) that the self-contact carries through each interface of a stack of
/// `sheets` sheets of equal vertex counts, numbered from the bottom, at the positions of
/// `frame`: the contact forces `−∇E` summed over the vertices of the sheets above interface
/// `k` (between sheets `k − 1` and `k`), for `k = 1 … sheets − 1`. The scene is built from the
/// run's settings and reference mesh with the library, and its contact term evaluated alone.
fn interface_forces(
    dir: &Path,
    settings: &str,
    mesh: &str,
    frame: &Path,
    sheets: usize,
) -> Vec<f64> {
    use shellsim::assembly::{Pattern, Want};
    use shellsim::energy::{HessianProjection, Potential};
    let text = std::fs::read_to_string(dir.join(settings)).unwrap();
    let m = shellsim::mesh::io::read_mesh(&dir.join(mesh)).unwrap();
    let sc = shellsim::model::Scene::build(
        m,
        shellsim::settings::Settings::from_str_with(&text, settings, &[]).unwrap(),
    )
    .unwrap();
    let x = shellsim::mesh::io::read_mesh(frame).unwrap().positions;
    let phi = vec![0.0; sc.num_scalar_dofs()];
    // The pairs at the frame (those at rest when they are the same).
    let rest = Pattern::for_scene(&sc);
    let p = rest.refreshed(&sc, &x, &phi, 0.0).unwrap_or(rest);
    let i = (0..sc.terms.len())
        .find(|&i| sc.terms[i].name() == "self_contact")
        .unwrap();
    let pot = Potential::new(&sc, &p);
    let mut g = vec![0.0; p.n];
    sc.terms[i].eval(
        &pot,
        &p.maps[i],
        &x,
        &phi,
        Want::Gradient,
        HessianProjection::None,
        &mut g,
        &mut [],
    );
    let n = x.len() / sheets;
    let up = |k: usize| -> f64 { (k * n..(k + 1) * n).map(|v| -g[3 * v + 2]).sum() };
    (1..sheets).map(|k| (k..sheets).map(up).sum()).collect()
}

/// Three 5 cm squares (h = 1 mm, E = 1 MPa, ρ = 1000 kg/m³) stacked a thickness apart under a
/// gravity of 1000 m/s²: the bottom one held, the others free to move up and down. Each
/// interface carries the weight above it, σ = ρ h g per sheet (1 and 2 kPa), below the
/// penalty's kδ/2 = 5 kPa (k = E/h, δ = h/100): its closed-form penetration into the offset is
/// √(2δσ/k), 4.47 µm and 6.32 µm. Measured as the offset less the mean distance between the
/// sheets: 0.42% and 0.46% below (the pressure varies a little over the jittered meshes, and
/// the mean of the square root is below the square root of the mean); asserted within 1%. The
/// contact forces through the two interfaces (`−∇E` of the contact term, summed over the
/// sheets above each) are the weights above them, the
/// pairs' normal forces sum to the weights above the two interfaces (measured to 1.6e-9), the
/// frames' mean contact pressure on each sheet is the weight pressure on its sides (to 3e-9),
/// and the held sheet's support carries all three sheets, all asserted to 1e-6.
#[test]
fn a_stack_of_sheets_sinks_into_its_offset_by_the_closed_form() {
    stack_of_three("penalty");
}

/// The same stack with IPC's log barrier (`law = "barrier"`, activation ĝ = h/100): the
/// sheets stop outside their offset, at the gap g where the barrier's pressure
/// `−k b′(g)` equals the weight pressure σ (found by bisection; b′ increases on (0, ĝ)):
/// 7.640 µm and 8.285 µm (k = E/h = 1e9 Pa/m, σ = 2 and 1 kPa). Measured as the mean distance
/// between the sheets less the offset: 0.13% and 0.08% above, asserted within 1%, and every
/// force and pressure balances as with the penalty. The planar start's symmetry-breaking
/// perturbation (1e-5 m, ten times the sheets' 1 µm gap) is scaled down by the contact's
/// collision detection.
#[test]
fn a_stack_of_sheets_on_the_barrier_stops_at_its_closed_form_gap() {
    stack_of_three("barrier");
}

/// Three stacked sheets under their weights with the normal law `law` (the penalty's test
/// above).
fn stack_of_three(law: &str) {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    let (h, e, rho, g, side) = (1e-3, 1e6, 1000.0, 1000.0, 0.05);
    let sheets: Vec<(f64, f64, f64)> = (0..3).map(|k| (0.0, 0.0, k as f64 * 1.001 * h)).collect();
    sheets_mesh(dir, "stack.vtk", side, 0.01, &sheets);
    let settings = format!(
        "[material]\nyoung = {e}\nthickness = {h}\ndensity = {rho}\n\
         [loads]\ngravity = [0, 0, -{g}]\n\
         [constraints]\nfix_boxes = [{{ min = [-1, -1, -1e-4], max = [1, 1, 1e-4] }}]\n\
         [[constraints.support]]\ncomponents = [\"x\", \"y\"]\n\
         inside = {{ min = [-1, -1, 5e-4], max = [1, 1, 1] }}\n\
         [self_contact]\nenabled = true\nlaw = \"{law}\"\n"
    );
    std::fs::write(dir.join("stack.toml"), settings).unwrap();
    shellsim(&["stack.toml", "stack.vtk", "--out", "out", "-q"], dir);
    let s: serde_json::Value = common::summary(&dir.join("out"));
    assert_eq!(s["converged"], true, "{s}");
    // The contact carries the weight above each interface: one sheet's and two sheets', and
    // the held sheet's support the weight of all three.
    let w1 = rho * h * g * side * side;
    let last = log_rows(&dir.join("out")).pop().unwrap();
    let carried = last["self_contact_force"];
    println!(
        "contact force {carried} N, weights above the interfaces {} N",
        3.0 * w1
    );
    assert!((carried - 3.0 * w1).abs() < 1e-6 * 3.0 * w1, "{carried}");
    let through = interface_forces(
        dir,
        "stack.toml",
        "stack.vtk",
        &dir.join("out").join(s["final_frame"].as_str().unwrap()),
        3,
    );
    println!("forces through the interfaces {through:?} N");
    for (k, f) in through.iter().enumerate() {
        let w = (2 - k) as f64 * w1;
        assert!((f - w).abs() < 1e-6 * w, "interface {}: {f} vs {w}", k + 1);
    }
    let held = s["reactions"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| r["support"] == "fix_boxes[0]")
        .unwrap_or_else(|| panic!("{}", s["reactions"]))["force"][2]
        .as_f64()
        .unwrap();
    assert!((held - 3.0 * w1).abs() < 1e-6 * 3.0 * w1, "{held}");
    let frames = common::finite_frames(&dir.join("out"), "vtu", "stack");
    let x = &frames.last().unwrap().positions;
    // The frames' contact pressure, per sheet (area-weighted): the top sheet is pressed from
    // below by its weight's pressure, the middle one from both sides (σ + 2σ), the held one
    // by 2σ.
    let fm = frames.last().unwrap();
    let pressure = &fm.face_fields["contact_pressure"].data;
    let nf = fm.faces.len() / 3;
    for (k, expected) in [(0, 2.0), (1, 3.0), (2, 1.0)] {
        let (mut pa, mut a) = (0.0, 0.0);
        for (f, pf) in pressure.iter().enumerate().skip(k * nf).take(nf) {
            let area = fm.face_area(f);
            pa += pf * area;
            a += area;
        }
        let sigma = expected * rho * h * g;
        println!(
            "sheet {k}: mean contact pressure {} Pa, expected {sigma} Pa",
            pa / a
        );
        assert!(
            (pa / a - sigma).abs() < 1e-6 * sigma,
            "sheet {k}: {}",
            pa / a
        );
    }
    let n = x.len() / 3;
    let mean_z = |k: usize| x[k * n..(k + 1) * n].iter().map(|p| p.z).sum::<f64>() / n as f64;
    let (k_pen, delta) = (e / h, h / 100.0);
    for (upper, carried) in [(1, 2.0), (2, 1.0)] {
        let sigma = carried * rho * h * g;
        // The penetration into the offset (negative: a gap outside it).
        let exact = if law == "barrier" {
            -common::barrier_gap(sigma, k_pen, delta)
        } else {
            (2.0 * delta * sigma / k_pen).sqrt()
        };
        let p = h - (mean_z(upper) - mean_z(upper - 1));
        println!("interface under sheet {upper}: penetration {p:.6e}, closed form {exact:.6e}");
        assert!((p - exact).abs() < 0.01 * exact.abs(), "{p} vs {exact}");
    }
}

/// A square dropped from 1 cm onto a held one, shifted so that it overhangs an edge, in
/// dynamic mode: it lands at 0.44 m/s, bounces and settles over the edge. No frame has
/// crossing faces or two mid-surfaces closer than the minimum separation (a tenth of the
/// offset): checked by the independent script. Measured: the closest approach 0.622 mm of the
/// 1 mm offset, at the impact, where the edges of the tilted sheet cross the held sheet's
/// edge (edge–edge pairs press only inside half the offset). The same with every face within
/// reach pressing, and with IPC's log barrier, whose faces never come within half the offset
/// (measured 0.634 mm).
#[test]
fn a_dropped_sheet_lands_on_another_without_crossing_it() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    let h = 1e-3;
    sheets_mesh(
        dir,
        "drop.vtk",
        0.05,
        0.01,
        &[(0.0, 0.0, 0.0), (0.003, 0.002, 0.01)],
    );
    std::fs::write(
        dir.join("drop.toml"),
        format!(
            "[material]\nyoung = 1e6\nthickness = {h}\ndensity = 1000\n\
             [solver]\nmode = \"dynamic\"\n\
             [time]\nend = 0.3\ndt = 1e-3\noutput_interval = 0.01\n\
             [loads]\ngravity = [0, 0, -9.81]\n\
             [constraints]\nfix_boxes = [{{ min = [-1, -1, -1e-4], max = [1, 1, 1e-4] }}]\n\
             [self_contact]\nenabled = true\n"
        ),
    )
    .unwrap();
    // Runs the drop into `out` with the `--set` overrides `set`: no face pair crosses in any
    // of the 31 frames; returns the closest mid-surface distance.
    let dropped = |out: &str, set: &[&str]| -> f64 {
        let mut args = vec!["drop.toml", "drop.vtk", "--out", out, "-q"];
        for s in set {
            args.extend(["--set", s]);
        }
        shellsim(&args, dir);
        let c = check(dir, "drop.vtk", out, 2.0 * (h + h / 100.0));
        println!("dropped sheet {set:?}: {c}");
        assert_eq!(c["crossing_pairs"], 0, "{c}");
        assert_eq!(c["frames"], 31);
        c["min_distance"].as_f64().unwrap()
    };
    let dmin = dropped("out", &[]);
    let last = log_rows(&dir.join("out")).pop().unwrap();
    assert!(
        last["self_contact_pairs"] > 0.0,
        "the sheet rests on the other"
    );
    assert!(dmin >= 0.1 * h && dmin < h, "{dmin}");
    // Every face within reach pressing (pairs = "all"): the same guarantee.
    let dmin = dropped("all", &["self_contact.pairs=\"all\""]);
    assert!(dmin >= 0.1 * h && dmin < h, "{dmin}");
    // IPC's log barrier: no vertex enters the offset and no edge comes within half of it,
    // so no two faces come closer than ξ/2.
    let dmin = dropped("barrier", &["self_contact.law=\"barrier\""]);
    assert!(dmin > 0.5 * h && dmin < h, "{dmin}");
    let gap = log_rows(&dir.join("barrier"))
        .iter()
        .map(|r| r["self_contact_gap"])
        .fold(f64::INFINITY, f64::min);
    assert!(gap > 0.5, "{gap}");
}

/// A 15 cm square at z = 0 and a 5 cm square 1.0005 h above it (h = 1 mm, edges about 1 cm,
/// jittered), written as `incline.vtk` in `dir`; returns the upper square's vertices.
fn incline_mesh(dir: &Path, h: f64) -> Vec<usize> {
    use shellsim::mesh::generate::{rectangle, Spacing};
    let mut mesh = shellsim::mesh::Mesh::default();
    for (x0, side, z, seed) in [(0.0, 0.15, 0.0, 3), (0.01, 0.05, 1.0005 * h, 4)] {
        let m = rectangle(
            x0,
            0.05 - side / 2.0,
            side,
            side,
            0.01,
            Spacing {
                jitter: 0.2,
                seed,
                ..Default::default()
            },
        );
        let base = mesh.positions.len();
        mesh.positions.extend(
            m.positions
                .iter()
                .map(|p| shellsim::math::Vec3::new(p.x, p.y, z)),
        );
        mesh.faces.extend(
            m.faces
                .iter()
                .map(|f| [f[0] + base, f[1] + base, f[2] + base]),
        );
    }
    let nv = mesh.positions.len();
    let top: Vec<usize> = (0..nv).filter(|&v| mesh.positions[v].z > 0.5 * h).collect();
    shellsim::mesh::io::write_mesh(
        &dir.join("incline.vtk"),
        &mesh,
        shellsim::mesh::io::Format::Vtk,
        "incline",
    )
    .unwrap();
    top
}

/// The run `out`'s summary, its final frame's path, and over the vertices `top` the mean
/// velocity (m/s) and displacement (m) there: plain, or weighted by the lumped masses (a third
/// of each face's reference area, the thickness and density being uniform) with `by_mass`.
fn final_means(
    out: &Path,
    top: &[usize],
    by_mass: bool,
) -> (serde_json::Value, std::path::PathBuf, [f64; 3], [f64; 3]) {
    let s = common::summary(out);
    let frame = out.join(s["final_frame"].as_str().unwrap());
    let m = shellsim::mesh::io::read_mesh(&frame).unwrap();
    let mut weight = vec![1.0; m.positions.len()];
    if by_mass {
        let u = &m.vertex_fields["displacement"];
        let rest = |v: usize| m.positions[v] - shellsim::math::Vec3::from_column_slice(u.get(v));
        weight.fill(0.0);
        for f in &m.faces {
            let a = 0.5
                * (rest(f[1]) - rest(f[0]))
                    .cross(&(rest(f[2]) - rest(f[0])))
                    .norm();
            for &v in f {
                weight[v] += a / 3.0;
            }
        }
    }
    let total: f64 = top.iter().map(|&v| weight[v]).sum();
    let mean = |name: &str| {
        let f = &m.vertex_fields[name];
        let mut out = [0.0; 3];
        for &v in top {
            for (k, o) in out.iter_mut().enumerate() {
                *o += f.get(v)[k] * weight[v] / total;
            }
        }
        out
    };
    let (v, u) = (mean("velocity"), mean("displacement"));
    (s, frame, v, u)
}

/// A 5 cm square (h = 1 mm, E = 1 MPa, ρ = 1000 kg/m³) resting on a held 15 cm one, gravity
/// tilted by θ = 30° from their normal (an incline), friction between the sheets μ, dynamic
/// mode. With μ = 0.3 < tan θ the top sheet slides at `a = g (sin θ − μ cos θ)`: its mean
/// velocity down the slope is `a t` (implicit Euler is exact under a constant force), counting
/// the momentum of its first settling onto the penalty, `v_x + μ v_z` (as on the plane
/// obstacle), asserted to 1e-3 (measured 8e-6), and its pairs' friction forces sum to μ times
/// the weight's normal part (1e-3; measured 1.4e-5). With μ = 0.8 > tan θ it sticks: the
/// smoothed friction balances the slope where `f₁ = 2r − r² = tan θ / μ`, so the sheet creeps
/// at exactly `r ε_v`, `r = 1 − √(1 − tan θ/μ)` (ε_v = 1e-5 m/s, `contact.slip_speed` set in the test;
/// measured to 5e-4, asserted to 1e-3). The sliding run's last frame and friction column are
/// the same bits on 1 thread as on 2.
#[test]
fn a_sheet_on_an_inclined_sheet_slides_or_sticks_by_coulomb() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    let h = 1e-3;
    let top = incline_mesh(dir, h);
    let (g, theta) = (9.81_f64, 30_f64.to_radians());
    for mu in [0.3, 0.8] {
        let tag = format!("mu{}", (mu * 10.0) as i32);
        std::fs::write(
            dir.join(format!("{tag}.toml")),
            format!(
                "[material]\nyoung = 1e6\nthickness = {h}\ndensity = 1000\n\
                 [solver]\nmode = \"dynamic\"\nsymmetry_breaking = 0\n\
                 [time]\nend = 0.2\ndt = 1e-3\ndt_max = 0.01\noutput_interval = 0.05\n\
                 [loads]\ngravity = [{}, 0, {}]\n\
                 [constraints]\nfix_boxes = [{{ min = [-1, -1, -1e-4], max = [1, 1, 1e-4] }}]\n\
                 [contact]\nslip_speed = 1e-5\n\
                 [self_contact]\nenabled = true\nfriction = {mu}\n",
                g * theta.sin(),
                -g * theta.cos()
            ),
        )
        .unwrap();
        shellsim(
            &[&format!("{tag}.toml"), "incline.vtk", "--out", &tag, "-q"],
            dir,
        );
        let (s, frame, v, u) = final_means(&dir.join(&tag), &top, false);
        let rows = log_rows(&dir.join(&tag));
        // The contact's timings: present, and growing over the run.
        for part in ["broad", "ccd", "assembly"] {
            let col = format!("self_contact_{part}_seconds");
            let first = rows[0][&col];
            let last = rows.last().unwrap()[&col];
            assert!(first >= 0.0 && last > first, "{col}: {first} → {last}");
        }
        let row = rows.last().unwrap().clone();
        let t = row["time"];
        let a = g * (theta.sin() - mu * theta.cos());
        let weight_n = 1000.0 * h * 0.05 * 0.05 * g * theta.cos();
        println!(
            "μ = {mu}: t {t} s, velocity {v:?} m/s, displacement {u:?} m, a t = {}; \
             friction {} N, μ N = {}",
            a * t,
            row["self_contact_friction"],
            mu * weight_n
        );
        assert!((t - 0.2).abs() < 1e-9, "{tag}: t = {t}");
        assert!(v[1].abs() < 1e-3 * (a * t).abs().max(1e-5), "{tag}: {v:?}");
        if mu < theta.tan() {
            // The same bits on one thread: frames and the friction column.
            shellsim(
                &[
                    &format!("{tag}.toml"),
                    "incline.vtk",
                    "--out",
                    "t1",
                    "-q",
                    "--threads",
                    "1",
                ],
                dir,
            );
            let one = dir.join("t1").join(s["final_frame"].as_str().unwrap());
            assert!(
                std::fs::read(&frame).unwrap() == std::fs::read(&one).unwrap(),
                "the final frame differs on 1 thread"
            );
            let row1 = log_rows(&dir.join("t1")).pop().unwrap();
            assert_eq!(
                row1["self_contact_friction"].to_bits(),
                row["self_contact_friction"].to_bits()
            );
            let slide = v[0] + mu * v[2];
            assert!(
                (slide / (a * t) - 1.0).abs() < 1e-3,
                "{tag}: {v:?} vs {}",
                a * t
            );
            let f = row["self_contact_friction"];
            assert!(
                (f / (mu * weight_n) - 1.0).abs() < 1e-3,
                "{tag}: friction {f} vs {}",
                mu * weight_n
            );
        } else {
            let creep = (1.0 - (1.0 - theta.tan() / mu).sqrt()) * 1e-5;
            assert!((v[0] / creep - 1.0).abs() < 1e-3, "{tag}: {v:?} vs {creep}");
            assert!(u[0].abs() <= 1e-5 * t, "{tag}: {u:?}");
        }
    }
}

/// The inclined sheet of the test above in explicit mode (no drag, MorphoShell's midedge
/// bending), where friction between sheets is Coulomb's stick/slip on the pressing pairs,
/// solved together in each step, with the pairs' normal dashpot (ζ = 1): with μ = 0.3 < tan θ
/// the upper sheet's momentum down the slope grows as `a t`, `a = g (sin θ − μ cos θ)`, once
/// the momentum of its bounce is counted (`v_x + μ v_z`, mass-weighted means; measured
/// 1.3e-4), and across the slope it does not move (1.6e-6 of `a t`); both asserted to 1e-3;
/// with μ = 0.8 it holds: it slips 0.5 µm while it lands, then stops dead (asserted: less
/// than 10 µm, and no speed down the slope above 1e-9 m/s). Without the dashpot the landed
/// sheet rang on its contact springs, undamped by the driver, and crept down at 4 mm/s with
/// μ = 0.8. Both runs end at the time limit (exit 1).
#[test]
fn a_sheet_on_an_inclined_sheet_slides_or_sticks_in_explicit_mode() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    let h = 1e-3;
    let top = incline_mesh(dir, h);
    let (g, theta) = (9.81_f64, 30_f64.to_radians());
    for mu in [0.3, 0.8] {
        let tag = format!("mu{}", (mu * 10.0) as i32);
        std::fs::write(
            dir.join(format!("{tag}.toml")),
            format!(
                "[material]\nyoung = 1e6\nthickness = {h}\ndensity = 1000\nbending = \"midedge_average\"\n\
                 [solver]\nmode = \"explicit\"\nsymmetry_breaking = 0\n\
                 [explicit]\ndamping_prefactor_dial = 0\ndamping_prefactor_wait = 0\n\
                 max_long_times = {}\nwindow_long_times = 0.01\nframes_per_long_time = 100\n\
                 [loads]\ngravity = [{}, 0, {}]\n\
                 [constraints]\nfix_boxes = [{{ min = [-1, -1, -1e-4], max = [1, 1, 1e-4] }}]\n\
                 [self_contact]\nenabled = true\nfriction = {mu}\n",
                LONG_TIMES,
                g * theta.sin(),
                -g * theta.cos()
            ),
        )
        .unwrap();
        let (code, _, err) = common::run_status(
            &[&format!("{tag}.toml"), "incline.vtk", "--out", &tag, "-q"],
            dir,
        );
        assert_eq!(code, 1, "{tag}: {err}");
        // Weighted by the lumped masses, the mean is the sheet's momentum over its mass: its
        // in-plane vibrations drop out.
        let (s, _, v, u) = final_means(&dir.join(&tag), &top, true);
        let t = s["time"].as_f64().unwrap();
        let a = g * (theta.sin() - mu * theta.cos());
        println!(
            "explicit μ = {mu}: t {t} s, velocity {v:?} m/s, displacement {u:?} m, a t = {}; {}",
            a * t,
            s["explicit"]
        );
        assert!(v[1].abs() < 1e-3 * (a * t).abs(), "{tag}: {v:?}");
        if mu < theta.tan() {
            let slide = v[0] + mu * v[2];
            assert!(
                (slide / (a * t) - 1.0).abs() < 1e-3,
                "{tag}: {v:?} vs {}",
                a * t
            );
        } else {
            assert!(u[0].abs() < 1e-5, "{tag}: {u:?}");
            assert!(v[0].abs() < 1e-9, "{tag}: {v:?}");
        }
    }
}

/// How long the explicit incline runs, in long times (6 s: 0.2 s, as in dynamic mode).
const LONG_TIMES: f64 = 0.0334;

/// Bad self-contact input is exit 2 with a message naming what is wrong, and nothing written:
/// two sheets that pass through each other (naming the two faces), two sheets closer than
/// their offset (naming the vertex and the face), an exclusion radius too small for a mesh
/// finer than its thickness (naming the radius that would do), a negative friction, and in
/// explicit mode the barrier (naming the key).
#[test]
fn bad_self_contact_input_is_named_and_writes_nothing() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    let h = 1e-3;
    // A square, and a second one standing up through its middle.
    use shellsim::math::Vec3;
    use shellsim::mesh::generate::{rectangle, Spacing};
    let flat = rectangle(0.0, 0.0, 0.02, 0.02, 0.005, Spacing::default());
    let mut mesh = flat.clone();
    let base = mesh.positions.len();
    mesh.positions.extend(
        flat.positions
            .iter()
            .map(|p| Vec3::new(p.x + 0.001, 0.0101, p.y - 0.0097)),
    );
    mesh.faces.extend(
        flat.faces
            .iter()
            .map(|f| [f[0] + base, f[1] + base, f[2] + base]),
    );
    let write = |name: &str, m: &shellsim::mesh::Mesh| {
        shellsim::mesh::io::write_mesh(&dir.join(name), m, shellsim::mesh::io::Format::Vtk, name)
            .unwrap()
    };
    write("crossed.vtk", &mesh);
    sheets_mesh(
        dir,
        "close.vtk",
        0.02,
        0.005,
        &[(0.0, 0.0, 0.0), (0.0, 0.0, 0.5 * h)],
    );
    sheets_mesh(dir, "fine.vtk", 0.01, 0.5 * h, &[(0.0, 0.0, 0.0)]);
    sheets_mesh(dir, "one.vtk", 0.02, 0.005, &[(0.0, 0.0, 0.0)]);
    let base = format!("[material]\nyoung = 1e6\nthickness = {h}\n");
    let cases: [(&str, &str, &str, &[&str]); 7] = [
        (
            "crossed.vtk",
            "",
            "",
            &["faces", "intersect", "passes through face"],
        ),
        (
            "close.vtk",
            "",
            "",
            &["vertex", "face", "closer than their offset"],
        ),
        (
            "fine.vtk",
            "exclusion = 2e-4\n",
            "",
            &["raise self_contact.exclusion to at least"],
        ),
        (
            "close.vtk",
            "friction = -0.1\n",
            "",
            &["self_contact.friction"],
        ),
        (
            "one.vtk",
            "law = \"barrier\"\n",
            "bending = \"patch_fit\"\n[solver]\nmode = \"explicit\"\n",
            &["self_contact.law", "explicit"],
        ),
        // The barrier's activation distance beyond the halo (the offset, 1 mm, by default).
        (
            "one.vtk",
            "law = \"barrier\"\nsmoothing = 2e-3\n",
            "",
            &["self_contact.smoothing", "halo"],
        ),
        (
            "one.vtk",
            "law = \"wall\"\n",
            "",
            &["law", "penalty", "barrier"],
        ),
    ];
    for (k, (mesh, extra, solver, words)) in cases.iter().enumerate() {
        let toml = format!("bad{k}.toml");
        std::fs::write(
            dir.join(&toml),
            format!("{base}{solver}[self_contact]\nenabled = true\n{extra}"),
        )
        .unwrap();
        let out = format!("out{k}");
        let (code, _, err) = common::run_status(&[&toml, mesh, "--out", &out, "-q"], dir);
        println!("{mesh} {extra}{solver}: {err}");
        assert_eq!(code, 2, "{mesh}: {err}");
        for w in *words {
            assert!(err.contains(w), "{mesh}: no {w:?} in {err}");
        }
        assert!(!err.contains("panicked"), "{err}");
        assert!(!dir.join(&out).exists(), "{mesh}: {out} was written");
    }
}

/// A 10 × 2 cm sheet (h = 1 mm, edges about 4 mm, jittered) folded flat onto itself through a
/// half circle of radius 1.5 h, written as `fold.vtk` in `dir`; per vertex, which layer it is
/// in (1 below, −1 above, 0 on the bend).
fn folded_sheet(dir: &Path) -> (shellsim::mesh::Mesh, Vec<f64>) {
    use shellsim::math::Vec3;
    use shellsim::mesh::generate::{rectangle, Spacing};
    let h = 1e-3;
    let flat = rectangle(
        0.0,
        0.0,
        0.1,
        0.02,
        0.004,
        Spacing {
            jitter: 0.2,
            seed: 11,
            ..Default::default()
        },
    );
    let r = 1.5 * h;
    let arc = std::f64::consts::PI * r;
    let mut folded = flat.clone();
    let mut layer = Vec::new();
    for p in folded.positions.iter_mut() {
        let s = p.x - 0.05;
        let (q, side) = if s <= 0.0 {
            (Vec3::new(p.x, p.y, 0.0), 1.0)
        } else if s < arc {
            let t = s / r;
            (Vec3::new(0.05 + r * t.sin(), p.y, r * (1.0 - t.cos())), 0.0)
        } else {
            (Vec3::new(0.05 - (s - arc), p.y, 2.0 * r), -1.0)
        };
        *p = q;
        layer.push(side);
    }
    shellsim::mesh::io::write_mesh(
        &dir.join("fold.vtk"),
        &folded,
        shellsim::mesh::io::Format::Vtk,
        "fold",
    )
    .unwrap();
    (folded, layer)
}

/// Writes `start{seed}.vtk` in `dir`: the folded sheet with random velocities (m/s), each
/// component uniform in ±`scale`, plus a thrust of the layers toward each other of
/// `scale` × (1.5 to 3).
fn thrust(
    dir: &Path,
    folded: &shellsim::mesh::Mesh,
    layer: &[f64],
    seed: u64,
    scale: f64,
) -> String {
    let mut rng = shellsim::mesh::generate::Rng::new(seed);
    let mut start = folded.clone();
    let v: Vec<f64> = layer
        .iter()
        .flat_map(|&side| {
            let toward = side * (1.5 + 1.5 * rng.uniform());
            [
                scale * rng.symmetric(),
                scale * rng.symmetric(),
                scale * (toward + rng.symmetric()),
            ]
        })
        .collect();
    start.vertex_fields.insert(
        "velocity".into(),
        shellsim::mesh::Field {
            components: 3,
            data: v,
        },
    );
    let frame = format!("start{seed}.vtk");
    shellsim::mesh::io::write_mesh(
        &dir.join(&frame),
        &start,
        shellsim::mesh::io::Format::Vtk,
        "start",
    )
    .unwrap();
    frame
}

/// Random thrusts on a folded sheet: a 10 × 2 cm strip (h = 1 mm, E = 1 MPa) folded at rest
/// over a half circle of radius 1.5 h, its layers 3 h apart, is started from its rest shape
/// with random velocities: each layer driven toward the other at 1.5–3 m/s, with random
/// in-plane and normal components of up to 1 m/s per vertex, three seeds, in dynamic mode
/// for 10 ms with a frame every 0.2 ms (the layers meet within 0.5 ms, crumple and bounce).
/// In no frame does a face cross another or two mid-surfaces come closer than the minimum
/// separation (a tenth of the offset), checked by the independent script over every pair of
/// faces. Measured: the closest approach 0.67–0.81 h; without self-contact the first seed's
/// layers cross at 794 face pairs.
#[test]
fn random_thrusts_on_a_folded_sheet_never_cross_it() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    let h = 1e-3;
    let (folded, layer) = folded_sheet(dir);
    std::fs::write(
        dir.join("thrust.toml"),
        format!(
            "[material]\nyoung = 1e6\nthickness = {h}\ndensity = 1000\n\
             [solver]\nmode = \"dynamic\"\nsymmetry_breaking = 0\n\
             [time]\nend = 0.01\ndt = 1e-4\ndt_max = 1e-4\noutput_interval = 2e-4\n\
             [self_contact]\nenabled = true\n"
        ),
    )
    .unwrap();
    for seed in 1..=3u64 {
        let frame = thrust(dir, &folded, &layer, seed, 1.0);
        let out = format!("seed{seed}");
        shellsim(
            &[
                "thrust.toml",
                "fold.vtk",
                "--out",
                &out,
                "-q",
                "--restart",
                &frame,
            ],
            dir,
        );
        let c = check(dir, "fold.vtk", &out, 2.0 * (h + h / 100.0));
        println!("seed {seed}: {c}");
        assert_eq!(c["crossing_pairs"], 0, "seed {seed}: {c}");
        assert_eq!(c["frames"], 51, "seed {seed}");
        let dmin = c["min_distance"].as_f64().unwrap();
        assert!(dmin >= 0.1 * h && dmin < h, "seed {seed}: {dmin}");
    }
}

/// Random thrusts in explicit mode, ten times harder: the folded sheet of the test above, its
/// layers driven toward each other at 15–30 m/s with random components of up to 10 m/s, three
/// seeds, under MorphoShell's damped explicit dynamics (self-contact's default stiffness
/// there, ρh/(4Δt²), is the stiffest the step resolves, and with its dashpot cannot stop every
/// vertex of such a thrust within the offset) for 4 ms with a frame every 0.08 ms. The
/// per-vertex displacement bounds pull back the vertices that would pass them: in no frame
/// does a face cross another or two mid-surfaces come closer than the minimum separation,
/// checked by the independent script (measured: 0.24–0.35 h at the closest), and they did act
/// (`contact_clipped` > 0: 21–37 vertex steps per run). The frames are bitwise identical on 1 and 3
/// threads, a restart from a frame follows the whole run to the bit, and the control without
/// self-contact crosses.
#[test]
fn random_thrusts_in_explicit_mode_never_cross_the_sheet() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    let h = 1e-3;
    let (folded, layer) = folded_sheet(dir);
    std::fs::write(
        dir.join("thrust.toml"),
        format!(
            "[material]\nyoung = 1e6\nthickness = {h}\ndensity = 1000\nbending = \"midedge_average\"\n\
             [solver]\nmode = \"explicit\"\n\
             [explicit]\nmax_long_times = 0.004\nwindow_long_times = 0.002\nframes_per_long_time = 12500\n\
             [self_contact]\nenabled = true\n"
        ),
    )
    .unwrap();
    let mut clipped = 0;
    for seed in 1..=3u64 {
        let frame = thrust(dir, &folded, &layer, seed, 10.0);
        let out = format!("seed{seed}");
        let args = [
            "thrust.toml",
            "fold.vtk",
            "--out",
            &out,
            "-q",
            "--restart",
            &frame,
        ];
        let (code, _, err) = common::run_status(&args, dir);
        assert_eq!(code, 1, "seed {seed}: the time limit ends the run: {err}");
        let s = common::summary(&dir.join(&out));
        println!("seed {seed}: {}", s["explicit"]);
        clipped += s["explicit"]["contact_clipped"].as_u64().unwrap();
        let c = check(dir, "fold.vtk", &out, 2.0 * (h + h / 100.0));
        println!("seed {seed}: {c}");
        assert_eq!(c["crossing_pairs"], 0, "seed {seed}: {c}");
        let dmin = c["min_distance"].as_f64().unwrap();
        assert!(
            dmin >= 0.1 * h * (1.0 - 1e-9) && dmin < h,
            "seed {seed}: {dmin}"
        );
    }
    assert!(clipped > 0, "the bounds never acted");
    let frames: Vec<String> = std::fs::read_dir(dir.join("seed1"))
        .unwrap()
        .filter_map(|e| {
            let name = e.ok()?.file_name().into_string().ok()?;
            name.ends_with(".vtu").then_some(name)
        })
        .collect();
    assert!(frames.len() > 40, "{} frames", frames.len());
    for t in ["1", "3"] {
        let out = format!("t{t}");
        let args = [
            "thrust.toml",
            "fold.vtk",
            "--out",
            &out,
            "-q",
            "--restart",
            "start1.vtk",
            "--threads",
            t,
        ];
        common::run_status(&args, dir);
        for f in &frames {
            let a = std::fs::read(dir.join("seed1").join(f)).unwrap();
            let b = std::fs::read(dir.join(&out).join(f)).unwrap();
            assert!(a == b, "{f} differs on {t} threads");
        }
    }
    // A restart from a frame takes the same steps: the pairs are gathered at every frame.
    let args = [
        "thrust.toml",
        "fold.vtk",
        "--out",
        "re",
        "-q",
        "--restart",
        "seed1/frame_00020.vtu",
    ];
    common::run_status(&args, dir);
    let state = |out: &str, k: usize| {
        let m = shellsim::mesh::io::read_mesh(&dir.join(out).join(format!("frame_{k:05}.vtu")))
            .unwrap();
        (
            m.positions,
            m.vertex_fields.get("velocity").map(|f| f.data.clone()),
        )
    };
    for j in 1..frames.len() - 20 {
        assert!(
            state("seed1", 20 + j) == state("re", j),
            "frame {j} of the restart differs from frame {} of the whole run",
            20 + j
        );
    }
    let args = [
        "thrust.toml",
        "fold.vtk",
        "--out",
        "off",
        "-q",
        "--restart",
        "start1.vtk",
        "--set",
        "self_contact.enabled=false",
    ];
    common::run_status(&args, dir);
    let c = check(dir, "fold.vtk", "off", 2.0 * (h + h / 100.0));
    println!("without self-contact: {c}");
    assert!(c["crossing_pairs"].as_u64().unwrap() > 0, "{c}");
}

/// A prescribed path that drives the sheet into another, in explicit mode: a 2 cm square
/// (h = 1 mm) 3 mm above a fixed one, every vertex moved 1 cm down with the dial, and a third,
/// free square far away (the driver needs a free vertex). The paths cannot be pulled back, so
/// once one leaves its displacement bound its move is checked by CCD; the move that would
/// bring a pair below its minimum separation stops the run (exit 1) with the reason naming
/// the vertex, and no frame has crossing faces or a pair closer than that separation
/// (checked by the independent script).
#[test]
fn a_prescribed_path_into_another_sheet_stops_the_explicit_run() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    let h = 1e-3;
    sheets_mesh(
        dir,
        "press.vtk",
        0.02,
        0.005,
        &[(0.0, 0.0, 0.0), (0.0, 0.0, 3.0 * h), (0.1, 0.0, 0.0)],
    );
    std::fs::write(
        dir.join("press.toml"),
        format!(
            "[material]\nyoung = 1e6\nthickness = {h}\ndensity = 1000\nbending = \"midedge_average\"\n\
             [solver]\nmode = \"explicit\"\nsymmetry_breaking = 0\n\
             [explicit]\nmax_long_times = 2\n\
             [constraints]\nfix_boxes = [{{ min = [-1, -1, -1e-4], max = [0.05, 1, 1e-4] }}]\n\
             [[constraints.displacement]]\ndisplacement = [0, 0, -0.01]\n\
             inside = {{ min = [-1, -1, 0.002], max = [1, 1, 1] }}\n\
             [self_contact]\nenabled = true\n"
        ),
    )
    .unwrap();
    let (code, _, err) =
        common::run_status(&["press.toml", "press.vtk", "--out", "out", "-q"], dir);
    assert_eq!(code, 1, "{err}");
    let s: serde_json::Value = common::summary(&dir.join("out"));
    let reason = s["reason"].as_str().unwrap();
    println!("{reason}");
    assert!(
        reason.contains("prescribed path of vertex") && reason.contains("min_separation"),
        "{reason}"
    );
    let c = check(dir, "press.vtk", "out", 2.0 * (h + h / 100.0));
    println!("{c}");
    assert_eq!(c["crossing_pairs"], 0, "{c}");
    let dmin = c["min_distance"].as_f64().unwrap();
    assert!(dmin >= 0.1 * h * (1.0 - 1e-9) && dmin < h, "{dmin}");
}

/// A stack of eight 5 cm squares (h = 1 mm, E = 1 MPa) a thickness apart, pressed between two
/// glass slides: plane obstacles, the lower fixed, the upper pushed down by F = 5 N (force
/// control, its height a global DOF of the static solve); the sheets held only in their plane.
/// Each of the seven interfaces carries the load: the contact forces through each (`−∇E` of the
/// contact term, summed over the sheets above it) equal F to 1e-6, the pairs' normal forces
/// sum to 7F and the
/// frames' mean contact pressure on each sheet is σ = F/A on the two outer sheets (pressed on
/// one side by another sheet) and 2σ on the six inner ones, all to 1e-6 (measured 3.8e-9 and
/// 1.1e-8); each interface sinks into its offset by the closed form √(2δσ/k) = 6.32 µm
/// (σ = 2 kPa < kδ/2) within 1% (measured 0.41% at worst); and no two faces cross or come
/// closer than the minimum separation, checked by the independent script (the closest,
/// 0.99295 mm, is the offset less the penetration).
#[test]
fn a_stack_of_eight_sheets_pressed_between_slides_carries_the_load_through_each() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    let (h, e, side, force) = (1e-3, 1e6, 0.05, 5.0);
    let gap = 1.0005 * h;
    let sheets: Vec<(f64, f64, f64)> = (0..8).map(|k| (0.0, 0.0, k as f64 * gap)).collect();
    sheets_mesh(dir, "stack8.vtk", side, 0.01, &sheets);
    let top = 7.0 * gap;
    let settings = format!(
        "[material]\nyoung = {e}\nthickness = {h}\n\
         [[constraints.support]]\ncomponents = [\"x\", \"y\"]\n\
         inside = {{ min = [-1, -1, -1], max = [1, 1, 1] }}\n\
         [[obstacles]]\nshape = \"plane\"\npoint = [0, 0, {}]\nnormal = [0, 0, 1]\n\
         [[obstacles]]\nshape = \"plane\"\npoint = [0, 0, {}]\nnormal = [0, 0, -1]\nforce = [0, 0, -{force}]\n\
         [self_contact]\nenabled = true\n",
        -h / 2.0,
        top + h / 2.0
    );
    std::fs::write(dir.join("stack8.toml"), settings).unwrap();
    shellsim(&["stack8.toml", "stack8.vtk", "--out", "out", "-q"], dir);
    let s: serde_json::Value = common::summary(&dir.join("out"));
    assert_eq!(s["converged"], true, "{s}");
    let last = log_rows(&dir.join("out")).pop().unwrap();
    let carried = last["self_contact_force"];
    println!(
        "contact force {carried} N against 7F = {} N; slides {} / {} N",
        7.0 * force,
        last["obstacle0_force_z"],
        last["obstacle1_force_z"]
    );
    assert!(
        (carried - 7.0 * force).abs() < 1e-6 * 7.0 * force,
        "{carried}"
    );
    let through = interface_forces(
        dir,
        "stack8.toml",
        "stack8.vtk",
        &dir.join("out").join(s["final_frame"].as_str().unwrap()),
        8,
    );
    println!("forces through the interfaces {through:?} N");
    for (k, f) in through.iter().enumerate() {
        assert!((f - force).abs() < 1e-6 * force, "interface {}: {f}", k + 1);
    }
    for k in ["obstacle0_force_z", "obstacle1_force_z"] {
        assert!(
            (last[k].abs() - force).abs() < 1e-6 * force,
            "{k}: {}",
            last[k]
        );
    }
    let frames = common::finite_frames(&dir.join("out"), "vtu", "stack8");
    let fm = frames.last().unwrap();
    let pressure = &fm.face_fields["contact_pressure"].data;
    let nf = fm.faces.len() / 8;
    let sigma = force / (side * side);
    for k in 0..8 {
        let (mut pa, mut a) = (0.0, 0.0);
        for (f, pf) in pressure.iter().enumerate().skip(k * nf).take(nf) {
            let area = fm.face_area(f);
            pa += pf * area;
            a += area;
        }
        let expected = if k == 0 || k == 7 { sigma } else { 2.0 * sigma };
        println!(
            "sheet {k}: mean contact pressure {} Pa, expected {expected} Pa",
            pa / a
        );
        assert!(
            (pa / a - expected).abs() < 1e-6 * expected,
            "sheet {k}: {}",
            pa / a
        );
    }
    let x = &fm.positions;
    let n = x.len() / 8;
    let mean_z = |k: usize| x[k * n..(k + 1) * n].iter().map(|p| p.z).sum::<f64>() / n as f64;
    let exact = (2.0 * (h / 100.0) * sigma / (e / h)).sqrt();
    for k in 1..8 {
        let p = h - (mean_z(k) - mean_z(k - 1));
        println!("interface {k}: penetration {p:.6e}, closed form {exact:.6e}");
        assert!(
            (p - exact).abs() < 0.01 * exact,
            "interface {k}: {p} vs {exact}"
        );
    }
    let c = check(dir, "stack8.vtk", "out", 2.0 * (h + h / 100.0));
    println!("stack of eight: {c}");
    assert_eq!(c["crossing_pairs"], 0, "{c}");
    let dmin = c["min_distance"].as_f64().unwrap();
    assert!(dmin >= 0.1 * h && dmin < h, "{c}");
}

/// The gallery's cloth folding over a sphere (`settings/cloth_folds_on_sphere.toml`, every
/// face within reach pressing, friction 0.3 between its layers) at a quarter of its size: a
/// 200-face square (edges 0.1 m), 2 s of dynamics. Its skirt folds onto itself: pairs press
/// from 0.3 s on (measured 2–9), no two faces ever cross, and no two mid-surfaces come closer
/// than the minimum separation (measured 0.249 mm of the 0.5 mm offset, an edge pair inside
/// half the offset), checked over every frame by the independent script. The control without
/// self-contact passes through itself (measured 574 crossing face pairs).
#[test]
fn a_cloth_dropped_on_a_sphere_folds_onto_itself_without_crossing() {
    let d = tempfile::tempdir().unwrap();
    presses_without_crossing(
        d.path(),
        "cloth_folds_on_sphere",
        &["square", "--size", "1", "--edge", "0.1"],
        &[],
        5e-4,
    );
}

/// The gallery's wetted paper strip rolling onto itself
/// (`settings/paper_strip_rolls_onto_itself.toml`: 120 × 10 mm, fibres across, wetted on top)
/// on a coarse mesh (edges 4 mm, 180 faces) for the first 1.5 s: it rolls up along its length
/// past two full turns (measured 2.4 at 1.4 s), its layers press (up to 29 pairs), no two faces
/// ever cross and no two mid-surfaces come closer than the minimum separation, checked over
/// every frame by the independent script. The control without self-contact passes through
/// itself.
#[test]
fn a_wetted_paper_strip_rolls_past_a_full_turn_onto_itself() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    presses_without_crossing(
        dir,
        "paper_strip_rolls_onto_itself",
        &[
            "rectangle",
            "--lx",
            "0.12",
            "--ly",
            "0.01",
            "--edge",
            "0.004",
        ],
        &["time.end=1.5"],
        1e-4,
    );
    // The turns of the strip's centreline (the mean of each station across the width), from
    // the spread of its tangent's angle in the x–z plane.
    let frames = common::finite_frames(&dir.join("on"), "vtu", "paper strip");
    let reference = &frames[0].positions;
    let mut stations: Vec<f64> = reference.iter().map(|p| p.x).collect();
    stations.sort_by(f64::total_cmp);
    stations.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
    let turns = |m: &shellsim::mesh::Mesh| {
        let centre: Vec<[f64; 2]> = stations
            .iter()
            .map(|&xs| {
                let at: Vec<_> = (0..reference.len())
                    .filter(|&v| (reference[v].x - xs).abs() < 1e-9)
                    .map(|v| m.positions[v])
                    .collect();
                let n = at.len() as f64;
                [
                    at.iter().map(|p| p.x).sum::<f64>() / n,
                    at.iter().map(|p| p.z).sum::<f64>() / n,
                ]
            })
            .collect();
        let angles: Vec<f64> = centre
            .windows(2)
            .map(|w| (w[1][1] - w[0][1]).atan2(w[1][0] - w[0][0]))
            .collect();
        let (mut angle, mut lo, mut hi) = (0.0_f64, 0.0_f64, 0.0_f64);
        for w in angles.windows(2) {
            angle += wrapped(w[1] - w[0]);
            lo = lo.min(angle);
            hi = hi.max(angle);
        }
        (hi - lo) / std::f64::consts::TAU
    };
    let most = frames.iter().map(turns).fold(0.0, f64::max);
    println!("wetted paper strip: {most:.2} turns");
    assert!(most > 1.5, "{most} turns");
}

/// An angle change brought into (−π, π].
fn wrapped(d: f64) -> f64 {
    d - std::f64::consts::TAU * (d / std::f64::consts::TAU).round()
}

/// How many turns a ring rolled up about one axis wraps: the axis is the deformed sheet's
/// direction of largest extent (principal axes of its vertices); the line through the ring's
/// centre across it, in the reference plane (the direction a least-squares linear map takes
/// closest to the axis, turned a right angle), is followed on either side of the hole (vertices
/// within `band` of it, ordered along it) and the polar angles of its points about the axis
/// (unwrapped) are summed over both sides.
fn ring_turns(
    reference: &[nalgebra::Vector3<f64>],
    x: &[nalgebra::Vector3<f64>],
    band: f64,
) -> f64 {
    use nalgebra::{Matrix2x3, Matrix3, Vector2};
    let n = reference.len() as f64;
    let (r0, x0) = (
        reference.iter().sum::<nalgebra::Vector3<f64>>() / n,
        x.iter().sum::<nalgebra::Vector3<f64>>() / n,
    );
    let mut cov = Matrix3::zeros();
    for p in x {
        cov += (p - x0) * (p - x0).transpose();
    }
    let eig = cov.symmetric_eigen();
    let mut order = [0, 1, 2];
    order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
    let (e1, e2, axis) = (
        eig.eigenvectors.column(order[0]).into_owned(),
        eig.eigenvectors.column(order[1]).into_owned(),
        eig.eigenvectors.column(order[2]).into_owned(),
    );
    // Least squares X A = P over the centred points: A = (XᵀX)⁻¹ XᵀP (2 × 3).
    let (mut xtx, mut xtp) = (nalgebra::Matrix2::zeros(), Matrix2x3::zeros());
    for (r, p) in reference.iter().zip(x) {
        let q = Vector2::new(r.x - r0.x, r.y - r0.y);
        xtx += q * q.transpose();
        xtp += q * (p - x0).transpose();
    }
    let a = xtx.try_inverse().unwrap() * xtp;
    let u = (a * axis).normalize();
    let across = Vector2::new(-u.y, u.x);
    let mut total = 0.0;
    for side in [-1.0, 1.0] {
        let mut line: Vec<(f64, f64)> = reference
            .iter()
            .zip(x)
            .filter_map(|(r, p)| {
                let q = Vector2::new(r.x - r0.x, r.y - r0.y);
                let s = q.dot(&across);
                (q.dot(&u).abs() < band && s * side > 0.0)
                    .then(|| (s, (p - x0).dot(&e2).atan2((p - x0).dot(&e1))))
            })
            .collect();
        line.sort_by(|a, b| a.0.total_cmp(&b.0));
        let swept: f64 = line.windows(2).map(|w| wrapped(w[1].1 - w[0].1)).sum();
        total += swept.abs();
    }
    total / std::f64::consts::TAU
}

/// The gallery's wide paper ring soaked on top (`settings/paper_annulus_rolls_up.toml`: radii
/// 10–40 mm) on a coarse mesh (edges 5 mm, 377 faces) for its first 1.2 s: it rolls up about a
/// diameter into a tube, its two halves wrapping past a full turn (measured 1.6 turns across
/// it at 1.2 s), its layers pressing (up to 14 pairs); no two faces ever cross and no two
/// mid-surfaces come closer than the minimum separation, checked over every frame by the
/// independent script. The control without self-contact passes through itself.
#[test]
fn a_wide_paper_ring_soaked_on_top_rolls_up_past_a_full_turn() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    presses_without_crossing(
        dir,
        "paper_annulus_rolls_up",
        &[
            "annulus", "--inner", "0.01", "--radius", "0.04", "--edge", "0.005",
        ],
        &["time.end=1.2"],
        1e-4,
    );
    let frames = common::finite_frames(&dir.join("on"), "vtu", "paper ring");
    let turns = ring_turns(
        &frames[0].positions,
        &frames.last().unwrap().positions,
        0.003,
    );
    println!("wide paper ring: {turns:.2} turns");
    assert!(turns > 1.2, "{turns} turns");
}

/// The tube's length between its end rings in `m` over the tube's length: the distance between
/// the centroids of the vertices whose stored tube position (`original`, the wrapper mesh's
/// `original_positions`) lies at x = 0 and at x = L, and the length of the polyline through
/// the centroids of every ring of constant x.
fn tube_length(m: &shellsim::mesh::Mesh, original: &[[f64; 3]]) -> (f64, f64) {
    let length = original.iter().map(|p| p[0]).fold(0.0, f64::max);
    let mut stations: Vec<f64> = original.iter().map(|p| p[0]).collect();
    stations.sort_by(f64::total_cmp);
    stations.dedup_by(|a, b| (*a - *b).abs() < 1e-12);
    let centroids: Vec<shellsim::math::Vec3> = stations
        .iter()
        .map(|&x| {
            let ring: Vec<_> = (0..original.len())
                .filter(|&v| (original[v][0] - x).abs() < 1e-12)
                .map(|v| m.positions[v])
                .collect();
            ring.iter().sum::<shellsim::math::Vec3>() / ring.len() as f64
        })
        .collect();
    let ends = (centroids[centroids.len() - 1] - centroids[0]).norm();
    let arc: f64 = centroids.windows(2).map(|w| (w[1] - w[0]).norm()).sum();
    (ends / length, arc / length)
}

#[test]
fn a_straw_wrapper_wetted_at_one_end_unbunches_into_its_tube_without_crossing() {
    // settings/caterpillar.toml on a wrapper 3 mm across and 4 mm long, bunched 8 times into
    // 2 folds (952 faces): the drop on its first panel wicks along it within a tenth of a
    // second, and the accordion opens.
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    std::fs::copy(
        root.join("settings/caterpillar.toml"),
        dir.join("scene.toml"),
    )
    .unwrap();
    let h = 5e-5;
    shellsim(
        &[
            "mesh",
            "wrapper",
            "--radius",
            "0.0015",
            "--lx",
            "0.004",
            "--folds",
            "2",
            "--bunching",
            "8",
            "--thickness",
            "5e-5",
            "--edge",
            "4e-4",
            "-o",
            "wrapper.vtk",
        ],
        dir,
    );
    let reference = shellsim::mesh::io::read_mesh(&dir.join("wrapper.vtk")).unwrap();
    let field = &reference.vertex_fields["original_positions"];
    let original: Vec<[f64; 3]> = (0..reference.positions.len())
        .map(|v| {
            let p = field.get(v);
            [p[0], p[1], p[2]]
        })
        .collect();
    let run = |out: &str, sets: &[&str]| {
        let mut args = vec!["scene.toml", "wrapper.vtk", "--out", out, "-q"];
        for s in sets {
            args.extend_from_slice(&["--set", s]);
        }
        shellsim(&args, dir);
        let s = common::summary(&dir.join(out));
        assert_eq!(s["converged"], true, "{out}: {s}");
        common::finite_frames(&dir.join(out), "vtu", out)
    };
    let drop = ["time.end=0.2", "time.output_interval=0.02"];
    let frames = run("drop", &drop);
    let extension: Vec<f64> = frames.iter().map(|m| tube_length(m, &original).0).collect();
    println!("caterpillar: end to end over the tube's length every 0.02 s: {extension:.4?}");
    // Bunched 8 times into U-turns: the ends start 2Nρ + (the first and last panels' offset)
    // apart, a third of the tube; the wetted wrapper reaches its tube within the run.
    assert!(extension[0] < 0.35, "{extension:?}");
    assert!(*extension.last().unwrap() > 0.95, "{extension:?}");
    let pressing = log_rows(&dir.join("drop"))
        .iter()
        .map(|r| r["self_contact_pairs"])
        .fold(0.0, f64::max);
    assert!(pressing > 0.0, "the unbunching folds press on each other");
    let r = 2.0 * (h + h / 100.0);
    let c = check(dir, "wrapper.vtk", "drop", r);
    println!("caterpillar: {pressing} pairs pressing at most: {c}");
    assert_eq!(c["crossing_pairs"], 0, "{c}");
    let dmin = c["min_distance"].as_f64().unwrap();
    assert!(dmin >= 0.1 * h, "{dmin}");
    // The control: without self-contact the opening folds pass through each other.
    let mut off = drop.to_vec();
    off.push("self_contact.enabled=false");
    run("off", &off);
    let c = check(dir, "wrapper.vtk", "off", r);
    assert!(c["crossing_pairs"].as_u64().unwrap() > 0, "{c}");
    // Soaked through at once (moisture 0.3 everywhere, past relax_moisture's 0.2): every
    // crease relaxes fully, and the rest state is the stored tube grown by 1 + μ m = 1.009,
    // stress-free, so the wrapper recovers that length between its ends and along its axis.
    let frames = run("wet", &["moisture.initial=0.3", "time.end=0.3"]);
    let (ends, arc) = tube_length(frames.last().unwrap(), &original);
    println!("caterpillar soaked: end to end {ends:.6}, along the axis {arc:.6} × the tube");
    for v in [ends, arc] {
        assert!((v - 1.009).abs() < 1e-5, "{v}");
    }
}
