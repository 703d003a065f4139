//! Criterion benches: the shell kernels per face (mid-edge average, edge-DOF sin, patch fit),
//! assembly of ~100k faces on 1 and 2 threads, and one Newton iteration (assemble + numeric
//! Cholesky + solve) on ~5k and ~20k-face meshes for every bending model, with the assembly and
//! the factorisation also timed apart; the moisture step; and a balloon frame at the size of
//! seed 002's Table 1 (`balloon`); self-contact between two sheets pressed together
//! (`self_contact`, at about 5k, 20k and 80k faces: the term's Hessian per pressing pair, the
//! gathering of the pairs, the CCD step bound, and one Newton iteration of the same scene).

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use shellsim::assembly::{Pattern, Want};
use shellsim::energy::Potential;
use shellsim::energy::{material::sv_matrix, shell_face, KoiterDensity, Lame2d};
use shellsim::math::{SMat, SVec, Sym2, Vec3};
use shellsim::mesh::generate::{rectangle, Rng, Spacing};
use shellsim::model::Scene;
use shellsim::settings::Settings;
use shellsim::solve::LinearSolver;
use std::hint::black_box;

#[path = "common/scene.rs"]
mod scene;
use scene::{curved, scene_with_material};

fn patch() -> ([Vec3; 6], KoiterDensity) {
    let mut rng = Rng::new(3);
    let base = [
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.3, 0.9, 0.0),
        Vec3::new(1.2, 1.0, 0.0),
        Vec3::new(-0.6, 0.5, 0.0),
        Vec3::new(0.5, -0.8, 0.0),
    ];
    let x = base.map(|p| p + Vec3::new(rng.symmetric(), rng.symmetric(), rng.symmetric()) * 0.2);
    let abar = Sym2::new(1.1, 0.05, 0.9);
    let (ws, wb) = KoiterDensity::weights(&abar, 0.01, 1.0);
    let d = KoiterDensity {
        c: sv_matrix(&abar, Lame2d::from_young_poisson(1e6, 0.3)),
        stretch: [(ws, abar), (0.0, Sym2::zeros())],
        bend: [(wb, Sym2::new(0.3, 0.0, -0.2)), (0.0, Sym2::zeros())],
        stiffen: 0.0,
    };
    (x, d)
}

fn kernel(c: &mut Criterion) {
    let (x, d) = patch();
    let mut g = c.benchmark_group("kernel");
    g.throughput(Throughput::Elements(1));
    g.bench_function("energy", |b| {
        b.iter(|| shell_face(black_box(&x), [true; 3], &d, None, None))
    });
    g.bench_function("energy+gradient", |b| {
        let mut gr = SVec::<18>::zeros();
        b.iter(|| shell_face(black_box(&x), [true; 3], &d, Some(&mut gr), None))
    });
    g.bench_function("energy+gradient+hessian", |b| {
        let mut gr = SVec::<18>::zeros();
        let mut h = SMat::<18, 18>::zeros();
        b.iter(|| shell_face(black_box(&x), [true; 3], &d, Some(&mut gr), Some(&mut h)))
    });
    {
        use shellsim::energy::midedge_angle::{midedge_angle_face, AngleVariant};
        let phi = [0.01, -0.02, 0.03];
        let sigma = [1.0, -1.0, 1.0];
        g.bench_function("midedge_sin/energy", |b| {
            b.iter(|| {
                midedge_angle_face::<_, false>(
                    black_box(&x),
                    [true; 3],
                    &phi,
                    sigma,
                    AngleVariant::Sin,
                    &d,
                    None,
                    None,
                )
            })
        });
        g.bench_function("midedge_sin/energy+gradient+hessian", |b| {
            let mut gr = SVec::<21>::zeros();
            let mut h = SMat::<21, 21>::zeros();
            b.iter(|| {
                midedge_angle_face::<_, false>(
                    black_box(&x),
                    [true; 3],
                    &phi,
                    sigma,
                    AngleVariant::Sin,
                    &d,
                    Some(&mut gr),
                    Some(&mut h),
                )
            })
        });
    }
    {
        // Seed 003's Baraff–Witkin membrane with no bending (9 DOFs), stretched past s = 1.
        use shellsim::energy::bending::none::NoBending;
        use shellsim::energy::membrane::baraff_witkin::BaraffWitkinFace;
        use shellsim::energy::membrane::WithKoiterBending;
        use shellsim::energy::shell::shell_element;
        let law = BaraffWitkinFace::new(
            &Sym2::new(1.1, 0.05, 0.9),
            &shellsim::math::Vec2::new(1.0, 0.2),
            0.01,
            5e5,
            2e5,
            100.0,
        );
        let dens = WithKoiterBending {
            law,
            koiter: KoiterDensity {
                stretch: [(0.0, Sym2::zeros()); 2],
                bend: [(0.0, Sym2::zeros()); 2],
                ..d
            },
        };
        let xs = [x[0] * 1.05, x[1] * 1.05, x[2], x[0], x[0], x[0]];
        for (name, gn) in [
            ("baraff_witkin/energy+gradient+hessian", false),
            ("baraff_witkin/psd", true),
        ] {
            g.bench_function(name, |b| {
                let mut gr = SVec::<9>::zeros();
                let mut h = SMat::<9, 9>::zeros();
                b.iter(|| {
                    if gn {
                        shell_element::<_, NoBending, 9, 3, true>(
                            &NoBending,
                            &(),
                            black_box(&xs),
                            &dens,
                            Some(&mut gr),
                            Some(&mut h),
                        )
                    } else {
                        shell_element::<_, NoBending, 9, 3, false>(
                            &NoBending,
                            &(),
                            black_box(&xs),
                            &dens,
                            Some(&mut gr),
                            Some(&mut h),
                        )
                    }
                })
            });
        }
    }
    g.finish();
}

