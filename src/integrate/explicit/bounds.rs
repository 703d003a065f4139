//! The explicit run's bounds, checked before anything is written, and the mesh's stability
//! limit measured at the start (the largest eigenvalue of `M⁻¹H` by power iteration on
//! gradients).

use super::Scales;
use crate::assembly::Want;
use crate::energy::Potential;
use crate::math::{human, Real, Vec3};
use crate::model::Scene;

/// Checks, before anything is written, that an explicit run of `scene` makes sense and
/// bounds its work; the error names the settings keys. A vertex must be free to move; the drag
/// must keep symplectic Euler stable, `c Δt < 2` (beyond, the velocity grows by `|1 − c Δt|`
/// per step); and the steps the time limit allows, `gradient_descent_steps + max_long_times ·
/// T / Δt`, must not exceed [`crate::settings::MAX_STEPS`].
pub fn check(scene: &Scene) -> Result<(), String> {
    let cf = &scene.settings.explicit;
    let nv = scene.body.num_vertices();
    if !(0..nv).any(|v| !scene.node_fixed[v] && scene.body.mass[v] > 0.0) {
        return Err(
            "every vertex is fixed (constraint_indicators, constraints.fix_tags, \
             fix_boxes, clamp or displacement): the explicit dynamics has nothing to move"
                .into(),
        );
    }
    let sca = Scales::of(&scene.body);
    let dt = cf.time_step_prefactor * sca.dt_unit;
    for (key, p) in [
        ("explicit.damping_prefactor_dial", cf.damping_prefactor_dial),
        ("explicit.damping_prefactor_wait", cf.damping_prefactor_wait),
    ] {
        // The drag per step, c Δt = p · 2 ω_L Δt, against its limit 2.
        let per_unit = 2.0 * sca.omega_long * dt;
        // NaN fails too.
        if (p * per_unit).is_nan() || p * per_unit >= 2.0 {
            return Err(format!(
                "invalid '{key}': {p_h} gives a drag of c Δt = {} per time step (c = {p_h} × 2 \
                 ω_L, ω_L = {} rad/s, Δt = {} s); symplectic Euler's drag is unstable from c Δt \
                 = 2, so this mesh and time step allow at most {}",
                human(p * per_unit),
                human(sca.omega_long),
                human(dt),
                human(2.0 / per_unit),
                p_h = crate::math::human(p)
            ));
        }
    }
    let steps = cf.gradient_descent_steps as Real + cf.max_long_times * sca.long_time / dt;
    let max = crate::settings::MAX_STEPS;
    if steps.is_nan() || steps > max {
        return Err(format!(
            "invalid 'explicit.max_long_times': {} long times of T = {} s at the time step Δt = \
             {} s (explicit.time_step_prefactor = {}) is {} steps, more than {max_h}. T/Δt is \
             set by the mesh and the material (thinnest thickness {} m, from \
             material.thickness or the mesh's ref_thicknesses; smallest altitude {} m; sample \
             length {} m): lower explicit.max_long_times, raise explicit.time_step_prefactor \
             up to the mesh's limit, or coarsen the mesh",
            cf.max_long_times,
            human(sca.long_time),
            human(dt),
            cf.time_step_prefactor,
            human(steps),
            human(sca.t),
            human(sca.a_min),
            human(sca.length),
            max_h = crate::math::human(max)
        ));
    }
    Ok(())
}

/// The largest eigenvalue `ω_max²` of `M⁻¹H` at `x` (1/s²), by power iteration on the
/// mass-scaled Hessian `M^{-½} H M^{-½}` applied by central differences of the gradient
/// (`iterations` gradient pairs). Fixed vertices and vertices without mass are left out.
pub fn max_frequency_squared(pot: &Potential, x: &[Vec3], iterations: usize) -> Real {
    let sc = pot.body;
    let n = x.len();
    let free: Vec<bool> = (0..n)
        .map(|v| !pot.node_fixed[v] && pot.mass[v] > 0.0)
        .collect();
    let inv_sqrt_m: Vec<Real> = (0..n)
        .map(|v| {
            if free[v] {
                1.0 / pot.mass[v].sqrt()
            } else {
                0.0
            }
        })
        .collect();
    // A deterministic start with every component nonzero.
    let mut z: Vec<Vec3> = (0..n)
        .map(|v| {
            let s = (v as Real + 1.0) * 0.618_033_988_749_895;
            let f = |k: Real| ((s * k).fract() - 0.5) * if free[v] { 1.0 } else { 0.0 };
            Vec3::new(f(1.0), f(7.0), f(13.0))
        })
        .collect();
    let size = sc.mesh.bbox_diagonal();
    let (mut xp, mut xm) = (x.to_vec(), x.to_vec());
    let (mut gp, mut gm) = (vec![0.0; 3 * n], vec![0.0; 3 * n]);
    let mut lambda = 0.0;
    for _ in 0..iterations {
        let zn = z.iter().map(|v| v.norm_squared()).sum::<Real>().sqrt();
        if zn == 0.0 {
            return 0.0;
        }
        let zhat: Vec<Vec3> = z.iter().map(|z| z / zn).collect();
        let u: Vec<Vec3> = zhat.iter().zip(&inv_sqrt_m).map(|(z, s)| z * *s).collect();
        let un = u.iter().map(|u| u.amax()).fold(0.0, Real::max);
        let eps = 1e-7 * size / un.max(Real::MIN_POSITIVE);
        for v in 0..n {
            xp[v] = x[v] + u[v] * eps;
            xm[v] = x[v] - u[v] * eps;
        }
        gp.iter_mut().for_each(|g| *g = 0.0);
        gm.iter_mut().for_each(|g| *g = 0.0);
        pot.eval(&xp, &[], Want::Gradient, &mut gp, &mut []);
        pot.eval(&xm, &[], Want::Gradient, &mut gm, &mut []);
        let mut rq = 0.0;
        for v in 0..n {
            let hu = Vec3::new(
                gp[3 * v] - gm[3 * v],
                gp[3 * v + 1] - gm[3 * v + 1],
                gp[3 * v + 2] - gm[3 * v + 2],
            ) / (2.0 * eps);
            z[v] = hu * inv_sqrt_m[v];
            rq += z[v].dot(&zhat[v]);
        }
        // The Rayleigh quotient ẑᵀ M^{-½} H M^{-½} ẑ of the unit vector ẑ.
        lambda = rq;
    }
    lambda
}
