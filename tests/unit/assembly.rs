//! Assembly: zero energy and gradient at rest, bitwise independence of the thread count, and
//! the assembled gradient/Hessian against finite differences of the assembled energy.

use shellsim::assembly::{Pattern, Want};
use shellsim::cases::Case;
use shellsim::energy::Potential;
use shellsim::math::Vec3;
use shellsim::mesh::generate::{rectangle, Rng, Spacing};
use shellsim::model::Scene;
use shellsim::settings::Settings;

fn scene(settings: &str, program: Option<Case>) -> Scene {
    scene_with_edge(settings, program, 0.125)
}

/// With edge 0.02 the mesh has 5000 faces, about 20 blocks: enough to run blocks in parallel.
fn scene_with_edge(settings: &str, program: Option<Case>, edge: f64) -> Scene {
    let mut m = rectangle(
        -0.5,
        -0.5,
        1.0,
        1.0,
        edge,
        Spacing {
            jitter: 0.2,
            seed: 4,
            ..Default::default()
        },
    );
    if let Some(c) = program {
        c.program(&mut m);
    }
    Scene::build(m, Settings::from_str_with(settings, "test", &[]).unwrap()).unwrap()
}

fn pattern(sc: &Scene) -> Pattern {
    Pattern::for_scene(sc)
}

/// Random edge DOFs of amplitude 0.05 rad (empty without them).
fn angles(sc: &Scene) -> Vec<f64> {
    let mut rng = Rng::new(9);
    (0..sc.body.num_edge_dofs())
        .map(|_| 0.05 * rng.symmetric())
        .collect()
}

/// Every bending model, as a settings line.
const MODELS: [&str; 4] = [
    "bending = \"midedge_average\"",
    "bending = \"patch_fit\"",
    "bending = \"midedge_sin\"",
    "bending = \"midedge_tan\"",
];

fn bumpy(sc: &Scene) -> Vec<Vec3> {
    let mut rng = Rng::new(1);
    sc.body
        .mesh
        .positions
        .iter()
        .map(|p| {
            Vec3::new(p.x, p.y, 0.3 * (p.x * p.x - 0.5 * p.y * p.y))
                + Vec3::new(rng.symmetric(), rng.symmetric(), rng.symmetric()) * 0.01
        })
        .collect()
}

#[test]
fn rest_state_has_zero_energy_and_gradient() {
    let sc = scene("", None);
    let p = pattern(&sc);
    let pot = Potential::new(&sc, &p);
    let mut g = vec![0.0; p.n];
    let phi = vec![0.0; sc.body.num_edge_dofs()];
    let e = pot.eval(
        &sc.body.mesh.positions,
        &phi,
        Want::Gradient,
        &mut g,
        &mut [],
    );
    assert!(e.abs() < 1e-20, "E = {e}");
    assert!(g.iter().all(|v: &f64| v.abs() < 1e-12), "gradient not zero");
}

#[test]
fn assembly_is_bitwise_identical_for_any_thread_count() {
    for model in [MODELS[0], MODELS[2]] {
        bitwise_identical(model);
    }
}

/// Every registered membrane material × every bending model (from the registry, so a new one
/// is checked without being listed here): energy, gradient and Hessian bitwise identical on 1,
/// 2 and 4 threads, and finite, on a bumped unit square programmed with a spherical cap.
#[test]
fn every_registered_material_and_bending_model_is_thread_independent() {
    use shellsim::energy::registry::{BENDINGS, MATERIALS};
    for m in MATERIALS {
        for &(_, bend) in BENDINGS {
            let sc = scene_with_edge(
                &format!(
                    "[material]\n{}\n{bend}\n[rest]\ntarget = \"mesh\"\n",
                    m.example
                ),
                Some(Case::SphericalCap),
                0.1,
            );
            let p = pattern(&sc);
            // Small bumps: inside every material's domain (Gent's lock included).
            let x: Vec<Vec3> = sc
                .body
                .mesh
                .positions
                .iter()
                .zip(bumpy(&sc))
                .map(|(a, b)| a + (b - a) * 0.2)
                .collect();
            let phi = angles(&sc);
            let eval = |threads: usize| {
                pool(threads).install(|| {
                    let pot = Potential {
                        dial: 0.7,
                        ..Potential::new(&sc, &p)
                    };
                    let mut g = vec![0.0; p.n];
                    let mut h = vec![0.0; p.nnz()];
                    let e = pot.eval(&x, &phi, Want::Hessian, &mut g, &mut h);
                    assert!(e.is_finite(), "{} {bend}: energy {e}", m.example);
                    (
                        e.to_bits(),
                        g.iter().map(|v: &f64| v.to_bits()).collect::<Vec<_>>(),
                        h.iter().map(|v: &f64| v.to_bits()).collect::<Vec<_>>(),
                    )
                })
            };
            let one = eval(1);
            assert!(one == eval(2) && one == eval(4), "{} {bend}", m.example);
        }
    }
}

