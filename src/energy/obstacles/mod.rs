//! Rigid obstacles (`[[obstacles]]`): spheres, capsules, infinite cylinders, planes and boxes,
//! fixed or moved with the dial, that the sheet's surfaces rest on or are pressed by. One file
//! per shape gives its signed distance `d(x)` with `∇d` and `∇²d` ([`Distance`]); this term
//! turns them into the ground's smoothed one-sided penalty ([`crate::contact`]).
//!
//! **Energy.** Vertex `v`'s gap to obstacle `o` is `g = d_o(x_v − s u_o) − h_v/2`, with `u_o`
//! the obstacle's `displacement`, `s` the dial (clamped to [0, 1]) and `h_v` the mean thickness
//! of the faces around `v` (the sheet's surface, not its mid-surface, touches). With the
//! penetration `p = max(0, −g)`:
//!
//! `E = Σ_o Σ_v k_o A_v ψ(p)`,
//! `∂E/∂x_v = −k_o A_v ψ′(p) ∇d`, `∂²E/∂x_v² = k_o A_v (ψ″(p) ∇d∇dᵀ − ψ′(p) ∇²d)`,
//!
//! `ψ` the C² penalty of [`crate::contact::penalty`] with smoothing δ, `A_v` the vertex's
//! reference area, `k_o` the stiffness (Pa/m). Defaults as for the ground: `k = E/h` and
//! `δ = h/100`, area-weighted over the sheet; in explicit mode `k` is at most `ρ h / Δt²`, the
//! stiffest spring the explicit step Δt resolves (ω Δt = 1, ω² = k/(ρh)). The curvature part `−ψ′∇²d` is negative
//! semi-definite on convex obstacles; the solver's Hessian handling (the adaptive projection,
//! the diagonal shift) takes care of it. A vertex term, so every driver sums it.
//!
//! **Friction** (`friction` μ > 0): in dynamic mode a second term, [`ObstacleFriction`], the
//! ground's lagged, smoothed Coulomb dissipation with the obstacle's normal; in explicit mode
//! stick/slip in the step ([`Obstacles`]' `explicit_step`), against fixed obstacles.
//!
//! **Force control** (`force`): such an obstacle is its own term, [`pressed::Pressed`], whose
//! offset along the force is a global DOF of the solve; this term skips it.
//!
//! `log.csv` gets, per obstacle `i`, the normal force it exerts on the sheet
//! (`obstacle{i}_force_x/y/z`, N) and the smallest gap (`obstacle{i}_gap`, m).
//!
//! Units: positions m, k Pa/m, A m², energies J. DOF order: `x[v]`.

pub mod capsule;
pub mod cuboid;
pub mod cylinder;
pub mod plane;
pub mod pressed;
pub mod sphere;

use super::term::{Term, VertexKernel, VertexTerm};
use crate::body::Body;
use crate::config::obstacle::{Control, Shape};
use crate::contact::{friction_potential, penalty};
use crate::energy::Potential;
use crate::math::{Mat3, Real, Vec3};
use crate::mesh::MeshError;

/// A shape's signed distance (m, negative inside), its gradient and its Hessian (1/m) at `x`.
pub trait Distance {
    /// `(d, ∇d, ∇²d)`.
    fn distance(&self, x: &Vec3) -> (Real, Vec3, Mat3);
}

/// `(r − R, w/r, (P − uuᵀ)/r)` for the offset `w` from the nearest point of a core (a point, a
/// segment, an axis), `r = ‖w‖`: the distance to a round surface of radius `R` about it. `P`
/// projects onto the directions in which the core does not extend. At `r = 0` (on the core,
/// deep inside) the direction is undefined: no gradient.
#[inline]
pub(crate) fn round_distance(w: Vec3, radius: Real, proj: &Mat3) -> (Real, Vec3, Mat3) {
    let r = w.norm();
    if r == 0.0 {
        return (-radius, Vec3::zeros(), Mat3::zeros());
    }
    let u = w / r;
    (r - radius, u, (proj - u * u.transpose()) / r)
}

/// The penalty `k A ψ(p)` of a vertex of stiffness × area `ka` at penetration `p > 0` against
/// a surface of unit normal `n` and distance Hessian `hd`, smoothing `delta`: energy (J),
/// gradient `−ka ψ′ n` (N) and Hessian `ka (ψ″ nnᵀ − ψ′ ∇²d)` (N/m) in the vertex's coordinates.
#[inline]
pub(crate) fn penalty_term(
    ka: Real,
    delta: Real,
    p: Real,
    n: &Vec3,
    hd: &Mat3,
) -> (Real, Vec3, Mat3) {
    let (psi, dpsi, ddpsi) = penalty(p, delta);
    (
        ka * psi,
        -n * (ka * dpsi),
        (n * n.transpose() * ddpsi - hd * dpsi) * ka,
    )
}