fn scene(edge: f64) -> Scene {
    scene_with(edge, "midedge_average")
}

fn scene_with(edge: f64, model: &str) -> Scene {
    scene_with_material(edge, model, "koiter")
}

fn potential<'a>(sc: &'a Scene, p: &'a Pattern) -> Potential<'a> {
    Potential {
        ..Potential::new(sc, p)
    }
}

/// The Hessian assembly of `sc` at `(x, phi)` on 1 and 2 threads, as `name/threads`.
fn bench_hessian(
    g: &mut criterion::BenchmarkGroup<criterion::measurement::WallTime>,
    name: &str,
    sc: &Scene,
    x: &[Vec3],
    phi: &[f64],
) {
    let p = Pattern::for_scene(sc);
    bench_hessian_pot(g, name, &potential(sc, &p), x, phi);
}

fn assembly(c: &mut Criterion) {
    // 224² cells × 2 ≈ 100k faces.
    let sc = scene(1.0 / 224.0);
    let p = Pattern::for_scene(&sc);
    let x = curved(&sc);
    let mut g = c.benchmark_group("assembly_100k");
    g.sample_size(10);
    g.throughput(Throughput::Elements(sc.body.num_faces() as u64));
    for threads in [1usize, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        g.bench_with_input(BenchmarkId::new("energy", threads), &threads, |b, _| {
            let pot = potential(&sc, &p);
            b.iter(|| pool.install(|| pot.eval(&x, &[], Want::Energy, &mut [], &mut [])))
        });
        g.bench_with_input(BenchmarkId::new("gradient", threads), &threads, |b, _| {
            let pot = potential(&sc, &p);
            let mut gr = vec![0.0; p.n];
            b.iter(|| pool.install(|| pot.eval(&x, &[], Want::Gradient, &mut gr, &mut [])))
        });
        g.bench_with_input(
            BenchmarkId::new("kernels_only", threads),
            &threads,
            |b, _| {
                use rayon::prelude::*;
                let pot = potential(&sc, &p);
                b.iter(|| {
                    pool.install(|| {
                        (0..sc.body.num_faces())
                            .into_par_iter()
                            .map(|f| {
                                let st = p.faces().element(f);
                                let has = [
                                    st[3] != usize::MAX,
                                    st[4] != usize::MAX,
                                    st[5] != usize::MAX,
                                ];
                                let xs: [Vec3; 6] = std::array::from_fn(|s| {
                                    if st[s] == usize::MAX {
                                        x[st[0]]
                                    } else {
                                        x[st[s]]
                                    }
                                });
                                let mut gr = SVec::<18>::zeros();
                                let mut h = SMat::<18, 18>::zeros();
                                shell_face(&xs, has, &pot.density(f), Some(&mut gr), Some(&mut h));
                                h[(0, 0)] + gr[0]
                            })
                            .sum::<f64>()
                    })
                })
            },
        );
        g.bench_with_input(BenchmarkId::new("hessian", threads), &threads, |b, _| {
            let pot = potential(&sc, &p);
            let mut gr = vec![0.0; p.n];
            let mut h = vec![0.0; p.nnz()];
            b.iter(|| pool.install(|| pot.eval(&x, &[], Want::Hessian, &mut gr, &mut h)))
        });
    }
    // The same Hessian assembly with edge DOFs (the default bending model).
    let sc = scene_with(1.0 / 224.0, "midedge_sin");
    let phi = vec![0.0; sc.body.num_edge_dofs()];
    bench_hessian(&mut g, "midedge_sin_hessian", &sc, &x, &phi);
    // A membrane-only (no bending) Baraff–Witkin sheet of the same size.
    let sc = scene_with_material(1.0 / 224.0, "none", "baraff_witkin");
    bench_hessian(&mut g, "baraff_witkin_membrane_hessian", &sc, &x, &[]);
    g.finish();
}