/// The spherical cap programmed by its mesh, with bending `model`, at edge length `edge`.
fn cap_scene(model: &str, edge: f64) -> Scene {
    scene_with_edge(
        &format!("[material]\n{model}\n[rest]\ntarget = \"mesh\"\n"),
        Some(Case::SphericalCap),
        edge,
    )
}

/// A rayon pool of `threads` threads.
fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
}

fn bitwise_identical(model: &str) {
    let sc = cap_scene(model, 0.02);
    let p = pattern(&sc);
    let x = bumpy(&sc);
    let phi = angles(&sc);
    let eval = |threads: usize| {
        pool(threads).install(|| {
            let pot = Potential {
                dial: 0.7,
                gravity: Vec3::new(0.0, 0.0, -9.81),
                ..Potential::new(&sc, &p)
            };
            let mut g = vec![0.0; p.n];
            let mut h = vec![0.0; p.nnz()];
            let e = pot.eval(&x, &phi, Want::Hessian, &mut g, &mut h);
            (
                e.to_bits(),
                g.iter().map(|v: &f64| v.to_bits()).collect::<Vec<_>>(),
                h.iter().map(|v: &f64| v.to_bits()).collect::<Vec<_>>(),
            )
        })
    };
    let one = eval(1);
    assert_eq!(one, eval(2));
    assert_eq!(one, eval(4));
}

/// The gradient-only assembly (owner-computes, one part per thread) gives the same bits for
/// any partition of the elements into parts: even ones for 1–4 threads, skewed ones installed
/// by hand (a part of one energy block, a part of nearly all, quadratically growing parts), and
/// run by a team of threads. Its energy is also the bits of the energy-only and the Hessian
/// assembly's. Patch fit (vertices only) and mid-edge (edge DOFs).
#[test]
fn gradient_is_bitwise_identical_for_any_partition() {
    for model in [MODELS[1], MODELS[2]] {
        let sc = cap_scene(model, 0.05);
        let p = pattern(&sc);
        let x = bumpy(&sc);
        let phi = angles(&sc);
        let pot = Potential {
            dial: 0.7,
            ..Potential::new(&sc, &p)
        };
        let grad = || {
            let mut g = vec![0.0; p.n];
            let e = pot.eval(&x, &phi, Want::Gradient, &mut g, &mut []);
            (
                e.to_bits(),
                g.iter().map(|v| v.to_bits()).collect::<Vec<u64>>(),
            )
        };
        let one = pool(1).install(grad);
        let mut g = vec![0.0; p.n];
        let e = pot.eval(&x, &phi, Want::Energy, &mut g, &mut []);
        assert_eq!(e.to_bits(), one.0, "{model}: energy-only assembly");
        let mut h = vec![0.0; p.nnz()];
        let e = pot.eval(&x, &phi, Want::Hessian, &mut g, &mut h);
        assert_eq!(e.to_bits(), one.0, "{model}: Hessian assembly");
        for t in [2, 3, 4] {
            let pl = pool(t);
            assert!(pl.install(grad) == one, "{model}: {t} threads, even parts");
            let team = shellsim::team::Team::new(t);
            assert!(
                pl.install(|| team.activate(grad)) == one,
                "{model}: a team of {t} threads"
            );
            let ne = p.maps.iter().map(|m| m.len()).max().unwrap();
            // Home ranges start at multiples of the energy block.
            let b = shellsim::assembly::ENERGY_BLOCK;
            let last = ne.div_ceil(b) - 1;
            let skews: Vec<Vec<usize>> = vec![
                (0..=t).map(|k| if k == t { ne } else { k * b }).collect(),
                (0..=t)
                    .map(|k| {
                        if k == 0 || k == t {
                            k / t * ne
                        } else {
                            (last - (t - k)) * b
                        }
                    })
                    .collect(),
                (0..=t)
                    .map(|k| {
                        if k == t {
                            ne
                        } else {
                            k * k * ne / (t * t) / b * b
                        }
                    })
                    .collect(),
            ];
            for cuts in &skews {
                for m in p.maps.iter().filter(|m| m.len() == ne) {
                    m.set_gradient_partition(cuts);
                }
                assert!(
                    pl.install(grad) == one,
                    "{model}: {t} threads, parts {cuts:?}"
                );
                assert!(
                    pl.install(|| team.activate(grad)) == one,
                    "{model}: a team of {t} threads, parts {cuts:?}"
                );
            }
        }
    }
}

