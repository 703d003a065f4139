//! The coupled field of a dynamic run, moisture or temperature: its prism-FEM diffusion, the
//! rest forms it sets each step, and for moisture the wet masses and the ground exchange
//! switched by contact, for temperature the highest temperature each node has reached (the
//! thermal shrink law's ratchet), the time windows of its surface conditions and its moving
//! sources.

use super::RunError;
use super::Sink;
use crate::body::Body;
use crate::diffusion::{Side, SurfaceBc};
use crate::energy::Potential;
use crate::math::{Real, Sym2, Vec3};
use crate::model::Scene;

/// The per-face fields moisture adds to frames: the content at the top and the bottom face.
pub const FRAME_FIELDS: [&str; 2] = ["moisture_top", "moisture_bottom"];

/// The per-face fields temperature adds to frames (K): the current temperature at the top and
/// bottom surfaces and the highest reached there.
pub const HEAT_FIELDS: [&str; 4] = [
    "temperature_top",
    "temperature_bottom",
    "temperature_max_top",
    "temperature_max_bottom",
];

/// The frame fields of a scene's coupled field (none without one).
pub fn frame_fields(s: &crate::settings::Settings) -> &'static [&'static str] {
    if s.moisture.enabled {
        &FRAME_FIELDS
    } else if s.temperature.enabled {
        &HEAT_FIELDS
    } else {
        &[]
    }
}

/// Which field diffuses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Field {
    /// `[moisture]`, driving a swelling law through the surface moisture.
    Moisture,
    /// `[temperature]`, driving the thermal shrink law through the highest temperature reached.
    Temperature,
}

/// A surface condition that holds during a time window `[from, until)` (s).
#[derive(Clone, Debug)]
struct Window {
    faces: Vec<usize>,
    side: Side,
    bc: SurfaceBc,
    from: Real,
    until: Real,
}

/// The diffusion of a dynamic run's coupled field and the rest forms it drives.
pub(super) struct Transport {
    pub(super) field: Field,
    pub(super) diffusion: crate::diffusion::Diffusion,
    /// Nodal values at the last accepted step, and the trial of the current one.
    pub(super) u: Vec<Real>,
    pub(super) trial: Vec<Real>,
    /// Temperature: the highest nodal values reached up to the accepted step and up to the
    /// trial (empty for moisture).
    pub(super) peak: Vec<Real>,
    pub(super) trial_peak: Vec<Real>,
    /// Largest nodal change of the last trial step.
    pub(super) change: Real,
    /// A step that changes a nodal value by more than this is cut (`max_change`).
    pub(super) max_change: Real,
    /// Lumped vertex masses with the absorbed water, at `u` and at `trial` (empty when
    /// `moisture.water_density = 0`, and for temperature).
    pub(super) mass: Vec<Real>,
    pub(super) trial_mass: Vec<Real>,
    /// `[moisture.ground]`: each face's own conditions (top, bottom), the ground's
    /// `(k, value, distance)`, and which sides currently touch it.
    pub(super) base: Vec<[SurfaceBc; 2]>,
    pub(super) taped: Vec<[bool; 2]>,
    /// Sides covered by tape (top, bottom): the growth law sees moisture 0 on them.
    pub(super) tape: Vec<[bool; 2]>,
    pub(super) ground: Option<(Real, Real, Real)>,
    /// Density of the absorbed water (kg/m³; 0 = masses stay dry).
    water_density: Real,
    pub(super) touching: Vec<[bool; 2]>,
    /// Temperature: the windowed conditions, and the heat sources with the volumetric heat
    /// capacity ρc (J/(m³·K)) that turns their W/m² into the diffusion's K·m/s.
    windows: Vec<Window>,
    sources: Vec<crate::config::temperature::HeatSource>,
    heat_capacity: Real,
    /// The height fractions of the law's sample heights (bottom 0, top 1).
    samples: [Real; 6],
    /// The moduli's factor against the field's mean through the thickness (softening).
    softening: Option<crate::config::values::Curve>,
}

