//! Self-contact: the term against finite differences on a strip folded onto itself (the flat
//! strip has no pairs; the fold gathers point–triangle and edge–edge pairs). The scenes that
//! run the term end to end are in `tests/self_contact.rs`.

use shellsim::assembly::{Pattern, Want};
use shellsim::contact::distance;
use shellsim::energy::HessianProjection;
use shellsim::energy::Potential;
use shellsim::math::{Real, Vec3};
use shellsim::mesh::generate::{rectangle, Rng, Spacing};
use shellsim::model::Scene;
use shellsim::settings::Settings;

/// A 1 × 0.2 strip, edges about `edge`, thickness 0.05, with self-contact.
fn strip(edge: Real, extra: &str) -> Scene {
    let m = rectangle(
        0.0,
        0.0,
        1.0,
        0.2,
        edge,
        Spacing {
            jitter: 0.2,
            seed: 7,
            ..Default::default()
        },
    );
    let s = format!(
        "[material]\nthickness = 0.05\nyoung = 1e6\n[self_contact]\nenabled = true\n{extra}"
    );
    Scene::build(m, Settings::from_str_with(&s, "test", &[]).unwrap()).unwrap()
}

/// The strip folded at x = 0.5 over a half circle of radius `gap/2`: the half beyond lies
/// flat `gap` above the half before, with a small random offset.
fn folded(sc: &Scene, gap: Real, noise: Real, seed: u64) -> Vec<Vec3> {
    let r = gap / 2.0;
    let arc = std::f64::consts::PI * r;
    let mut rng = Rng::new(seed);
    sc.body
        .mesh
        .positions
        .iter()
        .map(|p| {
            let s = p.x - 0.5;
            let q = if s <= 0.0 {
                Vec3::new(p.x, p.y, 0.0)
            } else if s < arc {
                let t = s / r;
                Vec3::new(0.5 + r * t.sin(), p.y, r * (1.0 - t.cos()))
            } else {
                Vec3::new(0.5 - (s - arc), p.y, gap)
            };
            q + Vec3::new(rng.symmetric(), rng.symmetric(), rng.symmetric()) * noise
        })
        .collect()
}

/// The strip folded with the layers `gap` apart (a noise of `noise`), and its pattern with the
/// pairs gathered there, for the first noise whose pairs (of term `i`) keep their closest features under
/// every perturbation of the finite-difference check: the distance's Hessian jumps where they
/// change, and differences across such a place would not measure it.
fn folded_without_feature_changes(
    sc: &Scene,
    p0: &Pattern,
    phi: &[Real],
    i: usize,
    (gap, noise): (Real, Real),
) -> (Vec<Vec3>, Pattern) {
    (11..60)
        .map(|seed| {
            let x = folded(sc, gap, noise, seed);
            let p = p0
                .refreshed(sc, &x, phi, 0.0)
                .expect("the fold brings pairs");
            (x, p)
        })
        .find(|(x, p)| kinds_hold(x, &p.maps[i].nodes, 1e-6))
        .expect("a noise with no pair on a change of closest features")
}

fn term_index(sc: &Scene) -> usize {
    (0..sc.terms.len())
        .find(|&i| sc.terms[i].name() == "self_contact")
        .expect("a self_contact term")
}

/// Term `i` of `sc` at `(x, phi)` with pattern `p`: its pairs press (energy > 0), and its
/// energy, gradient and Hessian match central differences.
fn pressing_term_matches_finite_differences(
    sc: &Scene,
    p: &Pattern,
    i: usize,
    x: &[Vec3],
    phi: &[Real],
) {
    let pot = Potential::new(sc, p);
    let term = &sc.terms[i];
    let map = &p.maps[i];
    let mut g = vec![0.0; p.n];
    let e = term.eval(
        &pot,
        map,
        x,
        phi,
        Want::Gradient,
        HessianProjection::None,
        &mut g,
        &mut [],
    );
    assert!(e > 0.0, "{}: the pairs press", term.name());
    super::terms::fd_check(
        sc,
        p,
        x,
        phi,
        term.name(),
        1,
        |g, h| g.max(h),
        |x, phi, want, g, h| {
            g.iter_mut().for_each(|v| *v = 0.0);
            h.iter_mut().for_each(|v| *v = 0.0);
            term.eval(&pot, map, x, phi, want, HessianProjection::None, g, h)
        },
    );
}

