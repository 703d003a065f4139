//! The explicit driver: MorphoShell's damped Newtonian dynamics (seed 001 §2, §8, §17).
//!
//! Each vertex i of lumped mass `m_i` (ρ h A / 3, reference areas) moves under the elastic and
//! external force `F_i = −∂Φ/∂x_i` and a linear viscous drag `−c m_i v_i`, integrated by
//! semi-implicit (symplectic) Euler:
//!
//! `v ← v + Δt (F/m − c v)`,   `x ← x + Δt v`.
//!
//! Only the gradient is assembled; no Hessian is built and nothing is factorised.
//!
//! ## Time step (dispersion relations)
//! With μ the smallest shear modulus, t the smallest thickness, ρ the density, ν Poisson's ratio,
//! `D = μ t³ / (6(1 − ν))` the flexural rigidity (`E t³/(12(1−ν²))` with `E = 2μ(1+ν)`) and
//! `a_min` the smallest altitude of the reference triangles:
//!
//! * in-plane waves travel at `c_s ~ √(μ/ρ)`; the shortest wave a mesh carries has a length of
//!   order `a_min`, so its angular frequency is `ω_s ~ c_s / a_min` up to a mesh- and
//!   convention-dependent factor;
//! * bending waves obey `ρ t ω² = D k⁴`, so `ω_b = √(D/(ρt)) k²` with `k ~ 2π / a_min`.
//!
//! Symplectic Euler is stable while `ω_max Δt < 2`. shellsim takes MorphoShell's rule
//!
//! `Δt = p · min(0.185 √(ρ/μ) a_min, √(ρt/D) a_min² / 2π)`,
//!
//! whose 0.185 MorphoShell calibrated so that p need not change when the stretching rather than
//! the bending bound is the smaller. The prefactor p (`explicit.time_step_prefactor`) absorbs
//! the factors of order one; its true limit depends on the mesh. The driver measures it at the
//! start: the largest eigenvalue `ω_max²` of `M⁻¹H` by power iteration on finite differences of
//! the gradient (no Hessian), giving the limit `p* = 2 / (ω_max Δt(p = 1))`, reported in
//! `summary.json` (`explicit.stable_prefactor`) and warned about when p exceeds it.
//!
//! ## Damping and time scales
//! The longest bending mode has `k = 2π / L`, with L the reference perimeter (MorphoShell's
//! sample length; for a closed surface, π × the bounding-box diagonal): `ω_L = √(D/(ρt)) k²`.
//! Critical damping of that mode is `c = 2 ω_L`; the drag rate is `c = p_d · 2 ω_L` with the
//! prefactor `p_d` of the phase (`damping_prefactor_dial` while the forms are dialled,
//! `damping_prefactor_wait` while waiting for equilibrium). The long time is the period of the
//! slowest mode, `T = max(2π/ω_L, L √(ρ/μ))`; the dial, the frame interval, the equilibrium
//! window and the run's time limit are multiples of it.
//!
//! ## Gradient-descent start
//! `explicit.gradient_descent_steps` steps of the overdamped limit `c m v = F` first
//! (`x ← x + Δt_gd F/(c m)`, velocities discarded), with `Δt_gd = c Δt² / 2`: forward Euler on
//! the overdamped dynamics is stable for `Δt_gd < 2c/ω_max²`, which `c Δt²/2` satisfies whenever
//! `Δt < 2/ω_max`.
//!
//! ## Dial, holds and the equilibrium test
//! The dial goes from 0 to 1 linearly over `dial_long_times` long times; at each of
//! `dial.holds` it stops until the sheet is at equilibrium. After dial 1 the run waits for
//! equilibrium and stops there. The default test (`"window"`) checks, once per window of
//! `window_long_times` long times: the force residual `‖∇Φ‖∞ / F` (shellsim's force scale, the
//! same as Newton's) below `force_tolerance`; the largest vertex displacement over the window
//! below `shape_tolerance` × the sheet's size; the change of Φ over the window below
//! `energy_tolerance` × |Φ|; and the kinetic energy below `energy_tolerance` × |Φ|. A shape
//! that still creeps fails the displacement test, so the test cannot fire while the shape moves.
//! `"morphoshell"` reproduces MorphoShell's test: the largest node force (drag included) below
//! `morphoshell_force_threshold` × μ t a_min and the largest speed below
//! `morphoshell_speed_threshold` × √(μ/ρ). Both include the force a term leaves unbalanced on
//! a degree of freedom it moves itself (a pressed slide, [`Term::explicit_unbalanced`]), so a
//! load the sheet does not carry is never reported as an equilibrium. Each frame's `residual`
//! (`log.csv`) is the window test's force measure at the frame's state.
//!
//! ## Bounds
//! Before anything is written ([`check`]): a vertex must be free; the drag must satisfy
//! `c Δt < 2`; and `gradient_descent_steps + max_long_times · T/Δt` at most
//! [`crate::settings::MAX_STEPS`]. The time limit is checked every step.
//!
//! [`Term::explicit_unbalanced`]: crate::energy::term::Term::explicit_unbalanced
//!
//! ## Failure
//! A state that is not finite, or a kinetic energy above 100 × μ t A (strains of order ten
//! everywhere), stops the run: `summary.json` gives the reason and the last good frame, and the
//! unstable state is never written.

