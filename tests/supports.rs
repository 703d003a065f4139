//! Supports through the binary: per-component supports and partial paths against the exact
//! uniaxial state of a St Venant–Kirchhoff sheet, the reactions of every support against the
//! applied loads (force and moment balance), symmetry planes (a quarter model equals the whole),
//! and the bad inputs of supports.

mod common;
use common::{cylinder_patch, graded_cylinder_patch, rectangle, run_status, shellsim};
use shellsim::mesh::io::read_mesh;
use shellsim::mesh::Mesh;
use std::path::Path;

fn summary(dir: &Path, out: &str) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join(out).join("summary.json")).unwrap())
        .unwrap()
}

/// Runs `dir/{m}.toml` on `dir/{m}.vtk` into `dir/{m}`, asserts that it converged, and returns
/// its summary, the input mesh and the final frame.
fn solved(dir: &Path, m: &str) -> (serde_json::Value, Mesh, Mesh) {
    shellsim(
        &[&format!("{m}.toml"), &format!("{m}.vtk"), "--out", m, "-q"],
        dir,
    );
    let s = summary(dir, m);
    assert_eq!(s["converged"], true, "{m}: {s}");
    let mesh = read_mesh(&dir.join(format!("{m}.vtk"))).unwrap();
    let frame = read_mesh(&dir.join(m).join(s["final_frame"].as_str().unwrap())).unwrap();
    (s, mesh, frame)
}

/// The reaction of support `name` in a summary: (force, moment).
fn reaction(s: &serde_json::Value, name: &str) -> ([f64; 3], [f64; 3]) {
    let r = s["reactions"]
        .as_array()
        .unwrap_or_else(|| panic!("no reactions in {s}"))
        .iter()
        .find(|r| r["support"] == name)
        .unwrap_or_else(|| panic!("no reaction of {name} in {s}"));
    let v = |k: &str| [0, 1, 2].map(|i| r[k][i].as_f64().unwrap());
    (v("force"), v("moment"))
}

/// The stretch λ of a St Venant–Kirchhoff bar in uniaxial stress with first Piola–Kirchhoff
/// stress `p` (Pa): `λ E (λ² − 1)/2 = p`, by Newton.
fn uniaxial_stretch(e: f64, p: f64) -> f64 {
    let mut l: f64 = 1.0;
    for _ in 0..60 {
        l -= (l * e * (l * l - 1.0) / 2.0 - p) / (e * (3.0 * l * l - 1.0) / 2.0);
    }
    l
}