fn newton_iteration(c: &mut Criterion) {
    let mut g = c.benchmark_group("newton_iteration");
    g.sample_size(10);
    for model in ["midedge_average", "midedge_sin", "patch_fit"] {
        for edge in [1.0 / 50.0, 1.0 / 100.0] {
            let sc = scene_with(edge, model);
            let p = Pattern::for_scene(&sc);
            let x = curved(&sc);
            let phi = vec![0.0; sc.body.num_edge_dofs()];
            let mut lin = LinearSolver::new(&p).unwrap();
            let pot = potential(&sc, &p);
            let mut gr = vec![0.0; p.n];
            let mut h = vec![0.0; p.nnz()];
            let nf = sc.body.num_faces();
            g.bench_function(BenchmarkId::new(format!("{model}/total"), nf), |b| {
                b.iter(|| {
                    pot.eval(&x, &phi, Want::Hessian, &mut gr, &mut h);
                    for i in 0..p.n {
                        h[p.diag(i)] += 1e-6;
                    }
                    lin.factor(&h).unwrap();
                    let mut rhs = gr.clone();
                    lin.solve_in_place(&mut rhs);
                    black_box(rhs[0])
                })
            });
            g.bench_function(BenchmarkId::new(format!("{model}/assembly"), nf), |b| {
                b.iter(|| pot.eval(&x, &phi, Want::Hessian, &mut gr, &mut h))
            });
            g.bench_function(BenchmarkId::new(format!("{model}/factor"), nf), |b| {
                pot.eval(&x, &phi, Want::Hessian, &mut gr, &mut h);
                for i in 0..p.n {
                    h[p.diag(i)] += 1e-6;
                }
                b.iter(|| lin.factor(black_box(&h)).unwrap())
            });
        }
    }
    g.finish();
}

