//! Prism-FEM moisture diffusion against Crank's analytic solutions (REFERENCES.md), the orders
//! of the space and time discretisations, the error control, mass conservation, and
//! contradictory boundary conditions.

use shellsim::diffusion::{
    robin_slab_surface, Diffusion, Diffusivity, Layering, Side, SurfaceBc, Tolerance,
};
use shellsim::math::{Real, Vec3};
use shellsim::mesh::generate::{rectangle, Spacing};
use std::f64::consts::PI;

fn plate(
    size: Real,
    edge: Real,
    h: Real,
    d: Diffusivity,
    layering: Layering,
) -> (Diffusion, usize, usize) {
    let m = rectangle(0.0, 0.0, size, size, edge, Spacing::default());
    let nf = m.faces.len();
    let dirs = vec![Vec3::new(1.0, 0.0, 0.0); nf];
    let diff = Diffusion::new(&m.positions, &m.faces, &vec![h; nf], &dirs, d, layering).unwrap();
    (diff, m.positions.len(), nf)
}

/// Sets `bc` on `sides` of every one of the `nf` faces.
fn everywhere(diff: &mut Diffusion, nf: usize, sides: &[Side], bc: SurfaceBc) {
    for f in 0..nf {
        for &side in sides {
            diff.set_surface(f, side, bc).unwrap();
        }
    }
}

/// Crank §4.3, slab −a < x < a with both faces at C_s = 1 from C₀ = 0: the mid-plane value.
fn crank_slab_mid(dt_over_a2: Real) -> Real {
    let mut s = 0.0;
    for n in 0..200 {
        let k = (2 * n + 1) as Real;
        s += (-1f64).powi(n) / k * (-k * k * PI * PI * dt_over_a2 / 4.0).exp();
    }
    1.0 - 4.0 / PI * s
}

/// Runs the slab (top and bottom held at 1) to `t_end` with fixed TR-BDF2 steps and returns the
/// mid-plane moisture.
fn slab(layers: usize, dt: Real, t_end: Real) -> Real {
    let a = 0.2e-3;
    let dcoef = 1e-10;
    let iso = Diffusivity {
        along: dcoef,
        across: dcoef,
        through: dcoef,
    };
    let (mut diff, nv, nf) = plate(1e-3, 5e-4, 2.0 * a, iso, Layering::uniform(layers));
    everywhere(
        &mut diff,
        nf,
        &[Side::Top, Side::Bottom],
        SurfaceBc::Value(1.0),
    );
    // The initial data is 0 everywhere, the surface nodes included: the surface value 1 holds
    // for t > 0 (the first solve imposes it). Starting them at 1 would add the content of a
    // ramp one layer wide, an O(Δz) error.
    let _ = nv;
    let mut u = vec![0.0; diff.num_nodes()];
    let steps = (t_end / dt).round() as usize;
    for _ in 0..steps {
        diff.step(&mut u, dt).unwrap();
    }
    u[diff.node(0, diff.column() / 2)]
}

/// Crank's slab check value (a = 0.2 mm, D = 1e-10 m²/s, t = 100 s, mid-plane 0.3145542331):
/// the orders of the discretisation, measured and printed. Space (quadratic layers 2 → 4 → 8,
/// Δt = 0.01 s so that time errors stay below 1e-9): fourth order measured (3.7, 4.1; the
/// Simpson-lumped quadratic elements superconverge at the nodes), asserted above 2.7. Time
/// (fixed TR-BDF2 steps 4 → 2 → 1 s, 8 layers, against Δt = 0.01 s on the same layers):
/// second order (2.03, 2.01).
#[test]
fn through_thickness_diffusion_matches_crank_slab() {
    let exact = crank_slab_mid(1e-10 * 100.0 / (0.2e-3f64).powi(2));
    assert!((exact - 0.3145542331).abs() < 1e-9, "series {exact}");
    let space: Vec<Real> = [2, 4, 8]
        .iter()
        .map(|&l| (slab(l, 0.01, 100.0) - exact).abs())
        .collect();
    let ps = [(space[0] / space[1]).log2(), (space[1] / space[2]).log2()];
    println!("slab, space: errors {space:?}, orders {ps:.2?}");
    assert!(ps.iter().all(|&p| p > 2.7), "space orders {ps:?}");
    assert!(space[2] / exact < 1e-4, "8 layers: {:e}", space[2] / exact);
    // Against the same layers at Δt = 0.01 s, so that the space error drops out.
    let fine = slab(8, 0.01, 100.0);
    let time: Vec<Real> = [4.0, 2.0, 1.0]
        .iter()
        .map(|&dt| (slab(8, dt, 100.0) - fine).abs())
        .collect();
    let pt = [(time[0] / time[1]).log2(), (time[1] / time[2]).log2()];
    println!("slab, time: errors {time:?}, orders {pt:.2?}");
    assert!(pt.iter().all(|&p| p > 1.8 && p < 2.3), "time orders {pt:?}");
}