/// A jittered square on rollers: x held on the edge x = −0.5, y held at one corner, z held
/// everywhere (an in-plane problem), pulled by a uniform traction t on x = +0.5. The exact
/// state is uniaxial: `λx E (λx² − 1)/2 = t/h`, `E_yy = −ν E_xx`, so the rollers let the sheet
/// contract across; every edge must have its exact length to 1e-6, the roller vertices keep
/// their x, and the rollers' reaction is −t·width in x, with zero y and z components, to 1e-9
/// of the load.
#[test]
fn rollers_let_a_pulled_sheet_contract_exactly() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    rectangle(dir, 1.0, 1.0, 0.1, &["--jitter", "0.25"], "sq.vtk");
    let (e, nu, h, t) = (1e6, 0.3, 0.01, 500.0);
    std::fs::write(
        dir.join("r.toml"),
        format!(
            "[material]\nyoung = {e}\npoisson = {nu}\nthickness = {h}\n\
             [solver]\ntolerance = 1e-11\nsymmetry_breaking = 0\n\
             [[constraints.support]]\ncomponents = [\"x\"]\ninside = {{ min = [-1, -1, -1], max = [-0.499, 1, 1] }}\n\
             [[constraints.support]]\ncomponents = [\"y\"]\ninside = {{ min = [-1, -1, -1], max = [-0.499, -0.499, 1] }}\n\
             [[constraints.support]]\ncomponents = [\"z\"]\ninside = {{ min = [-1, -1, -1], max = [1, 1, 1] }}\n\
             [[loads.traction]]\ntraction = [{t}, 0, 0]\ninside = {{ min = [0.499, -1, -1], max = [1, 1, 1] }}\n"
        ),
    )
    .unwrap();
    shellsim(&["r.toml", "sq.vtk", "--out", "o", "-q"], dir);
    let s = summary(dir, "o");
    assert_eq!(s["converged"], true, "{s}");
    let lx = uniaxial_stretch(e, t / h);
    let exx = (lx * lx - 1.0) / 2.0;
    let ly = (1.0 - 2.0 * nu * exx).sqrt();
    let mesh = read_mesh(&dir.join("sq.vtk")).unwrap();
    let frame = read_mesh(&dir.join("o").join(s["final_frame"].as_str().unwrap())).unwrap();
    let x = &frame.positions;
    let mut worst: f64 = 0.0;
    for f in &mesh.faces {
        for (i, j) in [(0, 1), (1, 2), (2, 0)] {
            let r = mesh.positions[f[j]] - mesh.positions[f[i]];
            let want = (lx * r.x).powi(2) + (ly * r.y).powi(2);
            worst = worst.max(((x[f[j]] - x[f[i]]).norm_squared() / want - 1.0).abs());
        }
    }
    println!("rollers: λx = {lx}, λy = {ly}, worst edge-length² error {worst:.2e}");
    assert!(
        1.0 - ly > 0.005,
        "the sheet must contract measurably: λy = {ly}"
    );
    assert!(worst < 1e-6, "not the uniaxial state: {worst:e}");
    let mut contracted: f64 = 0.0;
    for (v, p) in mesh.positions.iter().enumerate() {
        assert_eq!(x[v].z, p.z, "vertex {v} left its plane");
        if p.x < -0.499 {
            assert_eq!(x[v].x, p.x, "roller vertex {v} moved in x");
            contracted = contracted.max((x[v].y - p.y).abs());
        }
    }
    assert!(contracted > 1e-3, "the rollers held y: {contracted}");
    let load = t * 1.0;
    let (f, _) = reaction(&s, "support[0]");
    println!("roller reaction {f:?} against the load {load} N");
    assert!((f[0] + load).abs() < 1e-9 * load, "{f:?}");
    let (fy, _) = reaction(&s, "support[1]");
    let (fz, _) = reaction(&s, "support[2]");
    assert!(
        fy[1].abs() < 1e-9 * load && fz[2].abs() < 1e-9 * load,
        "{fy:?} {fz:?}"
    );
    // The frame's per-vertex reactions sum to the supports' totals.
    let field = &frame.vertex_fields["reaction"];
    let total_x: f64 = field.data.chunks(3).map(|r| r[0]).sum();
    assert!((total_x + load).abs() < 1e-9 * load, "{total_x}");
}

/// A partial path: the edge x = +0.5 of the same sheet is moved by δ along x only (its y and z
/// free), on the rollers of the previous test. The sheet is then in uniaxial stress with
/// `λx = 1 + δ`, and the path's reaction is the force that stretch needs,
/// `P = λx E E_xx h · width` (first Piola–Kirchhoff), within 1e-6; the rollers carry −P.
#[test]
fn a_partial_path_stretches_and_reports_its_force() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    rectangle(dir, 1.0, 1.0, 0.1, &["--jitter", "0.25"], "sq.vtk");
    let (e, nu, h, delta) = (1e6, 0.3, 0.01, 0.02);
    std::fs::write(
        dir.join("p.toml"),
        format!(
            "[material]\nyoung = {e}\npoisson = {nu}\nthickness = {h}\n\
             [solver]\ntolerance = 1e-11\nsymmetry_breaking = 0\n\
             [[constraints.support]]\ncomponents = [\"x\"]\ninside = {{ min = [-1, -1, -1], max = [-0.499, 1, 1] }}\n\
             [[constraints.support]]\ncomponents = [\"y\"]\ninside = {{ min = [-1, -1, -1], max = [-0.499, -0.499, 1] }}\n\
             [[constraints.support]]\ncomponents = [\"z\"]\ninside = {{ min = [-1, -1, -1], max = [0.499, 1, 1] }}\n\
             [[constraints.displacement]]\ndisplacement = [{delta}, 5, 5]\ncomponents = [\"x\"]\n\
             inside = {{ min = [0.499, -1, -1], max = [1, 1, 1] }}\n"
        ),
    )
    .unwrap();
    shellsim(&["p.toml", "sq.vtk", "--out", "o", "-q"], dir);
    let s = summary(dir, "o");
    assert_eq!(s["converged"], true, "{s}");
    let lx = 1.0 + delta;
    let exx = (lx * lx - 1.0) / 2.0;
    let force = lx * e * exx * h * 1.0;
    let mesh = read_mesh(&dir.join("sq.vtk")).unwrap();
    let frame = read_mesh(&dir.join("o").join(s["final_frame"].as_str().unwrap())).unwrap();
    for (v, p) in mesh.positions.iter().enumerate() {
        if p.x > 0.499 {
            assert_eq!(frame.positions[v].x, p.x + delta, "vertex {v} off its path");
            assert!(
                frame.positions[v].y != p.y || (p.y + 0.5).abs() < 1e-9,
                "y held at {v}"
            );
        }
    }
    let (path, _) = reaction(&s, "displacement[0]");
    let (rollers, _) = reaction(&s, "support[0]");
    println!("path reaction {path:?}, rollers {rollers:?}, closed form {force} N");
    assert!((path[0] / force - 1.0).abs() < 1e-6, "{path:?} vs {force}");
    assert!((path[0] + rollers[0]).abs() < 1e-9 * force);
}