/// The term alone against central differences on the folded strip, the layers 0.02 apart
/// (offset 0.05): every vertex of the folded part presses on a face below it, and the
/// edge–edge pairs, active inside half the offset, press too.
#[test]
fn self_contact_matches_finite_differences_on_a_folded_strip() {
    let sc = strip(0.05, "stiffness = 1e7\nsmoothing = 0.004\n");
    let phi = vec![0.0; sc.num_scalar_dofs()];
    let p0 = Pattern::for_scene(&sc);
    let i = term_index(&sc);
    assert!(p0.maps[i].nodes.is_empty(), "the flat strip has no pairs");
    let (x, p) = folded_without_feature_changes(&sc, &p0, &phi, i, (0.02, 0.002));
    let n = p.maps[i].nodes.len() / 4;
    let ee = p.maps[i].nodes.chunks(4).filter(|c| c[2] < c[3]).count();
    assert!(n > 50 && ee > 10, "{n} pairs, {ee} edge–edge");
    pressing_term_matches_finite_differences(&sc, &p, i, &x, &phi);
}

/// The term with IPC's log barrier (`law = "barrier"`, activation ĝ = 0.01) against central
/// differences on the strip folded with its layers 0.055 apart (offset 0.05, noise 0.001):
/// every pair of a vertex with the face below it is in the barrier's range (0.05, 0.06).
#[test]
fn the_barrier_matches_finite_differences_on_a_folded_strip() {
    let sc = strip(
        0.05,
        "law = \"barrier\"\nstiffness = 1e7\nsmoothing = 0.01\n",
    );
    let phi = vec![0.0; sc.num_scalar_dofs()];
    let p0 = Pattern::for_scene(&sc);
    let i = term_index(&sc);
    let (x, p) = folded_without_feature_changes(&sc, &p0, &phi, i, (0.055, 0.001));
    let n = p.maps[i].nodes.len() / 4;
    assert!(n > 50, "{n} pairs");
    pressing_term_matches_finite_differences(&sc, &p, i, &x, &phi);
}

/// IPC's log barrier against central differences of itself: `b′` and `b″` across its range,
/// and `b`, `b′`, `b″` vanishing at the activation distance, infinite at 0.
#[test]
fn the_log_barrier_matches_its_derivatives() {
    use shellsim::contact::barrier;
    let g_hat = 1e-3;
    for k in 1..100 {
        let g = g_hat * k as Real / 100.0;
        let h = 1e-6 * g;
        let (b, db, ddb) = barrier(g, g_hat);
        let fd1 = (barrier(g + h, g_hat).0 - barrier(g - h, g_hat).0) / (2.0 * h);
        let fd2 = (barrier(g + h, g_hat).1 - barrier(g - h, g_hat).1) / (2.0 * h);
        assert!(b > 0.0 && db < 0.0 && ddb > 0.0, "g = {g}: {b} {db} {ddb}");
        assert!(
            (fd1 - db).abs() <= 1e-7 * db.abs(),
            "b′ at {g}: {fd1} vs {db}"
        );
        assert!(
            (fd2 - ddb).abs() <= 1e-7 * ddb.abs(),
            "b″ at {g}: {fd2} vs {ddb}"
        );
    }
    assert_eq!(barrier(g_hat, g_hat), (0.0, 0.0, 0.0));
    assert_eq!(barrier(2.0 * g_hat, g_hat), (0.0, 0.0, 0.0));
    let (b, db, _) = barrier(g_hat * (1.0 - 1e-9), g_hat);
    assert!(
        b.abs() < 1e-20 && db.abs() < 1e-15,
        "continuous at ĝ: {b} {db}"
    );
    assert!(barrier(0.0, g_hat).0.is_infinite());
}