/// The mean over the triangle `p` of `exp(−|x − c|²/(2σ²))`: the edge-midpoint rule (exact
/// for quadratics) on the `n²` triangles of a regular split with edges at most σ/4, so that a
/// spot smaller than the mesh's faces still delivers its power (measured: a spot of σ = 1.5
/// mm on faces of 1 mm delivers its power to 1e-4, against 1.3% for the rule on whole faces).
/// Faces farther than 9σ from the centre count 0 (e^−40).
fn gaussian_face_mean(p: [Vec3; 3], c: Vec3, sigma: Real) -> Real {
    let centroid = (p[0] + p[1] + p[2]) / 3.0;
    let reach = p.iter().map(|q| (q - centroid).norm()).fold(0.0, Real::max);
    if (centroid - c).norm() - reach > 9.0 * sigma {
        return 0.0;
    }
    let longest = (0..3)
        .map(|k| (p[(k + 1) % 3] - p[k]).norm())
        .fold(0.0, Real::max);
    let n = ((4.0 * longest / sigma).ceil() as usize).clamp(1, 64);
    let (e1, e2) = ((p[1] - p[0]) / n as Real, (p[2] - p[0]) / n as Real);
    let at = |i: usize, j: usize| p[0] + e1 * i as Real + e2 * j as Real;
    let g = |x: Vec3| (-0.5 * (x - c).norm_squared() / (sigma * sigma)).exp();
    let tri =
        |a: Vec3, b: Vec3, d: Vec3| (g((a + b) * 0.5) + g((b + d) * 0.5) + g((d + a) * 0.5)) / 3.0;
    let mut sum = 0.0;
    for i in 0..n {
        for j in 0..n - i {
            sum += tri(at(i, j), at(i + 1, j), at(i, j + 1));
            if i + j + 1 < n {
                sum += tri(at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            }
        }
    }
    sum / (n * n) as Real
}

/// A region of faces with coefficients along, across and through (`None`: not given).
type Region<'a> = (
    &'a [i64],
    Option<&'a crate::settings::FixBox>,
    [Option<Real>; 3],
);

/// Per-face coefficients along, across and through: `uniform`, replaced on each region's faces
/// by the values it gives (`what[i]` names it), then by the face fields `fields` (when given;
/// checked positive and finite, naming the face).
fn per_face_diffusivity(
    sc: &Scene,
    uniform: [Real; 3],
    regions: &[Region],
    what: &str,
    fields: Option<[&str; 3]>,
) -> Result<Vec<crate::diffusion::Diffusivity>, RunError> {
    let mesh = &sc.body.mesh;
    let mut v = vec![uniform; mesh.faces.len()];
    for (i, (tags, inside, values)) in regions.iter().enumerate() {
        let faces = mesh.faces_matching(
            tags,
            inside.map(|b| (b.min, b.max)),
            &format!("{what}[{i}]"),
        )?;
        for f in faces {
            for (k, x) in values.iter().enumerate() {
                if let Some(x) = x {
                    v[f][k] = *x;
                }
            }
        }
    }
    for (k, name) in fields.into_iter().flatten().enumerate() {
        if let Some(field) = mesh.face_field(name, 1)? {
            for (f, &x) in field.data.iter().enumerate() {
                if !(x.is_finite() && x > 0.0) {
                    return Err(mesh
                        .invalid(format!(
                            "face field '{name}' at face {f} is {x}: a diffusivity must be \
                             positive and finite"
                        ))
                        .into());
                }
                v[f][k] = x;
            }
        }
    }
    Ok(v.into_iter()
        .map(|[along, across, through]| crate::diffusion::Diffusivity {
            along,
            across,
            through,
        })
        .collect())
}

/// The diffusion's condition of a settings one: `value` is the prescribed value or the flux,
/// `k` the transfer coefficient; fluxes and transfer coefficients are divided by `scale` (ρc
/// for heat, 1 for moisture).
fn surface_bc(
    kind: crate::settings::SurfaceKind,
    value: Real,
    k: Real,
    ambient: Real,
    scale: Real,
) -> SurfaceBc {
    use crate::settings::SurfaceKind;
    match kind {
        SurfaceKind::Sealed => SurfaceBc::Sealed,
        SurfaceKind::Value => SurfaceBc::Value(value),
        SurfaceKind::Flux => SurfaceBc::Flux(value / scale),
        SurfaceKind::Robin => SurfaceBc::Robin {
            k: k / scale,
            ambient,
        },
    }
}

/// The diffusion's side of a settings side.
fn side_of(s: crate::settings::SurfaceSide) -> Side {
    match s {
        crate::settings::SurfaceSide::Top => Side::Top,
        crate::settings::SurfaceSide::Bottom => Side::Bottom,
    }
}

