//! Terms: one finite-difference checker run over every registered term (every membrane material
//! × every bending model, damping, inertia, gravity, the ground, the loads) on a small mesh with
//! boundary faces; closed-form energies of the membrane materials; the Baraff–Witkin PSD option;
//! the low-rank global-term interface against a dense solve.

use shellsim::assembly::{ElementMap, Pattern, Want};
use shellsim::body::Body;
use shellsim::energy::bending::none::NoBending;
use shellsim::energy::membrane::baraff_witkin::BaraffWitkinFace;
use shellsim::energy::membrane::gent::GentFace;
use shellsim::energy::membrane::mooney_rivlin::MooneyRivlinFace;
use shellsim::energy::membrane::neo_hookean::NeoHookeanFace;
use shellsim::energy::membrane::{MembraneLaw, WithKoiterBending};
use shellsim::energy::potential::{Damping, Inertia};
use shellsim::energy::projection::jacobi_eigen;
use shellsim::energy::registry;
use shellsim::energy::shell::shell_element;
use shellsim::energy::term::{ExplicitHooks, LowRank, LowRankPart, Stencil, Term};
use shellsim::energy::Potential;
use shellsim::energy::{HessianProjection, KoiterDensity};
use shellsim::math::{Mat3, Real, SMat, SVec, Sym2, Vec2, Vec3};
use shellsim::mesh::generate::{rectangle, Rng, Spacing};
use shellsim::model::Scene;
use shellsim::settings::Settings;

fn strip_scene(settings: &str) -> Scene {
    let m = rectangle(
        0.0,
        0.0,
        1.0,
        0.5,
        0.125,
        Spacing {
            jitter: 0.2,
            seed: 3,
            ..Default::default()
        },
    );
    Scene::build(m, Settings::from_str_with(settings, "test", &[]).unwrap()).unwrap()
}

/// A stretched, sheared and bent configuration: some faces beyond s = 1, some below.
fn deformed(sc: &Scene) -> Vec<Vec3> {
    let mut rng = Rng::new(5);
    sc.body
        .mesh
        .positions
        .iter()
        .map(|p| {
            Vec3::new(
                1.06 * p.x + 0.05 * p.y,
                0.95 * p.y,
                0.2 * (p.x * p.x - 0.7 * p.y * p.y),
            ) + Vec3::new(rng.symmetric(), rng.symmetric(), rng.symmetric()) * 0.01
        })
        .collect()
}

/// The one finite-difference checker: `eval(x, phi, want, grad, values)` (overwriting the
/// buffers) has its gradient checked against central differences of its energy, and its
/// Hessian (pattern order, lower triangle) against central differences of its gradient, at every
/// `stride`-th free DOF (fixed nodes skipped), step 1e-6. Errors are relative to the largest
/// gradient entry and to `hess_scale(gmax, hmax)`.
#[allow(clippy::too_many_arguments)]
pub fn fd_check(
    sc: &Scene,
    p: &Pattern,
    x: &[Vec3],
    phi: &[Real],
    label: &str,
    stride: usize,
    hess_scale: impl Fn(Real, Real) -> Real,
    eval: impl Fn(&[Vec3], &[Real], Want, &mut [Real], &mut [Real]) -> Real,
) {
    let nx = 3 * sc.body.num_vertices();
    let node_of = |k: usize| {
        if k < nx {
            k / 3
        } else {
            sc.body.num_vertices() + (k - nx)
        }
    };
    let (mut g, mut h) = (vec![0.0; p.n], vec![0.0; p.nnz()]);
    eval(x, phi, Want::Hessian, &mut g, &mut h);
    let gmax = g.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let hmax = h.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let hs = hess_scale(gmax, hmax);
    let eps = 1e-6;
    let (mut gp, mut gm, mut scratch) = (vec![0.0; p.n], vec![0.0; p.n], vec![0.0; p.nnz()]);
    for k in (0..p.n).step_by(stride) {
        if sc.node_fixed[node_of(k)] {
            continue;
        }
        let (mut xp, mut xm) = (x.to_vec(), x.to_vec());
        let (mut pp, mut pm) = (phi.to_vec(), phi.to_vec());
        if k < nx {
            xp[k / 3][k % 3] += eps;
            xm[k / 3][k % 3] -= eps;
        } else {
            pp[k - nx] += eps;
            pm[k - nx] -= eps;
        }
        let ep = eval(&xp, &pp, Want::Gradient, &mut gp, &mut scratch);
        let em = eval(&xm, &pm, Want::Gradient, &mut gm, &mut scratch);
        let fd = (ep - em) / (2.0 * eps);
        assert!(
            (fd - g[k]).abs() < 1e-6 * gmax,
            "{label}: grad {k}: {} vs {fd}",
            g[k]
        );
        // Column k of the Hessian (lower part stored in column k, upper part in rows).
        for (pos, &row) in p.row_idx[p.col_ptr[k]..p.col_ptr[k + 1]].iter().enumerate() {
            if sc.node_fixed[node_of(row)] {
                continue;
            }
            let fd = (gp[row] - gm[row]) / (2.0 * eps);
            let val = h[p.col_ptr[k] + pos];
            assert!(
                (fd - val).abs() < 1e-6 * hs,
                "{label}: H({row},{k}): {val} vs {fd}"
            );
        }
    }
}

