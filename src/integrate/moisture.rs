//! The moisture coupling of a dynamic run: the prism-FEM diffusion, the rest forms and wet
//! masses it sets each step, and the ground exchange switched by contact.

use super::RunError;
use super::Sink;
use crate::body::Body;
use crate::energy::Potential;
use crate::math::{Real, Sym2, Vec3};
use crate::model::Scene;

/// The per-face fields moisture adds to frames: the content at the top and the bottom face.
pub const FRAME_FIELDS: [&str; 2] = ["moisture_top", "moisture_bottom"];

/// The moisture diffusion of a dynamic run and the rest forms it drives.
pub(super) struct Moisture {
    pub(super) diffusion: crate::diffusion::Diffusion,
    /// Nodal moisture at the last accepted step, and the trial of the current one.
    pub(super) u: Vec<Real>,
    pub(super) trial: Vec<Real>,
    /// Largest nodal change of the last trial step.
    pub(super) change: Real,
    /// Lumped vertex masses with the absorbed water, at `u` and at `trial` (empty when
    /// `moisture.water_density = 0`).
    pub(super) mass: Vec<Real>,
    pub(super) trial_mass: Vec<Real>,
    /// `[moisture.ground]`: each face's own conditions (top, bottom), the ground's
    /// `(k, value, distance)`, and which sides currently touch it.
    pub(super) base: Vec<[crate::diffusion::SurfaceBc; 2]>,
    pub(super) taped: Vec<[bool; 2]>,
    /// Sides covered by tape (top, bottom): the growth law sees moisture 0 there.
    pub(super) tape: Vec<[bool; 2]>,
    pub(super) ground: Option<(Real, Real, Real)>,
    /// Density of the absorbed water (kg/m³; 0 = masses stay dry).
    water_density: Real,
    pub(super) touching: Vec<[bool; 2]>,
}

impl Moisture {
    /// Builds the diffusion system of a scene with `moisture.enabled` (None otherwise).
    pub(super) fn new(sc: &Scene) -> Result<Option<Self>, RunError> {
        use crate::diffusion::{Diffusion, Diffusivity, Layering, Side, SurfaceBc};
        use crate::settings::{SurfaceKind, SurfaceSide};
        let mo = &sc.settings.moisture;
        if !mo.enabled {
            return Ok(None);
        }
        let dirs: Vec<Vec3> = sc.body.growth.direction.iter().map(|d| d.1).collect();
        let mut diffusion = Diffusion::new(
            &sc.body.mesh.positions,
            &sc.body.mesh.faces,
            &sc.body.thickness,
            &dirs,
            Diffusivity {
                along: mo.diffusivity_along,
                across: mo.diffusivity_across,
                through: mo.diffusivity_through,
            },
            Layering {
                count: mo.layers,
                grading: mo.grading,
            },
        )?;
        // Sides sealed on purpose (tape): the ground exchange leaves them sealed.
        let mut taped = vec![[false; 2]; sc.body.num_faces()];
        // Sides covered by tape (`tape = true`): a non-swelling layer for the growth law.
        let mut tape = vec![[false; 2]; sc.body.num_faces()];
        for b in &mo.boundary {
            let side = match b.side {
                SurfaceSide::Top => Side::Top,
                SurfaceSide::Bottom => Side::Bottom,
            };
            let bc = match b.kind {
                SurfaceKind::Sealed => SurfaceBc::Sealed,
                SurfaceKind::Value => SurfaceBc::Value(b.value),
                SurfaceKind::Flux => SurfaceBc::Flux(b.value),
                SurfaceKind::Robin => SurfaceBc::Robin {
                    k: b.k,
                    ambient: b.ambient,
                },
            };
            let faces = crate::body::region_faces(&sc.body.mesh, b)?;
            for f in faces {
                diffusion.set_surface(f, side, bc)?;
                if bc == SurfaceBc::Sealed {
                    taped[f][side as usize] = true;
                }
                if b.tape {
                    tape[f][side as usize] = true;
                }
            }
        }
        let u = vec![mo.initial; diffusion.num_nodes()];
        let nf = sc.body.num_faces();
        let base = (0..nf)
            .map(|f| {
                [
                    diffusion.surface(f, Side::Top),
                    diffusion.surface(f, Side::Bottom),
                ]
            })
            .collect();
        let h_mean = sc.body.thickness.iter().sum::<Real>() / nf.max(1) as Real;
        let ground = mo
            .ground
            .as_ref()
            .map(|g| (g.k, g.value, g.distance.or(h_mean)));
        let mut m = Moisture {
            trial: u.clone(),
            u,
            diffusion,
            change: 0.0,
            mass: Vec::new(),
            trial_mass: Vec::new(),
            base,
            taped,
            tape,
            ground,
            water_density: mo.water_density,
            touching: vec![[false; 2]; nf],
        };
        m.mass = m.masses_of(&sc.body, &m.u);
        m.trial_mass = m.mass.clone();
        Ok(Some(m))
    }