/// A validated shape, dispatched by a `match` (no virtual call per vertex).
#[derive(Clone, Copy, Debug)]
pub enum Solid {
    /// See [`sphere`].
    Sphere(sphere::Sphere),
    /// See [`capsule`].
    Capsule(capsule::Capsule),
    /// See [`cylinder`].
    Cylinder(cylinder::Cylinder),
    /// See [`plane`].
    Plane(plane::Plane),
    /// See [`cuboid`].
    Box(cuboid::Cuboid),
}

impl Solid {
    /// The body of a validated analytic shape; `None` for a mesh (its contact is the sheet's
    /// pairs with its triangles, [`crate::energy::self_contact`]).
    pub fn of(s: &Shape) -> Option<Solid> {
        let v = |a: &[Real; 3]| Vec3::from(*a);
        Some(match s {
            Shape::Sphere { center, radius } => Solid::Sphere(sphere::Sphere {
                center: v(center),
                radius: *radius,
            }),
            Shape::Capsule { a, b, radius } => Solid::Capsule(capsule::Capsule {
                a: v(a),
                b: v(b),
                radius: *radius,
            }),
            Shape::Cylinder {
                point,
                axis,
                radius,
            } => Solid::Cylinder(cylinder::Cylinder {
                point: v(point),
                axis: v(axis),
                radius: *radius,
            }),
            Shape::Plane { point, normal } => Solid::Plane(plane::Plane {
                point: v(point),
                normal: v(normal),
            }),
            Shape::Box { min, max } => Solid::Box(cuboid::Cuboid {
                min: v(min),
                max: v(max),
            }),
            Shape::Mesh => return None,
        })
    }
}

impl Distance for Solid {
    #[inline]
    fn distance(&self, x: &Vec3) -> (Real, Vec3, Mat3) {
        match self {
            Solid::Sphere(s) => s.distance(x),
            Solid::Capsule(s) => s.distance(x),
            Solid::Cylinder(s) => s.distance(x),
            Solid::Plane(s) => s.distance(x),
            Solid::Box(s) => s.distance(x),
        }
    }
}

/// One obstacle with its contact law.
#[derive(Clone, Copy, Debug)]
pub struct Obstacle {
    /// Its index in `[[obstacles]]` (the `obstacle{i}_…` columns of `log.csv`).
    pub index: usize,
    /// Coulomb coefficient μ (0: frictionless).
    pub friction: Real,
    /// Force control: the unit direction, the force at dial 1 (N) and the mass (kg, 0 when
    /// none); such an obstacle is its own term ([`pressed`]), skipped by [`Obstacles`].
    pub pressed: Option<(Vec3, Real, Real)>,
    /// Its shape at dial 0.
    pub body: Solid,
    /// Offset at dial 1 (m).
    pub displacement: Vec3,
    /// Penalty stiffness k (Pa/m).
    pub stiffness: Real,
    /// Smoothing length δ (m).
    pub smoothing: Real,
}

/// Every obstacle, with the per-vertex areas and half thicknesses.
#[derive(Clone, Debug)]
pub struct Obstacles {
    /// The obstacles.
    pub list: Vec<Obstacle>,
    /// Reference area per vertex A_v (m²).
    pub area: Vec<Real>,
    /// Half thickness per vertex h_v/2 (m).
    pub half_thickness: Vec<Real>,
    /// The sheet's area-weighted mean thickness (m).
    pub h_mean: Real,
}

impl Obstacles {
    /// Penetration, `∇d` and `∇²d` of vertex `v` at `x` against obstacle `o` at dial `s`.
    #[inline]
    fn contact(&self, o: &Obstacle, v: usize, x: &Vec3, s: Real) -> (Real, Vec3, Mat3) {
        let (d, n, h) = o.body.distance(&(x - o.displacement * s.clamp(0.0, 1.0)));
        (self.half_thickness[v] - d, n, h)
    }

    /// Whether any obstacle has friction.
    pub fn has_friction(&self) -> bool {
        self.list.iter().any(|o| o.friction > 0.0)
    }

