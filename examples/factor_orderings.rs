//! The sparse factorisation of one scene's Hessian under each fill-reducing ordering: unknowns,
//! factor non-zeros, flops, the symbolic analysis and the numeric factorisation and one solve
//! (best of `REPEATS`, the variants alternated so that a noisy machine treats them alike), on
//! one thread; and nested dissection split at its top separator on one and on two threads.
//!
//!     cargo run --release --example factor_orderings -- SETTINGS MESH [REPEATS]
//!
//! The Hessian is assembled at the reference configuration and shifted by its mean diagonal so
//! that every ordering factorises the same positive-definite matrix (the cost of a numeric
//! factorisation does not depend on the values).
use std::time::Instant;

use shellsim::assembly::{Pattern, Want};
use shellsim::energy::Potential;
use shellsim::linalg::{LinearSolver, Ordering};
use shellsim::mesh::io::read_mesh;
use shellsim::model::Scene;
use shellsim::settings::Settings;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    anyhow::ensure!(
        args.len() >= 3,
        "usage: factor_orderings SETTINGS MESH [REPEATS]"
    );
    let repeats: usize = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(5);
    let settings = Settings::load(std::path::Path::new(&args[1]), &[])?;
    let scene = Scene::build(read_mesh(std::path::Path::new(&args[2]))?, settings)?;
    let p = Pattern::for_scene(&scene);
    let pot = Potential::new(&scene, &p);
    let x = scene.body.mesh.positions.clone();
    let phi = vec![0.0; scene.num_scalar_dofs()];
    let (mut g, mut h) = (vec![0.0; p.n], vec![0.0; p.nnz()]);
    pot.eval(&x, &phi, Want::Hessian, &mut g, &mut h);
    let mean = (0..p.n).map(|i| h[p.diag(i)].abs()).sum::<f64>() / p.n as f64;
    for i in 0..p.n {
        h[p.diag(i)] += mean;
    }
    if let Some(d) = shellsim::linalg::ordering::nested_dissection(p.n, &p.col_ptr, &p.row_idx) {
        println!(
            "top-level dissection: halves of {} and {} unknowns, separator of {}",
            d.sizes[0], d.sizes[1], d.sizes[2]
        );
    }
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    let pool2 = rayon::ThreadPoolBuilder::new().num_threads(2).build()?;
    let variants = [
        ("amd", Ordering::Amd, false, 1),
        ("nested_dissection", Ordering::NestedDissection, false, 1),
        ("nd split, 1 thread", Ordering::NestedDissection, true, 1),
        ("nd split, 2 threads", Ordering::NestedDissection, true, 2),
    ];
    let mut solvers = Vec::new();
    for (name, o, split, threads) in variants {
        let mut lin =
            LinearSolver::from_csc(p.n, p.col_ptr.clone(), p.row_idx.clone())?.with_ordering(o);
        if split {
            lin = lin.with_split();
        }
        let t = Instant::now();
        lin.analyse()?;
        solvers.push((
            name,
            lin,
            threads,
            t.elapsed().as_secs_f64(),
            f64::INFINITY,
            f64::INFINITY,
        ));
    }
    let b: Vec<f64> = (0..p.n).map(|i| ((i * 7919) % 101) as f64 - 50.0).collect();
    let mut x0: Option<Vec<f64>> = None;
    for _ in 0..repeats {
        for s in solvers.iter_mut() {
            let p = if s.2 == 1 { &pool } else { &pool2 };
            p.install(|| -> anyhow::Result<()> {
                let t = Instant::now();
                s.1.factor(&h)?;
                s.4 = s.4.min(t.elapsed().as_secs_f64());
                let mut x = b.clone();
                let t = Instant::now();
                s.1.solve_in_place(&mut x);
                s.5 = s.5.min(t.elapsed().as_secs_f64());
                let r = x0.get_or_insert_with(|| x.clone());
                let d = r
                    .iter()
                    .zip(&x)
                    .fold(0.0f64, |m, (a, c)| m.max((a - c).abs()));
                let s0 = r.iter().fold(0.0f64, |m, a| m.max(a.abs()));
                anyhow::ensure!(
                    d <= 1e-8 * s0,
                    "{}: solution differs by {d:e} of {s0:e}",
                    s.0
                );
                Ok(())
            })?;
        }
    }
    println!(
        "{} faces, {} unknowns\nvariant              factor_nnz   flops      analysis_ms  factor_ms  solve_ms",
        scene.body.num_faces(),
        p.n
    );
    for (name, lin, _, analysis, factor, solve) in &solvers {
        println!(
            "{:<20} {:>10}  {:>9.3e}  {:>11.1}  {:>9.2}  {:>8.2}",
            name,
            lin.factor_nnz(),
            lin.factor_flops(),
            1e3 * analysis,
            1e3 * factor,
            1e3 * solve
        );
    }
    Ok(())
}