/// A cantilever strip clamped at x = −0.5 under gravity and a point load at its tip, bent
/// far (tip deflection ≈ 0.4 of its length), solved from the flat strip with default solver
/// settings (statics ramps the weight with the dial like the tip load; with the full weight in
/// every step this run did not converge). At the equilibrium the clamp's reaction balances
/// the weight and the load, and its moment about the origin (its forces' moments and the
/// couple through the boundary normals it sets, `boundary_rotations`) balances theirs (Σ x × f
/// over the final positions): the imbalance is the sum of the free DOFs' residual forces, so it is
/// bounded by their number × tolerance × F (`force_scale`), and here below 1e-7 of the load.
#[test]
fn a_clamp_reaction_balances_the_weight_and_the_load() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    rectangle(dir, 1.0, 0.1, 0.025, &[], "c.vtk");
    let (e, h, rho, g, p) = (1e7, 0.01, 100.0, 9.81, 0.05);
    std::fs::write(
        dir.join("c.toml"),
        format!(
            "[material]\nyoung = {e}\npoisson = 0.3\nthickness = {h}\ndensity = {rho}\n\
             [solver]\nsymmetry_breaking = 0\n\
             [loads]\ngravity = [0, 0, -{g}]\n\
             [[loads.point]]\nforce = [0, 0, -{p}]\ninside = {{ min = [0.499, -1, -1], max = [1, 1, 1] }}\n\
             [[constraints.clamp]]\ninside = {{ min = [-1, -1, -1], max = [-0.499, 1, 1] }}\n"
        ),
    )
    .unwrap();
    shellsim(&["c.toml", "c.vtk", "--out", "o", "-q"], dir);
    let s = summary(dir, "o");
    assert_eq!(s["converged"], true, "{s}");
    let mesh = read_mesh(&dir.join("c.vtk")).unwrap();
    let frame = read_mesh(&dir.join("o").join(s["final_frame"].as_str().unwrap())).unwrap();
    let x = &frame.positions;
    let nv = mesh.positions.len();
    // The applied loads: the lumped weights (ρ h A/3 per face corner) and the tip load shared
    // by the tip vertices, at the final positions.
    let mut f_ext = vec![[0.0f64; 3]; nv];
    for (f, face) in mesh.faces.iter().enumerate() {
        let w = rho * h * mesh.face_area(f) / 3.0 * g;
        for &v in face {
            f_ext[v][2] -= w;
        }
    }
    let tip: Vec<usize> = (0..nv).filter(|&v| mesh.positions[v].x >= 0.499).collect();
    for &v in &tip {
        f_ext[v][2] -= p / tip.len() as f64;
    }
    // Every vertex's load counts, the held ones' too: it goes straight into their support.
    let (mut fsum, mut msum) = ([0.0f64; 3], [0.0f64; 3]);
    for v in 0..nv {
        let (r, q) = (f_ext[v], x[v]);
        let m = [
            q.y * r[2] - q.z * r[1],
            q.z * r[0] - q.x * r[2],
            q.x * r[1] - q.y * r[0],
        ];
        for k in 0..3 {
            fsum[k] += r[k];
            msum[k] += m[k];
        }
    }
    // The clamp's forces at its boundary vertices, and the couple it carries through the
    // boundary normals it sets (the strip's bending moment at the wall).
    let (f, mf) = reaction(&s, "clamp[0]");
    let (f0, couple) = reaction(&s, "boundary_rotations");
    assert_eq!(f0, [0.0; 3]);
    let m = [0, 1, 2].map(|k| mf[k] + couple[k]);
    assert!(
        couple[1].abs() > 0.1 * msum[1].abs(),
        "the clamp carries a couple: {couple:?} against {msum:?}"
    );
    let load = -fsum[2];
    let tip_z = tip.iter().map(|&v| x[v].z).sum::<f64>() / tip.len() as f64;
    println!("clamp reaction {f:?} / {m:?}; loads {fsum:?} / {msum:?}; tip z {tip_z}");
    assert!(tip_z < -0.2, "the strip must bend far: tip z {tip_z}");
    for k in 0..3 {
        assert!(
            (f[k] + fsum[k]).abs() < 1e-9 * load,
            "force {k}: {f:?} vs {fsum:?}"
        );
        assert!(
            (m[k] + msum[k]).abs() < 1e-9 * load,
            "moment {k}: {m:?} vs {msum:?}"
        );
    }
    // log.csv carries the same totals at the last frame.
    let log = std::fs::read_to_string(dir.join("o/log.csv")).unwrap();
    let head: Vec<&str> = log.lines().next().unwrap().split(',').collect();
    let last: Vec<&str> = log.lines().last().unwrap().split(',').collect();
    let col = head
        .iter()
        .position(|h| *h == "reaction_force_clamp_0_z")
        .unwrap_or_else(|| panic!("no reaction column in {head:?}"));
    let logged: f64 = last[col].parse().unwrap();
    assert!(
        (logged - f[2]).abs() <= 1e-12 * load,
        "{logged} vs {}",
        f[2]
    );
}