/// Term `i` alone through [`fd_check`], every DOF; its Hessian relative to the larger of the
/// largest gradient and Hessian entries (a dead load has no Hessian at all).
pub fn check_term(sc: &Scene, p: &Pattern, pot: &Potential, x: &[Vec3], phi: &[Real], i: usize) {
    let term = &sc.terms[i];
    let map: &ElementMap = &p.maps[i];
    let label = format!("{} ({:?})", term.name(), sc.settings.material.model);
    let mut g = vec![0.0; p.n];
    term.eval(
        pot,
        map,
        x,
        phi,
        Want::Gradient,
        HessianProjection::None,
        &mut g,
        &mut [],
    );
    assert!(
        g.iter().any(|v| *v != 0.0),
        "{label}: zero gradient: the check would be empty"
    );
    fd_check(
        sc,
        p,
        x,
        phi,
        &label,
        1,
        |g, h| g.max(h),
        |x, phi, want, g, h| {
            g.iter_mut().for_each(|v| *v = 0.0);
            h.iter_mut().for_each(|v| *v = 0.0);
            term.eval(pot, map, x, phi, want, HessianProjection::None, g, h)
        },
    );
}

/// The prism element's other laws and thickness modes, beyond its registry example.
const MATERIAL_VARIANTS: [&str; 2] = [
    "model = \"prism\"\npoisson = 0.5\nprism = { law = \"neo_hookean\" }",
    "model = \"prism\"\npoisson = 0.4\nprism = { law = \"neo_hookean\", thickness = \"pbd\" }",
];

/// Every registered shell term (material × bending model), with damping and inertia in a
/// dynamic scene with gravity and a ground, and every vertex term, against finite differences.
#[test]
fn every_registered_term_matches_finite_differences() {
    let mut checked = std::collections::BTreeSet::new();
    let materials = registry::MATERIALS
        .iter()
        .map(|e| e.example)
        .chain(MATERIAL_VARIANTS);
    for mat in materials {
        for &(_, bend) in registry::BENDINGS {
            let settings = format!(
                "[material]\n{mat}\n{bend}\nthickness = 0.05\n[solver]\nmode = \"dynamic\"\n\
                 [loads]\ngravity = [0, 0, -9.81]\n[contact]\nenabled = true\npoint = [0, 0, \
                 -0.045]\nfriction = 0.3\n[constraints]\nfix_boxes = [{{ min = [-1, -1, -1], \
                 max = [0.01, 2, 1] }}]"
            );
            let sc = strip_scene(&settings);
            let p = Pattern::for_scene(&sc);
            let x = deformed(&sc);
            let mut rng = Rng::new(2);
            let phi: Vec<Real> = (0..sc.body.num_edge_dofs())
                .map(|_| 0.05 * rng.symmetric())
                .collect();
            let (a_prev, b_prev) = sc
                .body
                .forms(&sc.body.mesh.positions, &vec![0.0; phi.len()]);
            let xhat: Vec<Vec3> = x.iter().map(|p| p * 0.99).collect();
            let normal: Vec<Real> = (0..sc.body.num_vertices())
                .map(|v| 0.1 + 0.01 * v as Real)
                .collect();
            let pot = Potential {
                dial: 0.7,
                inertia: Some(Inertia {
                    inv_dt2: 1e4,
                    xhat: &xhat,
                    dofs_hat: &[],
                }),
                damping: Some(Damping {
                    eta_over_dt: 3.0,
                    a_prev: &a_prev,
                    b_prev: &b_prev,
                }),
                gravity: Vec3::new(0.0, 0.0, -9.81),
                friction: Some(shellsim::energy::potential::Friction {
                    x_prev: &xhat,
                    dial_prev: 0.7,
                    normal_force: &normal,
                    x_lag: &xhat,
                    dial_lag: 0.7,
                    eps: 1e-3,
                }),
                ..Potential::new(&sc, &p)
            };
            for i in 0..sc.terms.len() {
                check_term(&sc, &p, &pot, &x, &phi, i);
                checked.insert(sc.terms[i].name());
            }
        }
    }
    // The loads, on a sheet whose boundary is held (as the pressure needs), with edge DOFs.
    let sc = strip_scene(
        "[material]\nthickness = 0.05\n[constraints]\nfix_boxes = [\
         { min = [-1, -1, -1], max = [0.01, 2, 1] }, { min = [0.99, -1, -1], max = [2, 2, 1] },\
         { min = [-1, -1, -1], max = [2, 0.01, 1] }, { min = [-1, 0.49, -1], max = [2, 2, 1] }]\n\
         [[loads.point]]\nforce = [1, 2, 3]\ninside = { min = [0.4, 0.2, -1], max = [0.6, 0.3, 1] }\n\
         [[loads.traction]]\ntraction = [0, 1, -2]\ninside = { min = [0.9, -1, -1], max = [2, 2, 1] }\n\
         [[loads.pressure]]\npressure = 1e3\n",
    );
    let p = Pattern::for_scene(&sc);
    let x = deformed(&sc);
    let phi = vec![0.01; sc.body.num_edge_dofs()];
    let pot = Potential {
        dial: 0.6,
        ..Potential::new(&sc, &p)
    };
    for i in 0..sc.terms.len() {
        if sc.terms[i].name() != "traction" {
            check_term(&sc, &p, &pot, &x, &phi, i);
        }
        checked.insert(sc.terms[i].name());
    }
    for name in [
        "shell",
        "contact",
        "friction",
        "inertia",
        "gravity",
        "point_load",
        "traction",
        "pressure",
    ] {
        assert!(checked.contains(name), "{name} was not checked");
    }
}

/// The strip rolled about the y axis into an arc of total angle `turn` (clamped end at x = 0,
/// along the arc of radius 1/κ), with a small random offset.
fn rolled(sc: &Scene, turn: Real, noise: Real) -> Vec<Vec3> {
    let kappa = turn / 1.0;
    let mut rng = Rng::new(9);
    sc.body
        .mesh
        .positions
        .iter()
        .map(|p| {
            let a = kappa * p.x;
            Vec3::new(a.sin() / kappa, p.y, (1.0 - a.cos()) / kappa)
                + Vec3::new(rng.symmetric(), rng.symmetric(), rng.symmetric()) * noise
        })
        .collect()
}

