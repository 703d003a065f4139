//! Error against cost of the through-thickness moisture discretisation: a slab of half-thickness
//! l exchanging moisture through both faces (Robin, Biot number Bi = k l / D), from 0 towards an
//! ambient 1, against Crank's series for the surface moisture (Crank 1975, §4.3.6, Eq. 4.53):
//!
//! `u_s(T) = 1 − Σₙ 2 Bi exp(−βₙ² T) / (βₙ² + Bi² + Bi)`, `βₙ tan βₙ = Bi`, `T = D t / l²`
//! ([`shellsim::diffusion::robin_slab_surface`]).
//!
//! For each layering (count, grading) and tolerance it prints the largest relative error of the
//! surface moisture over T ∈ [0.05, 2], the sub-steps and factorisations the error control
//! needed, and the wall time of one diffusion step on a 5k-face sheet with that layering.
//! Run: `cargo run --release --example moisture_accuracy`.

use shellsim::diffusion::{
    robin_slab_surface, Diffusion, Diffusivity, Layering, Side, SurfaceBc, Tolerance,
};
use shellsim::math::{Real, Vec3};
use shellsim::mesh::generate::{rectangle, Spacing};
use std::time::Instant;

fn sheet(edge: Real, size: Real, h: Real, d: Real, layering: Layering, bi: Real) -> Diffusion {
    let m = rectangle(0.0, 0.0, size, size, edge, Spacing::default());
    let nf = m.faces.len();
    let dirs = vec![Vec3::new(1.0, 0.0, 0.0); nf];
    let iso = Diffusivity {
        along: d,
        across: d,
        through: d,
    };
    let mut diff = Diffusion::new(&m.positions, &m.faces, &vec![h; nf], &dirs, iso, layering)
        .expect("diffusion system");
    let k = bi * d / (0.5 * h);
    for f in 0..nf {
        for side in [Side::Top, Side::Bottom] {
            diff.set_surface(f, side, SurfaceBc::Robin { k, ambient: 1.0 })
                .expect("one condition per side");
        }
    }
    diff
}

/// Largest relative error of the surface moisture at the sample times, and the control's work.
fn slab_error(layering: Layering, rtol: Real, bi: Real, calls: usize) -> (Real, usize, usize) {
    let (h, d) = (1e-4, 1e-9);
    let l = 0.5 * h;
    let mut diff = sheet(1e-3, 1e-3, h, d, layering, bi);
    let samples = [0.05, 0.1, 0.2, 0.5, 1.0, 2.0];
    let mut u = vec![0.0; diff.num_nodes()];
    let tol = Tolerance {
        rtol,
        atol: 1e-3 * rtol,
    };
    let (mut err, mut subs, mut facs) = (0.0 as Real, 0, 0);
    let mut t_prev = 0.0;
    for &ts in &samples {
        // `calls` equal mechanical steps between samples.
        let dt = (ts - t_prev) * l * l / d / calls as Real;
        for _ in 0..calls {
            let a = diff.advance(&mut u, dt, tol).expect("diffusion step");
            subs += a.substeps;
            facs += a.factorisations;
        }
        t_prev = ts;
        let us = diff.surface_moisture(&u, 0).0;
        let exact = robin_slab_surface(bi, ts);
        err = err.max(((us - exact) / exact).abs());
    }
    (err, subs, facs)
}

/// Wall time of one `advance` on a 5k-face sheet (after warm-up, factors cached).
fn step_cost(layering: Layering) -> Real {
    let mut diff = sheet(0.02, 1.0, 1e-4, 1e-9, layering, 1.0);
    let mut u = vec![0.0; diff.num_nodes()];
    let tol = Tolerance {
        rtol: 1e-3,
        atol: 1e-6,
    };
    let dt = 0.05;
    for _ in 0..20 {
        diff.advance(&mut u, dt, tol).expect("diffusion step");
    }
    let reps = 20;
    let t0 = Instant::now();
    let (mut subs, mut cg) = (0, 0);
    for _ in 0..reps {
        let a = diff.advance(&mut u, dt, tol).expect("diffusion step");
        subs += a.substeps;
        cg += a.cg_iterations;
    }
    if std::env::var_os("VERBOSE").is_some() {
        eprintln!(
            "{layering:?}: {subs} substeps, {cg} CG iterations, {} nodes",
            u.len()
        );
    }
    let per_substep = t0.elapsed().as_secs_f64() / subs.max(1) as Real;
    1e3 * per_substep
}

fn main() {
    println!("Robin slab, surface moisture vs Crank's series, T = D t / l² in [0.05, 2]");
    println!("layers grading   rtol | max rel. error Bi=0.1     Bi=1    Bi=10 | substeps factors | ms/substep (5k faces)");
    for (count, grading) in [
        (2, 1.0),
        (3, 1.0),
        (4, 1.0),
        (6, 1.0),
        (8, 1.0),
        (3, 2.0),
        (4, 1.5),
        (4, 2.0),
        (5, 1.5),
        (5, 2.0),
        (6, 1.5),
        (6, 2.0),
    ] {
        let layering = Layering { count, grading };
        for rtol in [1e-2, 1e-3, 1e-4] {
            let mut errs = Vec::new();
            let (mut subs, mut facs) = (0, 0);
            for bi in [0.1, 1.0, 10.0] {
                let (e, s, f) = slab_error(layering, rtol, bi, 4);
                errs.push(e);
                subs += s;
                facs += f;
            }
            println!(
                "{count:>6} {grading:>7} {rtol:>6.0e} | {:>20.2e} {:>8.2e} {:>8.2e} | {subs:>8} {facs:>7} | {:.2}",
                errs[0],
                errs[1],
                errs[2],
                if rtol == 1e-3 { step_cost(layering) } else { Real::NAN },
            );
        }
    }
}