use super::{Progress, RunError, Solver};
use crate::assembly::Want;
use crate::math::{human, Real, Vec3};
use crate::output::{ExplicitReport, Writer};
use crate::scene::Scene;
use crate::settings::EquilibriumTest;
use crate::solve::{Potential, State};

pub use crate::scales::Scales;

/// Checks, before anything is written, that an explicit run of `scene` makes sense and
/// bounds its work; the error names the settings keys. A vertex must be free to move; the drag
/// must keep symplectic Euler stable, `c Δt < 2` (beyond, the velocity grows by `|1 − c Δt|`
/// per step); and the steps the time limit allows, `gradient_descent_steps + max_long_times ·
/// T / Δt`, must not exceed [`crate::settings::MAX_STEPS`].
pub fn check(scene: &Scene) -> Result<(), String> {
    let cf = &scene.settings.explicit;
    let nv = scene.num_vertices();
    if !(0..nv).any(|v| !scene.node_fixed[v] && scene.mass[v] > 0.0) {
        return Err(
            "every vertex is fixed (constraint_indicators, constraints.fix_tags, \
             fix_boxes, clamp or displacement): the explicit dynamics has nothing to move"
                .into(),
        );
    }
    let sca = Scales::of(scene);
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
    let sc = pot.scene;
    let n = x.len();
    let free: Vec<bool> = (0..n)
        .map(|v| !sc.node_fixed[v] && pot.mass[v] > 0.0)
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

/// The forces of one explicit step: `g ← ∇Φ(x)` (zeroed first; N), returning Φ (J).
#[inline]
pub fn gradient(pot: &Potential, x: &[Vec3], g: &mut [Real]) -> Real {
    pot.eval(x, &[], Want::Gradient, g, &mut [])
}

/// One symplectic Euler step with drag rate `c` (1/s) and step `dt` (s):
/// `v ← v + dt (−g/m − c v)`, `x ← x + dt v`, with `inv_m` the inverse lumped masses (0 for
/// fixed vertices, which keep v = 0).
#[inline]
pub fn advance(x: &mut [Vec3], v: &mut [Vec3], g: &[Real], inv_m: &[Real], c: Real, dt: Real) {
    for (i, (xi, vi)) in x.iter_mut().zip(v.iter_mut()).enumerate() {
        let f = Vec3::new(g[3 * i], g[3 * i + 1], g[3 * i + 2]);
        advance_node(xi, vi, f, inv_m[i], c, dt);
    }
}

/// [`advance`] for one vertex with gradient `f` (N): the one place its arithmetic is written,
/// so that the fused step ([`Step`]) gives the same bits.
#[inline(always)]
fn advance_node(x: &mut Vec3, v: &mut Vec3, f: Vec3, inv_m: Real, c: Real, dt: Real) {
    if inv_m == 0.0 {
        *v = Vec3::zeros();
        return;
    }
    *v += (-f * inv_m - *v * c) * dt;
    *x += *v * dt;
}

/// A pointer for writes by several threads to entries that each belongs to one of them, with
/// the slice's length (checked in debug builds).
#[derive(Clone, Copy)]
struct Disjoint(*mut Vec3, usize);
// SAFETY: shared only by `Step::take`, whose parts write disjoint entries.
unsafe impl Send for Disjoint {}
unsafe impl Sync for Disjoint {}

impl Disjoint {
    /// Entry `u`.
    ///
    /// # Safety
    /// `u` is in bounds and no other thread touches it meanwhile.
    #[inline(always)]
    unsafe fn at<'a>(self, u: usize) -> &'a mut Vec3 {
        debug_assert!(u < self.1, "Disjoint::at({u}) beyond {}", self.1);
        unsafe { &mut *self.0.add(u) }
    }
}

/// The explicit step, `g ← ∇Φ(x)` then [`advance`], fused when it can be.
///
/// When the scene's only term goes through [`crate::assembly::assemble_elements`] and does
/// not act on the step ([`crate::energy::term::Term::acts_on_explicit_steps`]), each vertex is
/// advanced inside the gradient's parallel parts, by the part that owns it, right after that
/// part has summed its force ([`crate::assembly::assemble_elements_owned`], through
/// [`crate::solve::Potential::owned`]). The new positions go
/// into a second buffer, since other parts may still be reading the old ones, and the two are
/// swapped when the parts are done. A step is then one parallel region with no serial pass over
/// the nodes, and no core rereads the forces and positions another core has just written. The
/// arithmetic is that of the unfused step, in the same order (the force of a node is
/// `0 + Σ` of its element entries, zero where the term's mask fixes it or a DOF is pinned,
/// then [`advance`]), so both give the same bits, for any number of threads.
pub struct Step {
    /// Whether the scene allows fusing.
    fusable: bool,
    /// The other position buffer.
    next: Vec<Vec3>,
    /// Vertices in no element of the term: no part owns them, the caller advances them with
    /// no force.
    orphans: Vec<usize>,
    /// Per DOF: whether it is pinned (its force is zero).
    pinned: Vec<bool>,
}

impl Step {
    /// The step for `pot`'s scene; `fuse = false` keeps it unfused (for comparisons).
    pub fn new(pot: &Potential, fuse: bool) -> Step {
        let sc = pot.scene;
        let nv = sc.num_vertices();
        let fusable = fuse
            && sc.terms.len() == 1
            && pot.pattern.maps.len() == 1
            && !sc.terms[0].acts_on_explicit_steps();
        let mut used = vec![!fusable; nv];
        if fusable {
            let map = &pot.pattern.maps[0];
            for e in 0..map.len() {
                for &u in map.element(e) {
                    if u < nv {
                        used[u] = true;
                    }
                }
            }
        }
        let mut pinned = vec![false; pot.pattern.n];
        for &d in &sc.pinned_dofs {
            pinned[d] = true;
        }
        Step {
            fusable,
            next: if fusable {
                vec![Vec3::zeros(); nv]
            } else {
                Vec::new()
            },
            orphans: (0..nv).filter(|&u| !used[u]).collect(),
            pinned,
        }
    }

    /// Whether [`Step::take`] fuses the update into the gradient.
    pub fn fused(&self) -> bool {
        self.fusable
    }

    /// One step from positions `x` (m) with velocities `v` (m/s), drag rate `c` (1/s) and step
    /// `dt` (s), `inv_m` the inverse lumped masses (1/kg, 0 where fixed); returns Φ(x) (J).
    /// `g` is scratch: it holds ∇Φ(x) (N) after an unfused step, zeros after a fused one.
    #[allow(clippy::too_many_arguments)]
    pub fn take(
        &mut self,
        pot: &Potential,
        x: &mut Vec<Vec3>,
        v: &mut [Vec3],
        g: &mut [Real],
        inv_m: &[Real],
        c: Real,
        dt: Real,
    ) -> Real {
        if !self.fusable {
            let energy = gradient(pot, x, g);
            advance(x, v, g, inv_m, c, dt);
            return energy;
        }
        let (n, pinned) = (x.len(), &self.pinned);
        // The writes through `Disjoint` below rely on these.
        assert!(
            v.len() == n && self.next.len() == n && inv_m.len() == n && pinned.len() >= 3 * n,
            "a step built for another scene"
        );
        let (vp, np) = (
            Disjoint(v.as_mut_ptr(), v.len()),
            Disjoint(self.next.as_mut_ptr(), self.next.len()),
        );
        let old: &[Vec3] = x;
        // Whether the term's gradient handed its parts to the hook (a term that does not
        // assemble through the parts writes `g` instead).
        let taken_flag = std::sync::atomic::AtomicBool::new(false);
        let taken = &taken_flag;
        let hook = move |nodes: &[u32], sums: &[Real], fixed: &[bool]| {
            taken.store(true, std::sync::atomic::Ordering::Relaxed);
            let mut at = 0;
            for &u in nodes {
                let u = u as usize;
                if u >= n {
                    // An edge node: no position.
                    at += 1;
                    continue;
                }
                let force = |k: usize| {
                    if fixed[u] || pinned[3 * u + k] {
                        0.0
                    } else {
                        0.0 + sums[at + k]
                    }
                };
                let f = Vec3::new(force(0), force(1), force(2));
                at += 3;
                let mut xu = old[u];
                // SAFETY: each vertex is owned by one part, and only its part's hook writes
                // its velocity and new position (`Disjoint`); `v` and `next` outlive the call.
                unsafe {
                    advance_node(&mut xu, vp.at(u), f, inv_m[u], c, dt);
                    *np.at(u) = xu;
                }
            }
        };
        let fused = Potential {
            owned: Some(&hook),
            ..*pot
        };
        let energy = gradient(&fused, old, g);
        if !taken_flag.load(std::sync::atomic::Ordering::Relaxed) {
            // The term did not assemble through the parts: `g` is its gradient.
            advance(x, v, g, inv_m, c, dt);
            return energy;
        }
        for &u in &self.orphans {
            let mut xu = x[u];
            advance_node(&mut xu, &mut v[u], Vec3::zeros(), inv_m[u], c, dt);
            self.next[u] = xu;
        }
        std::mem::swap(x, &mut self.next);
        energy
    }
}

/// Where the dial is.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Phase {
    /// Dialling towards the next hold (or 1).
    Dial,
    /// Waiting for equilibrium at a hold (or at 1).
    Wait,
}