    /// The normal force `λ = k A_v ψ′(p)` (N) on vertex `v` at `x` from obstacle `k` at dial `s`.
    #[inline]
    pub fn normal_force(&self, k: usize, v: usize, x: &Vec3, s: Real) -> Real {
        let o = &self.list[k];
        let (p, _, _) = self.contact(o, v, x, s);
        if p <= 0.0 {
            return 0.0;
        }
        self.pressure_force(o, v, p)
    }

    /// `k A_v ψ′(p)` (N): the normal force of obstacle `o` on vertex `v` at penetration `p > 0`.
    #[inline]
    fn pressure_force(&self, o: &Obstacle, v: usize, p: Real) -> Real {
        o.stiffness * self.area[v] * penalty(p, o.smoothing).1
    }
}

/// The obstacles' lagged, smoothed Coulomb friction in dynamic mode, the ground's law
/// ([`crate::contact::friction_potential`]) against each frictional obstacle `o`:
///
/// `D_v = Σ_o μ_o λ_o f₀(‖T_o (x_v − x⁰_v − u_o Δs)‖)`,
///
/// with `λ_o = k_o A_v ψ′(p)` and the tangent projector `T_o = I − n nᵀ`, `n = ∇d_o`, both taken
/// at the friction lag's iterate ([`crate::energy::potential::Friction::x_lag`]), and
/// `u_o Δs` the obstacle's own motion over the step (the slip is relative to it). Only while the
/// potential carries a [`crate::energy::potential::Friction`]. Units: N, m, J. DOF order: `x[v]`.
pub struct ObstacleFriction(pub Obstacles);

impl ObstacleFriction {
    /// Energy, gradient and Hessian of vertex `v` at `x` against obstacle `o` (module doc of
    /// [`ObstacleFriction`]); `None` out of contact at the lagged iterate.
    #[inline]
    fn one(
        &self,
        fr: &crate::energy::potential::Friction,
        dial: Real,
        o: &Obstacle,
        v: usize,
        x: &Vec3,
    ) -> Option<(Real, Vec3, [[Real; 3]; 3])> {
        let obs = &self.0;
        let (p, n, _) = obs.contact(o, v, &fr.x_lag[v], fr.dial_lag);
        if p <= 0.0 {
            return None;
        }
        let lambda = obs.pressure_force(o, v, p);
        let moved = o.displacement * (dial.clamp(0.0, 1.0) - fr.dial_prev.clamp(0.0, 1.0));
        let d = x - fr.x_prev[v] - moved;
        Some(friction_potential(o.friction * lambda, &n, &d, fr.eps))
    }
}

impl VertexKernel for ObstacleFriction {
    #[inline]
    fn eval(&self, pot: &Potential, _: &[Real], v: usize, x: &Vec3) -> Option<(Real, Vec3, Mat3)> {
        let fr = pot.friction.as_ref()?;
        let mut out: Option<(Real, Vec3, Mat3)> = None;
        for o in self.0.list.iter().filter(|o| o.friction > 0.0) {
            let Some((e, g, h)) = self.one(fr, pot.dial, o, v, x) else {
                continue;
            };
            let h = Mat3::from_fn(|r, c| h[r][c]);
            out = Some(match out {
                None => (e, g, h),
                Some((e0, g0, h0)) => (e0 + e, g0 + g, h0 + h),
            });
        }
        out
    }

    fn lags_normals(&self) -> bool {
        true
    }

    /// Over every vertex and frictional obstacle, the largest normal force at `trial` and the
    /// largest change from the lagged iterate.
    fn lag_change(&self, trial: &[Vec3], dial: Real, lag: &[Vec3], dial_lag: Real) -> (Real, Real) {
        let o = &self.0;
        let (mut scale, mut diff) = (0.0 as Real, 0.0 as Real);
        for (v, (xt, xl)) in trial.iter().zip(lag).enumerate() {
            for k in (0..o.list.len()).filter(|&k| o.list[k].friction > 0.0) {
                let new = o.normal_force(k, v, xt, dial);
                let old = o.normal_force(k, v, xl, dial_lag);
                scale = scale.max(new);
                diff = diff.max((new - old).abs());
            }
        }
        (scale, diff)
    }

    /// Per frictional obstacle `i`, the friction force it exerted on the sheet over the last
    /// step (`obstacle{i}_friction_x/y/z`, N; 0 where the frame's potential carries no step,
    /// the first frame), so that the normal and friction forces together balance the loads.
    fn observables(&self, pot: &Potential, x: &[Vec3]) -> Vec<(String, Real)> {
        let mut out = Vec::new();
        for o in &self.0.list {
            let i = o.index;
            if o.friction <= 0.0 {
                continue;
            }
            let mut f = Vec3::zeros();
            if let Some(fr) = pot.friction.as_ref() {
                for (v, xv) in x.iter().enumerate() {
                    if pot.body.fixed[v] {
                        continue;
                    }
                    if let Some((_, g, _)) = self.one(fr, pot.dial, o, v, xv) {
                        f -= g;
                    }
                }
            }
            for (k, c) in ["x", "y", "z"].iter().zip(f.iter()) {
                out.push((format!("obstacle{i}_friction_{k}"), *c));
            }
        }
        out
    }
}

