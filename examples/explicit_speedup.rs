//! The explicit step's speed-up on 2 threads, measured so that a shared host's drift cancels.
//!
//! Bursts of steps alternate in one process:
//! - the step on 1 thread;
//! - the step on 2 threads (a team, as the explicit driver runs it);
//! - the control: two independent 1-thread runs of the step at once, each with its own pattern,
//!   state and thread, sharing nothing written. Twice the 1-thread time over the slower of the
//!   two is the speed-up the host allows two threads on work that needs no communication.
//!
//! Ratios are of medians over the bursts and of minima (the burst the host disturbed least).
//! The scene is the `explicit_step` bench's: MorphoShell's GCM cone with the patch fit, while
//! waiting (densities computed once), at the bench's three sizes or at the mesh edges given.
//!
//! `cargo run --release --example explicit_speedup [EDGE ...]`
use shellsim::assembly::Pattern;
use shellsim::energy::potential::Potential;
use shellsim::integrate::explicit::Step;
use shellsim::math::Vec3;
use shellsim::mesh::generate::{annulus, Spacing};
use shellsim::model::Scene;
use shellsim::team::Team;
use std::time::Instant;

/// Steps per burst, bursts per mode, and bursts discarded as warm-up.
const BURST: usize = 500;
const BURSTS: usize = 40;
const WARM: usize = 4;

/// One run of the step: its own pattern, positions, velocities and gradient scratch.
struct Chain {
    step: Step,
    x: Vec<Vec3>,
    v: Vec<Vec3>,
    g: Vec<f64>,
}

impl Chain {
    fn new(pot: &Potential, x0: &[Vec3]) -> Chain {
        Chain {
            step: Step::new(pot, true),
            x: x0.to_vec(),
            v: vec![Vec3::zeros(); x0.len()],
            g: vec![0.0; pot.pattern.n],
        }
    }

    /// Seconds per step over one burst, on the calling thread's pool with a team of `threads`.
    fn burst(&mut self, pot: &Potential, inv_m: &[f64], threads: usize) -> f64 {
        let team = Team::new(threads);
        team.activate(|| {
            let clock = Instant::now();
            for _ in 0..BURST {
                let (x, v, g) = (&mut self.x, &mut self.v, &mut self.g);
                self.step.take(pot, x, v, g, inv_m, 1e-3, 1e-9);
            }
            clock.elapsed().as_secs_f64() / BURST as f64
        })
    }
}

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a thread pool")
}

fn main() {
    let edges: Vec<f64> = std::env::args()
        .skip(1)
        .map(|s| s.parse().expect("an edge length"))
        .collect();
    let edges = if edges.is_empty() {
        vec![0.085, 0.05, 0.025]
    } else {
        edges
    };
    println!(
        "faces | µs per step, median (min): 1 thread | 2 threads | control | \
         speed-up, median (min): 2 threads | control"
    );
    for edge in edges {
        let sweep = shellsim::cases::gcm_cone_sweep();
        let mut mesh = annulus(1.0, 1.4, sweep, edge, Spacing::default());
        shellsim::cases::Case::GcmCone.program(&mut mesh);
        let settings = shellsim::settings::Settings::from_str_with(
            "[material]\nyoung = 3.0\npoisson = 0.5\ndensity = 1.0\nthickness = 0.01\n\
             bending = \"patch_fit\"\n[rest]\ntarget = \"mesh\"\n[solver]\nmode = \"explicit\"\n",
            "explicit_speedup",
            &[],
        )
        .expect("settings");
        let sc = Scene::build(mesh, settings).expect("scene");
        let nf = sc.body.num_faces();
        let inv_m: Vec<f64> = sc.body.mass.iter().map(|m| 1.0 / m).collect();
        let x0: Vec<Vec3> = sc
            .body
            .mesh
            .positions
            .iter()
            .map(|p| Vec3::new(p.x, p.y, (4.0 - p.x * p.x - p.y * p.y).sqrt()))
            .collect();
        let patterns: Vec<Pattern> = (0..3).map(|_| Pattern::for_scene(&sc)).collect();
        let frozen: Vec<_> = {
            let pot = Potential::new(&sc, &patterns[0]);
            (0..nf).map(|f| pot.density(f)).collect()
        };
        let pots: Vec<Potential> = patterns
            .iter()
            .map(|p| Potential {
                frozen: Some(&frozen[..]),
                ..Potential::new(&sc, p)
            })
            .collect();
        // The measured chain (1 and 2 threads alternately) and the control's two.
        let mut main = Chain::new(&pots[0], &x0);
        let mut control: Vec<Chain> = pots[1..].iter().map(|p| Chain::new(p, &x0)).collect();
        let (one, two) = (pool(1), pool(2));
        let solo: Vec<rayon::ThreadPool> = (0..2).map(|_| pool(1)).collect();
        let mut times: [Vec<f64>; 3] = Default::default();
        for burst in 0..BURSTS {
            let t1 = one.install(|| main.burst(&pots[0], &inv_m, 1));
            let t2 = two.install(|| main.burst(&pots[0], &inv_m, 2));
            let tc = std::thread::scope(|s| {
                let runs: Vec<_> = control
                    .iter_mut()
                    .zip(&solo)
                    .zip(&pots[1..])
                    .map(|((c, pl), pot)| {
                        let inv_m = &inv_m;
                        s.spawn(move || pl.install(|| c.burst(pot, inv_m, 1)))
                    })
                    .collect();
                runs.into_iter()
                    .map(|r| r.join().expect("a control run"))
                    .fold(0.0, f64::max)
            });
            if burst >= WARM {
                for (ts, t) in times.iter_mut().zip([t1, t2, tc]) {
                    ts.push(t * 1e6);
                }
            }
        }
        for t in &mut times {
            t.sort_by(f64::total_cmp);
        }
        let med = |k: usize| times[k][times[k].len() / 2];
        let min = |k: usize| times[k][0];
        println!(
            "{nf:5} | {:.1} ({:.1}) | {:.1} ({:.1}) | {:.1} ({:.1}) | {:.2}× ({:.2}×) | {:.2}× ({:.2}×)",
            med(0),
            min(0),
            med(1),
            min(1),
            med(2),
            min(2),
            med(0) / med(1),
            min(0) / min(1),
            2.0 * med(0) / med(2),
            2.0 * min(0) / min(2),
        );
    }
}
