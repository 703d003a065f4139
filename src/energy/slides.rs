//! Glass slides (seed 001 §12): two horizontal planes squeezing the sheet, the lower one fixed at
//! `z = z_l`, the upper one at `z = z_u` moved at a prescribed speed or pressed by a prescribed
//! force. A vertex beyond a slide by `d` feels a stiff spring, MorphoShell's per-node penalty
//!
//! `E_v = ½ k [(z − z_u)₊² + (z_l − z)₊²]`,   `k = p_k μ t`
//!
//! (μ, t the smallest shear modulus and thickness; N/m; gradient `k(z − z_u)₊ − k(z_l − z)₊`
//! along z, Hessian `k` on zz while in contact). DOF order: `x[v]`.
//!
//! **Friction** (explicit mode, [`crate::energy::term::ExplicitHooks::explicit_step`]): Coulomb
//! stick/slip on a vertex in contact, normal force `N = k d`, mass m. With `v*` the in-plane
//! velocity the step would reach without friction (elastic and other forces, drag excluded), the
//! vertex sticks when friction can stop it within the step, `|v*| ≤ Δt μ_f N / m` (its in-plane
//! force and velocity are set to 0; at rest this is MorphoShell's `|f_h| < μ_f N`), else it
//! slides with the force `μ_f N v*/|v*|` against that velocity, so friction only dissipates.
//!
//! **Contact damping** (explicit mode; `contact_damping` ζ, default 1): a dashpot
//! `c = ζ 2√(k m)` on the normal velocity `w = v_z − v_slide` of a vertex in contact relative to
//! the slide it touches, ζ the fraction of critical damping of the vertex on its penalty spring,
//! applied implicitly (`w' = w*/(1 + Δt c/m)`, stable for any ζ). It acts only on motion into
//! or out of a slide, so equilibria are unchanged; it damps the stiff vertical oscillations
//! that the global drag, tuned to the slowest bending mode, leaves alive.
//!
//! **Motion** (explicit mode; with `after_dial` only once the dial has reached 1): speed control
//! moves the upper slide down at `speed` until it has moved `travel`; force control moves it overdamped, `ζ dz_u/dt = F_up − F`, with `F_up` the
//! sheet's push on it, F the prescribed downward force and ζ the drag (default: the sheet's mass
//! times its waiting drag rate), integrated by backward Euler (unconditionally stable; the
//! explicit update pumps energy into the sheet once the contact is stiff against ζ/Δt). The implicit modes hold both slides still (frictionless).
//! A moved slide stops at the lower one. A pressed slide does not: the penalty acts on the
//! mid-surface, so a sheet lying flat between the slides carries the force only with the upper
//! plane below the lower one by the penalty's give, `2F/(n k)` for n vertices, each pushed from
//! both sides (clamped at the lower slide, the upper one would sit in an empty gap with no
//! contact and the force unbalanced). The explicit driver's equilibrium test requires the
//! balance `F_up = F` ([`crate::energy::term::ExplicitHooks::explicit_unbalanced`]); a pressed slide
//! that no free vertex touches while below the lower slide has passed the sheet, and the run
//! stops with that reason.
//!
//! `log.csv` gets the slides' heights, the gap and the forces on each, computed from the state
//! of the frame (never accumulated across steps).

use super::term::{VertexKernel, VertexTerm};
use crate::body::Body;
use crate::energy::Potential;
use crate::math::{Mat3, Real, Vec3};
use crate::mesh::MeshError;
use crate::settings::SlideControl;

/// The slides' kernel. Its state ([`crate::energy::term::Stateful`], under the name `slides`)
/// is the upper slide's height (m) and its velocity over the current step (m/s).
pub struct Slides {
    /// Spring constant k (N/m).
    pub k: Real,
    /// Lower slide height (m).
    pub lower: Real,
    /// Upper slide's starting height (m).
    pub upper0: Real,
    /// Coulomb coefficient.
    pub friction: Real,
    /// Normal contact damping, a fraction of critical.
    pub contact_damping: Real,
    /// Speed or force control.
    pub control: SlideControl,
    /// Downward speed (m/s) and the distance to travel (m).
    pub speed: Real,
    /// See `speed`.
    pub travel: Real,
    /// Downward force (N) and drag (N·s/m) of force control.
    pub force: Real,
    /// See `force`.
    pub drag: Real,
    /// The upper slide stays still until the dial reaches 1.
    pub after_dial: bool,
}

/// The name of the slides' term and state.
const NAME: &str = "slides";

impl Slides {
    /// The upper slide's height (m) and velocity (m/s) that `pot` is evaluated with.
    pub fn upper(pot: &Potential) -> (Real, Real) {
        match pot.term_state(NAME) {
            [z, v] => (*z, *v),
            _ => (Real::NAN, 0.0),
        }
    }