impl VertexKernel for Obstacles {
    #[inline]
    fn eval(&self, pot: &Potential, _: &[Real], v: usize, x: &Vec3) -> Option<(Real, Vec3, Mat3)> {
        let mut out: Option<(Real, Vec3, Mat3)> = None;
        for o in self.list.iter().filter(|o| o.pressed.is_none()) {
            let (p, n, hd) = self.contact(o, v, x, pot.dial);
            if p <= 0.0 {
                continue;
            }
            let (e, g, h) = penalty_term(o.stiffness * self.area[v], o.smoothing, p, &n, &hd);
            out = Some(match out {
                None => (e, g, h),
                Some((e0, g0, h0)) => (e0 + e, g0 + g, h0 + h),
            });
        }
        out
    }

    /// Explicit mode: Coulomb stick/slip against each frictional obstacle, as the slides'
    /// ([`crate::energy::slides`]) with the obstacle's normal `n = ∇d`: with `N = k A_v ψ′(p)`
    /// and `v*` the velocity the step would reach, `T v*` its tangential part, the vertex sticks
    /// (its tangential force and velocity are removed) when `|T v*| ≤ Δt μ N / m`, else it
    /// slides with the force `μ N T v*/|T v*|` against that velocity.
    fn explicit_step(&self, pot: &Potential, x: &[Vec3], v: &mut [Vec3], g: &mut [Real], dt: Real) {
        let fixed = &pot.body.fixed;
        for (i, xi) in x.iter().enumerate() {
            if fixed[i] {
                continue;
            }
            for o in self.list.iter().filter(|o| o.friction > 0.0) {
                let (p, n, _) = self.contact(o, i, xi, pot.dial);
                if p <= 0.0 {
                    continue;
                }
                let limit = o.friction * o.stiffness * self.area[i] * penalty(p, o.smoothing).1;
                let m = pot.mass[i];
                let gi = Vec3::new(g[3 * i], g[3 * i + 1], g[3 * i + 2]);
                let reach = v[i] - gi * (dt / m);
                let tangential = reach - n * n.dot(&reach);
                let speed = tangential.norm();
                let gi = if speed <= dt * limit / m {
                    // Friction stops the vertex within the step: it sticks.
                    v[i] = n * n.dot(&v[i]);
                    n * n.dot(&gi)
                } else {
                    // It slides, and friction opposes that velocity.
                    gi + tangential * (limit / speed)
                };
                g[3 * i..3 * i + 3].copy_from_slice(gi.as_slice());
            }
        }
    }

    fn explicit_hooks(&self) -> bool {
        self.has_friction()
    }

    fn observables(&self, pot: &Potential, x: &[Vec3]) -> Vec<(String, Real)> {
        let mut out = Vec::new();
        for o in &self.list {
            let i = o.index;
            if o.pressed.is_some() {
                continue;
            }
            let (mut f, mut gap) = (Vec3::zeros(), Real::INFINITY);
            for (v, xv) in x.iter().enumerate() {
                if self.area[v] == 0.0 {
                    continue;
                }
                let (p, n, _) = self.contact(o, v, xv, pot.dial);
                gap = gap.min(-p);
                if p > 0.0 {
                    f += n * self.pressure_force(o, v, p);
                }
            }
            for (k, c) in ["x", "y", "z"].iter().zip(f.iter()) {
                out.push((format!("obstacle{i}_force_{k}"), *c));
            }
            out.push((format!("obstacle{i}_gap"), gap));
        }
        out
    }
}