/// The slab of half-thickness l exchanging with an ambient moisture through both faces
/// (Robin, Bi = k l / D = 0.1, 1, 10) against Crank's series for the surface moisture, with
/// the default layering and tolerance of `[moisture]` and the error-controlled `advance` over
/// uneven steps: within 1% of the exact surface value at every T = D t / l² from 0.05 to 2
/// (measured: ≤ 0.08%, see `examples/moisture_accuracy.rs`). The series itself is checked at
/// T = 0 (it sums to the initial 0, to its 2 000-term truncation) and against its early-time
/// asymptote 2 Bi √(T/π).
#[test]
fn default_layering_resolves_the_robin_slab_surface() {
    assert!(robin_slab_surface(1.0, 1e-3) < 0.04);
    for bi in [0.1, 1.0, 10.0] {
        let early = robin_slab_surface(bi, 1e-6);
        let asym = 2.0 * bi * (1e-6 / PI).sqrt();
        assert!(
            (early / asym - 1.0).abs() < 0.01,
            "Bi {bi}: {early} vs {asym}"
        );
    }
    let defaults = shellsim::settings::Moisture::default();
    let layering = Layering {
        count: defaults.layers,
        grading: defaults.grading,
    };
    let (h, d) = (1e-4, 1e-9);
    let l = 0.5 * h;
    for bi in [0.1, 1.0, 10.0] {
        let iso = Diffusivity {
            along: d,
            across: d,
            through: d,
        };
        let (mut diff, _, nf) = plate(1e-3, 1e-3, h, iso, layering);
        let k = bi * d / l;
        let robin = SurfaceBc::Robin { k, ambient: 1.0 };
        everywhere(&mut diff, nf, &[Side::Top, Side::Bottom], robin);
        let tol = Tolerance {
            rtol: defaults.tolerance,
            atol: 1e-3 * defaults.tolerance,
        };
        let mut u = vec![0.0; diff.num_nodes()];
        let mut t = 0.0;
        let mut worst: Real = 0.0;
        // Steps of growing, uneven length, as a run's mechanics would take them.
        let mut dt = 1e-3 * l * l / d;
        let mut sample = 0.05;
        while sample <= 2.0 + 1e-12 {
            let t_sample = sample * l * l / d;
            while t < t_sample - 1e-12 {
                let step = dt.min(t_sample - t);
                diff.advance(&mut u, step, tol).unwrap();
                t += step;
                dt *= 1.37;
            }
            let us = diff.surface_moisture(&u, 0).0;
            let exact = robin_slab_surface(bi, sample);
            worst = worst.max((us / exact - 1.0).abs());
            sample *= 1.5;
        }
        println!("Robin slab Bi {bi}: largest relative error of the surface moisture {worst:.2e}");
        assert!(worst < 0.01, "Bi {bi}: {worst:e}");
    }
}

/// The embedded error estimate of one TR-BDF2 step is third order in the step on a smooth
/// solution (its ratio between h and h/2 near 8), so the error control can trust it; and
/// `advance` meets its tolerance: the error against a fine reference is below 10× the
/// tolerance times the solution over a whole step of many sub-steps.
#[test]
fn error_estimate_and_control() {
    let iso = Diffusivity {
        along: 1e-9,
        across: 1e-9,
        through: 1e-9,
    };
    let smooth = || {
        let (mut diff, _, nf) = plate(1e-3, 1e-3, 1e-4, iso, Layering::uniform(4));
        let robin = SurfaceBc::Robin {
            k: 1e-5,
            ambient: 1.0,
        };
        everywhere(&mut diff, nf, &[Side::Top], robin);
        // A smooth start: the profile after 1 s.
        let mut u = vec![0.0; diff.num_nodes()];
        for _ in 0..100 {
            diff.step(&mut u, 0.01).unwrap();
        }
        (diff, u)
    };
    let est: Vec<Real> = [0.4, 0.2, 0.1]
        .iter()
        .map(|&h| {
            let (mut diff, mut u) = smooth();
            diff.step(&mut u, h).unwrap()
        })
        .collect();
    let ratios = [est[0] / est[1], est[1] / est[2]];
    println!("error estimates {est:?}, ratios {ratios:.2?}");
    assert!(ratios.iter().all(|&r| r > 6.0 && r < 10.0), "{ratios:?}");

    let (mut reference, mut fine) = smooth();
    for _ in 0..4000 {
        reference.step(&mut fine, 1e-3).unwrap();
    }
    let (mut diff, mut u) = smooth();
    let tol = Tolerance {
        rtol: 1e-4,
        atol: 1e-8,
    };
    let a = diff.advance(&mut u, 4.0, tol).unwrap();
    let err = u
        .iter()
        .zip(&fine)
        .map(|(a, b)| (a - b).abs() / b.abs().max(1e-3))
        .fold(0.0, Real::max);
    println!("advance over 4 s: {a:?}, largest relative error {err:.2e}");
    assert!(a.substeps > 1, "{a:?}");
    assert!(err < 1e-3, "{err:e}");
}