/// The Scordelis–Lo roof (MacNeal & Harder 1985): a cylindrical shell of radius 25, length 50,
/// half angle 40°, t = 0.25, E = 4.32e8, ν = 0, on rigid diaphragms at its curved ends (x and z
/// held; the axis is y), its straight edges free, under its weight 90 per unit area (here
/// × 1e-3, so the response is linear: the deflection × 1e3 against the reference 0.3024 at the
/// middle of a free edge). The quarter model θ ∈ [0, 40°], y ∈ [0, 25] with symmetry planes
/// x = 0 and y = 0 equals the whole roof on the mirrored mesh (each quarter of the 32² roof is
/// the 16² quarter) to the solver's tolerance: measured 1e-9. A plane through a shell that
/// bends across it is a symmetry plane only with its boundary rotation set, so this also
/// checks that condition. The numbers: 2048 faces whole, 0.2907 (−3.9%); quarters of 2048 and
/// 4608 faces: 0.2980 (−1.5%) and 0.2994 (−1.0%) (docs/benchmarks.md).
#[test]
fn a_quarter_model_with_symmetry_planes_equals_the_whole() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    let (r, th) = (25.0f64, 40f64.to_radians());
    cylinder_patch(dir, "full.vtk", r, (-th, th), (-25.0, 25.0), (32, 32), 0.0);
    cylinder_patch(dir, "quarter.vtk", r, (0.0, th), (0.0, 25.0), (16, 16), 0.0);
    let common = "[material]\nthickness = 0.25\nyoung = 4.32e8\npoisson = 0.0\ndensity = 360\n\
        [loads]\ngravity = [0, 0, -0.001]\n\
        [[constraints.support]]\ncomponents = [\"x\", \"z\"]\n\
        inside = { min = [-30, 24.999, -30], max = [30, 25.001, 30] }\n";
    std::fs::write(
        dir.join("full.toml"),
        format!(
            "{common}[[constraints.support]]\ncomponents = [\"x\", \"z\"]\n\
             inside = {{ min = [-30, -25.001, -30], max = [30, -24.999, 30] }}\n\
             [[constraints.support]]\ncomponents = [\"y\"]\n\
             inside = {{ min = [-30, -0.001, -30], max = [30, 0.001, 30] }}\n"
        ),
    )
    .unwrap();
    std::fs::write(
        dir.join("quarter.toml"),
        format!(
            "{common}[[constraints.symmetry]]\naxis = \"x\"\n\
             [[constraints.symmetry]]\naxis = \"y\"\n"
        ),
    )
    .unwrap();
    let mut w = Vec::new();
    for m in ["full", "quarter"] {
        let (_, mesh, frame) = solved(dir, m);
        // The middle of a free edge: θ = 40°, y = 0.
        let v = (0..mesh.positions.len())
            .min_by(|&a, &b| {
                let dist = |v: usize| {
                    let p = mesh.positions[v];
                    (p.x - r * th.sin()).hypot(p.y)
                };
                dist(a).total_cmp(&dist(b))
            })
            .unwrap();
        w.push(-1e3 * (frame.positions[v].z - mesh.positions[v].z));
    }
    println!(
        "Scordelis–Lo deflection ×1e3: whole {}, quarter {} (reference 0.3024)",
        w[0], w[1]
    );
    assert!((w[0] / w[1] - 1.0).abs() < 1e-6, "{w:?}");
    assert!((w[0] / 0.3024 - 1.0).abs() < 0.05, "{w:?}");
}

