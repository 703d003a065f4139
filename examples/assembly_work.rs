//! A fixed amount of work for instruction counts (`perf stat -e instructions`,
//! `valgrind --tool=callgrind`), steady on a noisy machine where wall times are not: builds a
//! jittered, spherical-cap-programmed sheet (the benches' scene, `benches/common/scene.rs`) and
//! assembles energy, gradient and Hessian a fixed number of times on one thread, printing the
//! wall time per assembly.
//!
//!     cargo run --release --example assembly_work -- BENDING EDGE REPEATS
use shellsim::assembly::{Pattern, Want};
use shellsim::energy::Potential;

#[path = "../benches/common/scene.rs"]
mod scene;
use scene::{curved, scene_with_material};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let model = args.get(1).map_or("midedge_sin", |s| s.as_str());
    let edge: f64 = args
        .get(2)
        .and_then(|s| s.parse().ok())
        .unwrap_or(1.0 / 100.0);
    let repeats: usize = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(5);
    let sc = scene_with_material(edge, model, "koiter");
    let p = Pattern::for_scene(&sc);
    let x = curved(&sc);
    let phi = vec![0.01; sc.body.num_edge_dofs()];
    let pot = Potential::new(&sc, &p);
    let (mut g, mut h) = (vec![0.0; p.n], vec![0.0; p.nnz()]);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let mut e = 0.0;
    let start = std::time::Instant::now();
    pool.install(|| {
        for _ in 0..repeats {
            e += pot.eval(&x, &phi, Want::Hessian, &mut g, &mut h);
        }
    });
    let per = start.elapsed().as_secs_f64() / repeats.max(1) as f64;
    println!(
        "{} faces, {model}: energy {e:.6e}, h[0] {:.6e}, {:.1} ms per assembly",
        sc.body.num_faces(),
        h[0],
        1e3 * per
    );
}