/// The column-preconditioned CG and the sparse Cholesky give the same solution (strong lateral
/// coupling: a large step on a plate with fast in-plane diffusion).
#[test]
fn cg_and_cholesky_agree() {
    let d = Diffusivity {
        along: 1e-6,
        across: 5e-7,
        through: 1e-9,
    };
    let run = |direct: bool| {
        let (mut diff, _, nf) = plate(1e-2, 1e-3, 1e-4, d, Layering::uniform(3));
        for f in 0..nf / 3 {
            diff.set_surface(f, Side::Top, SurfaceBc::Value(0.3))
                .unwrap();
        }
        if direct {
            diff.use_direct_solver();
        }
        let mut u = vec![0.0; diff.num_nodes()];
        let tol = Tolerance {
            rtol: 1e-3,
            atol: 1e-6,
        };
        let mut report = Vec::new();
        for _ in 0..5 {
            report.push(diff.advance(&mut u, 2.0, tol).unwrap());
        }
        (u, report)
    };
    let (cg, rc) = run(false);
    let (direct, rd) = run(true);
    assert!(
        rd.iter()
            .all(|a| a.cg_iterations == 0 && a.direct_solves > 0),
        "{rd:?}"
    );
    assert!(rc.iter().any(|a| a.cg_iterations > 0), "{rc:?}");
    let diff = cg
        .iter()
        .zip(&direct)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, Real::max);
    println!("CG {rc:?}\ndirect {rd:?}\nlargest difference {diff:e}");
    assert!(diff < 1e-9, "{diff:e}");
}

/// Lateral diffusion on a unit square plate whose rim is held at 1 (all layers), from 0:
/// the centre value against the separable Fourier series, with anisotropic in-plane
/// diffusivity (D_x = 1, D_y = 0.5, so the series uses D_x π²m² + D_y π²n²).
#[test]
fn lateral_diffusion_matches_the_fourier_solution() {
    let (dx, dy) = (1.0, 0.5);
    let t_end = 0.05;
    let exact = {
        let mut s = 0.0;
        for m in (1..80).step_by(2) {
            for n in (1..80).step_by(2) {
                let (mr, nr) = (m as Real, n as Real);
                s += (mr * PI * 0.5).sin()
                    * (nr * PI * 0.5).sin()
                    * (-(dx * mr * mr + dy * nr * nr) * PI * PI * t_end).exp()
                    / (mr * nr);
            }
        }
        1.0 - 16.0 / (PI * PI) * s
    };
    let run = |edge: Real, dt: Real| -> Real {
        let d = Diffusivity {
            along: dx,
            across: dy,
            through: 1.0,
        };
        let m = rectangle(0.0, 0.0, 1.0, 1.0, edge, Spacing::default());
        let nf = m.faces.len();
        let dirs = vec![Vec3::new(1.0, 0.0, 0.0); nf];
        let mut diff = Diffusion::new(
            &m.positions,
            &m.faces,
            &vec![0.01; nf],
            &dirs,
            d,
            Layering::uniform(1),
        )
        .unwrap();
        let mut u = vec![0.0; diff.num_nodes()];
        let mut centre = 0;
        for (v, p) in m.positions.iter().enumerate() {
            let rim = p.x < 1e-12 || p.y < 1e-12 || p.x > 1.0 - 1e-12 || p.y > 1.0 - 1e-12;
            for k in 0..diff.column() {
                if rim {
                    diff.set_node_value(diff.node(v, k), 1.0);
                    u[diff.node(v, k)] = 1.0;
                }
            }
            if (p.x - 0.5).abs() < 1e-12 && (p.y - 0.5).abs() < 1e-12 {
                centre = v;
            }
        }
        for _ in 0..(t_end / dt).round() as usize {
            diff.step(&mut u, dt).unwrap();
        }
        u[diff.node(centre, diff.column() / 2)]
    };
    let errs: Vec<Real> = [0.125, 0.0625, 0.03125]
        .iter()
        .map(|&h| (run(h, 1e-4) - exact).abs() / exact)
        .collect();
    let ps = [(errs[0] / errs[1]).log2(), (errs[1] / errs[2]).log2()];
    println!("plate: exact centre {exact:.6}, relative errors {errs:?}, orders {ps:.2?}");
    assert!(errs[2] < 5e-3, "{errs:?}");
    assert!(ps[1] > 1.7, "space order {ps:?}");
}