    /// The diffusion's error tolerance: `moisture.tolerance` relative, with an absolute floor
    /// of `10⁻³` of it times the moisture scale (the largest of the initial moisture, every
    /// prescribed, ambient and ground moisture, and the current largest nodal value), so that
    /// nodes the moisture has not yet reached do not hold the sub-steps down.
    pub(super) fn tolerance(&self, sc: &Scene) -> crate::diffusion::Tolerance {
        use crate::settings::SurfaceKind;
        let mo = &sc.settings.moisture;
        let mut scale = mo.initial.abs();
        for b in &mo.boundary {
            match b.kind {
                SurfaceKind::Value => scale = scale.max(b.value.abs()),
                SurfaceKind::Robin => scale = scale.max(b.ambient.abs()),
                SurfaceKind::Flux | SurfaceKind::Sealed => {}
            }
        }
        if let Some(g) = &mo.ground {
            scale = scale.max(g.value.abs());
        }
        let now = self.u.iter().fold(0.0, |m: Real, u| m.max(u.abs()));
        crate::diffusion::Tolerance {
            rtol: mo.tolerance,
            atol: 1e-3 * mo.tolerance * scale.max(now).max(Real::MIN_POSITIVE),
        }
    }

    /// Switches the ground exchange of every face side on or off from the positions `x`: a side
    /// touches when it faces the ground (its outward normal within 60° of the ground's inward
    /// one) and the face's centroid is within `distance` of the ground, thickness included.
    pub(super) fn update_ground(
        &mut self,
        sc: &Scene,
        x: &[Vec3],
    ) -> Result<(), crate::diffusion::SurfaceError> {
        use crate::diffusion::{Side, SurfaceBc};
        let (Some((k, value, distance)), Some(g)) = (self.ground, &sc.body.ground) else {
            return Ok(());
        };
        for (f, face) in sc.body.mesh.faces.iter().enumerate() {
            let [p0, p1, p2] = face.map(|v| x[v]);
            let n = (p1 - p0).cross(&(p2 - p0)).normalize();
            let c = (p0 + p1 + p2) / 3.0;
            let facing = n.dot(&g.normal);
            let gap = g.normal.dot(&(c - g.point)) - 0.5 * sc.body.thickness[f] * facing.abs();
            let near = gap <= distance && facing.abs() >= 0.5;
            // The top (+n) faces the ground when n points into it.
            let touch = [near && facing < 0.0, near && facing > 0.0];
            for (s, side) in [Side::Top, Side::Bottom].into_iter().enumerate() {
                if touch[s] == self.touching[f][s] {
                    continue;
                }
                let base = self.base[f][s];
                if self.taped[f][s] || matches!(base, SurfaceBc::Value(_)) {
                    continue;
                }
                let bc = if touch[s] {
                    SurfaceBc::Robin { k, ambient: value }
                } else {
                    base
                };
                self.diffusion.replace_surface(f, side, bc)?;
                self.touching[f][s] = touch[s];
            }
        }
        Ok(())
    }