/// The end moment against finite differences, with and without edge DOFs, after its tracked
/// angles were accepted past π (the strip rolled to 1.1π, then evaluated near 1.3π), and its
/// turn counted through full turns.
#[test]
fn end_moment_matches_finite_differences_past_a_half_turn() {
    for bend in ["midedge_sin", "midedge_average"] {
        let sc = strip_scene(&format!(
            "[material]\nthickness = 0.05\nbending = \"{bend}\"\n\
             [[constraints.clamp]]\ninside = {{ min = [-1, -1, -1], max = [0.01, 2, 1] }}\n\
             [[loads.moment]]\nmoment = 2.0\ninside = {{ min = [0.99, -1, -1], max = [2, 2, 1] }}\n"
        ));
        let p = Pattern::for_scene(&sc);
        let i = (0..sc.terms.len())
            .find(|&i| sc.terms[i].name() == "moment")
            .expect("a moment term");
        let phi = vec![0.02; sc.body.num_edge_dofs()];
        // Accept in steps below π/2, as the solver would.
        let mut states = sc.initial_states.clone();
        for k in 1..=11 {
            sc.terms[i].tracked().expect("the moment tracks").accept(
                &rolled(&sc, 0.1 * k as Real * std::f64::consts::PI, 0.0),
                &phi,
                states.get_mut("moment"),
            );
        }
        let x = rolled(&sc, 1.3 * std::f64::consts::PI, 0.01);
        let pot = Potential {
            dial: 0.8,
            states: &states,
            ..Potential::new(&sc, &p)
        };
        check_term(&sc, &p, &pot, &x, &phi, i);
        // The turn counts through the half turn: each tip face is flat with its boundary edge
        // along y, so its normal's angle is κ(1 + x_k)/2 (x_k its third vertex), linear in κ.
        let turn = |t: Real| {
            let x = rolled(&sc, t * std::f64::consts::PI, 0.0);
            let obs = shellsim::energy::term::observables(sc.terms[i].as_ref(), &pot, &x, &phi);
            obs.iter().find(|(n, _)| n == "moment_rotation").unwrap().1
        };
        let (t11, t13) = (turn(1.1), turn(1.3));
        assert!(t11 > std::f64::consts::PI, "{bend}: turn {t11}");
        assert!(
            (t13 / t11 - 13.0 / 11.0).abs() < 1e-12,
            "{bend}: turns {t11}, {t13}"
        );
    }
}

/// Per unit element weight (V = h A₀ = 1: ā = I on the unit right triangle, h = 2), λ = 1,
/// μ = 0.7, r = 100, the values of REFERENCES.md from positions through the shell kernel.
#[test]
fn baraff_witkin_closed_form_energies() {
    let law = BaraffWitkinFace::new(
        &Sym2::new(1.0, 0.0, 1.0),
        &Vec2::new(1.0, 0.0),
        2.0,
        1.0,
        0.7,
        100.0,
    );
    let dens = WithKoiterBending {
        law,
        koiter: no_bending_wells(),
    };
    let energy = |f: [[Real; 2]; 3]| {
        let fm = |p: Vec2| {
            Vec3::new(
                f[0][0] * p.x + f[0][1] * p.y,
                f[1][0] * p.x + f[1][1] * p.y,
                f[2][0] * p.x + f[2][1] * p.y,
            )
        };
        let x = [
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(0.0, 1.0),
        ]
        .map(fm);
        let xs = [x[0], x[1], x[2], x[0], x[0], x[0]];
        let mut g = SVec::<9>::zeros();
        let e = shell_element::<_, NoBending, 9, 3, false>(
            &NoBending,
            &(),
            &xs,
            &dens,
            Some(&mut g),
            None,
        );
        (e, g)
    };
    let (e, g) = energy([[1.0, 0.0], [0.0, 1.0], [0.0, 0.0]]);
    assert!(
        e.abs() < 1e-15 && g.amax() < 1e-14,
        "rest: {e}, {}",
        g.amax()
    );
    let (e, _) = energy([[1.1, 0.0], [0.0, 1.0], [0.0, 0.0]]);
    assert!((e - 0.11).abs() < 1e-12, "uniaxial 1.1: {e}");
    let (e, _) = energy([[0.9, 0.0], [0.0, 1.0], [0.0, 0.0]]);
    assert!((e - 0.01).abs() < 1e-12, "compression 0.9: {e}");
    let (e, _) = energy([[1.0, 0.2], [0.0, 1.0], [0.0, 0.0]]);
    assert!((e - 0.0291689).abs() < 1e-7, "shear 0.2: {e}");
    // No Poisson coupling: stretching along û leaves the transverse force zero.
    let (_, g) = energy([[1.1, 0.0], [0.0, 1.0], [0.0, 0.0]]);
    assert!(
        g[7].abs() < 1e-14 && g[4].abs() < 1e-14,
        "transverse forces {}, {}",
        g[4],
        g[7]
    );
}

fn no_bending_wells() -> KoiterDensity {
    KoiterDensity {
        c: Mat3::zeros(),
        stretch: [(0.0, Sym2::zeros()); 2],
        bend: [(0.0, Sym2::zeros()); 2],
        stiffen: 0.0,
    }
}