/// Sealed everywhere: the total moisture 1ᵀMu is conserved to 1e-12 over 200 steps, with
/// anisotropic diffusivity and several layers.
#[test]
fn sealed_sheet_conserves_moisture() {
    let d = Diffusivity {
        along: 2e-10,
        across: 1e-10,
        through: 5e-11,
    };
    let (mut diff, _, _) = plate(1e-2, 2.5e-3, 1e-4, d, Layering::uniform(4));
    let mut rng = shellsim::mesh::generate::Rng::new(3);
    let mut u: Vec<Real> = (0..diff.num_nodes()).map(|_| rng.uniform()).collect();
    let m0 = diff.total(&u);
    for _ in 0..200 {
        diff.step(&mut u, 0.5).unwrap();
    }
    let m1 = diff.total(&u);
    assert!(((m1 - m0) / m0).abs() < 1e-12, "{m0} -> {m1}");
    assert!(u.iter().all(|v| v.is_finite()));
}

/// Two different conditions on one face's surface are contradictory input.
#[test]
fn contradictory_surface_conditions_are_rejected() {
    let iso = Diffusivity {
        along: 1.0,
        across: 1.0,
        through: 1.0,
    };
    let (mut diff, _, _) = plate(1.0, 0.5, 0.1, iso, Layering::uniform(1));
    diff.set_surface(0, Side::Top, SurfaceBc::Value(1.0))
        .unwrap();
    diff.set_surface(0, Side::Top, SurfaceBc::Value(1.0))
        .unwrap();
    let e = diff
        .set_surface(0, Side::Top, SurfaceBc::Flux(1.0))
        .unwrap_err();
    assert!(
        matches!(
            e,
            shellsim::diffusion::SurfaceError::Contradict { face: 0, .. }
        ),
        "{e}"
    );
    assert!(e.to_string().contains("face 0"), "{e}");
    diff.set_surface(
        0,
        Side::Bottom,
        SurfaceBc::Robin {
            k: 1.0,
            ambient: 0.5,
        },
    )
    .unwrap();
}

/// A prescribed flux adds exactly q·A·t (TR-BDF2 conserves the balance); evaporation to
/// an ambient moisture (Robin) drives the sheet to that moisture.
#[test]
fn flux_and_robin_conditions_balance() {
    let d = Diffusivity {
        along: 1e-9,
        across: 1e-9,
        through: 1e-9,
    };
    let (mut diff, _, nf) = plate(1e-2, 2.5e-3, 1e-4, d, Layering::uniform(2));
    everywhere(&mut diff, nf, &[Side::Top], SurfaceBc::Flux(1e-6));
    let mut u = vec![0.0; diff.num_nodes()];
    for _ in 0..50 {
        diff.step(&mut u, 2.0).unwrap();
    }
    let added = 1e-6 * 1e-4 * 100.0; // q × area × t
    let total = diff.total(&u);
    assert!((total / added - 1.0).abs() < 1e-12, "{total} vs {added}");

    let (mut diff, _, nf) = plate(1e-2, 2.5e-3, 1e-4, d, Layering::uniform(2));
    let robin = SurfaceBc::Robin {
        k: 1e-5,
        ambient: 0.3,
    };
    everywhere(&mut diff, nf, &[Side::Bottom], robin);
    let mut u = vec![0.0; diff.num_nodes()];
    for _ in 0..200 {
        diff.step(&mut u, 10.0).unwrap();
    }
    assert!(u.iter().all(|v| (v - 0.3).abs() < 1e-6), "{:?}", &u[..4]);
}

/// Failure messages end up in `summary.json`'s `reason`: a non-finite number in them is
/// written as "not finite", never as `NaN` or `inf`.
#[test]
fn failure_messages_print_no_non_finite_numbers() {
    use shellsim::solve::newton::SolveError;
    let texts = [
        SolveError::LineSearchStalled {
            residual: Real::INFINITY,
            slope: Real::NEG_INFINITY,
        }
        .to_string(),
        SolveError::NotConverged {
            iterations: 40,
            residual: Real::NAN,
        }
        .to_string(),
        shellsim::diffusion::DiffusionError::StepControl {
            h: 1e-9,
            error: Real::NAN,
        }
        .to_string(),
    ];
    for t in &texts {
        assert!(t.contains("not finite"), "{t}");
        assert!(
            !t.to_lowercase().contains("nan") && !t.contains("inf"),
            "{t}"
        );
    }
}