    /// Penetrations beyond the upper slide at height `upper` and the lower slide (m, ≥ 0).
    #[inline]
    fn depths(&self, upper: Real, z: Real) -> (Real, Real) {
        ((z - upper).max(0.0), (self.lower - z).max(0.0))
    }

    /// Total forces (N) the sheet at positions `x` exerts on the upper slide at height `upper`
    /// (upward) and on the lower one (downward).
    pub fn forces(&self, upper: Real, x: &[Vec3], fixed: &[bool]) -> (Real, Real) {
        let (mut up, mut down) = (0.0, 0.0);
        for (v, p) in x.iter().enumerate() {
            if !fixed[v] {
                let (du, dl) = self.depths(upper, p.z);
                up += self.k * du;
                down += self.k * dl;
            }
        }
        (up, down)
    }
}

impl Slides {
    /// The force-controlled slide's next height: backward Euler of `ζ dz/dt = F_up(z) − F`
    /// over `dt` with the sheet at `x`, `F_up(z) = Σ k (x_z − z)₊`. Forward Euler is unstable
    /// once `dt Σk/ζ > 2` (a few nodes in contact with MorphoShell's stiffness suffice), and the
    /// slide then pumps energy into the sheet. `h(z) = ζ(z − z₀)/dt − F_up(z) + F` is increasing
    /// and concave (F_up is convex, piecewise linear), so Newton from `z₀` lands left of the
    /// root after one step and then climbs to it monotonically, exactly after as many steps as
    /// contact changes.
    fn pressed(&self, x: &[Vec3], fixed: &[bool], z0: Real, dt: Real) -> Real {
        let rate = self.drag / dt;
        let mut z = z0;
        for _ in 0..64 {
            let (mut push, mut slope) = (0.0, rate);
            for (p, &f) in x.iter().zip(fixed) {
                if !f && p.z > z {
                    push += self.k * (p.z - z);
                    slope += self.k;
                }
            }
            let h = rate * (z - z0) - push + self.force;
            let step = h / slope;
            z -= step;
            if step.abs() <= 1e-15 * (1.0 + z.abs()) {
                break;
            }
        }
        z
    }
}

impl VertexKernel for Slides {
    /// The penalties of both slides, the upper one at its height `own[0]`.
    #[inline]
    fn eval(&self, _: &Potential, own: &[Real], _: usize, x: &Vec3) -> Option<(Real, Vec3, Mat3)> {
        let upper = own.first().copied().unwrap_or(Real::NAN);
        let (du, dl) = self.depths(upper, x.z);
        if du == 0.0 && dl == 0.0 {
            return None;
        }
        let mut h = Mat3::zeros();
        h[(2, 2)] = self.k;
        Some((
            0.5 * self.k * (du * du + dl * dl),
            Vec3::new(0.0, 0.0, self.k * (du - dl)),
            h,
        ))
    }

    fn observables(&self, pot: &Potential, x: &[Vec3]) -> Vec<(String, Real)> {
        let upper = Self::upper(pot).0;
        let (up, down) = self.forces(upper, x, &pot.body.fixed);
        vec![
            ("slide_upper_z".into(), upper),
            ("slide_lower_z".into(), self.lower),
            ("slide_gap".into(), upper - self.lower),
            ("slide_upper_force".into(), up),
            ("slide_lower_force".into(), down),
        ]
    }

    fn explicit_hooks(&self) -> bool {
        true
    }

    /// A pressed slide is balanced when the sheet pushes back with the prescribed force. One
    /// that no free vertex touches any more while below the lower slide has passed the sheet:
    /// nothing can carry its force.
    fn explicit_unbalanced(&self, pot: &Potential, x: &[Vec3]) -> Result<Real, String> {
        if self.control != SlideControl::Force || (self.after_dial && pot.dial < 1.0) {
            return Ok(0.0);
        }
        let upper = Self::upper(pot).0;
        let (up, _) = self.forces(upper, x, &pot.body.fixed);
        if up == 0.0 && self.force > 0.0 && upper < self.lower {
            return Err(format!(
                "slides: the force-controlled upper slide (slides.force = {} N) has passed every \
                 free vertex of the sheet and the lower slide (upper z = {} m, lower z = {} \
                 m): nothing carries its force",
                crate::math::human(self.force),
                crate::math::human(upper),
                crate::math::human(self.lower)
            ));
        }
        Ok((self.force - up).abs())
    }