/// A random rest metric, warp direction and deformed triangle.
fn random_bw(rng: &mut Rng) -> (BaraffWitkinFace, [Vec3; 6]) {
    let abar = Sym2::new(
        1.0 + 0.5 * rng.uniform(),
        0.3 * rng.symmetric(),
        0.7 + 0.5 * rng.uniform(),
    );
    let dir = Vec2::new(rng.symmetric(), rng.symmetric()) + Vec2::new(0.05, 0.0);
    let law = BaraffWitkinFace::new(
        &abar,
        &dir,
        0.1,
        1.0 + rng.uniform(),
        0.7 * rng.uniform() + 0.1,
        100.0 * rng.uniform(),
    );
    let x0 = Vec3::new(rng.symmetric(), rng.symmetric(), rng.symmetric());
    let x = [
        x0,
        x0 + Vec3::new(1.0, 0.0, 0.0)
            + Vec3::new(rng.symmetric(), rng.symmetric(), rng.symmetric()) * 0.4,
        x0 + Vec3::new(0.2, 1.0, 0.0)
            + Vec3::new(rng.symmetric(), rng.symmetric(), rng.symmetric()) * 0.4,
    ];
    (law, [x[0], x[1], x[2], x[0], x[0], x[0]])
}

/// The closed-form PSD Hessian has no negative eigenvalue over 10⁴ random states (stretched,
/// compressed and sheared); the exact one does, so the test can fail.
#[test]
fn baraff_witkin_psd_option_is_psd() {
    let mut rng = Rng::new(11);
    let mut exact_negative = 0;
    for _ in 0..10_000 {
        let (law, xs) = random_bw(&mut rng);
        let dens = WithKoiterBending {
            law,
            koiter: no_bending_wells(),
        };
        let mut h = SMat::<9, 9>::zeros();
        shell_element::<_, NoBending, 9, 3, true>(&NoBending, &(), &xs, &dens, None, Some(&mut h));
        let (vals, _) = jacobi_eigen(&h);
        let scale = vals.amax().max(1e-300);
        assert!(
            vals.min() >= -1e-10 * scale,
            "negative eigenvalue {} (scale {scale})",
            vals.min()
        );
        shell_element::<_, NoBending, 9, 3, false>(&NoBending, &(), &xs, &dens, None, Some(&mut h));
        if jacobi_eigen(&h).0.min() < -1e-8 * scale {
            exact_negative += 1;
        }
    }
    assert!(
        exact_negative > 100,
        "only {exact_negative} indefinite exact Hessians"
    );
}

/// Rotating the deformed state rotates the gradient and leaves the energy unchanged.
#[test]
fn baraff_witkin_is_rotation_invariant() {
    let mut rng = Rng::new(13);
    for _ in 0..100 {
        let (law, xs) = random_bw(&mut rng);
        let dens = WithKoiterBending {
            law,
            koiter: no_bending_wells(),
        };
        let axis = Vec3::new(rng.symmetric(), rng.symmetric(), rng.symmetric()).normalize();
        let r = nalgebra::Rotation3::from_axis_angle(
            &nalgebra::Unit::new_normalize(axis),
            3.0 * rng.symmetric(),
        );
        let xr = xs.map(|p| r * p + Vec3::new(0.3, -2.0, 1.0));
        let (mut g, mut gr) = (SVec::<9>::zeros(), SVec::<9>::zeros());
        let e = shell_element::<_, NoBending, 9, 3, false>(
            &NoBending,
            &(),
            &xs,
            &dens,
            Some(&mut g),
            None,
        );
        let er = shell_element::<_, NoBending, 9, 3, false>(
            &NoBending,
            &(),
            &xr,
            &dens,
            Some(&mut gr),
            None,
        );
        assert!((e - er).abs() <= 1e-12 * e.abs().max(1e-12), "{e} vs {er}");
        for v in 0..3 {
            let gv = r * Vec3::new(g[3 * v], g[3 * v + 1], g[3 * v + 2]);
            let grv = Vec3::new(gr[3 * v], gr[3 * v + 1], gr[3 * v + 2]);
            assert!(
                (gv - grv).norm() <= 1e-10 * g.amax().max(1e-12),
                "{gv} vs {grv}"
            );
        }
    }
}

/// Every obstacle shape, moved with the dial into a deformed strip so that some vertices are
/// in contact (on both branches of the smoothed penalty), and its friction (dynamic mode, the
/// normals lagged at other positions and dial, the obstacle moving over the step, slips on both
/// branches of the smoothed Coulomb law), against finite differences.
#[test]
fn obstacles_match_finite_differences() {
    for shape in [
        "shape = \"sphere\"\ncenter = [0.5, 0.25, -0.5]\nradius = 0.45",
        "shape = \"capsule\"\na = [0.3, 0.25, -0.5]\nb = [0.7, 0.3, -0.5]\nradius = 0.45",
        "shape = \"cylinder\"\npoint = [0.5, 0.25, -0.5]\naxis = [0.2, 1, 0]\nradius = 0.45",
        "shape = \"plane\"\npoint = [0, 0, -0.05]\nnormal = [0.1, 0, 1]",
        "shape = \"box\"\nmin = [0.2, 0.1, -1]\nmax = [0.8, 0.35, -0.05]",
    ] {
        let sc = strip_scene(&format!(
            "[material]\nthickness = 0.05\n[solver]\nmode = \"dynamic\"\n[constraints]\n\
             fix_boxes = [{{ min = [-1, -1, -1], max = [0.01, 2, 1] }}]\n[[obstacles]]\n{shape}\n\
             displacement = [0, 0, 0.2]\nfriction = 0.4\n"
        ));
        let p = Pattern::for_scene(&sc);
        let x = deformed(&sc);
        let phi = vec![0.0; sc.body.num_edge_dofs()];
        let mut rng = Rng::new(5);
        let x_prev: Vec<Vec3> = x
            .iter()
            .map(|v| v + Vec3::new(rng.symmetric(), rng.symmetric(), rng.symmetric()) * 0.004)
            .collect();
        let x_lag: Vec<Vec3> = x.iter().map(|v| v + Vec3::new(0.0, 0.0, -0.002)).collect();
        let pot = Potential {
            dial: 0.6,
            friction: Some(shellsim::energy::potential::Friction {
                x_prev: &x_prev,
                dial_prev: 0.55,
                normal_force: &[],
                x_lag: &x_lag,
                dial_lag: 0.58,
                eps: 0.003,
            }),
            ..Potential::new(&sc, &p)
        };
        for name in ["obstacles", "obstacle_friction"] {
            let i = (0..sc.terms.len())
                .find(|&i| sc.terms[i].name() == name)
                .unwrap();
            let e = sc.terms[i].eval(
                &pot,
                &p.maps[i],
                &x,
                &phi,
                Want::Energy,
                HessianProjection::None,
                &mut [],
                &mut [],
            );
            assert!(e > 0.0, "{shape}: {name}: no contact");
            check_term(&sc, &p, &pot, &x, &phi, i);
        }
    }
}