/// A symmetry plane with an oblique normal: the quarter Scordelis–Lo roof of the previous test,
/// rotated by 35° about the cylinder's axis (y) with its gravity, so that the plane x = 0
/// becomes `(cos 35°, 0, −sin 35°)·x = 0` (given as `normal`); the diaphragm still holds the
/// two components across the axis and the plane y = 0 is unchanged. Rotated back, every
/// displacement must equal the axis-aligned model's to 1e-6 of the largest (both solved to
/// 1e-10): the oblique plane holds the normal component and sets the boundary rotation exactly
/// as the axis-aligned one. The supports' forces balance the weight to the residual the
/// tolerance allows, and the oblique plane's reaction lies along its normal.
#[test]
fn an_oblique_symmetry_plane_equals_the_axis_aligned_one() {
    use shellsim::math::{Mat3, Vec3};
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    let (r, th) = (25.0f64, 40f64.to_radians());
    cylinder_patch(dir, "quarter.vtk", r, (0.0, th), (0.0, 25.0), (12, 12), 0.0);
    let (c, s) = (35f64.to_radians().cos(), 35f64.to_radians().sin());
    let rot = Mat3::new(c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c);
    let mut mesh = read_mesh(&dir.join("quarter.vtk")).unwrap();
    for p in &mut mesh.positions {
        *p = rot * *p;
    }
    shellsim::mesh::io::write_mesh(
        &dir.join("rotated.vtk"),
        &mesh,
        shellsim::mesh::io::Format::VtkAscii,
        "rotated",
    )
    .unwrap();
    let (rho, h, g) = (360.0, 0.25, 0.001);
    let gravity = rot * Vec3::new(0.0, 0.0, -g);
    let n = rot * Vec3::x();
    let common = format!(
        "[material]\nthickness = {h}\nyoung = 4.32e8\npoisson = 0.0\ndensity = {rho}\n\
         [solver]\ntolerance = 1e-10\n\
         [[constraints.support]]\ncomponents = [\"x\", \"z\"]\n\
         inside = {{ min = [-30, 24.999, -30], max = [30, 25.001, 30] }}\n\
         [[constraints.symmetry]]\naxis = \"y\"\n"
    );
    std::fs::write(
        dir.join("quarter.toml"),
        format!(
            "{common}[loads]\ngravity = [0, 0, {}]\n[[constraints.symmetry]]\nnormal = [1, 0, 0]\n",
            -g
        ),
    )
    .unwrap();
    std::fs::write(
        dir.join("rotated.toml"),
        format!(
            "{common}[loads]\ngravity = [{}, {}, {}]\n\
             [[constraints.symmetry]]\nnormal = [{}, {}, {}]\n",
            gravity.x, gravity.y, gravity.z, n.x, n.y, n.z
        ),
    )
    .unwrap();
    let mut u = Vec::new();
    for m in ["quarter", "rotated"] {
        let (sm, mesh, frame) = solved(dir, m);
        let back = if m == "rotated" {
            rot.transpose()
        } else {
            Mat3::identity()
        };
        u.push(
            (0..mesh.positions.len())
                .map(|v| back * (frame.positions[v] - mesh.positions[v]))
                .collect::<Vec<Vec3>>(),
        );
        {
            let area: f64 = (0..mesh.faces.len()).map(|f| mesh.face_area(f)).sum();
            let weight = (if m == "rotated" {
                gravity
            } else {
                Vec3::new(0.0, 0.0, -g)
            }) * (rho * h * area);
            let total: Vec3 = sm["reactions"]
                .as_array()
                .unwrap()
                .iter()
                .map(|r| Vec3::from_fn(|k, _| r["force"][k].as_f64().unwrap()))
                .sum();
            let (fs, _) = reaction(&sm, "symmetry[1]");
            let fs = Vec3::from(fs);
            let n = back.transpose() * Vec3::x();
            println!(
                "oblique plane: reactions {total:?} against the weight {weight:?}; plane's \
                 reaction {fs:?}"
            );
            // At the converged state the imbalance is the sum of the free DOFs' residuals,
            // each below tolerance × force scale (a floor above round-off on this stiff shell).
            let bound =
                3.0 * mesh.positions.len() as f64 * 1e-10 * sm["force_scale"].as_f64().unwrap();
            assert!((total + weight).norm() < bound, "{total:?}, {bound:e}");
            assert!(
                fs.norm() > 1e-3 * weight.norm(),
                "the plane carries nothing: {fs:?}"
            );
            assert!(
                fs.cross(&n).norm() < 1e-9 * fs.norm(),
                "{fs:?} is not along {n:?}"
            );
        }
    }
    let big = u[0].iter().fold(0.0f64, |m, v| m.max(v.norm()));
    let worst = u[0]
        .iter()
        .zip(&u[1])
        .fold(0.0f64, |m, (a, b)| m.max((a - b).norm()));
    println!(
        "oblique symmetry plane: largest displacement {big:.4e}, worst difference {worst:.2e}"
    );
    assert!(big > 1e-4, "{big}");
    assert!(worst < 1e-6 * big, "{worst:e} of {big:e}");
}