impl Transport {
    /// Builds the diffusion system of a scene with `moisture.enabled` or
    /// `temperature.enabled` (None otherwise).
    pub(super) fn new(sc: &Scene) -> Result<Option<Self>, RunError> {
        if sc.settings.moisture.enabled {
            Self::moisture(sc).map(Some)
        } else if sc.settings.temperature.enabled {
            Self::temperature(sc).map(Some)
        } else {
            Ok(None)
        }
    }

    /// A transport with no conditions set yet and every node at `initial`.
    fn empty(
        sc: &Scene,
        field: Field,
        diffusivity: &[crate::diffusion::Diffusivity],
        layering: crate::diffusion::Layering,
        initial: Real,
        max_change: Real,
    ) -> Result<Self, RunError> {
        let dirs: Vec<Vec3> = sc.body.growth.direction.iter().map(|d| d.1).collect();
        let diffusion = crate::diffusion::Diffusion::with_faces(
            &sc.body.mesh.positions,
            &sc.body.mesh.faces,
            &sc.body.thickness,
            &dirs,
            diffusivity,
            layering,
        )?;
        let samples = crate::rest::laws::sample_heights(1.0).map(|z| z + 0.5);
        let u = vec![initial; diffusion.num_nodes()];
        let nf = sc.body.num_faces();
        let peak = if field == Field::Temperature {
            u.clone()
        } else {
            Vec::new()
        };
        Ok(Transport {
            field,
            trial: u.clone(),
            trial_peak: peak.clone(),
            peak,
            u,
            diffusion,
            change: 0.0,
            max_change,
            mass: Vec::new(),
            trial_mass: Vec::new(),
            base: Vec::new(),
            taped: vec![[false; 2]; nf],
            tape: vec![[false; 2]; nf],
            ground: None,
            water_density: 0.0,
            touching: vec![[false; 2]; nf],
            windows: Vec::new(),
            sources: Vec::new(),
            heat_capacity: 1.0,
            samples,
            softening: None,
        })
    }

    /// The moisture's diffusion, conditions, ground exchange and wet masses.
    fn moisture(sc: &Scene) -> Result<Self, RunError> {
        use crate::diffusion::Layering;
        let mo = &sc.settings.moisture;
        let regions: Vec<_> = mo
            .regions
            .iter()
            .map(|r| (&r.tags[..], r.inside.as_ref(), r.values()))
            .collect();
        let per_face = per_face_diffusivity(
            sc,
            [
                mo.diffusivity_along,
                mo.diffusivity_across,
                mo.diffusivity_through,
            ],
            &regions,
            "moisture.regions",
            Some([
                "diffusivity_along",
                "diffusivity_across",
                "diffusivity_through",
            ]),
        )?;
        let mut m = Self::empty(
            sc,
            Field::Moisture,
            &per_face,
            Layering {
                count: mo.layers,
                grading: mo.grading,
            },
            mo.initial,
            mo.max_change,
        )?;
        for b in &mo.boundary {
            let side = side_of(b.side);
            let bc = surface_bc(b.kind, b.value, b.k, b.ambient, 1.0);
            let faces = crate::body::region_faces(&sc.body.mesh, b)?;
            for f in faces {
                m.diffusion.set_surface(f, side, bc)?;
                // Sides sealed on purpose (tape): the ground exchange leaves them sealed.
                if bc == SurfaceBc::Sealed {
                    m.taped[f][side as usize] = true;
                }
                // Sides covered by tape (`tape = true`): a non-swelling layer for the law.
                if b.tape {
                    m.tape[f][side as usize] = true;
                }
            }
        }
        m.keep_base();
        let nf = sc.body.num_faces();
        let h_mean = sc.body.thickness.iter().sum::<Real>() / nf.max(1) as Real;
        m.ground = mo
            .ground
            .as_ref()
            .map(|g| (g.k, g.value, g.distance.or(h_mean)));
        m.water_density = mo.water_density;
        m.softening = mo
            .softening
            .as_deref()
            .map(crate::config::values::Curve::from_rows);
        m.mass = m.masses_of(&sc.body, &m.u);
        m.trial_mass = m.mass.clone();
        Ok(m)
    }