/// One moisture-diffusion step (the default layering, 5k faces; the factorisations are cached)
/// plus the rest forms of every face from the new surface moisture: the extra cost of a coupled
/// time step, to set against `newton_iteration` on the same mesh.
fn moisture_step(c: &mut Criterion) {
    use shellsim::diffusion::{Diffusion, Diffusivity, Layering, Side, SurfaceBc, Tolerance};
    let mut g = c.benchmark_group("moisture_step");
    g.sample_size(20);
    let sc = scene(1.0 / 50.0);
    let nf = sc.body.num_faces();
    let dirs = vec![Vec3::new(1.0, 0.0, 0.0); nf];
    let d = Diffusivity {
        along: 1e-9,
        across: 5e-10,
        through: 1e-9,
    };
    let mut diff = Diffusion::new(
        &sc.body.mesh.positions,
        &sc.body.mesh.faces,
        &sc.body.thickness,
        &dirs,
        d,
        Layering {
            count: shellsim::settings::Moisture::default().layers,
            grading: shellsim::settings::Moisture::default().grading,
        },
    )
    .unwrap();
    for f in 0..nf {
        diff.set_surface(f, Side::Top, SurfaceBc::Value(0.2))
            .unwrap();
    }
    let mut u = vec![0.0; diff.num_nodes()];
    g.bench_function(BenchmarkId::new("diffuse", nf), |b| {
        let tol = Tolerance {
            rtol: 1e-3,
            atol: 2e-7,
        };
        b.iter(|| diff.advance(black_box(&mut u), 0.05, tol).unwrap())
    });
    g.bench_function(BenchmarkId::new("rest_forms", nf), |b| {
        b.iter(|| {
            (0..nf)
                .map(|f| {
                    let (mt, mb) = diff.surface_moisture(&u, f);
                    let r = shellsim::rest::laws::linear_swelling::linear_swelling(
                        &sc.body.rest.abar0[f],
                        &sc.body.rest.bbar0[f],
                        sc.body.thickness[f],
                        mt,
                        mb,
                        0.01,
                    );
                    r.0[0] + r.1[0]
                })
                .sum::<f64>()
        })
    });
    g.finish();
}

/// The whole coupled loop (moisture and mechanics): the first 0.2 s of the wetted paper strip
/// (settings/paper_strip_cd.toml, 1 200 faces, edge DOFs; Δt ≤ 0.05 s, cut by
/// `moisture.max_change` to about 16 steps): diffusion, rest forms, moisture masses and the
/// Newton solve, on 1 and 2 threads. The summary's `moisture_seconds` splits the
/// step into its diffusion and mechanics parts; the ratio is printed once per thread count.
fn coupled_step(c: &mut Criterion) {
    let mut g = c.benchmark_group("coupled_step");
    g.sample_size(10);
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/settings/paper_strip_cd.toml"
    ))
    .unwrap();
    let overrides: Vec<String> = [
        "time.end=0.2",
        "time.dt=0.05",
        "time.dt_max=0.05",
        "time.output_interval=0.2",
        "output.format=\"vtu\"",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let settings = Settings::from_str_with(&text, "paper_strip_cd", &overrides).unwrap();
    let mesh = rectangle(-0.03, -0.005, 0.06, 0.01, 0.001, Spacing::default());
    let sc = Scene::build(mesh, settings).unwrap();
    let dir = tempfile::tempdir().unwrap();
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let once = || {
            let mut w = shellsim::output::Writer::new(dir.path(), &sc, true).unwrap();
            shellsim::integrate::run(&sc, &mut w, &mut shellsim::integrate::Quiet, threads, None)
                .unwrap()
        };
        let s = pool.install(once);
        eprintln!(
            "coupled_step {threads} thread(s): {} faces, {} steps, {} Newton iterations; \
             diffusion + rest forms {:.1} of {:.1} ms ({:.1}%), coupled / mechanics = {:.3}",
            s.faces,
            s.steps,
            s.newton_iterations,
            1e3 * s.moisture_seconds,
            1e3 * s.wall_seconds,
            100.0 * s.moisture_seconds / s.wall_seconds,
            s.wall_seconds / (s.wall_seconds - s.moisture_seconds)
        );
        g.bench_function(BenchmarkId::new("paper_strip_0.2s", threads), |b| {
            b.iter(|| pool.install(once))
        });
    }
    g.finish();
}