/// The pinched cylinder with rigid diaphragms (MacNeal & Harder 1985): R = 300, L = 600,
/// t = 3, E = 3e6, ν = 0.3, two opposite radial loads P at mid-length; reference deflection
/// under a load 164.24 P/(E t) = 1.82488e-5 P. The octant model (θ from the load to 90°, y from
/// mid-length to the diaphragm at y = 300) has symmetry planes x = 0, y = 0 and z = 0, the
/// diaphragm holding x and z, and carries P/4 (P = 1000, a linear response). On a uniform 48²
/// grid (4608 faces) the point load's singularity leaves +6.4%; grading the same grid toward
/// the load (θ and y as the 1.35th power of the grid coordinate) brings it within 2%
/// (measured +1.64%), as the benchmark target asks on at most ~5k faces.
#[test]
fn the_pinched_cylinder_octant_on_a_graded_grid_is_within_two_percent() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    let n = 48;
    let settings = "[material]\nthickness = 3.0\nyoung = 3e6\npoisson = 0.3\n\
        [[loads.point]]\nforce = [0, 0, -250]\ninside = { min = [-1e-6, -1e-6, 299], max = [1e-6, 1e-6, 301] }\n\
        [[constraints.support]]\ncomponents = [\"x\", \"z\"]\n\
        inside = { min = [-400, 299.999, -400], max = [400, 300.001, 400] }\n\
        [[constraints.symmetry]]\naxis = \"x\"\n[[constraints.symmetry]]\naxis = \"y\"\n\
        [[constraints.symmetry]]\naxis = \"z\"\n";
    let mut err = Vec::new();
    for gamma in [1.0f64, 1.35] {
        let m = format!("pc{gamma}");
        let half_pi = std::f64::consts::FRAC_PI_2;
        graded_cylinder_patch(
            dir,
            &format!("{m}.vtk"),
            300.0,
            (0.0, half_pi),
            (0.0, 300.0),
            (n, n),
            0.0,
            gamma,
        );
        std::fs::write(dir.join(format!("{m}.toml")), settings).unwrap();
        let (_, mesh, frame) = solved(dir, &m);
        // The load point (θ = 0, y = 0) is vertex 0.
        let w = (mesh.positions[0].z - frame.positions[0].z) / 1000.0;
        err.push(w / 1.82488e-5 - 1.0);
    }
    println!(
        "pinched cylinder octant, 4608 faces: uniform {:+.2}%, graded {:+.2}%",
        100.0 * err[0],
        100.0 * err[1]
    );
    assert!(err[1].abs() < 0.02, "{err:?}");
    assert!(
        err[0].abs() > 2.0 * err[1].abs(),
        "grading should matter: {err:?}"
    );
}