/// Why the loop ended.
enum Stop {
    /// The equilibrium test fired at dial 1.
    Converged,
    /// The state blew up: it is not written.
    Unstable(String),
    /// Interrupted, or a load that cannot balance: the state reached is written.
    Other(String),
    /// The time limit `explicit.max_long_times` was reached: the state reached is written.
    TimeLimit,
}

/// The largest force (N) a term leaves unbalanced on a degree of freedom of its own
/// ([`crate::energy::term::Term::explicit_unbalanced`]), or why one never balances.
fn unbalanced(pot: &Potential, x: &[Vec3]) -> Result<Real, String> {
    let mut worst: Real = 0.0;
    for term in pot.scene.terms.iter() {
        worst = worst.max(term.explicit_unbalanced(pot, x)?);
    }
    Ok(worst)
}

/// The residual a frame reports: the window test's force measure `‖∇Φ‖∞ / F`, the terms'
/// unbalanced forces included, at positions `x` (`g` is scratch).
fn residual_at(pot: &Potential, x: &[Vec3], g: &mut [Real]) -> Real {
    gradient(pot, x, g);
    let f = pot.scene.force_scale.max(Real::MIN_POSITIVE);
    pot.residual(g).max(unbalanced(pot, x).unwrap_or(0.0) / f)
}

