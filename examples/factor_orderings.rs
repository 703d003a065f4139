//! The sparse factorisation of one scene's Hessian under each fill-reducing ordering: unknowns,
//! factor non-zeros, flops, the symbolic analysis and the numeric factorisation (best of
//! `REPEATS`, orderings alternated so that a noisy machine treats them alike), one thread.
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
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    let orders = [Ordering::Amd, Ordering::NestedDissection];
    let mut solvers = Vec::new();
    for o in orders {
        let mut lin = LinearSolver::new(&p)?.with_ordering(o);
        let t = Instant::now();
        lin.analyse()?;
        solvers.push((lin, t.elapsed().as_secs_f64(), f64::INFINITY));
    }
    pool.install(|| -> anyhow::Result<()> {
        for _ in 0..repeats {
            for s in solvers.iter_mut() {
                let t = Instant::now();
                s.0.factor(&h)?;
                s.2 = s.2.min(t.elapsed().as_secs_f64());
            }
        }
        Ok(())
    })?;
    println!(
        "{} faces, {} unknowns\nordering            factor_nnz   flops      analysis_ms  factor_ms",
        scene.body.num_faces(),
        p.n
    );
    for (lin, analysis, factor) in &solvers {
        println!(
            "{:<19} {:>10}  {:>9.3e}  {:>11.1}  {:>9.2}",
            lin.ordering().map_or("-", |o| o.name()),
            lin.factor_nnz(),
            lin.factor_flops(),
            1e3 * analysis,
            1e3 * factor
        );
    }
    Ok(())
}