/// A force-controlled sphere pressed into a deformed strip, its offset a global DOF (the last
/// scalar DOF), with its inertia in dynamics, against finite differences: the coupling of every
/// vertex to the offset, the force's work and the inertia.
#[test]
fn a_force_controlled_obstacle_matches_finite_differences() {
    let sc = strip_scene(
        "[material]\nthickness = 0.05\n[solver]\nmode = \"dynamic\"\n[constraints]\n\
         fix_boxes = [{ min = [-1, -1, -1], max = [0.01, 2, 1] }]\n[[obstacles]]\n\
         shape = \"sphere\"\ncenter = [0.5, 0.25, 0.6]\nradius = 0.45\nforce = [0.2, 0, -3]\n\
         mass = 0.7\n",
    );
    assert_eq!(sc.globals.len(), 1);
    assert_eq!(sc.globals[0].name, "obstacle0_offset");
    let p = Pattern::for_scene(&sc);
    let x = deformed(&sc);
    let mut phi = vec![0.0; sc.num_scalar_dofs()];
    let k = phi.len() - 1;
    phi[k] = 0.13;
    let mut dofs_hat = phi.clone();
    dofs_hat[k] = 0.11;
    let xhat = x.clone();
    let pot = Potential {
        dial: 0.8,
        inertia: Some(Inertia {
            inv_dt2: 1e4,
            xhat: &xhat,
            dofs_hat: &dofs_hat,
        }),
        ..Potential::new(&sc, &p)
    };
    let i = (0..sc.terms.len())
        .find(|&i| sc.terms[i].name() == "pressed_obstacles")
        .unwrap();
    let obs = shellsim::energy::term::observables(sc.terms[i].as_ref(), &pot, &x, &phi);
    let gap = obs.iter().find(|(n, _)| n == "obstacle0_gap").unwrap().1;
    assert!(gap < -0.01, "no deep contact: gap {gap}");
    check_term(&sc, &p, &pot, &x, &phi, i);
}

/// The energy and the nominal stress `∂W/∂λ₁` of the rubber membranes under in-plane stretches
/// (λ₁, λ₂) with λ₃ = 1/(λ₁λ₂), uniaxial (λ₂ = λ₁^(−1/2)) and equibiaxial (λ₂ = λ₁), against
/// `W = c₁(I₁ − 3) + c₂(I₂ − 3)`, `I₁ = λ₁² + λ₂² + λ₃²`, `I₂ = λ₁²λ₂² + λ₁⁻² + λ₂⁻²`, and
/// Gent's `W = −(μ J_m/2) ln(1 − (I₁ − 3)/J_m)` with `μ = 2c₁`, whose stress is the neo-Hookean
/// one divided by `1 − (I₁ − 3)/J_m`.
#[test]
fn rubber_membranes_closed_form_energy_and_stress() {
    // Unit right triangle, ā = I, h = 2: rest volume V = 1.
    let abar = Sym2::new(1.0, 0.0, 1.0);
    let (c1, c2) = (0.3, 0.1);
    let nh = NeoHookeanFace::new(&abar, 2.0, 2.0 * c1, 1.0);
    let mr = MooneyRivlinFace { nh, w2: c2 };
    // Above the largest I₁ − 3 below (21.5, equibiaxial λ = 3.5), where the lock is strong.
    let jm = 25.0;
    let gent = GentFace { nh, jm };
    for l1 in [0.7, 1.0, 1.3, 2.0, 3.5] {
        for (kind, l2) in [("uniaxial", 1.0 / Real::sqrt(l1)), ("equibiaxial", l1)] {
            let l3 = 1.0 / (l1 * l2);
            let i1 = l1 * l1 + l2 * l2 + l3 * l3;
            let i2 = l1 * l1 * l2 * l2 + 1.0 / (l1 * l1) + 1.0 / (l2 * l2);
            let w_nh = c1 * (i1 - 3.0);
            let w_mr = w_nh + c2 * (i2 - 3.0);
            let p_nh = 2.0 * c1 * (l1 - 1.0 / (l1 * l1 * l1 * l2 * l2));
            let p_mr = p_nh + 2.0 * c2 * (l1 * l2 * l2 - 1.0 / (l1 * l1 * l1));
            let w_gent = -c1 * jm * (1.0 - (i1 - 3.0) / jm).ln();
            let p_gent = p_nh / (1.0 - (i1 - 3.0) / jm);
            let a = Sym2::new(l1 * l1, 0.0, l2 * l2);
            // ∂W/∂λ₁ = ∂W/∂a11 · 2λ₁.
            let nh_law = |a: &Sym2, g: &mut Sym2| nh.eval(a, Some((g, &mut Mat3::zeros())));
            let mr_law = |a: &Sym2, g: &mut Sym2| mr.eval(a, Some((g, &mut Mat3::zeros())));
            let gent_law = |a: &Sym2, g: &mut Sym2| gent.eval(a, Some((g, &mut Mat3::zeros())));
            type Law<'a> = &'a dyn Fn(&Sym2, &mut Sym2) -> Real;
            for (name, law, w, p) in [
                ("neo-Hookean", &nh_law as Law, w_nh, p_nh),
                ("Mooney-Rivlin", &mr_law as Law, w_mr, p_mr),
                ("Gent", &gent_law as Law, w_gent, p_gent),
            ] {
                let mut ga = Sym2::zeros();
                let e = law(&a, &mut ga);
                assert!(
                    (e - w).abs() < 1e-12 * w.abs().max(1.0),
                    "{name} {kind} λ={l1}: W {e} vs {w}"
                );
                let stress = ga[0] * 2.0 * l1;
                assert!(
                    (stress - p).abs() < 1e-12 * p.abs().max(1.0),
                    "{name} {kind} λ={l1}: P {stress} vs {p}"
                );
            }
        }
    }
}

