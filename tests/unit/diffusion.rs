//! Prism-FEM moisture diffusion against Crank's analytic solutions (REFERENCES.md), mass
//! conservation, and contradictory boundary conditions.

use shellsim::diffusion::{Diffusion, Diffusivity, Side, SurfaceBc};
use shellsim::math::{Real, Vec3};
use shellsim::mesh::generate::{rectangle, Spacing};
use std::f64::consts::PI;

fn plate(
    size: Real,
    edge: Real,
    h: Real,
    d: Diffusivity,
    layers: usize,
) -> (Diffusion, usize, usize) {
    let m = rectangle(0.0, 0.0, size, size, edge, Spacing::default());
    let nf = m.faces.len();
    let dirs = vec![Vec3::new(1.0, 0.0, 0.0); nf];
    let diff = Diffusion::new(&m.positions, &m.faces, &vec![h; nf], &dirs, d, layers).unwrap();
    (diff, m.positions.len(), nf)
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

/// Runs the slab (top and bottom held at 1) to `t_end` and returns the mid-plane moisture.
fn slab(layers: usize, dt: Real, t_end: Real) -> Real {
    let a = 0.2e-3;
    let dcoef = 1e-10;
    let iso = Diffusivity {
        along: dcoef,
        across: dcoef,
        through: dcoef,
    };
    let (mut diff, nv, nf) = plate(1e-3, 5e-4, 2.0 * a, iso, layers);
    for f in 0..nf {
        diff.set_surface(f, Side::Top, SurfaceBc::Value(1.0))
            .unwrap();
        diff.set_surface(f, Side::Bottom, SurfaceBc::Value(1.0))
            .unwrap();
    }
    // The initial data is 0 everywhere, the surface nodes included: the surface value 1 holds
    // for t > 0 (the first solve imposes it). Starting them at 1 would add the content of a
    // ramp one layer wide, an O(Δz) error.
    let _ = nv;
    let mut u = vec![0.0; diff.num_nodes()];
    let steps = (t_end / dt).round() as usize;
    for _ in 0..steps {
        diff.step(&mut u, dt).unwrap();
    }
    u[diff.node(0, layers / 2)]
}

/// Crank's slab check value (a = 0.2 mm, D = 1e-10 m²/s, t = 100 s, mid-plane 0.3145542331):
/// error ≤ 0.5% with 16 layers and Δt = 0.05 s; second order in space (layers 4 → 8 → 16 at
/// Δt = 0.01 s) and first order in time (Δt 2 → 1 → 0.5 s at 64 layers), measured and printed.
#[test]
fn through_thickness_diffusion_matches_crank_slab() {
    let exact = crank_slab_mid(1e-10 * 100.0 / (0.2e-3f64).powi(2));
    assert!((exact - 0.3145542331).abs() < 1e-9, "series {exact}");
    let e = (slab(16, 0.05, 100.0) - exact).abs() / exact;
    println!("slab, 16 layers, dt 0.05 s: relative error {e:.2e}");
    assert!(e < 5e-3, "relative error {e}");
    let space: Vec<Real> = [4, 8, 16]
        .iter()
        .map(|&l| (slab(l, 0.01, 100.0) - exact).abs())
        .collect();
    let ps = [(space[0] / space[1]).log2(), (space[1] / space[2]).log2()];
    println!("slab, space: errors {space:?}, orders {ps:.2?}");
    assert!(
        ps.iter().all(|&p| p > 1.7 && p < 2.5),
        "space orders {ps:?}"
    );
    let time: Vec<Real> = [2.0, 1.0, 0.5]
        .iter()
        .map(|&dt| (slab(64, dt, 100.0) - exact).abs())
        .collect();
    let pt = [(time[0] / time[1]).log2(), (time[1] / time[2]).log2()];
    println!("slab, time: errors {time:?}, orders {pt:.2?}");
    assert!(pt.iter().all(|&p| p > 0.8 && p < 1.3), "time orders {pt:?}");
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
        let mut diff =
            Diffusion::new(&m.positions, &m.faces, &vec![0.01; nf], &dirs, d, 1).unwrap();
        let mut u = vec![0.0; diff.num_nodes()];
        let mut centre = 0;
        for (v, p) in m.positions.iter().enumerate() {
            let rim = p.x < 1e-12 || p.y < 1e-12 || p.x > 1.0 - 1e-12 || p.y > 1.0 - 1e-12;
            for k in 0..2 {
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
        u[diff.node(centre, 1)]
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
    let (mut diff, _, _) = plate(1e-2, 2.5e-3, 1e-4, d, 4);
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
    let (mut diff, _, _) = plate(1.0, 0.5, 0.1, iso, 1);
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

/// A prescribed flux adds exactly q·A·t (backward Euler conserves the balance); evaporation to
/// an ambient moisture (Robin) drives the sheet to that moisture.
#[test]
fn flux_and_robin_conditions_balance() {
    let d = Diffusivity {
        along: 1e-9,
        across: 1e-9,
        through: 1e-9,
    };
    let (mut diff, _, nf) = plate(1e-2, 2.5e-3, 1e-4, d, 2);
    for f in 0..nf {
        diff.set_surface(f, Side::Top, SurfaceBc::Flux(1e-6))
            .unwrap();
    }
    let mut u = vec![0.0; diff.num_nodes()];
    for _ in 0..50 {
        diff.step(&mut u, 2.0).unwrap();
    }
    let added = 1e-6 * 1e-4 * 100.0; // q × area × t
    let total = diff.total(&u);
    assert!((total / added - 1.0).abs() < 1e-12, "{total} vs {added}");

    let (mut diff, _, nf) = plate(1e-2, 2.5e-3, 1e-4, d, 2);
    for f in 0..nf {
        diff.set_surface(
            f,
            Side::Bottom,
            SurfaceBc::Robin {
                k: 1e-5,
                ambient: 0.3,
            },
        )
        .unwrap();
    }
    let mut u = vec![0.0; diff.num_nodes()];
    for _ in 0..200 {
        diff.step(&mut u, 10.0).unwrap();
    }
    assert!(u.iter().all(|v| (v - 0.3).abs() < 1e-6), "{:?}", &u[..4]);
}