    fn explicit_step(&self, pot: &Potential, x: &[Vec3], v: &mut [Vec3], g: &mut [Real], dt: Real) {
        if self.friction == 0.0 && self.contact_damping == 0.0 {
            return;
        }
        let fixed = &pot.body.fixed;
        let (upper, upper_velocity) = Self::upper(pot);
        for (i, p) in x.iter().enumerate() {
            if fixed[i] {
                continue;
            }
            let (du, dl) = self.depths(upper, p.z);
            let normal = self.k * (du + dl);
            if normal == 0.0 {
                continue;
            }
            let m = pot.body.mass[i];
            if self.contact_damping > 0.0 {
                // The dashpot c = ζ 2√(km) on the normal velocity relative to the slide that
                // the step reaches, taken implicitly, w' = w*/(1 + Δt c/m): stable for any ζ.
                let c = self.contact_damping * 2.0 * (self.k * m).sqrt();
                let slide = if du > 0.0 { upper_velocity } else { 0.0 };
                let w = (v[i].z - slide - dt * g[3 * i + 2] / m) / (1.0 + dt * c / m);
                g[3 * i + 2] += c * w;
            }
            if self.friction > 0.0 {
                let limit = self.friction * normal;
                // The in-plane velocity the step would reach without friction.
                let px = v[i].x - dt * g[3 * i] / m;
                let py = v[i].y - dt * g[3 * i + 1] / m;
                let ps = px.hypot(py);
                if ps <= dt * limit / m {
                    // Friction stops the vertex within the step: it sticks.
                    g[3 * i] = 0.0;
                    g[3 * i + 1] = 0.0;
                    v[i].x = 0.0;
                    v[i].y = 0.0;
                } else {
                    // It slides, and friction opposes that velocity.
                    g[3 * i] += limit * px / ps;
                    g[3 * i + 1] += limit * py / ps;
                }
            }
        }
    }

    /// The upper slide's motion over the step, from the positions the gradient is taken at (no
    /// lag between the slide and the sheet: a slide moved from the previous positions drives a
    /// slow limit cycle through the contact).
    fn explicit_begin(&self, body: &Body, dial: Real, x: &[Vec3], dt: Real, own: &mut [Real]) {
        let fixed = &body.fixed;
        if self.after_dial && dial < 1.0 {
            own[1] = 0.0;
            return;
        }
        let z = own[0];
        let next = match self.control {
            SlideControl::Speed => {
                let bottom = self.upper0 - self.travel * self.speed.signum();
                let z1 = z - self.speed * dt;
                if self.speed > 0.0 {
                    z1.max(bottom)
                } else {
                    z1.min(bottom)
                }
            }
            SlideControl::Force => self.pressed(x, fixed, z, dt),
        };
        // A slide moved to a position stops at the lower one. A pressed slide does not: the
        // contact is a penalty on the mid-surface, so a sheet lying flat between the slides
        // carries the force only with the upper plane below the lower one, by the penalty's
        // give (each vertex pushed from both sides, at the middle of the overlap).
        let next = match self.control {
            SlideControl::Speed => next.max(self.lower + 1e-12 * (1.0 + self.lower.abs())),
            SlideControl::Force => next,
        };
        own[1] = (next - z) / dt;
        own[0] = next;
    }

    /// The upper slide's height (m) and velocity (m/s): its starting height, at rest.
    fn initial_state(&self) -> Option<Vec<Real>> {
        Some(vec![self.upper0, 0.0])
    }
}

/// The slides' term when `[slides]` is enabled. A vertex starting beyond a slide is an error
/// naming it.
pub fn term(
    body: &Body,
    s: &crate::config::slides::Slides,
    explicit: &crate::config::explicit::Explicit,
) -> Result<Option<Box<dyn super::term::Term>>, MeshError> {
    if !s.enabled {
        return Ok(None);
    }
    let mesh = &body.mesh;
    let (zmin, zmax) = mesh
        .positions
        .iter()
        .fold((Real::INFINITY, Real::NEG_INFINITY), |(a, b), p| {
            (a.min(p.z), b.max(p.z))
        });
    let lower = s.lower.unwrap_or(zmin);
    let upper = s.upper.unwrap_or(zmax);
    if upper <= lower {
        return Err(mesh.invalid(format!(
            "slides: the upper slide (z = {upper}) must be above the lower one (z = {lower})"
        )));
    }
    for (v, p) in mesh.positions.iter().enumerate() {
        if p.z > upper || p.z < lower {
            return Err(mesh.invalid(format!(
                "slides: vertex {v} (z = {}) starts outside the gap between the slides \
                 (z = {lower} … {upper}); the slides must not start intersecting the sheet",
                p.z
            )));
        }
    }
    let sc = crate::scales::Scales::of(body);
    let drag = s.drag.unwrap_or_else(|| {
        let mass: Real = body.mass.iter().sum();
        let rate = explicit.damping_prefactor_wait.max(1.0) * 2.0 * sc.omega_long;
        mass * rate
    });
    let k = s.stiffness_prefactor * sc.mu * sc.t;
    Ok(Some(Box::new(VertexTerm {
        name: NAME,
        report: true,
        kernel: Slides {
            k,
            lower,
            upper0: upper,
            friction: s.friction,
            contact_damping: s.contact_damping.unwrap_or(1.0),
            control: s.control,
            speed: s.speed,
            travel: s.travel,
            force: s.force,
            drag,
            after_dial: s.after_dial,
        },
    })))
}