/// Gent rubber with `J_m → ∞` is the neo-Hookean law: energy, gradient and Hessian agree to
/// round-off at `J_m = 10¹⁴` (the difference is of order ψ/J_m ≈ 10⁻¹⁴), on stretches and
/// shears well away from the lock; and the energy is `+∞` at and beyond it.
#[test]
fn gent_tends_to_neo_hookean_and_locks() {
    let abar = Sym2::new(1.2, 0.3, 0.9);
    let nh = NeoHookeanFace::new(&abar, 0.01, 4e5, 1.0);
    let gent = GentFace { nh, jm: 1e14 };
    for a in [
        Sym2::new(1.2, 0.3, 0.9),
        Sym2::new(2.5, -0.4, 1.1),
        Sym2::new(0.8, 0.1, 3.0),
    ] {
        let (mut g0, mut h0, mut g1, mut h1) =
            (Sym2::zeros(), Mat3::zeros(), Sym2::zeros(), Mat3::zeros());
        let e0 = nh.eval(&a, Some((&mut g0, &mut h0)));
        let e1 = gent.eval(&a, Some((&mut g1, &mut h1)));
        assert!(
            (e1 - e0).abs() <= 1e-12 * e0.abs().max(nh.w),
            "{e1} vs {e0}"
        );
        assert!(
            (g1 - g0).norm() <= 1e-12 * g0.norm().max(nh.w),
            "{g1} vs {g0}"
        );
        assert!((h1 - h0).norm() <= 1e-12 * h0.norm(), "{h1} vs {h0}");
    }
    // Equibiaxial λ with 2λ² + λ⁻⁴ − 3 = J_m: locked.
    let locked = GentFace { nh, jm: 1.0 };
    let (mut g, mut h) = (Sym2::zeros(), Mat3::zeros());
    let big = Sym2::new(1.2 * 4.0, 0.3 * 4.0, 0.9 * 4.0);
    assert_eq!(locked.eval(&big, Some((&mut g, &mut h))), Real::INFINITY);
    assert!(g.iter().chain(h.iter()).all(|v| v.is_finite()));
}

/// A test global term: a tether `E = k/2 (wᵀx − c)²` over every position DOF, whose Hessian
/// `k w wᵀ` is dense and rank one. It has no elements (empty stencil): all of its Hessian is
/// the low-rank part.
struct Tether {
    k: Real,
    w: Vec<Real>,
    c: Real,
}

impl Term for Tether {
    fn name(&self) -> &'static str {
        "tether"
    }
    fn stencil(&self, _: &Body) -> Stencil {
        Stencil {
            slot_dofs: vec![3],
            nodes: vec![],
            anchors: vec![],
        }
    }
    fn eval(
        &self,
        _: &Potential,
        _: &ElementMap,
        x: &[Vec3],
        _: &[Real],
        want: Want,
        _: HessianProjection,
        grad: &mut [Real],
        _: &mut [Real],
    ) -> Real {
        let s: Real = x
            .iter()
            .flat_map(|p| p.iter().copied())
            .zip(&self.w)
            .map(|(a, b)| a * b)
            .sum::<Real>()
            - self.c;
        if want != Want::Energy {
            for (g, w) in grad.iter_mut().zip(&self.w) {
                *g += self.k * s * w;
            }
        }
        0.5 * self.k * s * s
    }
    fn low_rank(&self) -> Option<&dyn LowRankPart> {
        Some(self)
    }
}

impl LowRankPart for Tether {
    fn low_rank(&self, _: &Potential, x: &[Vec3], phi: &[Real], out: &mut Vec<LowRank>) {
        let mut u = self.w.clone();
        u.resize(3 * x.len() + phi.len(), 0.0);
        out.push(LowRank { c: self.k, u });
    }
}