/// The balloon of seed 002's Table 1 size: the teddy of `settings/balloon_teddy.toml` at
/// 11,562 vertices (the seed's is 11,090), its prism membrane (neo-Hookean, incompressible
/// thickness) and its gas, one implicit step of 1/30 s at a state inflated by 20%: the prism
/// kernel per face, the Hessian assembly on 1 and 2 threads, the factorisation, the rank-one
/// part (the gas's `∇V` and its Sherman–Morrison preparation: one extra solve), one Newton
/// iteration, and one frame (an implicit step of at most 3 Newton iterations).
fn balloon(c: &mut Criterion) {
    use shellsim::energy::potential::Inertia;
    use shellsim::solve::{newton, NewtonOptions, State};
    let mesh = shellsim::mesh::surfaces::closed_shape("teddy", 0.05, 0.0026).unwrap();
    let settings = Settings::from_str_with(
        "[material]\nmodel = \"prism\"\nbending = \"none\"\nyoung = 1e6\npoisson = 0.5\n\
         thickness = 2e-4\nprism = { law = \"neo_hookean\" }\n[gas]\ncontrol = \"amount\"\n\
         amount = 4.1\n[solver]\nmode = \"dynamic\"\n",
        "bench",
        &[],
    )
    .unwrap();
    let sc = Scene::build(mesh, settings).unwrap();
    let p = Pattern::for_scene(&sc);
    let x: Vec<Vec3> = sc.body.mesh.positions.iter().map(|q| q * 1.2).collect();
    let xhat = x.clone();
    let pot = Potential {
        dial: 0.5,
        inertia: Some(Inertia {
            inv_dt2: 900.0,
            xhat: &xhat,
            dofs_hat: &[],
        }),
        ..Potential::new(&sc, &p)
    };
    let nf = sc.body.num_faces();
    let mut g = c.benchmark_group("balloon_teddy");
    g.sample_size(10);
    g.bench_function("prism_kernel_per_face", |b| {
        use shellsim::energy::membrane::prism::PrismFace;
        use shellsim::energy::membrane::MembraneLaw;
        use shellsim::settings::PrismLaw;
        let abar = Sym2::new(1.0, 0.3, 0.9);
        let face = PrismFace::new(PrismLaw::NeoHookean, &abar, 2e-4, 1e6, 0.5, None, 1.0);
        let a = Sym2::new(1.5, 0.4, 1.3);
        let (mut ga, mut haa) = (Sym2::zeros(), shellsim::math::Mat3::zeros());
        b.iter(|| face.eval(black_box(&a), Some((&mut ga, &mut haa))))
    });
    bench_hessian_pot(&mut g, &format!("hessian_{nf}_faces"), &pot, &x, &[]);
    let mut gr = vec![0.0; p.n];
    let mut h = vec![0.0; p.nnz()];
    pot.eval(&x, &[], Want::Hessian, &mut gr, &mut h);
    let mut lin = LinearSolver::new(&p).unwrap();
    println!(
        "balloon: {} vertices, {nf} faces, {} DOFs, factor non-zeros {}",
        sc.body.num_vertices(),
        p.n,
        lin.factor_nnz()
    );
    g.bench_function("factorisation", |b| {
        b.iter(|| lin.factor(black_box(&h)).unwrap())
    });
    lin.factor(&h).unwrap();
    g.bench_function("solve", |b| {
        b.iter(|| {
            let mut r = gr.clone();
            lin.solve_in_place(&mut r);
            black_box(r[0])
        })
    });
    g.bench_function("rank_one", |b| {
        b.iter(|| {
            let lr = pot.low_rank(&x, &[]);
            let wb = shellsim::solve::low_rank::Woodbury::new(&mut lin, &lr);
            let mut r = gr.clone();
            wb.solve_in_place(&mut lin, &mut r);
            black_box(r[0])
        })
    });
    g.bench_function("newton_iteration", |b| {
        b.iter(|| {
            pot.eval(&x, &[], Want::Hessian, &mut gr, &mut h);
            lin.factor(&h).unwrap();
            let lr = pot.low_rank(&x, &[]);
            let wb = shellsim::solve::low_rank::Woodbury::new(&mut lin, &lr);
            let mut r = gr.clone();
            wb.solve_in_place(&mut lin, &mut r);
            black_box(r[0])
        })
    });
    let mut ws = shellsim::solve::newton::Workspace::new(&p);
    for threads in [1usize, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        g.bench_with_input(BenchmarkId::new("frame", threads), &threads, |b, _| {
            b.iter(|| {
                pool.install(|| {
                    let mut st = State {
                        x: x.clone(),
                        dofs: Vec::new(),
                        terms: sc.initial_states.clone(),
                    };
                    let opts = NewtonOptions {
                        max_iter: 3,
                        ..NewtonOptions::default()
                    };
                    black_box(newton(&pot, &mut lin, &mut ws, &mut st, opts).iterations)
                })
            })
        });
    }
    g.finish();
}