/// The pinched hemisphere with an 18° hole (MacNeal & Harder 1985): radius 10, t = 0.04,
/// E = 6.825e7, ν = 0.3, free edges, four radial point loads ±2 alternating on the equator;
/// reference displacement 0.094 under a load. The quarter model (azimuth 0–90°, polar angle
/// 18–90°) with symmetry planes x = 0 and y = 0 carries +1 outward at (10, 0, 0) and −1 at
/// (0, 10, 0) (each point on a plane takes half its load), scaled by 1e-3 for a linear
/// response; one equator vertex holds z (it carries nothing). 1152 faces: measured 0.09389
/// (−0.12%); 2048 / 4608: −0.43% / −0.53% (MacNeal & Harder's 0.094 is itself ~0.5% above the
/// converged thin-shell value). Asserted: within 2%, and the two loads' displacements equal.
#[test]
fn the_pinched_hemisphere_quarter_matches_the_reference() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    let (r, n) = (10.0f64, 24usize);
    let a0 = 18f64.to_radians();
    let mut s = format!(
        "# vtk DataFile Version 3.0\nhemisphere\nASCII\nDATASET POLYDATA\nPOINTS {} double\n",
        (n + 1) * (n + 1)
    );
    for j in 0..=n {
        for i in 0..=n {
            let al = a0 + (std::f64::consts::FRAC_PI_2 - a0) * j as f64 / n as f64;
            let be = std::f64::consts::FRAC_PI_2 * i as f64 / n as f64;
            s += &format!(
                "{} {} {}\n",
                r * al.sin() * be.cos(),
                r * al.sin() * be.sin(),
                r * al.cos()
            );
        }
    }
    s += &format!("POLYGONS {} {}\n", 2 * n * n, 8 * n * n);
    for j in 0..n {
        for i in 0..n {
            let a = j * (n + 1) + i;
            let (b, c, e) = (a + 1, a + n + 1, a + n + 2);
            if (i + j) % 2 == 0 {
                s += &format!("3 {a} {e} {b}\n3 {a} {c} {e}\n");
            } else {
                s += &format!("3 {a} {c} {b}\n3 {b} {c} {e}\n");
            }
        }
    }
    std::fs::write(dir.join("h.vtk"), s).unwrap();
    std::fs::write(
        dir.join("h.toml"),
        "[material]\nthickness = 0.04\nyoung = 6.825e7\npoisson = 0.3\n\
         [[loads.point]]\nforce = [0.001, 0, 0]\n\
         inside = { min = [9.999, -1e-6, -1e-6], max = [10.001, 1e-6, 1e-6] }\n\
         [[loads.point]]\nforce = [0, -0.001, 0]\n\
         inside = { min = [-1e-6, 9.999, -1e-6], max = [1e-6, 10.001, 1e-6] }\n\
         [[constraints.symmetry]]\naxis = \"x\"\n[[constraints.symmetry]]\naxis = \"y\"\n\
         [[constraints.support]]\ncomponents = [\"z\"]\n\
         inside = { min = [7.0, 7.0, -1e-6], max = [7.1, 7.1, 1e-6] }\n",
    )
    .unwrap();
    shellsim(&["h.toml", "h.vtk", "--out", "o", "-q"], dir);
    let s = summary(dir, "o");
    assert_eq!(s["converged"], true, "{s}");
    let frame = read_mesh(&dir.join("o").join(s["final_frame"].as_str().unwrap())).unwrap();
    let mesh = read_mesh(&dir.join("h.vtk")).unwrap();
    let (va, vb) = (n * (n + 1), n * (n + 1) + n);
    let ua = 1e3 * (frame.positions[va].x - mesh.positions[va].x);
    let ub = -1e3 * (frame.positions[vb].y - mesh.positions[vb].y);
    println!("pinched hemisphere, quarter of 1152 faces: {ua} and {ub} (reference 0.094)");
    assert!((ua / 0.094 - 1.0).abs() < 0.02, "{ua}");
    assert!((ua / ub - 1.0).abs() < 1e-4, "{ua} {ub}");
}