/// Newton with the low-rank part (Woodbury on the sparse factor) takes the same step as a dense
/// solve of the full Hessian, and converges on a scene whose only coupling of the two ends is
/// the dense term.
#[test]
fn low_rank_term_solves_like_the_dense_matrix() {
    let mut sc = strip_scene(
        "[material]\nbending = \"midedge_average\"\nthickness = 0.05\n[constraints]\n\
         fix_boxes = [{ min = [-1, -1, -1], max = [0.01, 2, 1] }]",
    );
    let nv = sc.body.num_vertices();
    let mut rng = Rng::new(8);
    let w: Vec<Real> = (0..3 * nv)
        .map(|k| {
            if sc.body.fixed[k / 3] {
                0.0
            } else {
                rng.symmetric()
            }
        })
        .collect();
    assert!(sc
        .terms
        .push(Box::new(Tether {
            k: 1e5,
            w: w.clone(),
            c: 0.3
        }))
        .is_ok());
    let p = Pattern::for_scene(&sc);
    let pot = Potential::new(&sc, &p);
    // Stretched along x (a positive definite sparse part), slightly rippled.
    let x: Vec<Vec3> = sc
        .body
        .mesh
        .positions
        .iter()
        .map(|q| Vec3::new(1.02 * q.x, q.y, 0.002 * (7.0 * q.x).sin() * q.y))
        .collect();
    let (mut g, mut h) = (vec![0.0; p.n], vec![0.0; p.nnz()]);
    pot.eval(&x, &[], Want::Hessian, &mut g, &mut h);
    // Dense reference: the sparse lower triangle mirrored, plus k w wᵀ.
    let n = p.n;
    let mut dense = nalgebra::DMatrix::<Real>::zeros(n, n);
    for col in 0..n {
        for k in p.col_ptr[col]..p.col_ptr[col + 1] {
            let row = p.row_idx[k];
            dense[(row, col)] = h[k];
            dense[(col, row)] = h[k];
        }
    }
    let lr = pot.low_rank(&x, &[]);
    assert_eq!(lr.len(), 1);
    for i in 0..n {
        for j in 0..n {
            dense[(i, j)] += lr[0].c * lr[0].u[i] * lr[0].u[j];
        }
    }
    let rhs = nalgebra::DVector::from_iterator(n, g.iter().map(|v| -v));
    let want = dense.clone().lu().solve(&rhs).unwrap();
    let mut lin = shellsim::solve::LinearSolver::new(&p).unwrap();
    lin.factor(&h).unwrap();
    let wb = shellsim::solve::low_rank::Woodbury::new(&mut lin, &lr);
    let mut step: Vec<Real> = g.iter().map(|v| -v).collect();
    assert!(wb.solve_in_place(&mut lin, &mut step));
    let err = step
        .iter()
        .zip(want.iter())
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, Real::max);
    assert!(
        err <= 1e-8 * want.amax(),
        "Woodbury vs dense: {err} (step {})",
        want.amax()
    );
    assert!(wb.keeps_positive_definite());
    // Without the low-rank part the step differs: the check can fail.
    let mut plain: Vec<Real> = g.iter().map(|v| -v).collect();
    lin.solve_in_place(&mut plain);
    let diff = plain
        .iter()
        .zip(want.iter())
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, Real::max);
    assert!(diff > 1e-3 * want.amax());
    // Newton converges with the tether satisfied.
    let mut state = shellsim::solve::State {
        x: x.clone(),
        dofs: Vec::new(),
        terms: Default::default(),
    };
    let mut ws = shellsim::solve::newton::Workspace::new(&p);
    let rep = shellsim::solve::newton(
        &pot,
        &mut lin,
        &mut ws,
        &mut state,
        shellsim::solve::NewtonOptions {
            tol: 1e-9,
            max_iter: 100,
            ..Default::default()
        },
    );
    assert!(rep.converged, "{rep:?}");
    let s: Real = state
        .x
        .iter()
        .flat_map(|p| p.iter().copied())
        .zip(&w)
        .map(|(a, b)| a * b)
        .sum();
    // At equilibrium the tether's force balances the elastic forces; the constraint is soft,
    // but k is large: wᵀx is close to c.
    assert!((s - 0.3).abs() < 0.05, "wᵀx = {s}");
}

/// The scene's slides term.
fn slides_term(sc: &Scene) -> &dyn ExplicitHooks {
    sc.terms
        .iter()
        .find(|t| t.name() == "slides")
        .expect("the slides term")
        .explicit()
        .expect("the slides act on explicit steps")
}

/// Slide friction (explicit mode) on a strip pressed 0.01 into the lower slide, normal force
/// N = k · 0.01 per vertex with k = 100 μ t = 2 N/m, limit μ_f N: a vertex at rest with an
/// in-plane force below the limit sticks (force and velocity zeroed); at rest above it, it slides
/// with friction of exactly the limit against the force; moving against a force above the limit,
/// friction opposes the velocity (it dissipates), where a rule opposing the force would push.
#[test]
fn slide_friction_sticks_at_rest_and_brakes_sliding() {
    let sc = strip_scene(
        "[material]\nyoung = 3.0\npoisson = 0.5\ndensity = 1.0\nthickness = 0.02\n\
         bending = \"patch_fit\"\n[solver]\nmode = \"explicit\"\n\
         [slides]\nenabled = true\nlower = -0.1\nupper = 0.1\nfriction = 0.5\n",
    );
    let p = Pattern::for_scene(&sc);
    let pot = Potential::new(&sc, &p);
    let slides = slides_term(&sc);
    let limit = 0.5 * 2.0 * 0.01;
    let n = sc.body.num_vertices();
    let x: Vec<Vec3> = sc
        .body
        .mesh
        .positions
        .iter()
        .map(|q| Vec3::new(q.x, q.y, -0.11))
        .collect();
    let force = |i: usize| match i % 3 {
        0 => Vec3::new(0.5 * limit, 0.0, 0.0),
        1 => Vec3::new(0.0, 2.0 * limit, 0.0),
        _ => Vec3::new(2.0 * limit, 0.0, 0.0),
    };
    let v0 = |i: usize| {
        if i % 3 == 2 {
            Vec3::new(-1.0, 0.0, 0.0)
        } else {
            Vec3::zeros()
        }
    };
    let mut v: Vec<Vec3> = (0..n).map(v0).collect();
    let mut g = vec![0.0; p.n];
    for i in 0..n {
        let f = force(i);
        g[3 * i..3 * i + 3].copy_from_slice(&[-f.x, -f.y, -f.z]);
    }
    let dt = 1e-4;
    slides.explicit_step(&pot, &x, &mut v, &mut g, dt);
    for i in 0..n {
        let after = -Vec3::new(g[3 * i], g[3 * i + 1], g[3 * i + 2]);
        let friction = after - force(i);
        match i % 3 {
            0 => {
                assert_eq!((after.x, after.y), (0.0, 0.0), "vertex {i} sticks");
                assert_eq!(v[i], Vec3::zeros(), "vertex {i} stays at rest");
            }
            1 => assert!(
                (friction - Vec3::new(0.0, -limit, 0.0)).norm() < 1e-15,
                "vertex {i}: friction {friction:?} against the force"
            ),
            _ => {
                assert!(
                    (friction - Vec3::new(limit, 0.0, 0.0)).norm() < 1e-15,
                    "vertex {i}: friction {friction:?} against the velocity"
                );
                assert!(friction.dot(&v[i]) < 0.0, "vertex {i}: friction dissipates");
            }
        }
    }
}