/// The Hessian assembly of a potential at `(x, phi)` on 1 and 2 threads, as `name/threads`.
fn bench_hessian_pot(
    g: &mut criterion::BenchmarkGroup<criterion::measurement::WallTime>,
    name: &str,
    pot: &Potential,
    x: &[Vec3],
    phi: &[f64],
) {
    for threads in [1usize, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        g.bench_with_input(BenchmarkId::new(name, threads), &threads, |b, _| {
            let mut gr = vec![0.0; pot.pattern.n];
            let mut h = vec![0.0; pot.pattern.nnz()];
            b.iter(|| pool.install(|| pot.eval(x, phi, Want::Hessian, &mut gr, &mut h)))
        });
    }
}

/// One explicit step (gradient + symplectic Euler update, fused as the driver runs it) of
/// MorphoShell's GCM cone with the patch fit, at the sizes MorphoShell was timed at (743–2060
/// triangles) and at ~8.6k, on 1 and 2 threads:
/// per step while the forms are dialled (densities recomputed) and while waiting (densities
/// computed once). Report: time per step / faces = µs per triangle-step.
fn explicit_step(c: &mut Criterion) {
    use shellsim::integrate::explicit::Step;
    for edge in [0.085, 0.05, 0.025] {
        let mut mesh = shellsim::mesh::generate::annulus(
            1.0,
            1.4,
            shellsim::cases::gcm_cone_sweep(),
            edge,
            Spacing::default(),
        );
        shellsim::cases::Case::GcmCone.program(&mut mesh);
        let settings = shellsim::settings::Settings::from_str_with(
            "[material]\nyoung = 3.0\npoisson = 0.5\ndensity = 1.0\nthickness = 0.01\n\
             bending = \"patch_fit\"\n[rest]\ntarget = \"mesh\"\n[solver]\nmode = \"explicit\"\n",
            "bench",
            &[],
        )
        .unwrap();
        let sc = Scene::build(mesh, settings).unwrap();
        let p = Pattern::for_scene(&sc);
        let nf = sc.body.num_faces();
        let mut g = c.benchmark_group(format!("explicit_step_{nf}"));
        g.throughput(Throughput::Elements(nf as u64));
        let inv_m: Vec<f64> = sc.body.mass.iter().map(|m| 1.0 / m).collect();
        let x0 = curved(&sc);
        let frozen: Vec<KoiterDensity> = {
            let pot = Potential::new(&sc, &p);
            (0..nf).map(|f| pot.density(f)).collect()
        };
        for threads in [1usize, 2] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            for (name, fr) in [("dialling", None), ("waiting", Some(&frozen[..]))] {
                g.bench_with_input(BenchmarkId::new(name, threads), &threads, |b, _| {
                    let pot = Potential {
                        dial: if fr.is_some() { 1.0 } else { 0.5 },
                        frozen: fr,
                        ..Potential::new(&sc, &p)
                    };
                    let mut x = x0.clone();
                    let mut v = vec![Vec3::zeros(); x.len()];
                    let mut gr = vec![0.0; p.n];
                    // The whole loop runs inside the pool with a team of as many threads, as
                    // a run does (`cli` installs the pool once, the explicit driver starts
                    // the team): the per-step cost includes no hand-off into either.
                    pool.install(|| {
                        let team = shellsim::team::Team::new(threads);
                        team.activate(|| {
                            let mut step = Step::new(&pot, true);
                            b.iter(|| step.take(&pot, &mut x, &mut v, &mut gr, &inv_m, 1e-3, 1e-9))
                        })
                    })
                });
            }
        }
    }
}