/// The closest features of each pair of `nodes` at `x`.
fn kinds(x: &[Vec3], nodes: &[usize]) -> Vec<distance::Kind> {
    nodes
        .chunks(4)
        .map(|n| {
            let y = [x[n[0]], x[n[1]], x[n[2]], x[n[3]]];
            if n[2] > n[3] {
                distance::point_triangle(&y).kind
            } else {
                distance::edge_edge(&y).kind
            }
        })
        .collect()
}

/// Whether no pair's closest features change when any coordinate moves by ±`eps`.
fn kinds_hold(x: &[Vec3], nodes: &[usize], eps: Real) -> bool {
    let k0 = kinds(x, nodes);
    for v in 0..x.len() {
        for c in 0..3 {
            for s in [eps, -eps] {
                let mut y = x.to_vec();
                y[v][c] += s;
                if kinds(&y, nodes) != k0 {
                    return false;
                }
            }
        }
    }
    true
}

/// The term with friction (dynamic mode, μ = 0.4) against central differences on the folded
/// strip: the friction's normal forces, normals and closest points are lagged at a nearby
/// iterate, and the step started with the folded half moved against the other by `slide`
/// (plus a noise of a tenth of ε per vertex). The smoothed friction's third derivative jumps
/// where a pair's slip crosses the smoothing ε, so each check keeps every slip to one side:
/// a slide of 0.3 ε sticks every pair, one of 3 ε slides them all.
#[test]
fn self_contact_friction_matches_finite_differences() {
    let sc = strip(
        0.05,
        "stiffness = 1e7\nsmoothing = 0.004\nfriction = 0.4\n[solver]\nmode = \"dynamic\"\n",
    );
    let phi = vec![0.0; sc.num_scalar_dofs()];
    let p0 = Pattern::for_scene(&sc);
    let i = term_index(&sc);
    let (x, p) = folded_without_feature_changes(&sc, &p0, &phi, i, (0.02, 0.002));
    let eps = 1e-3;
    let mut rng = Rng::new(3);
    let lag: Vec<Vec3> = x
        .iter()
        .map(|p| p + Vec3::new(rng.symmetric(), rng.symmetric(), rng.symmetric()) * 1e-4)
        .collect();
    let term = &sc.terms[i];
    let map = &p.maps[i];
    assert!(term.lagged().is_some(), "friction lags its normal forces");
    for slide in [0.3, 3.0] {
        let prev: Vec<Vec3> = x
            .iter()
            .zip(&sc.body.mesh.positions)
            .map(|(p, r)| {
                let moved = if r.x > 0.5 {
                    Vec3::new(0.8, 0.6, 0.0) * slide * eps
                } else {
                    Vec3::zeros()
                };
                p - moved - Vec3::new(rng.symmetric(), rng.symmetric(), rng.symmetric()) * 0.1 * eps
            })
            .collect();
        let pot = Potential {
            friction: Some(shellsim::energy::potential::Friction {
                x_prev: &prev,
                dial_prev: 0.0,
                normal_force: &[],
                x_lag: &lag,
                dial_lag: 0.0,
                eps,
            }),
            ..Potential::new(&sc, &p)
        };
        // The friction alone: the whole term less the normal law (its reported energy).
        let whole = term.eval(
            &pot,
            map,
            &x,
            &phi,
            Want::Energy,
            HessianProjection::None,
            &mut [],
            &mut [],
        );
        let normal = shellsim::energy::term::energies(term.as_ref(), &pot, map, &x, &phi)[0].1;
        assert!(
            whole - normal > 1e-3 * normal,
            "friction dissipates: {whole} vs {normal}"
        );
        super::terms::fd_check(
            &sc,
            &p,
            &x,
            &phi,
            &format!("self_contact friction, slide {slide} ε"),
            1,
            |g, h| g.max(h),
            |x, phi, want, g, h| {
                g.iter_mut().for_each(|v| *v = 0.0);
                h.iter_mut().for_each(|v| *v = 0.0);
                term.eval(&pot, map, x, phi, want, HessianProjection::None, g, h)
            },
        );
    }
}