#[test]
fn assembled_derivatives_match_finite_differences() {
    for model in MODELS {
        assembled_derivatives(model);
    }
}

fn assembled_derivatives(model: &str) {
    let sc = scene(&format!("[material]\n{model}\n[rest]\ntarget = \"mesh\"\n[constraints]\nfix_boxes = [{{ min = [-1, -1, -1], max = [-0.45, 1, 1] }}]\n"), Some(Case::Hyperboloid));
    let p = pattern(&sc);
    let x = bumpy(&sc);
    let phi = angles(&sc);
    let xhat: Vec<Vec3> = x.iter().map(|v| v * 1.01).collect();
    let a_prev = vec![shellsim::math::Sym2::new(0.01, 0.001, 0.012); sc.body.num_faces()];
    let b_prev = vec![shellsim::math::Sym2::new(0.001, 0.0, -0.001); sc.body.num_faces()];
    let pot = Potential {
        dial: 0.6,
        inertia: Some(shellsim::energy::potential::Inertia {
            inv_dt2: 1e4,
            xhat: &xhat,
            dofs_hat: &[],
        }),
        damping: Some(shellsim::energy::potential::Damping {
            eta_over_dt: 0.5,
            a_prev: &a_prev,
            b_prev: &b_prev,
        }),
        gravity: Vec3::new(0.0, 0.0, -9.81),
        ..Potential::new(&sc, &p)
    };
    check_fd(&sc, &p, &pot, &x, &phi, model, 7);
}

/// The assembled gradient and Hessian of `pot` at `(x, phi)` against central differences of
/// the assembled energy and gradient (every `stride`-th DOF), through the one checker.
fn check_fd(
    sc: &Scene,
    p: &Pattern,
    pot: &Potential,
    x: &[Vec3],
    phi: &[f64],
    label: &str,
    stride: usize,
) {
    super::terms::fd_check(
        sc,
        p,
        x,
        phi,
        label,
        stride,
        |_, h| h,
        |x, phi, want, g, h| pot.eval(x, phi, want, g, h),
    );
}

#[test]
fn ground_contact_and_friction_match_finite_differences() {
    // Half the bumpy sheet below the ground plane z = 0, penetrations on both sides of the
    // smoothing length, slips on both sides of ε.
    let sc = scene(
        "[rest]\ntarget = \"mesh\"\n[solver]\nmode = \"dynamic\"\n\
         [contact]\nenabled = true\nstiffness = 1e7\nsmoothing = 0.01\nfriction = 0.4\n\
         [constraints]\nfix_boxes = [{ min = [-1, -1, -1], max = [-0.45, 1, 1] }]\n",
        Some(Case::Hyperboloid),
    );
    let g = sc.body.ground.as_ref().unwrap();
    assert_eq!((g.stiffness, g.smoothing, g.friction), (1e7, 0.01, 0.4));
    let p = pattern(&sc);
    let x = bumpy(&sc);
    let phi = angles(&sc);
    let pen: Vec<f64> = (0..x.len()).map(|v| g.penetration(v, &x[v])).collect();
    assert!(pen.iter().any(|&q| q > 0.0 && q < 0.01) && pen.iter().any(|&q| q > 0.01));
    assert!(pen.iter().filter(|&&q| q == 0.0).count() > x.len() / 4);
    let mut rng = Rng::new(3);
    let x_prev: Vec<Vec3> = x
        .iter()
        .map(|v| v + Vec3::new(rng.symmetric(), rng.symmetric(), rng.symmetric()) * 0.004)
        .collect();
    let lambda: Vec<f64> = (0..x.len()).map(|v| 1.0 + (v % 5) as f64).collect();
    let pot = Potential {
        friction: Some(shellsim::energy::potential::Friction {
            x_prev: &x_prev,
            dial_prev: 1.0,
            normal_force: &lambda,
            x_lag: &x,
            dial_lag: 1.0,
            eps: 0.003,
        }),
        ..Potential::new(&sc, &p)
    };
    check_fd(&sc, &p, &pot, &x, &phi, "contact", 1);
    // The normal forces are k A ψ′(p): ψ′ = p²/(2δ) below δ, p − δ/2 beyond.
    let lam = g.normal_forces(&x);
    for v in 0..x.len() {
        let q = pen[v];
        let psi1 = if q <= 0.01 { q * q / 0.02 } else { q - 0.005 };
        assert!((lam[v] - 1e7 * g.area[v] * psi1).abs() <= 1e-9 * lam[v].max(1e-300));
    }
}