/// Writing one frame of a ~100k-face sheet (the benchmark square on the unit sphere, every
/// field a run writes, in double): shellsim's writer in its variants. Prints bytes per face of
/// each. Report: ms per frame and bytes per face.
fn frame_write(c: &mut Criterion) {
    use shellsim::mesh::io::{mesh_to_bytes_with, Format};
    use shellsim::mesh::vtu::{Compression, Encoding, VtuOptions};
    let sc = scene::scene_with_material(0.0048, "midedge_sin", "koiter");
    let p = Pattern::for_scene(&sc);
    let pot = Potential::new(&sc, &p);
    let state = shellsim::solve::State {
        x: curved(&sc),
        dofs: vec![0.0; p.n - 3 * sc.body.num_vertices()],
        terms: sc.initial_states.clone(),
    };
    let v = vec![Vec3::new(1e-3, -2e-3, 5e-4); sc.body.num_vertices()];
    // One real frame, every field in double, read back: the mesh the variants write.
    let dir = tempfile::tempdir().unwrap();
    let mut s2 = sc.settings.clone();
    s2.output.precision = shellsim::settings::Precision::Double;
    s2.output.fields = vec!["all".into()];
    let sc2 = Scene::build(sc.body.mesh.clone(), s2).unwrap();
    let mut w = shellsim::output::Writer::new(dir.path(), &sc2, true).unwrap();
    let pot2 = Potential::new(&sc2, &p);
    w.frame(&pot2, &state, &v, Default::default(), None::<&()>)
        .unwrap();
    let frame = shellsim::mesh::io::read_mesh(&dir.path().join("frame_00000.vtu")).unwrap();
    let nf = frame.faces.len();
    let restart = ["velocity", "edge_angles", "displacement"];
    let single = |n: &str| !restart.contains(&n);
    let out = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("target/frame_write");
    let mut g = c.benchmark_group(format!("frame_write_{nf}"));
    g.sample_size(10);
    let variants = [
        (
            "zlib_appended_single",
            Compression::Zlib,
            Encoding::Appended,
            true,
        ),
        (
            "zlib_appended_double",
            Compression::Zlib,
            Encoding::Appended,
            false,
        ),
        (
            "lz4_appended_single",
            Compression::Lz4,
            Encoding::Appended,
            true,
        ),
        (
            "none_appended_single",
            Compression::None,
            Encoding::Appended,
            true,
        ),
        (
            "zlib_base64_single",
            Compression::Zlib,
            Encoding::Base64,
            true,
        ),
    ];
    for (name, compression, encoding, sp) in variants {
        let o = VtuOptions {
            compression,
            encoding,
        };
        let f = |n: &str| sp && single(n);
        let bytes = mesh_to_bytes_with(&frame, Format::Vtu, "", &o, &f);
        eprintln!("{name}: {:.1} bytes/face", bytes.len() as f64 / nf as f64);
        // Kept for `scripts/vtk_read_time.py` (VTK's read time of each variant).
        let _ = std::fs::create_dir_all(&out);
        let _ = std::fs::write(out.join(format!("{name}.vtu")), &bytes);
        g.bench_function(name, |b| {
            b.iter(|| black_box(mesh_to_bytes_with(&frame, Format::Vtu, "", &o, &f)))
        });
    }
    let _ = pot;
}

/// Two square sheets of side 1 (h = 2 mm, edges `edge`), the upper one `gap` above the lower
/// at the evaluated state and 1.5 offsets above in the reference mesh; the scene, the pattern
/// with the pairs gathered at that state, and the state.
fn two_sheets(edge: f64, gap: f64) -> (Scene, Pattern, Vec<Vec3>) {
    let h = 0.002;
    let mut mesh = shellsim::mesh::Mesh::default();
    for (k, z) in [(0u64, 0.0), (1, 1.5 * h)] {
        let m = rectangle(
            0.0,
            0.0,
            1.0,
            1.0,
            edge,
            Spacing {
                jitter: 0.2,
                seed: 3 + k,
                ..Default::default()
            },
        );
        let base = mesh.positions.len();
        mesh.positions
            .extend(m.positions.iter().map(|p| Vec3::new(p.x, p.y, z)));
        mesh.faces.extend(
            m.faces
                .iter()
                .map(|f| [f[0] + base, f[1] + base, f[2] + base]),
        );
    }
    let n0 = mesh.positions.len() / 2;
    let s = format!(
        "[material]\nthickness = {h}\n[self_contact]\nenabled = true\n\
         [constraints]\nfix_boxes = [{{ min = [-1, -1, -1], max = [2, 2, 1e-4] }}]\n"
    );
    let sc = Scene::build(mesh, Settings::from_str_with(&s, "bench", &[]).unwrap()).unwrap();
    let mut x = sc.body.mesh.positions.clone();
    let mut rng = Rng::new(7);
    for p in &mut x[n0..] {
        p.z = gap + 1e-2 * gap * rng.symmetric();
    }
    let phi = vec![0.0; sc.num_scalar_dofs()];
    let p = Pattern::for_scene(&sc)
        .refreshed(&sc, &x, &phi, 0.0)
        .expect("the pressed sheets have pairs");
    (sc, p, x)
}