/// A strip (h = 0.05) held 0.01 above a mesh obstacle, an icosphere of radius 0.15 (162
/// vertices) under its middle: the mesh obstacles' term against central differences, with
/// pairs of every kind (strip vertices on the ball's faces, the ball's vertices on the strip's
/// faces, the strip's edges across the ball's). The obstacle's vertices are no DOFs: their
/// stencil slots are absent.
#[test]
fn a_mesh_obstacle_matches_finite_differences() {
    mesh_obstacle_against_finite_differences("", None);
}

/// The same ball force-controlled (`force` along ê = (0.2, −0.1, 1)/‖·‖, mass 0.7 kg, in
/// dynamics), placed at its offset q = 0.004 along ê, with the inertia of the offset (q̂ =
/// 0.003, 1/Δt² = 10⁴): every pair with the ball couples its strip vertices to the offset, a
/// global DOF, through the ball's vertices moving by ê per unit of it, and the force's own
/// element adds −F q + M (q − q̂)²/(2Δt²); all against central differences in x and q.
#[test]
fn a_force_controlled_mesh_obstacle_matches_finite_differences() {
    let e = Vec3::new(0.2, -0.1, 1.0).normalize();
    mesh_obstacle_against_finite_differences(
        &format!(
            "force = [{}, {}, {}]\nmass = 0.7\n[solver]\nmode = \"dynamic\"\n",
            3.0 * e.x,
            3.0 * e.y,
            3.0 * e.z
        ),
        Some((e, 0.004)),
    );
}