#[test]
fn colouring_separates_stencils() {
    let sc = scene_with_edge("", None, 0.02);
    let p = pattern(&sc);
    let mut seen = vec![usize::MAX; sc.body.num_vertices() + sc.body.num_edge_dofs()];
    let mut total = 0;
    for (c, blocks) in p.colours().iter().enumerate() {
        for (b, block) in blocks.iter().enumerate() {
            let tag = c * 100_000 + b;
            for &f in block {
                total += 1;
                let mut st: Vec<usize> = p
                    .faces()
                    .element(f)
                    .iter()
                    .copied()
                    .filter(|&v| v != usize::MAX)
                    .collect();
                st.sort_unstable();
                st.dedup();
                for v in st {
                    // A vertex may appear in several faces of one block, never in two blocks of a colour.
                    assert!(
                        seen[v] == usize::MAX || seen[v] / 100_000 != c || seen[v] == tag,
                        "colour {c}: vertex {v} shared by two blocks"
                    );
                    seen[v] = tag;
                }
            }
        }
    }
    assert_eq!(total, sc.body.num_faces());
    assert!(p.colours().iter().map(|c| c.len()).sum::<usize>() >= 16);
    assert!(p.num_colours() < 16, "{} colours", p.num_colours());
}

/// "No growth" on a curved reference mesh is stress-free for every mid-edge model at φ = 0 (the
/// reference curvature is computed in each model's own terms).
#[test]
fn curved_reference_is_at_rest_for_every_midedge_model() {
    for model in [MODELS[0], MODELS[2], MODELS[3]] {
        let mut m = rectangle(
            -0.5,
            -0.5,
            1.0,
            1.0,
            0.125,
            Spacing {
                jitter: 0.2,
                seed: 4,
                ..Default::default()
            },
        );
        for p in &mut m.positions {
            p.z = 0.3 * (p.x * p.x - 0.5 * p.y * p.y);
        }
        let sc = Scene::build(
            m,
            Settings::from_str_with(&format!("[material]\n{model}\n"), "test", &[]).unwrap(),
        )
        .unwrap();
        let p = pattern(&sc);
        let pot = Potential {
            ..Potential::new(&sc, &p)
        };
        let mut g = vec![0.0; p.n];
        let phi = vec![0.0; sc.body.num_edge_dofs()];
        let e = pot.eval(
            &sc.body.mesh.positions,
            &phi,
            Want::Gradient,
            &mut g,
            &mut [],
        );
        assert!(e.abs() < 1e-20, "{model}: E = {e}");
        assert!(
            g.iter().all(|v: &f64| v.abs() < 1e-12),
            "{model}: gradient not zero"
        );
    }
}