/// Self-contact of two sheets pressed into their offset (every vertex of both presses), at
/// about 5k, 20k and 80k faces: the term's energy, gradient and Hessian (throughput: pressing
/// pairs), the gathering of the pairs (broad phase and distance filter), the CCD step bound of a
/// random step of a tenth of the offset, and one Newton iteration (assembly of every term with
/// the Gauss–Newton projection, numeric Cholesky, solve) of the same scene.
fn self_contact(c: &mut Criterion) {
    let mut g = c.benchmark_group("self_contact");
    g.sample_size(10);
    // About 5k, 20k and 80k faces: the scaling of the broad phase, CCD and assembly.
    for edge in [1.0 / 35.0, 1.0 / 71.0, 1.0 / 141.0] {
        let (sc, p, x) = two_sheets(edge, 0.0018);
        let i = (0..sc.terms.len())
            .find(|&i| sc.terms[i].name() == "self_contact")
            .unwrap();
        let pot = potential(&sc, &p);
        let phi = vec![0.0; sc.num_scalar_dofs()];
        let (mut gr, mut h) = (vec![0.0; p.n], vec![0.0; p.nnz()]);
        let pairs = p.maps[i].nodes.len() / 4;
        let nf = sc.body.num_faces();
        let term = &sc.terms[i];
        g.throughput(Throughput::Elements(pairs as u64));
        g.bench_function(BenchmarkId::new("term_hessian_per_pair", nf), |b| {
            b.iter(|| {
                term.eval(
                    &pot,
                    &p.maps[i],
                    &x,
                    &phi,
                    Want::Hessian,
                    shellsim::energy::HessianProjection::None,
                    &mut gr,
                    &mut h,
                )
            })
        });
        g.bench_function(BenchmarkId::new("gather_per_pair", nf), |b| {
            b.iter(|| {
                black_box(
                    term.changing()
                        .unwrap()
                        .stencil_at(&sc.body, &x, &phi, 0.0)
                        .nodes
                        .len(),
                )
            })
        });
        let mut rng = Rng::new(11);
        let step: Vec<f64> = (0..p.n).map(|_| 2e-4 * rng.symmetric()).collect();
        g.bench_function(BenchmarkId::new("ccd_step_bound_per_pair", nf), |b| {
            b.iter(|| black_box(pot.step_bound(&x, &phi, &step).fraction))
        });
        g.throughput(Throughput::Elements(1));
        let mut lin = LinearSolver::new(&p).unwrap();
        // The contact's Hessian is indefinite where its distance curves (−ψ′∇²d): the
        // iteration factorises the Gauss–Newton model, as Newton does when the exact one fails.
        g.bench_function(BenchmarkId::new("newton_iteration", nf), |b| {
            b.iter(|| {
                pot.eval_projected(
                    &x,
                    &phi,
                    Want::Hessian,
                    shellsim::energy::HessianProjection::GaussNewton,
                    &mut gr,
                    &mut h,
                );
                for k in 0..p.n {
                    h[p.diag(k)] += 1e-6;
                }
                lin.factor(&h).unwrap();
                let mut rhs = gr.clone();
                lin.solve_in_place(&mut rhs);
                black_box(rhs[0])
            })
        });
    }
    g.finish();
}

criterion_group!(
    benches,
    self_contact,
    explicit_step,
    frame_write,
    kernel,
    assembly,
    newton_iteration,
    moisture_step,
    coupled_step,
    balloon
);
criterion_main!(benches);