/// A snapshot for the window test.
struct Window {
    x: Vec<Vec3>,
    energy: Real,
}

/// What an explicit run's frame records for an exact restart (see `DriverState`).
#[allow(clippy::too_many_arguments)]
fn saved(
    t: Real,
    dial: Real,
    phase: Phase,
    next_hold: Option<usize>,
    holds_reached: usize,
    next_frame: Real,
    steps: usize,
    gd_left: usize,
    energy_floor: Real,
    window: &Window,
) -> super::DriverState {
    let mut e = std::collections::BTreeMap::new();
    e.insert("phase".into(), if phase == Phase::Dial { 0.0 } else { 1.0 });
    e.insert("next_frame".into(), next_frame);
    e.insert("steps".into(), steps as Real);
    e.insert("gradient_descent_left".into(), gd_left as Real);
    e.insert("energy_floor".into(), energy_floor);
    if window.energy.is_finite() {
        e.insert("window_energy".into(), window.energy);
    }
    super::DriverState {
        time: t,
        dial,
        next_hold,
        holds_reached,
        explicit: e,
        window_positions: Some(window.x.iter().flat_map(|p| [p.x, p.y, p.z]).collect()),
        ..Default::default()
    }
}

pub(super) fn run_explicit(
    s: &mut Solver,
    writer: &mut Writer,
    progress: &mut dyn Progress,
    mut state: State,
    from: super::Resume,
) -> Result<(), RunError> {
    let super::Resume {
        v: v0,
        t0,
        dial: dial0,
        driver,
    } = from;
    let sc = s.scene;
    if s.changing {
        return Err(RunError::Unsupported(
            "a term's elements change during the run (Term::stencil_at), which the explicit \
             driver does not follow: use solver.mode = \"dynamic\""
                .into(),
        ));
    }
    // The pattern is fixed: the explicit driver assembles gradients only, on its elements.
    let pat = s.pattern();
    let cf = sc.settings.explicit.clone();
    let holds = sc.settings.dial.holds.clone();
    let sca = Scales::of(sc);
    let n = state.x.len();
    let dt = cf.time_step_prefactor * sca.dt_unit;
    let rate_dial = cf.damping_prefactor_dial * 2.0 * sca.omega_long;
    let rate_wait = cf.damping_prefactor_wait * 2.0 * sca.omega_long;
    let dial_time = cf.dial_long_times * sca.long_time;
    let size = sc.mesh.bbox_diagonal();
    let area: Real = (0..sc.num_faces())
        .map(|f| {
            let [a, b, c] = sc.mesh.face_positions(f);
            0.5 * (b - a).cross(&(c - a)).norm()
        })
        .sum();
    let blow_up = 100.0 * sca.mu * sca.t * area;
    let mass = &sc.mass;
    let inv_m: Vec<Real> = (0..n)
        .map(|v| {
            if !sc.node_fixed[v] && mass[v] > 0.0 {
                1.0 / mass[v]
            } else {
                0.0
            }
        })
        .collect();

    // The mesh's stability limit, measured at the start (gradient only).
    let omega2 = {
        let pot = s.potential(&pat, 0.0);
        max_frequency_squared(&pot, &state.x, 60)
    };
    let stable_prefactor = (omega2 > 0.0).then(|| 2.0 / (omega2.sqrt() * sca.dt_unit));
    if let Some(p) = stable_prefactor {
        if cf.time_step_prefactor > p {
            s.summary.warnings.push(format!(
                "explicit.time_step_prefactor = {} is above this mesh's stability limit {p:.3} \
                 (measured at the start); the run will likely blow up",
                cf.time_step_prefactor
            ));
        }
    }
    let mut report = ExplicitReport {
        time_step: dt,
        stable_prefactor,
        long_time: sca.long_time,
        damping_rate_dial: rate_dial,
        damping_rate_wait: rate_wait,
        sample_length: sca.length,
        min_altitude: sca.a_min,
        equilibrium_test: match cf.equilibrium {
            EquilibriumTest::Window => "window",
            EquilibriumTest::Morphoshell => "morphoshell",
        }
        .into(),
        microseconds_per_face_step: 0.0,
        holds_reached: 0,
    };

    // Dial from the start time (a restart resumes the linear dial; holds already passed stay
    // passed).
    let mut dial = match dial0 {
        Some(d) => d,
        None if dial_time > 0.0 => (t0 / dial_time).min(1.0),
        None => 1.0,
    };
    let mut next_hold = holds.iter().position(|&h| h > dial);
    let mut phase = if dial >= 1.0 {
        Phase::Wait
    } else {
        Phase::Dial
    };
    if dial_time == 0.0 && next_hold.is_some() {
        // Holds with an instant dial: jump to the first one and wait.
        dial = holds[next_hold.unwrap_or(0)];
        phase = Phase::Wait;
    }
    let mut holds_reached = 0;
    let mut v = v0.unwrap_or_else(|| vec![Vec3::zeros(); n]);
    let mut g = vec![0.0; pat.n];
    // The frames' residuals are taken here: `g` carries a test step's forces to its update.
    let mut scratch = vec![0.0; pat.n];
    let mut t = t0;
    let frame_interval = sca.long_time / cf.frames_per_long_time;
    let mut next_frame = t0 + frame_interval;
    let window_steps = ((cf.window_long_times * sca.long_time / dt).round() as usize).max(1);
    let t_max = cf.max_long_times * sca.long_time;
    // The energy scale of the window test: the energy itself, but at least 1e-6 of the
    // target's energy in the starting shape (a compatible target relaxes to Φ ≈ 0, where a
    // test relative to Φ alone would ask for round-off).
    let mut energy_floor = {
        let pot = s.potential(&pat, 1.0);
        1e-6 * gradient(&pot, &state.x, &mut g).abs()
    };
    let mut window = Window {
        x: state.x.clone(),
        energy: Real::NAN,
    };
    let mut gd_left = cf.gradient_descent_steps;
    let mut steps: usize = 0;
    // A restart with the driver's state resumes its exact time, phase, windows and frames.
    if let Some(d) = &driver {
        let get = |k: &str| d.explicit.get(k).copied();
        let bad = |what: &str| {
            RunError::Restart(format!("the frame's explicit state has no valid '{what}'"))
        };
        t = d.time;
        dial = d.dial.clamp(0.0, 1.0);
        next_hold = d.next_hold.filter(|&k| k < holds.len());
        holds_reached = d.holds_reached;
        phase = match get("phase") {
            Some(0.0) => Phase::Dial,
            Some(1.0) => Phase::Wait,
            _ => return Err(bad("phase")),
        };
        let count = |k: &str| match get(k) {
            Some(c) if c >= 0.0 && c.fract() == 0.0 && c < 1e15 => Ok(c as usize),
            _ => Err(bad(k)),
        };
        steps = count("steps")?;
        gd_left = count("gradient_descent_left")?;
        next_frame = get("next_frame")
            .filter(|f| f.is_finite())
            .ok_or_else(|| bad("next_frame"))?;
        energy_floor = get("energy_floor")
            .filter(|f| f.is_finite())
            .ok_or_else(|| bad("energy_floor"))?;
        window.energy = get("window_energy").unwrap_or(Real::NAN);
        match &d.window_positions {
            Some(w) if w.len() == 3 * n && w.iter().all(|c| c.is_finite()) => {
                for (i, p) in window.x.iter_mut().enumerate() {
                    *p = Vec3::new(w[3 * i], w[3 * i + 1], w[3 * i + 2]);
                }
            }
            _ => return Err(bad("window_positions")),
        }
    }
    s.summary.holds_reached = holds_reached;
    report.holds_reached = holds_reached;
    // The driver's state as a frame records it.
    macro_rules! state_now {
        () => {
            saved(
                t,
                dial,
                phase,
                next_hold,
                holds_reached,
                next_frame,
                steps,
                gd_left,
                energy_floor,
                &window,
            )
        };
    }
    {
        let pot = s.potential(&pat, dial);
        s.summary.residual = residual_at(&pot, &state.x, &mut scratch);
        s.driver = state_now!();
        s.frame(writer, &pot, &state, &v, t)?;
    }
    let clock = std::time::Instant::now();
    // The densities at a dial that stays put (holds, waiting), computed once.
    let mut frozen: Option<(Real, Vec<crate::energy::material::KoiterDensity>)> = None;
    // The steps' gradients run on a team of spinning threads: a step is too short for rayon's
    // sleeping workers to be woken twice per step (`crate::team`).
    let team = crate::team::Team::new(rayon::current_num_threads());
    let mut step = Step::new(&s.potential(&pat, dial), true);
    let stop = team.activate(|| -> Result<Stop, RunError> {
        Ok(loop {
            if let Some(f) = super::interruption("t", t) {
                break Stop::Other(f.to_string());
            }
            if phase == Phase::Wait && frozen.as_ref().is_none_or(|(d, _)| *d != dial) {
                let pot = s.potential(&pat, dial);
                frozen = Some((dial, (0..sc.num_faces()).map(|f| pot.density(f)).collect()));
            }
            let pot = Potential {
                frozen: frozen
                    .as_ref()
                    .filter(|(d, _)| *d == dial)
                    .map(|(_, v)| &v[..]),
                ..s.potential(&pat, dial)
            };
            sc.prescribe(&mut state.x, dial);
            // Terms whose own state follows the sheet (a moving slide) catch up with it first.
            for term in sc.terms.iter() {
                term.explicit_begin(&pot, &state.x, dt);
            }
            let c = if phase == Phase::Dial {
                rate_dial
            } else {
                rate_wait
            };
            let test = steps.is_multiple_of(window_steps) && steps > 0;
            // Most steps are one fused gradient-and-update; the equilibrium test needs the force
            // and the state it belongs to, the gradient-descent start its own update.
            let fused = step.fused() && gd_left == 0 && !test;
            let clock = std::time::Instant::now();
            let energy = if fused {
                step.take(&pot, &mut state.x, &mut v, &mut g, &inv_m, c, dt)
            } else {
                gradient(&pot, &state.x, &mut g)
            };
            s.summary.timing.newton.assembly += clock.elapsed().as_secs_f64();
            // Terms that act on the step itself (slide friction), before the equilibrium test sees
            // the forces (a fused step has none).
            if !fused {
                for term in sc.terms.iter() {
                    term.explicit_step(&pot, &state.x, &mut v, &mut g, dt);
                }
            }
            // The equilibrium test, once per window (before the step, at the state the force
            // belongs to).
            if test {
                let healthy = energy.is_finite()
                    && state.x.iter().all(|p| p.iter().all(|c| c.is_finite()))
                    && v.iter().all(|p| p.iter().all(|c| c.is_finite()));
                let kinetic: Real = v
                    .iter()
                    .zip(mass)
                    .map(|(v, m)| 0.5 * m * v.norm_squared())
                    .sum();
                if !healthy || kinetic > blow_up {
                    break Stop::Unstable(format!(
                        "the explicit dynamics went unstable at t = {t_h} s (energy {energy_h} J, \
                     kinetic {kinetic_h} J): lower explicit.time_step_prefactor (now {}, this \
                     mesh's measured limit {})",
                        cf.time_step_prefactor,
                        stable_prefactor.map_or("unknown".into(), |p| format!("{p:.3}")),
                        t_h = crate::math::human(t),
                        energy_h = crate::math::human(energy),
                        kinetic_h = crate::math::human(kinetic)
                    ));
                }
                // A load the sheet can never balance (a pressed slide past the sheet) stops the
                // run; one not balanced yet keeps it going.
                let unbalanced = match unbalanced(&pot, &state.x) {
                    Ok(f) => f,
                    Err(why) => break Stop::Other(why),
                };
                let at_rest = phase == Phase::Wait
                    && match cf.equilibrium {
                        EquilibriumTest::Window => {
                            let force_scale = sc.force_scale.max(Real::MIN_POSITIVE);
                            let r = pot.residual(&g).max(unbalanced / force_scale);
                            let moved = state
                                .x
                                .iter()
                                .zip(&window.x)
                                .map(|(a, b)| (a - b).norm())
                                .fold(0.0, Real::max);
                            let scale = energy.abs().max(energy_floor).max(Real::MIN_POSITIVE);
                            r <= cf.force_tolerance
                                && moved <= cf.shape_tolerance * size
                                && (energy - window.energy).abs() <= cf.energy_tolerance * scale
                                && kinetic <= cf.energy_tolerance * scale
                        }
                        EquilibriumTest::Morphoshell => {
                            let (mut fmax, mut vmax): (Real, Real) = (0.0, 0.0);
                            for i in 0..n {
                                if inv_m[i] == 0.0 {
                                    continue;
                                }
                                let f = -Vec3::new(g[3 * i], g[3 * i + 1], g[3 * i + 2])
                                    - v[i] * (c * mass[i]);
                                fmax = fmax.max(f.norm());
                                vmax = vmax.max(v[i].norm());
                            }
                            fmax = fmax.max(unbalanced);
                            fmax / (sca.mu * sca.t * sca.a_min) < cf.morphoshell_force_threshold
                                && vmax / (sca.mu / sca.rho).sqrt() < cf.morphoshell_speed_threshold
                        }
                    };
                window.x.copy_from_slice(&state.x);
                window.energy = energy;
                if at_rest {
                    if dial >= 1.0 {
                        break Stop::Converged;
                    }
                    holds_reached += 1;
                    report.holds_reached = holds_reached;
                    s.summary.holds_reached = holds_reached;
                    phase = Phase::Dial;
                    let pot = s.potential(&pat, dial);
                    s.summary.residual = residual_at(&pot, &state.x, &mut scratch);
                    next_frame = t + frame_interval;
                    s.driver = state_now!();
                    s.frame(writer, &pot, &state, &v, t)?;
                }
            }
            // The step.
            if gd_left > 0 {
                let cg = c.max(Real::MIN_POSITIVE);
                let h = cg * dt * dt / 2.0;
                for i in 0..n {
                    let f = Vec3::new(g[3 * i], g[3 * i + 1], g[3 * i + 2]);
                    v[i] = -f * (inv_m[i] / cg);
                    state.x[i] += v[i] * h;
                }
                gd_left -= 1;
                if gd_left == 0 {
                    v.iter_mut().for_each(|v| *v = Vec3::zeros());
                }
            } else if !fused {
                advance(&mut state.x, &mut v, &g, &inv_m, c, dt);
            }
            t += dt;
            steps += 1;
            s.summary.steps += 1;
            // The time limit, every step (a comparison): a window longer than the time left
            // does not carry the run past it.
            if t >= t_max {
                break Stop::TimeLimit;
            }
            if phase == Phase::Dial && dial < 1.0 {
                dial = if dial_time > 0.0 {
                    (dial + dt / dial_time).min(1.0)
                } else {
                    1.0
                };
                if let Some(k) = next_hold {
                    if dial >= holds[k] {
                        dial = holds[k];
                        next_hold = (k + 1 < holds.len()).then_some(k + 1);
                        phase = Phase::Wait;
                    }
                }
                if dial >= 1.0 {
                    phase = Phase::Wait;
                }
            }
            if t >= next_frame {
                let pot = s.potential(&pat, dial);
                let healthy = state.x.iter().all(|p| p.iter().all(|c| c.is_finite()));
                if !healthy {
                    break Stop::Unstable(format!(
                        "the explicit dynamics went unstable at t = {t_h} s (a position is not \
                     finite): lower explicit.time_step_prefactor (now {})",
                        cf.time_step_prefactor,
                        t_h = crate::math::human(t)
                    ));
                }
                s.summary.residual = residual_at(&pot, &state.x, &mut scratch);
                next_frame += frame_interval;
                s.driver = state_now!();
                s.frame(writer, &pot, &state, &v, t)?;
                progress.update(
                    if phase == Phase::Dial {
                        0.5 * dial
                    } else {
                        0.5 + 0.5 * (t / t_max).min(1.0)
                    },
                    &format!(
                        "explicit {}  t {} s  dt {} s  dial {}  E {} J",
                        if phase == Phase::Dial {
                            "dialling"
                        } else {
                            "waiting"
                        },
                        human(t),
                        human(dt),
                        human(dial),
                        human(energy)
                    ),
                );
            }
        })
    })?;
    drop(team);
    let wall = clock.elapsed().as_secs_f64();
    report.microseconds_per_face_step =
        1e6 * wall / (steps.max(1) as Real * sc.num_faces() as Real);
    let pot = s.potential(&pat, dial);
    s.summary.residual = residual_at(&pot, &state.x, &mut scratch);
    s.summary.time = Some(t);
    s.summary.dial = dial;
    s.summary.explicit = Some(report);
    s.driver = state_now!();
    match stop {
        Stop::Converged => {
            s.summary.converged = true;
            s.summary.energy = Writer::energies(&pot, &state, &v);
            s.frame(writer, &pot, &state, &v, t)?;
        }
        Stop::Unstable(reason) => {
            s.summary.converged = false;
            s.summary.residual = Real::NAN;
            s.summary.reason = format!(
                "{reason}; the run stopped, last good frame {}",
                writer.last_frame()
            );
        }
        Stop::Other(_) | Stop::TimeLimit => {
            s.summary.converged = false;
            s.summary.reason = match stop {
                Stop::Other(reason) => reason,
                _ => format!(
                    "no equilibrium after explicit.max_long_times = {} long times ({t_h} s); \
                     residual {}",
                    cf.max_long_times,
                    crate::math::human(s.summary.residual),
                    t_h = crate::math::human(t)
                ),
            };
            s.summary.energy = Writer::energies(&pot, &state, &v);
            s.frame(writer, &pot, &state, &v, t)?;
        }
    }
    Ok(())
}