/// Bad symmetry planes: one that no vertex lies on (along an axis or oblique), one with a bending
/// model that has no boundary rotation to set, both or neither of axis and normal, a zero
/// normal, and a path on an oblique plane's vertices; each exit 2 naming the key.
#[test]
fn bad_symmetry_planes_are_refused() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    rectangle(dir, 1.0, 0.5, 0.1, &[], "r.vtk");
    let cases: [(&str, &[&str]); 7] = [
        (
            "[[constraints.symmetry]]\naxis = \"x\"\nat = 0.123\n",
            &["constraints.symmetry[0]", "no vertex lies on the plane x = 0.123"],
        ),
        (
            "[material]\nbending = \"patch_fit\"\n[[constraints.symmetry]]\naxis = \"x\"\nat = 0.5\n",
            &["constraints.symmetry[0]", "midedge_sin"],
        ),
        (
            "[[constraints.symmetry]]\naxis = \"x\"\nnormal = [1, 0, 0]\n",
            &["constraints.symmetry[0]", "both axis and normal"],
        ),
        (
            "[[constraints.symmetry]]\nat = 0.5\n",
            &["constraints.symmetry[0]", "needs the plane's normal"],
        ),
        (
            "[[constraints.symmetry]]\nnormal = [0, 0, 0]\n",
            &["constraints.symmetry[0].normal", "non-zero"],
        ),
        (
            "[[constraints.symmetry]]\nnormal = [3, 4, 0]\nat = 5\n",
            &["constraints.symmetry[0]", "no vertex lies on the plane (0.6, 0.8, 0)·x = 5"],
        ),
        // The plane through the edge x = 0.5 at 45° to the sheet, and a path on that edge.
        (
            "[[constraints.symmetry]]\nnormal = [1, 0, 1]\nat = 0.3535533905932738\n\
             [[constraints.displacement]]\ndisplacement = [0, 0.1, 0]\n\
             inside = { min = [0.49, -1, -1], max = [1, 1, 1] }\n",
            &["constraints.displacement[0]", "oblique symmetry plane"],
        ),
    ];
    refused(dir, &cases);
}

/// Bad supports: a selection of no vertex, no component, a component listed twice, an unknown
/// component, a component both held and on a path, and supports that leave the sheet free to
/// translate along a net load (the system would be singular), each exit 2 naming the key.
#[test]
fn bad_supports_are_refused() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    rectangle(dir, 1.0, 0.5, 0.1, &[], "r.vtk");
    let cases: [(&str, &[&str]); 7] = [
        (
            "[[constraints.support]]\ncomponents = [\"x\"]\ninside = { min = [5, 5, 5], max = [6, 6, 6] }\n",
            &["constraints.support[0]", "selects no vertex"],
        ),
        (
            "[[constraints.support]]\ncomponents = []\ntags = [1]\n",
            &["constraints.support[0].components", "at least one"],
        ),
        (
            "[[constraints.support]]\ncomponents = [\"z\", \"z\"]\ntags = [1]\n",
            &["constraints.support[0].components", "twice"],
        ),
        (
            "[[constraints.support]]\ncomponents = [\"w\"]\ntags = [1]\n",
            &["components", "w"],
        ),
        // Nothing holds the sheet, and a net load pushes it.
        (
            "[[loads.point]]\nforce = [0, 0, 1]\ninside = { min = [0.49, -1, -1], max = [1, 1, 1] }\n",
            &["constraints", "free to translate along (0, 0, 1)", "net force of 1 N"],
        ),
        // A support that leaves a translation free along the load.
        (
            "[[constraints.support]]\ncomponents = [\"x\", \"z\"]\ninside = { min = [-1, -1, -1], max = [-0.49, 1, 1] }\n\
             [[loads.traction]]\ntraction = [0, 2, 0]\ninside = { min = [0.49, -1, -1], max = [1, 1, 1] }\n",
            &["constraints", "free to translate along (0, 1, 0)"],
        ),
        (
            "[[constraints.support]]\ncomponents = [\"x\"]\ninside = { min = [0.49, -1, -1], max = [1, 1, 1] }\n\
             [[constraints.displacement]]\ndisplacement = [0.1, 0, 0]\ncomponents = [\"x\", \"y\"]\n\
             inside = { min = [0.49, -1, -1], max = [1, 1, 1] }\n",
            &["constraints.displacement[0]", "x component", "constraints.support"],
        ),
    ];
    refused(dir, &cases);
}

/// Runs each of `cases` (settings, the texts its error must contain) on `dir/r.vtk`: exit 2,
/// each text in the message, no panic, and no output folder.
fn refused(dir: &Path, cases: &[(&str, &[&str])]) {
    for (settings, needles) in cases {
        std::fs::write(dir.join("bad.toml"), settings).unwrap();
        let (code, _, err) = run_status(&["bad.toml", "r.vtk", "--out", "obad", "-q"], dir);
        assert_eq!(code, 2, "{settings}: {err}");
        for n in needles.iter() {
            assert!(err.contains(n), "{settings}: '{n}' not in: {err}");
        }
        assert!(!err.contains("panicked"), "{err}");
        assert!(!dir.join("obad").exists(), "a refused run wrote its folder");
    }
}