/// The obstacles of a scene with `[[obstacles]]`, else `None`. Errors name the obstacle and
/// the vertex: a shape that starts closer to a vertex than half its thickness (inside the
/// sheet; touching, to 1e-9 of the half thickness, is allowed).
pub fn build(
    body: &Body,
    list: &[crate::config::obstacle::ObstacleSettings],
    mode: crate::settings::Mode,
    explicit: &crate::config::explicit::Explicit,
) -> Result<Option<Obstacles>, MeshError> {
    if list
        .iter()
        .all(|o| o.shape == Some(crate::config::obstacle::ShapeKind::Mesh))
    {
        return Ok(None);
    }
    let mesh = &body.mesh;
    let nv = mesh.positions.len();
    let c = crate::body::ContactAreas::of(mesh, &body.thickness, &body.young);
    // The explicit step Δt resolves a vertex spring k A_v with ω Δt ≤ 2, ω² = k A_v / m_v =
    // k / (ρ h): the default stiffness there is ρ h / Δt² (ω Δt = 1) when it is below E/h.
    let mut k_default = c.e_over_h;
    if mode == crate::settings::Mode::Explicit {
        let dt = explicit.time_step_prefactor * crate::scales::Scales::of(body).dt_unit;
        let rho_h = body.density * c.h_mean;
        k_default = k_default.min(rho_h / (dt * dt));
    }
    let mut obstacles = Vec::with_capacity(list.len());
    for (i, o) in list.iter().enumerate() {
        let invalid = |e: crate::config::Invalid| mesh.invalid(format!("{}: {}", e.key, e.reason));
        let shape = o.shape(i).map_err(invalid)?;
        let Some(body) = Solid::of(&shape) else {
            continue;
        };
        let pressed = match o.control(i).map_err(invalid)? {
            Control::Moved(_) => None,
            Control::Pressed {
                direction,
                magnitude,
                mass,
            } => Some((Vec3::from(direction), magnitude, mass.unwrap_or(0.0))),
        };
        obstacles.push(Obstacle {
            index: i,
            pressed,
            body,
            displacement: Vec3::from(o.displacement),
            stiffness: o.stiffness.unwrap_or(k_default),
            smoothing: o.smoothing.unwrap_or(c.h_mean / 100.0),
            friction: o.friction,
        });
    }
    let term = Obstacles {
        list: obstacles,
        area: c.area,
        half_thickness: c.half_thickness,
        h_mean: c.h_mean,
    };
    for o in &term.list {
        let i = o.index;
        for v in (0..nv).filter(|&v| term.area[v] > 0.0) {
            let (p, _, _) = term.contact(o, v, &mesh.positions[v], 0.0);
            // Touching is allowed (up to round-off of the half thickness).
            if p > 1e-9 * term.half_thickness[v] {
                let x = mesh.positions[v];
                return Err(mesh.invalid(format!(
                    "obstacles[{i}] starts inside the sheet: vertex {v} at ({}, {}, {}) is {} m \
                     inside its surface offset by half the thickness ({} m); move the obstacle \
                     away or let its displacement bring it in",
                    crate::math::human(x.x),
                    crate::math::human(x.y),
                    crate::math::human(x.z),
                    crate::math::human(p),
                    crate::math::human(term.half_thickness[v])
                )));
            }
        }
    }
    Ok(Some(term))
}

/// The terms of a scene with `[[obstacles]]`: their contact (with explicit stick/slip), and in
/// dynamic mode their friction when any has some.
pub fn terms(
    body: &Body,
    list: &[crate::config::obstacle::ObstacleSettings],
    mode: crate::settings::Mode,
    explicit: &crate::config::explicit::Explicit,
) -> Result<Vec<Box<dyn Term>>, MeshError> {
    let Some(obstacles) = build(body, list, mode, explicit)? else {
        return Ok(Vec::new());
    };
    let pressed: Vec<Box<dyn Term>> = obstacles
        .list
        .iter()
        .filter_map(|o| {
            let (direction, force, mass) = o.pressed?;
            Some(Box::new(pressed::Pressed {
                index: o.index,
                body: o.body,
                direction,
                force,
                mass,
                stiffness: o.stiffness,
                smoothing: o.smoothing,
                sheet: Obstacles {
                    list: Vec::new(),
                    area: obstacles.area.clone(),
                    half_thickness: obstacles.half_thickness.clone(),
                    h_mean: obstacles.h_mean,
                },
                max_step: obstacles.h_mean / 2.0,
                node: usize::MAX,
            }) as Box<dyn Term>)
        })
        .collect();
    let dynamic = mode == crate::settings::Mode::Dynamic;
    let friction =
        (dynamic && obstacles.has_friction()).then(|| ObstacleFriction(obstacles.clone()));
    let mut t: Vec<Box<dyn Term>> = vec![Box::new(VertexTerm {
        name: "obstacles",
        report: true,
        kernel: obstacles,
    })];
    if let Some(kernel) = friction {
        t.push(Box::new(VertexTerm {
            name: "obstacle_friction",
            report: false,
            kernel,
        }));
    }
    t.extend(pressed);
    Ok(t)
}