/// The mesh obstacles' term on the strip over the icosphere against central differences (the
/// settings `extra` added to the obstacle's table; `push`, the direction and offset of a
/// force-controlled ball).
fn mesh_obstacle_against_finite_differences(extra: &str, push: Option<(Vec3, Real)>) {
    use shellsim::elements::ABSENT;
    let dir = tempfile::tempdir().unwrap();
    let ball_file = dir.path().join("ball.vtk");
    let ball = shellsim::mesh::generate::icosphere(0.15, 2);
    shellsim::mesh::io::write_mesh(&ball_file, &ball, shellsim::mesh::io::Format::Vtk, "ball")
        .unwrap();
    let m = rectangle(
        0.0,
        0.0,
        1.0,
        0.2,
        0.05,
        Spacing {
            jitter: 0.2,
            seed: 7,
            ..Default::default()
        },
    );
    let s = format!(
        "[material]\nthickness = 0.05\nyoung = 1e6\n[[obstacles]]\nshape = \"mesh\"\n\
         file = \"{}\"\ntranslate = [0.5, 0.1, -0.2]\nstiffness = 1e7\nsmoothing = 0.004\n{extra}",
        ball_file.display()
    );
    let sc = Scene::build(m, Settings::from_str_with(&s, "test", &[]).unwrap()).unwrap();
    let i = (0..sc.terms.len())
        .find(|&i| sc.terms[i].name() == "mesh_obstacles")
        .expect("a mesh_obstacles term");
    let mut phi = vec![0.0; sc.num_scalar_dofs()];
    let (direction, q) = push.unwrap_or((Vec3::zeros(), 0.0));
    if push.is_some() {
        assert_eq!(sc.globals.len(), 1);
        assert_eq!(sc.globals[0].name, "obstacle0_offset");
        *phi.last_mut().unwrap() = q;
    }
    let p0 = Pattern::for_scene(&sc);
    let nv = sc.body.num_vertices();
    let ball_at = |q: Real| -> Vec<Vec3> {
        ball.positions
            .iter()
            .map(|p| p + Vec3::new(0.5, 0.1, -0.2) + direction * q)
            .collect()
    };
    // The pairs' four nodes (the stencil's first four slots, without the force's element).
    let pairs = |nodes: &[usize], slots: usize| -> Vec<usize> {
        nodes
            .chunks(slots)
            .filter(|n| n[0] != usize::MAX)
            .flat_map(|n| n[..4].iter().copied())
            .collect()
    };
    // The pairs' closest features at the sheet's `x`, the ball's vertices numbered after it,
    // unchanged by a move of ±1e-6 of any coordinate or of the offset.
    let hold = |x: &[Vec3], nodes: &[usize]| {
        let at =
            |x: &[Vec3], q: Real| -> Vec<Vec3> { x.iter().copied().chain(ball_at(q)).collect() };
        let all = at(x, q);
        let inner: Vec<usize> = nodes
            .iter()
            .map(|&u| if u >= ABSENT { nv + (u - ABSENT) } else { u })
            .collect();
        let k0 = kinds(&all, &inner);
        let offsets = [1e-6, -1e-6]
            .iter()
            .all(|s| kinds(&at(x, q + s), &inner) == k0);
        offsets
            && (0..nv).all(|v| {
                (0..3).all(|c| {
                    [1e-6, -1e-6].iter().all(|s| {
                        let mut y = all.clone();
                        y[v][c] += s;
                        kinds(&y, &inner) == k0
                    })
                })
            })
    };
    let (x, p) = (1..60)
        .map(|seed| {
            let mut rng = Rng::new(seed);
            let x: Vec<Vec3> = sc
                .body
                .mesh
                .positions
                .iter()
                .map(|v| {
                    v + Vec3::new(0.0, 0.0, -0.04)
                        + Vec3::new(rng.symmetric(), rng.symmetric(), rng.symmetric()) * 0.002
                })
                .collect();
            let p = p0.refreshed(&sc, &x, &phi, 0.0).expect("the ball is near");
            (x, p)
        })
        .find(|(x, p)| hold(x, &pairs(&p.maps[i].nodes, p.maps[i].slots)))
        .expect("a noise with no pair on a change of closest features");
    let nodes = pairs(&p.maps[i].nodes, p.maps[i].slots);
    let sheet_on_ball = nodes
        .chunks(4)
        .filter(|n| n[2] > n[3] && n[0] < ABSENT)
        .count();
    let ball_on_sheet = nodes
        .chunks(4)
        .filter(|n| n[2] > n[3] && n[0] >= ABSENT)
        .count();
    let edges = nodes.chunks(4).filter(|n| n[2] < n[3]).count();
    println!("{sheet_on_ball} strip vertices, {ball_on_sheet} ball vertices, {edges} edge pairs");
    assert!(sheet_on_ball > 3 && ball_on_sheet > 0 && edges > 3);
    if push.is_none() {
        pressing_term_matches_finite_differences(&sc, &p, i, &x, &phi);
        return;
    }
    let mut dofs_hat = phi.clone();
    *dofs_hat.last_mut().unwrap() = 0.003;
    let pot = Potential {
        inertia: Some(shellsim::energy::potential::Inertia {
            inv_dt2: 1e4,
            xhat: &x,
            dofs_hat: &dofs_hat,
        }),
        ..Potential::new(&sc, &p)
    };
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
    assert!(g[p.n - 1] != 0.0, "the offset has a gradient");
    super::terms::check_term(&sc, &p, &pot, &x, &phi, i);
    // The offset moves every vertex of the ball: a step of the offset alone 0.1 into the strip
    // (the ball's top is 6 mm into its offset) is cut by CCD short of the minimum separation,
    // where the state is admitted and past which it is not; the same step away is whole.
    let limit = sc.terms[i].step_limit().expect("the term bounds the steps");
    let mut step = vec![0.0; p.n];
    let along = |dq: Real| {
        let mut s = phi.clone();
        *s.last_mut().unwrap() += dq;
        s
    };
    step[p.n - 1] = 0.1;
    let bound = limit.max_fraction(&pot, &p.maps[i], &x, &phi, &step);
    println!(
        "a push of the ball 0.1 into the strip: fraction {}",
        bound.fraction
    );
    assert!(bound.fraction > 0.0 && bound.fraction < 0.1, "{bound:?}");
    assert!(limit.admits(&pot, &p.maps[i], &x, &along(bound.fraction * 0.1)));
    assert!(!limit.admits(&pot, &p.maps[i], &x, &along(0.1)));
    step[p.n - 1] = -0.1;
    let away = limit.max_fraction(&pot, &p.maps[i], &x, &phi, &step);
    assert_eq!(away.fraction, 1.0, "{away:?}");
}