/// The explicit step fused into the gradient's parts gives the bits of the unfused step
/// (gradient, then update), over many steps, for 1–3 threads and skewed parts: on a free cap
/// (pinned DOFs) and on a clamped one with a vertex in no face (advanced by the caller).
#[test]
fn fused_explicit_step_gives_the_unfused_bits() {
    use shellsim::integrate::explicit::Step;
    let free = cap_scene(MODELS[1], 0.05);
    let clamped = {
        let settings = format!(
            "[material]\n{}\n[rest]\ntarget = \"mesh\"\n[[constraints.clamp]]\n\
             inside = {{ min = [-1, -1, -1], max = [-0.3, 1, 1] }}\n",
            MODELS[1]
        );
        let mut m = rectangle(-0.5, -0.5, 1.0, 1.0, 0.05, Spacing::default());
        Case::SphericalCap.program(&mut m);
        m.positions.push(Vec3::new(2.0, 2.0, 0.0));
        Scene::build(m, Settings::from_str_with(&settings, "test", &[]).unwrap()).unwrap()
    };
    assert!(!free.body.pinned_dofs.is_empty());
    assert!(clamped.node_fixed.iter().any(|&f| f));
    for sc in [&free, &clamped] {
        let p = pattern(sc);
        let pot = Potential::new(sc, &p);
        let inv_m: Vec<f64> = (0..sc.body.num_vertices())
            .map(|v| {
                if sc.node_fixed[v] {
                    0.0
                } else {
                    1.0 / sc.body.mass[v].max(1e-12)
                }
            })
            .collect();
        let x0 = bumpy(sc);
        let v0: Vec<Vec3> = (0..x0.len())
            .map(|i| Vec3::new(0.0, 0.0, 0.01 * (1 + i % 3) as f64))
            .collect();
        // dt well inside the stability limit of this mesh, drag 1/s: the sheet moves. An odd
        // number of steps, so that a vertex the fused step skipped shows in the swapped buffer.
        let run = |fuse: bool| {
            let mut step = Step::new(&pot, fuse);
            assert_eq!(step.fused(), fuse);
            let (mut x, mut v, mut g) = (x0.clone(), v0.clone(), vec![0.0; p.n]);
            for _ in 0..41 {
                step.take(&pot, &mut x, &mut v, &mut g, &inv_m, 1.0, 1e-4);
            }
            let bits = |a: &[Vec3]| {
                a.iter()
                    .flat_map(|p| p.iter().map(|c| c.to_bits()))
                    .collect::<Vec<u64>>()
            };
            (bits(&x), bits(&v), x)
        };
        let (xs, vs, x) = pool(1).install(|| run(false));
        let moved = x
            .iter()
            .zip(&x0)
            .map(|(a, b)| (a - b).norm())
            .fold(0.0, f64::max);
        assert!(moved > 1e-4, "the sheet must move: {moved}");
        assert!(pool(1).install(|| run(true)) == (xs.clone(), vs.clone(), x.clone()));
        for t in [2, 3] {
            let team = shellsim::team::Team::new(t);
            let pl = pool(t);
            assert!(
                pl.install(|| team.activate(|| run(true))) == (xs.clone(), vs.clone(), x.clone()),
                "team of {t}"
            );
            let b = shellsim::assembly::ENERGY_BLOCK;
            let ne = p.maps[0].len();
            let cuts: Vec<usize> = (0..=t).map(|k| if k == t { ne } else { k * b }).collect();
            p.maps[0].set_gradient_partition(&cuts);
            assert!(
                pl.install(|| team.activate(|| run(true))) == (xs.clone(), vs.clone(), x.clone()),
                "team of {t}, parts {cuts:?}"
            );
        }
    }
    // An energy-only assembly does not call the hook; a gradient calls it once per part and
    // leaves the gradient vector alone.
    let p = pattern(&free);
    let x = bumpy(&free);
    let mut g = vec![0.0; p.n];
    let calls = std::sync::atomic::AtomicUsize::new(0);
    let hook = |_: &[u32], _: &[f64], _: &[bool]| {
        calls.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    };
    let pot = Potential {
        owned: Some(&hook),
        ..Potential::new(&free, &p)
    };
    pot.eval(&x, &[], Want::Energy, &mut g, &mut []);
    assert_eq!(calls.load(std::sync::atomic::Ordering::Relaxed), 0);
    pool(2).install(|| pot.eval(&x, &[], Want::Gradient, &mut g, &mut []));
    assert_eq!(
        calls.load(std::sync::atomic::Ordering::Relaxed),
        2,
        "one call per part"
    );
    assert!(
        g.iter().all(|v| *v == 0.0),
        "the gradient vector was written"
    );
}