    /// The heat conduction: diffusivities k/(ρc), the permanent conditions set at once, the
    /// windowed ones kept for [`Self::update_windows`], the sources.
    fn temperature(sc: &Scene) -> Result<Self, RunError> {
        use crate::diffusion::Layering;
        let te = &sc.settings.temperature;
        let rc = sc.settings.material.density * te.specific_heat;
        let regions: Vec<_> = te
            .regions
            .iter()
            .map(|r| (&r.tags[..], r.inside.as_ref(), r.values()))
            .collect();
        let mut per_face = per_face_diffusivity(
            sc,
            [
                te.conductivity_along,
                te.conductivity_across,
                te.conductivity_through,
            ],
            &regions,
            "temperature.regions",
            None,
        )?;
        // Conductivities to diffusivities, k/(ρc).
        for d in &mut per_face {
            (d.along, d.across, d.through) = (d.along / rc, d.across / rc, d.through / rc);
        }
        let mut m = Self::empty(
            sc,
            Field::Temperature,
            &per_face,
            Layering {
                count: te.layers,
                grading: te.grading,
            },
            te.initial,
            te.max_change,
        )?;
        m.heat_capacity = rc;
        // Overlapping windows were checked with the scene (`body::check_heat_regions`).
        for (i, b) in te.boundary.iter().enumerate() {
            let side = side_of(b.side);
            // The heat equation divided by ρc: h/(ρc) in m/s, q/(ρc) in K·m/s.
            let bc = surface_bc(b.kind, b.value, b.h, b.ambient, rc);
            let faces = crate::body::select::faces_matching(
                &sc.body.mesh,
                &b.tags,
                b.inside.as_ref(),
                &format!("temperature.boundary[{i}]"),
            )?;
            if b.permanent() {
                for &f in &faces {
                    m.diffusion.set_surface(f, side, bc)?;
                }
            } else {
                m.windows.push(Window {
                    faces,
                    side,
                    bc,
                    from: b.from,
                    until: b.until.unwrap_or(Real::INFINITY),
                });
            }
        }
        m.keep_base();
        m.sources = te.source.clone();
        m.softening = te
            .softening
            .as_deref()
            .map(crate::config::values::Curve::from_rows);
        Ok(m)
    }

    /// Records each face side's permanent condition as set now (`base`): the one a ground
    /// contact or a window replaces for a while.
    fn keep_base(&mut self) {
        let d = &self.diffusion;
        self.base = (0..self.taped.len())
            .map(|f| [d.surface(f, Side::Top), d.surface(f, Side::Bottom)])
            .collect();
    }

    /// The first time after `t` (s) at which a windowed condition starts or ends, or a source
    /// switches on or off: a step does not cross it.
    pub(super) fn next_switch(&self, t: Real) -> Option<Real> {
        let ends = |s: &crate::config::temperature::HeatSource| {
            [s.path.first(), s.path.last()].map(|w| w.map_or(Real::NAN, |w| w[0]))
        };
        self.windows
            .iter()
            .flat_map(|w| [w.from, w.until])
            .chain(self.sources.iter().flat_map(ends))
            .filter(|&s| s > t && s.is_finite())
            .min_by(Real::total_cmp)
    }

    /// Sets the conditions in force during the step from `t` (s): each face side's permanent
    /// condition, replaced by a windowed one while it is open.
    pub(super) fn update_windows(&mut self, t: Real) -> Result<(), crate::diffusion::SurfaceError> {
        if self.windows.is_empty() {
            return Ok(());
        }
        let mut want = self.base.clone();
        for w in &self.windows {
            if t >= w.from && t < w.until {
                for &f in &w.faces {
                    want[f][w.side as usize] = w.bc;
                }
            }
        }
        for (f, sides) in want.iter().enumerate() {
            for (s, side) in [Side::Top, Side::Bottom].into_iter().enumerate() {
                if self.diffusion.surface(f, side) != sides[s] {
                    self.diffusion.replace_surface(f, side, sides[s])?;
                }
            }
        }
        Ok(())
    }

    /// Sets the sources' heat flux for the step from `t` to `t + h` (s), evaluated at its
    /// midpoint: on each face side, the Gaussian spot of every source whose path covers the
    /// midpoint, averaged over the face's reference triangle ([`gaussian_face_mean`]).
    pub(super) fn update_sources(&mut self, sc: &Scene, t: Real, h: Real) {
        if self.sources.is_empty() {
            return;
        }
        let tm = t + 0.5 * h;
        let nf = sc.body.num_faces();
        let mut q = vec![[0.0; 2]; nf];
        for s in &self.sources {
            let Some(c) = s.centre(tm) else {
                continue;
            };
            let c = Vec3::from(c);
            let sigma2 = s.radius * s.radius;
            let peak = s.power / (2.0 * std::f64::consts::PI * sigma2);
            let side = side_of(s.side) as usize;
            for (f, qf) in q.iter_mut().enumerate() {
                let g = gaussian_face_mean(sc.body.mesh.face_positions(f), c, s.radius);
                qf[side] += peak * g / self.heat_capacity;
            }
        }
        self.diffusion.set_sources(&q);
    }