    /// Resumes the nodal moisture and the diffusion's next sub-step of a restart's driver
    /// state (a state without moisture keeps the initial moisture).
    pub(super) fn resume(&mut self, sc: &Scene, d: &super::DriverState) -> Result<(), String> {
        let Some(u) = &d.moisture else {
            return Ok(());
        };
        if u.len() != self.u.len() || u.iter().any(|v| !v.is_finite()) {
            return Err(format!(
                "the frame's moisture state has {} values, this scene's diffusion {} (or one is \
                 not finite): it belongs to another scene",
                u.len(),
                self.u.len()
            ));
        }
        self.u.copy_from_slice(u);
        self.trial.copy_from_slice(u);
        self.mass = self.masses_of(&sc.body, &self.u);
        if let Some(h) = d.diffusion_substep {
            self.diffusion.resume_substep(h);
        }
        Ok(())
    }

    /// Lumped vertex masses with face densities ρ_shell + (m⁺ + m⁻)/2 · ρ_water (seed 000 §3,
    /// "Mass Matrix"); empty when the water density is 0 (the scene's masses apply).
    pub(super) fn masses_of(&self, sc: &Body, u: &[Real]) -> Vec<Real> {
        let rho_w = self.water_density;
        if rho_w == 0.0 {
            return Vec::new();
        }
        let mut mass = sc.mass.clone();
        for (f, face) in sc.mesh.faces.iter().enumerate() {
            let (top, bottom) = self.diffusion.surface_moisture(u, f);
            let area = sc.mesh.face_area(f);
            let dm = 0.5 * (top + bottom) * rho_w * sc.thickness[f] * area / 3.0;
            for &v in face {
                mass[v] += dm;
            }
        }
        mass
    }

    /// The masses at the accepted state (`trial = false`) or the trial one (the scene's without
    /// water density).
    pub(super) fn mass<'s>(&'s self, sc: &'s Body, trial: bool) -> &'s [Real] {
        let m = if trial { &self.trial_mass } else { &self.mass };
        if m.is_empty() {
            &sc.mass
        } else {
            m
        }
    }

    /// Rest forms of every face from the moisture `u`.
    ///
    /// A taped side (`moisture.boundary.tape`) is a layer that does not swell: the law sees
    /// moisture 0 there, so wet paper under tape curls away from it as a bilayer does.
    pub(super) fn targets_of(
        &self,
        sc: &Scene,
        u: &[Real],
    ) -> Result<Vec<(Sym2, Sym2)>, crate::rest::laws::GrowthError> {
        (0..sc.body.num_faces())
            .map(|f| {
                let (mut top, mut bottom) = self.diffusion.surface_moisture(u, f);
                if self.tape[f][0] {
                    top = 0.0;
                }
                if self.tape[f][1] {
                    bottom = 0.0;
                }
                let m = (top, bottom);
                let reference = (sc.body.rest.abar0[f], sc.body.rest.bbar0[f]);
                crate::rest::laws::growth_face(
                    &sc.body.growth,
                    f,
                    reference,
                    sc.body.thickness[f],
                    m,
                )
                .map(|g| (g.abar, g.bbar))
            })
            .collect()
    }

    /// Hands the surface moisture of the accepted state to the writer for the next frame.
    pub(super) fn publish(&self, writer: &mut dyn Sink) {
        let nf = writer.num_faces();
        let (mut top, mut bottom) = (Vec::with_capacity(nf), Vec::with_capacity(nf));
        for f in 0..nf {
            let (a, b) = self.diffusion.surface_moisture(&self.u, f);
            top.push(a);
            bottom.push(b);
        }
        let [t, b] = FRAME_FIELDS;
        writer.set_face_field(t, top);
        writer.set_face_field(b, bottom);
    }
}

/// The potential of the accepted state of a dynamic run: with moisture, its rest forms
/// `targets` and its wet masses.
pub(super) fn accepted<'a>(
    base: Potential<'a>,
    moisture: Option<&'a Moisture>,
    targets: &'a [(Sym2, Sym2)],
) -> Potential<'a> {
    match moisture {
        Some(m) => Potential {
            rest_override: Some(targets),
            mass: m.mass(base.body, false),
            ..base
        },
        None => base,
    }
}