/// Contact damping (explicit mode, ζ = 1): on a vertex in contact the dashpot `c = 2√(k m)`
/// acts on the normal velocity relative to the slide that the step reaches, implicitly: after
/// the step's update `v_z' = v_z − Δt g_z/m` equals `w = (v_z − v_slide − Δt g_z⁰/m)/(1 + Δt c/m)`
/// plus the slide's velocity, and the added force opposes `w` (it dissipates). Tolerances:
/// round-off of velocities of order 1 m/s, and of the slide's velocity from its heights. A vertex riding
/// the moving upper slide at the slide's speed feels none; one out of contact feels none.
#[test]
fn slide_contact_damping_is_an_implicit_dashpot_relative_to_the_slide() {
    let sc = strip_scene(
        "[material]\nyoung = 3.0\npoisson = 0.5\ndensity = 1.0\nthickness = 0.02\n\
         bending = \"patch_fit\"\n[solver]\nmode = \"explicit\"\n\
         [slides]\nenabled = true\nlower = -0.1\nupper = 0.1\ncontrol = \"speed\"\n\
         speed = 2.0\ntravel = 0.05\ncontact_damping = 1\n",
    );
    let p = Pattern::for_scene(&sc);
    let pot = Potential::new(&sc, &p);
    let slides = slides_term(&sc);
    let (k, dt, speed) = (2.0, 1e-3, 2.0);
    let n = sc.body.num_vertices();
    // Vertex kinds: 0 pressed into the lower slide, moving down; 1 riding the upper slide at its
    // speed; 2 in contact with the upper slide, moving up into it; 3 free in the gap.
    let z = |i: usize| match i % 4 {
        0 => -0.11,
        1 | 2 => 0.1 - speed * dt + 0.005,
        _ => 0.0,
    };
    let vz = |i: usize| match i % 4 {
        0 => -1.0,
        1 => -speed,
        2 => 0.5,
        _ => 0.7,
    };
    let x: Vec<Vec3> = sc
        .body
        .mesh
        .positions
        .iter()
        .enumerate()
        .map(|(i, q)| Vec3::new(q.x, q.y, z(i)))
        .collect();
    let mut states = sc.initial_states.clone();
    slides.explicit_begin(&sc.body, pot.dial, &x, dt, states.get_mut("slides"));
    let pot = Potential {
        states: &states,
        ..pot
    };
    let mut v: Vec<Vec3> = (0..n).map(|i| Vec3::new(0.0, 0.0, vz(i))).collect();
    // The penalty's own gradient along z, and an in-plane force that must stay untouched.
    let g0: Vec<Real> = (0..n)
        .flat_map(|i| {
            let gz = match i % 4 {
                0 => -k * 0.01,
                2 => k * 0.005,
                _ => 0.0,
            };
            [0.3, -0.2, gz]
        })
        .collect();
    let mut g = g0.clone();
    slides.explicit_step(&pot, &x, &mut v, &mut g, dt);
    for i in 0..n {
        let m = sc.body.mass[i];
        let c = 2.0 * (k * m).sqrt();
        assert_eq!(
            (g[3 * i], g[3 * i + 1]),
            (0.3, -0.2),
            "vertex {i}: in-plane force"
        );
        let added = g[3 * i + 2] - g0[3 * i + 2];
        let slide = if i % 4 == 1 || i % 4 == 2 {
            -speed
        } else {
            0.0
        };
        match i % 4 {
            3 => assert_eq!(added, 0.0, "vertex {i} is out of contact"),
            _ => {
                let w = (vz(i) - slide - dt * g0[3 * i + 2] / m) / (1.0 + dt * c / m);
                let after = vz(i) - dt * g[3 * i + 2] / m;
                assert!(
                    (after - slide - w).abs() <= 1e-12 * (1.0 + w.abs()),
                    "vertex {i}: relative velocity {} after the step, implicit {w}",
                    after - slide
                );
                assert!(
                    (added - c * w).abs() <= 1e-12 * c * (1.0 + w.abs()),
                    "vertex {i}: dashpot {added} vs {}",
                    c * w
                );
                if i % 4 == 1 {
                    // Riding the slide with no net force: no relative motion, no damping, up to
                    // the round-off of the slide's velocity, (z₁ − z₀)/Δt ~ ε·0.1/Δt = 1e-14 m/s.
                    assert!(
                        added.abs() <= 1e-12 * c,
                        "vertex {i} rides the slide: {added}"
                    );
                } else {
                    assert!(-added * w < 0.0, "vertex {i}: the dashpot dissipates");
                }
            }
        }
    }
}