/// The skew vertices' projection on the stored lower triangle equals the dense
/// `T H T + s (I − P)` (T block diagonal: P at skew vertices, I elsewhere) to round-off, on a
/// pattern with vertex and scalar nodes, one skew vertex held along one direction and one along
/// two, and random symmetric values.
#[test]
fn skew_projection_matches_the_dense_product() {
    use shellsim::elements::Stencil;
    use shellsim::math::Mat3;
    let nv = 5;
    let x: Vec<Vec3> = (0..nv).map(|i| Vec3::new(i as f64, 0.0, 0.0)).collect();
    // Vertex triangles with one scalar node each (nodes 5, 6), and a vertex pair.
    let st = Stencil {
        slot_dofs: vec![3, 3, 3, 1],
        nodes: vec![0, 1, 2, 5, 1, 3, 4, 6],
        anchors: vec![x[1], x[3]],
    };
    let pair = Stencil {
        slot_dofs: vec![3, 3],
        nodes: vec![0, 4],
        anchors: vec![x[2]],
    };
    let mut p = Pattern::build(&x, 2, &[st, pair]);
    let n = p.n;
    let mut rng = Rng::new(7);
    let mut dense = vec![vec![0.0; n]; n];
    let mut values = vec![0.0; p.nnz()];
    for c in 0..n {
        for k in p.col_ptr[c]..p.col_ptr[c + 1] {
            let r = p.row_idx[k];
            values[k] = rng.symmetric();
            dense[r][c] = values[k];
            dense[c][r] = values[k];
        }
    }
    let unit = |v: Vec3| v.normalize();
    let a = unit(Vec3::new(1.0, 2.0, -0.5));
    let (b1, b2) = (
        unit(Vec3::new(0.3, -1.0, 0.2)),
        unit(Vec3::new(0.0, 0.2, 1.0)),
    );
    let b2 = unit(b2 - b1 * b1.dot(&b2));
    let proj = |v: usize| match v {
        1 => Some(Mat3::identity() - a * a.transpose()),
        3 => Some(Mat3::identity() - b1 * b1.transpose() - b2 * b2.transpose()),
        _ => None,
    };
    p.pin_skew(&[1, 3]);
    let scale = 2.5;
    p.project_skew(&mut values, &proj, scale);
    // Dense T H T + s (I − P).
    let mut t = vec![vec![0.0; n]; n];
    for (i, row) in t.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    for v in [1, 3] {
        let pv = proj(v).unwrap();
        for i in 0..3 {
            for j in 0..3 {
                t[3 * v + i][3 * v + j] = pv[(i, j)];
            }
        }
    }
    let mul = |a: &Vec<Vec<f64>>, b: &Vec<Vec<f64>>| {
        (0..n)
            .map(|i| {
                (0..n)
                    .map(|j| (0..n).map(|k| a[i][k] * b[k][j]).sum())
                    .collect()
            })
            .collect::<Vec<Vec<f64>>>()
    };
    let mut want = mul(&mul(&t, &dense), &t);
    for v in [1, 3] {
        let pv = proj(v).unwrap();
        for i in 0..3 {
            for j in 0..3 {
                want[3 * v + i][3 * v + j] += scale * (Mat3::identity() - pv)[(i, j)];
            }
        }
    }
    let mut worst: f64 = 0.0;
    for c in 0..n {
        for k in p.col_ptr[c]..p.col_ptr[c + 1] {
            worst = worst.max((values[k] - want[p.row_idx[k]][c]).abs());
        }
    }
    assert!(worst < 1e-14, "{worst:e}");
    // The held directions decouple: a held direction's row of T H T + s(I − P) is s times it.
    let row: f64 = (0..n)
        .map(|j| {
            let e: f64 = (0..3).map(|i| a[i] * want[3 + i][j]).sum();
            let expect = if (3..6).contains(&j) {
                scale * a[j - 3]
            } else {
                0.0
            };
            (e - expect).abs()
        })
        .fold(0.0, f64::max);
    assert!(row < 1e-14, "{row:e}");
}

/// The best 2-thread speed-up the colouring allows: each colour runs its blocks in parallel and
/// waits for its largest, so a colour of total work `T` and largest block `B` takes at least
/// `max(B, T/2)` (work counted in elements).
fn two_thread_bound(colours: &[Vec<Vec<usize>>]) -> f64 {
    let (mut serial, mut parallel) = (0usize, 0.0f64);
    for blocks in colours {
        let total: usize = blocks.iter().map(Vec::len).sum();
        let largest = blocks.iter().map(Vec::len).max().unwrap_or(0);
        serial += total;
        parallel += (largest as f64).max(total as f64 / 2.0);
    }
    serial as f64 / parallel
}

/// A small, long mesh still assembles on both cores: the paper walker's 60 × 8 mm strip of 960
/// faces (fixed blocks of 256 faces gave it 4 blocks, one per colour, and a bound of 1.0), and
/// a 5000-face square. The bound is what the colouring permits; the walker's measured
/// assembly speed-up is in docs/speed.md.
#[test]
fn small_meshes_colour_into_enough_blocks_for_two_threads() {
    let strip = shellsim::mesh::io::read_mesh(std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/meshes/paper_walker.vtk"
    )))
    .unwrap();
    let sc = Scene::build(strip, Settings::from_str_with("", "test", &[]).unwrap()).unwrap();
    let p = pattern(&sc);
    let bound = two_thread_bound(p.colours());
    assert!(bound >= 1.8, "walker strip: 2-thread bound {bound:.2}");
    let sc = scene_with_edge("", None, 0.02);
    let bound = two_thread_bound(pattern(&sc).colours());
    assert!(bound >= 1.9, "5000-face square: 2-thread bound {bound:.2}");
}