    /// The diffusion's error tolerance. Moisture: `moisture.tolerance` relative, with an
    /// absolute floor of `10⁻³` of it times the moisture scale (the largest of the initial
    /// moisture, every prescribed, ambient and ground moisture, and the current largest nodal
    /// value), so that nodes the moisture has not yet reached do not hold the sub-steps down.
    /// Temperature: absolute, `temperature.tolerance` times the largest temperature difference
    /// of the scene (of every prescribed or ambient temperature and every current nodal one from
    /// the initial temperature, at least 1 K): the conduction is the same whatever the origin of
    /// the temperature scale, and so is its error control.
    pub(super) fn tolerance(&self, sc: &Scene) -> crate::diffusion::Tolerance {
        use crate::settings::SurfaceKind;
        match self.field {
            Field::Moisture => {
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
            Field::Temperature => {
                let te = &sc.settings.temperature;
                let t0 = te.initial;
                let mut scale: Real = 1.0;
                for b in &te.boundary {
                    match b.kind {
                        SurfaceKind::Value => scale = scale.max((b.value - t0).abs()),
                        SurfaceKind::Robin => scale = scale.max((b.ambient - t0).abs()),
                        SurfaceKind::Flux | SurfaceKind::Sealed => {}
                    }
                }
                let now = self.u.iter().fold(0.0, |m: Real, u| m.max((u - t0).abs()));
                crate::diffusion::Tolerance {
                    rtol: 0.0,
                    atol: te.tolerance * scale.max(now),
                }
            }
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

    /// Resumes the nodal values (and for temperature the highest reached) and the
    /// diffusion's next sub-step of a restart's driver state (a state without them keeps the
    /// initial values).
    pub(super) fn resume(&mut self, sc: &Scene, d: &super::DriverState) -> Result<(), String> {
        let (name, u) = match self.field {
            Field::Moisture => ("moisture", &d.moisture),
            Field::Temperature => ("temperature", &d.temperature),
        };
        let Some(u) = u else {
            return Ok(());
        };
        let n = self.u.len();
        let fits = |v: &[Real]| v.len() == n && v.iter().all(|x| x.is_finite());
        if !fits(u) {
            return Err(format!(
                "the frame's {name} state has {} values, this scene's diffusion {} (or one is \
                 not finite): it belongs to another scene",
                u.len(),
                n
            ));
        }
        self.u.copy_from_slice(u);
        self.trial.copy_from_slice(u);
        if self.field == Field::Temperature {
            match &d.temperature_max {
                Some(p) if fits(p) => {
                    self.peak.copy_from_slice(p);
                    self.trial_peak.copy_from_slice(p);
                }
                _ => {
                    return Err(
                        "the frame's temperature state has no highest temperatures of the right \
                         length: it belongs to another scene"
                            .into(),
                    )
                }
            }
        }
        self.mass = self.masses_of(&sc.body, &self.u);
        if let Some(h) = d.diffusion_substep {
            self.diffusion.resume_substep(h);
        }
        Ok(())
    }

    /// After a trial step: the highest values reached up to it (temperature).
    pub(super) fn raise_peak(&mut self) {
        for ((t, p), u) in self.trial_peak.iter_mut().zip(&self.peak).zip(&self.trial) {
            *t = p.max(*u);
        }
    }

    /// The trial becomes the accepted state.
    pub(super) fn accept(&mut self) {
        self.u.copy_from_slice(&self.trial);
        self.peak.copy_from_slice(&self.trial_peak);
        std::mem::swap(&mut self.mass, &mut self.trial_mass);
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

    /// Whether the masses follow the moisture (`moisture.water_density > 0`).
    pub(super) fn wet(&self) -> bool {
        self.field == Field::Moisture && self.water_density > 0.0
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

    /// Rest forms and thickness of every face from the trial state (`trial = true`) or the
    /// accepted one: the surface moisture, or the highest temperatures reached, sampled through
    /// the thickness at the law's heights.
    ///
    /// A taped side (`moisture.boundary.tape`) is a layer that does not swell: the law sees
    /// moisture 0 there, so wet paper under tape curls away from it as a bilayer does.
    pub(super) fn targets_of(
        &self,
        sc: &Scene,
        trial: bool,
    ) -> Result<Targets, crate::rest::laws::GrowthError> {
        let u = if trial { &self.trial } else { &self.u };
        let peak = if trial { &self.trial_peak } else { &self.peak };
        let nf = sc.body.num_faces();
        let mut out = Targets {
            forms: Vec::with_capacity(nf),
            thickness: Vec::new(),
            modulus: Vec::new(),
        };
        if let Some(curve) = &self.softening {
            // The face's mean through the thickness of the current field.
            let w = crate::rest::laws::sample_weights();
            out.modulus = (0..nf)
                .map(|f| {
                    let p = self.diffusion.profile(u, f, &self.samples);
                    curve.at(p.iter().zip(w).map(|(v, w)| v * w).sum())
                })
                .collect();
        }
        for f in 0..nf {
            let (m, heat) = match self.field {
                Field::Moisture => {
                    let (mut top, mut bottom) = self.diffusion.surface_moisture(u, f);
                    if self.tape[f][0] {
                        top = 0.0;
                    }
                    if self.tape[f][1] {
                        bottom = 0.0;
                    }
                    ((top, bottom), None)
                }
                Field::Temperature => (
                    (0.0, 0.0),
                    Some(self.diffusion.profile(peak, f, &self.samples)),
                ),
            };
            let reference = (sc.body.rest.abar0[f], sc.body.rest.bbar0[f]);
            let g = crate::rest::laws::growth_face(
                &sc.body.growth,
                f,
                reference,
                sc.body.thickness[f],
                m,
                heat,
            )?;
            out.forms.push((g.abar, g.bbar));
            if g.thickness_ratio != 1.0 && out.thickness.is_empty() {
                out.thickness = vec![1.0; nf];
            }
            if !out.thickness.is_empty() {
                out.thickness[f] = g.thickness_ratio;
            }
        }
        Ok(out)
    }

    /// Hands the field at the accepted state to the writer for the next frame: the surface
    /// moisture, or the surface temperatures and the highest reached there.
    pub(super) fn publish(&self, writer: &mut dyn Sink) {
        let nf = writer.num_faces();
        let surfaces = |u: &[Real]| -> (Vec<Real>, Vec<Real>) {
            (0..nf)
                .map(|f| self.diffusion.surface_moisture(u, f))
                .unzip()
        };
        let (top, bottom) = surfaces(&self.u);
        match self.field {
            Field::Moisture => {
                let [t, b] = FRAME_FIELDS;
                writer.set_face_field(t, top);
                writer.set_face_field(b, bottom);
            }
            Field::Temperature => {
                let (max_top, max_bottom) = surfaces(&self.peak);
                for (name, v) in HEAT_FIELDS
                    .into_iter()
                    .zip([top, bottom, max_top, max_bottom])
                {
                    writer.set_face_field(name, v);
                }
            }
        }
    }
}

/// Rest forms set by the coupled field: per face `(ā, b̄)`, and the rest thickness over the
/// reference one (empty when every face keeps its thickness).
#[derive(Clone, Debug, Default)]
pub(super) struct Targets {
    pub(super) forms: Vec<(Sym2, Sym2)>,
    pub(super) thickness: Vec<Real>,
    /// The factor on each face's moduli (softening; empty without it).
    pub(super) modulus: Vec<Real>,
}

impl Targets {
    /// The potential `base` with these rest forms.
    pub(super) fn apply<'a>(&'a self, base: Potential<'a>) -> Potential<'a> {
        Potential {
            rest_override: Some(&self.forms),
            thickness_override: (!self.thickness.is_empty()).then_some(&self.thickness[..]),
            modulus_override: (!self.modulus.is_empty()).then_some(&self.modulus[..]),
            ..base
        }
    }
}

/// The potential of the accepted state of a dynamic run: with a coupled field, its rest forms
/// `targets` and (moisture) its wet masses.
pub(super) fn accepted<'a>(
    base: Potential<'a>,
    field: Option<&'a Transport>,
    targets: &'a Targets,
) -> Potential<'a> {
    match field {
        Some(m) => targets.apply(Potential {
            mass: m.mass(base.body, false),
            ..base
        }),
        None => base,
    }
}
