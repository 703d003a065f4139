//! Waves between stiff veins: a blade that grows between veins it is attached to buckles into
//! waves whose number and onset follow the linear Föppl–von Kármán plate-buckling estimate.
//!
//! ## The estimate
//! A rectangular plate a × b, thickness h, under a uniaxial compressive stress σ along a
//! (Timoshenko & Gere 1961, *Theory of Elastic Stability*, §9.2), buckles at
//! `σ_cr = k π² D/(b² h)`, `D = E h³/(12(1 − ν²))`, into half-waves of length a/m with the m
//! that minimises k: for edges held by stiff veins that let it turn (simply supported) k = 4 at
//! half-waves as long as the plate is wide, a/m = b; for veins that clamp it, k = 6.97 at
//! a/m ≈ 0.66 b. Here the blade grows along a by ε (with −ν ε across, so that the stress is
//! uniaxial, σ = E ε) inside a frame of fixed vertices: it buckles at `ε_cr = σ_cr/E`.
//!
//! With a = 4b, h = b/100: 4 half-waves between hinging veins and 6 between clamping ones;
//! ε_cr = 3.62e-4 and 6.30e-4.

mod common;

use common::{run_settings, shellsim};
use shellsim::math::Real;
use std::path::Path;

const B: Real = 0.01;
const H: Real = 1e-4;
const NU: Real = 0.3;

/// Grows the 40 × 10 mm plate in `dir` by `eps` along x inside a frame of fixed vertices, one
/// row deep (hinged) or two (clamped); the deflection z along the centre line y = 0 in x order.
fn grow(dir: &Path, eps: Real, clamped: bool, tag: &str) -> Vec<Real> {
    let (ex, ey) = if clamped {
        (0.0194, 0.0044)
    } else {
        (0.01999, 0.00499)
    };
    let settings = format!(
        "[material]\nyoung = 1e7\npoisson = {NU}\nthickness = {H}\n[growth]\n\
         law = \"machine_direction\"\nmu = 1.0\nmu_perp = {mp}\nmoisture_top = {eps:e}\n\
         moisture_bottom = {eps:e}\nmachine_direction = [1, 0, 0]\n[constraints]\n\
         fix_boxes = [{{ min = [-1, -1, -1], max = [1, -{ey}, 1] }}, \
         {{ min = [-1, {ey}, -1], max = [1, 1, 1] }}, {{ min = [-1, -1, -1], max = [-{ex}, 1, 1] }}, \
         {{ min = [{ex}, -1, -1], max = [1, 1, 1] }}]\n",
        mp = -NU
    );
    let frames = run_settings(dir, tag, &settings, "plate.vtk");
    let (first, last) = (&frames[0], frames.last().unwrap());
    let mut line: Vec<(Real, Real)> = (0..first.positions.len())
        .filter(|&i| first.positions[i].y.abs() < 1e-9)
        .map(|i| (first.positions[i].x, last.positions[i].z))
        .collect();
    line.sort_by(|a, b| a.0.total_cmp(&b.0));
    line.into_iter().map(|p| p.1).collect()
}

/// The number of half-waves of `z`: its sign changes plus one, ignoring values below 1e-3 of
/// the largest (the nodes on the frame).
fn half_waves(z: &[Real]) -> usize {
    let top = z.iter().fold(0.0, |m: Real, v| m.max(v.abs()));
    let signs: Vec<bool> = z
        .iter()
        .filter(|v| v.abs() > 1e-3 * top)
        .map(|v| *v > 0.0)
        .collect();
    1 + signs.windows(2).filter(|w| w[0] != w[1]).count()
}

/// Between hinging veins the plate stays flat at 0.9 ε_cr and buckles at 1.1 ε_cr into 4
/// half-waves; between clamping veins it stays flat at 0.8 ε_cr and buckles at 1.27 ε_cr into 6
/// (measured: flat amplitudes below 1e-16 m; buckled 30 and 43 µm, 4 and 6 half-waves). The
/// onset is bracketed to ±10% and ±27%, and the wave count is exact.
#[test]
fn a_blade_between_stiff_veins_buckles_into_the_plate_estimates_waves() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    shellsim(
        &[
            "mesh",
            "rectangle",
            "--lx",
            "0.04",
            "--ly",
            "0.01",
            "--edge",
            "0.0005",
            "-o",
            "plate.vtk",
        ],
        d,
    );
    let pi2 = std::f64::consts::PI.powi(2);
    let eps_cr = |k: Real| k * pi2 * H * H / (12.0 * (1.0 - NU * NU) * B * B);
    for (clamped, k, below, above, waves) in [(false, 4.0, 0.9, 1.1, 4), (true, 6.97, 0.8, 1.27, 6)]
    {
        let cr = eps_cr(k);
        let name = if clamped { "clamped" } else { "hinged" };
        let flat = grow(d, below * cr, clamped, &format!("{name}_below"));
        let amp = flat.iter().fold(0.0, |m: Real, v| m.max(v.abs()));
        let buckled = grow(d, above * cr, clamped, &format!("{name}_above"));
        let amp_b = buckled.iter().fold(0.0, |m: Real, v| m.max(v.abs()));
        let n = half_waves(&buckled);
        println!(
            "{name}: ε_cr {cr:.3e}; at {below} ε_cr amplitude {amp:.1e} m, at {above} ε_cr \
             {amp_b:.1e} m in {n} half-waves (estimate {waves})"
        );
        assert!(amp < 1e-9 * B, "{name}: buckled below the estimate ({amp})");
        assert!(
            amp_b > 1e-3 * B,
            "{name}: flat above the estimate ({amp_b})"
        );
        assert_eq!(n, waves, "{name}: {buckled:?}");
    }
}
