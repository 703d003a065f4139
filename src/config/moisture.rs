//! `[moisture]`: the moisture diffusion through the sheet's layers and along it, its boundary
//! conditions and the wet ground, that drive the swelling laws in time.

use super::growth::{Growth, GrowthLaw};
use super::limits::{MAX_LAYERS, MAX_MOISTURE};
use super::selection::FixBox;
use super::solver::Mode;
use super::values::{Auto, AutoOr};
use super::{Check, Invalid};
use crate::math::Real;
use serde::{Deserialize, Serialize};

/// `[moisture]`: prism-FEM diffusion through the sheet (see [`crate::diffusion`]); each time
/// step diffuses, then sets the rest forms from the surface moisture with `growth.law`.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Moisture {
    /// Solve the diffusion (dynamic mode with a moisture-driven growth law; default `false`).
    pub enabled: bool,
    /// Diffusivity along the machine direction (m²/s, default `1e-10`).
    pub diffusivity_along: Real,
    /// Diffusivity across it, in the plane (m²/s, default `1e-10`).
    pub diffusivity_across: Real,
    /// Diffusivity through the thickness (m²/s, default `1e-10`).
    pub diffusivity_through: Real,
    /// Element layers through the thickness, each quadratic through its height (default `5`).
    pub layers: usize,
    /// Thickness ratio of neighbouring layers from the two surfaces inwards (≥ 1; default
    /// `1.5`): thin layers at the surfaces resolve the moisture entering or leaving them.
    /// `1` gives equal layers. The defaults hold the surface moisture of a slab exchanging
    /// through both faces within 0.1% of Crank's series for Biot numbers 0.03–100 from
    /// t = 0.05 l²/D (l the half-thickness) on.
    pub grading: Real,
    /// Relative local error allowed per diffusion sub-step (default `1e-3`): each time step is
    /// covered by as many error-controlled sub-steps as this needs (see `crate::diffusion`).
    pub tolerance: Real,
    /// Initial moisture everywhere (default `0`).
    pub initial: Real,
    /// Density of the absorbed water (kg/m³, default `1000`): each face's density is
    /// ρ = ρ_shell + (m⁺ + m⁻)/2 · ρ_water (seed 000 §3, mass matrix), with the moisture m a
    /// volume fraction. `0` keeps the density constant.
    pub water_density: Real,
    /// Largest change of the nodal moisture allowed in one time step; a step that exceeds it
    /// is cut (halved) before the mechanical solve, and Δt grows only while changes stay below
    /// half of it (default `0.02`).
    pub max_change: Real,
    /// Surface conditions by region; faces without one are sealed.
    pub boundary: Vec<MoistureBoundary>,
    /// Diffusivities on regions of faces (veins that carry water, a printed layer that blocks
    /// it), over the uniform ones; the face fields `diffusivity_along`, `diffusivity_across` and
    /// `diffusivity_through` take precedence over both.
    pub regions: Vec<DiffusionRegion>,
    /// Exchange with a moist ground (`[moisture.ground]`, needs `[contact]`), else none.
    pub ground: Option<GroundMoisture>,
    /// Softening: rows `[m, factor]`, the moduli of each face times the factor at its mean
    /// moisture through the thickness (linear between rows, constant beyond; default none).
    pub softening: Option<Vec<[Real; 2]>>,
}

/// `[moisture.ground]`: a face side that faces the ground (`[contact]`) and is within
/// `distance` of it exchanges moisture with it, `−D∂u/∂n = k (u − value)`, instead of its own
/// condition; sealed sides (tape) and prescribed values stay as they are. Re-evaluated every
/// time step from the current positions.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GroundMoisture {
    /// Transfer coefficient k (m/s, default `1e-5`).
    pub k: Real,
    /// Moisture of the ground (default `0.3`).
    pub value: Real,
    /// Largest gap between the sheet's surface and the ground that counts as touching (m;
    /// `"auto"`: the thickness, default).
    pub distance: AutoOr,
}

impl Default for GroundMoisture {
    fn default() -> Self {
        GroundMoisture {
            k: 1e-5,
            value: 0.3,
            distance: AutoOr::Auto(Auto::Auto),
        }
    }
}

impl Default for Moisture {
    fn default() -> Self {
        Moisture {
            enabled: false,
            diffusivity_along: 1e-10,
            diffusivity_across: 1e-10,
            diffusivity_through: 1e-10,
            layers: 5,
            grading: 1.5,
            tolerance: 1e-3,
            initial: 0.0,
            water_density: 1000.0,
            max_change: 0.02,
            boundary: Vec::new(),
            regions: Vec::new(),
            ground: None,
            softening: None,
        }
    }
}

/// `[[moisture.regions]]` (and, with conductivities, `[[temperature.regions]]`): coefficients of
/// the faces whose `tri_tags` is one of `tags` (any, when empty) and whose reference centroid
/// lies in `inside` (when given); each given value replaces the uniform one there (later regions
/// over earlier ones).
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DiffusionRegion {
    /// Tags (default: `[]`).
    pub tags: Vec<i64>,
    /// Box (m, default: none).
    pub inside: Option<FixBox>,
    /// Along the machine direction (m²/s).
    pub diffusivity_along: Option<Real>,
    /// Across it, in the plane (m²/s).
    pub diffusivity_across: Option<Real>,
    /// Through the thickness (m²/s).
    pub diffusivity_through: Option<Real>,
}

impl DiffusionRegion {
    /// The values along, across and through (the given ones).
    pub fn values(&self) -> [Option<Real>; 3] {
        [
            self.diffusivity_along,
            self.diffusivity_across,
            self.diffusivity_through,
        ]
    }
}

/// Checks a region of coefficients `values` (named `names`) at `key`: tags or a box, a finite
/// box, positive finite values.
pub(crate) fn check_region(
    key: &str,
    tags: &[i64],
    inside: Option<&FixBox>,
    names: [&str; 3],
    values: [Option<Real>; 3],
) -> Result<(), Invalid> {
    let ck = Check;
    ck.region(key, tags, inside)?;
    for (n, v) in names.iter().zip(values) {
        if let Some(v) = v {
            ck.pos(&format!("{key}.{n}"), v)?;
        }
    }
    Ok(())
}

/// One surface condition on a region of faces.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MoistureBoundary {
    /// Faces whose `tri_tags` is one of these (empty: every face).
    pub tags: Vec<i64>,
    /// Only faces whose reference centroid lies in this box (m), e.g. a taped end.
    pub inside: Option<FixBox>,
    /// With `kind = "sealed"`: the side is covered by tape, a layer that neither lets water
    /// through nor swells; the growth law sees moisture 0 on it (default `false`).
    pub tape: bool,
    /// `"top"` (the normal side) or `"bottom"`.
    pub side: SurfaceSide,
    /// `"value"` (prescribed moisture), `"flux"` (inward flux), `"robin"` (exchange with an
    /// ambient moisture) or `"sealed"`.
    pub kind: SurfaceKind,
    /// Moisture for `"value"`, inward flux (m/s) for `"flux"`.
    pub value: Real,
    /// Transfer coefficient k (m/s) for `"robin"`.
    pub k: Real,
    /// Ambient moisture for `"robin"`.
    pub ambient: Real,
}

impl Default for MoistureBoundary {
    fn default() -> Self {
        MoistureBoundary {
            tags: Vec::new(),
            inside: None,
            tape: false,
            side: SurfaceSide::Top,
            kind: SurfaceKind::Sealed,
            value: 0.0,
            k: 0.0,
            ambient: 0.0,
        }
    }
}

/// Top or bottom surface.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SurfaceSide {
    /// `z = +h/2`.
    #[default]
    Top,
    /// `z = −h/2`.
    Bottom,
}

/// Kind of surface condition.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SurfaceKind {
    /// No flux.
    #[default]
    Sealed,
    /// Prescribed moisture.
    Value,
    /// Prescribed inward flux.
    Flux,
    /// Exchange with the ambient.
    Robin,
}

impl Moisture {
    /// Validates `[moisture]` (when enabled): diffusivities, layers, the surfaces, the ground exchange, and the dynamic mode and swelling law it needs.
    /// `growth` is `[growth]` (the swelling law moisture drives), `ground` whether `[contact]`
    /// builds a ground, `mode` the run's mode.
    pub fn validate(&self, growth: &Growth, ground: bool, mode: Mode) -> Result<(), Invalid> {
        let ck = Check;
        let g = growth;
        let mo = self;
        if mo.enabled {
            for (k, v) in [
                ("moisture.diffusivity_along", mo.diffusivity_along),
                ("moisture.diffusivity_across", mo.diffusivity_across),
                ("moisture.diffusivity_through", mo.diffusivity_through),
            ] {
                ck.pos(k, v)?;
            }
            ck.pos("moisture.max_change", mo.max_change)?;
            ck.nonneg("moisture.water_density", mo.water_density)?;
            if let Some(g) = &mo.ground {
                ck.nonneg("moisture.ground.k", g.k)?;
                if !g.value.is_finite() {
                    return ck.inv(
                        "moisture.ground.value",
                        format!("must be finite, got {}", crate::math::human(g.value)),
                    );
                }
                if let AutoOr::Value(d) = g.distance {
                    ck.nonneg("moisture.ground.distance", d)?;
                }
                if !ground {
                    return ck.inv(
                        "moisture.ground",
                        "needs a ground: set contact.enabled = true".into(),
                    );
                }
            }
            if mo.layers == 0 || mo.layers > MAX_LAYERS {
                return ck.inv(
                    "moisture.layers",
                    format!("must lie in 1..={MAX_LAYERS}, got {}", mo.layers),
                );
            }
            let half = (mo.layers / 2) as i32;
            if !(mo.grading >= 1.0 && mo.grading <= 10.0) || mo.grading.powi(half) > 1e6 {
                return ck.inv(
                    "moisture.grading",
                    format!(
                        "must lie in 1..=10 with grading^(layers/2) ≤ 1e6 (thickest to thinnest \
                         layer), got {} with {} layers",
                        crate::math::human(mo.grading),
                        mo.layers
                    ),
                );
            }
            if !(mo.tolerance >= 1e-10 && mo.tolerance <= 0.1) {
                return ck.inv(
                    "moisture.tolerance",
                    format!(
                        "must lie in 1e-10..=0.1, got {}",
                        crate::math::human(mo.tolerance)
                    ),
                );
            }
            if !mo.initial.is_finite() || mo.initial.abs() > MAX_MOISTURE {
                return ck.inv(
                    "moisture.initial",
                    format!(
                        "must lie in ±{MAX_MOISTURE_h}, got {}",
                        crate::math::human(mo.initial),
                        MAX_MOISTURE_h = crate::math::human(MAX_MOISTURE)
                    ),
                );
            }
            if mode != Mode::Dynamic {
                return ck.inv(
                    "moisture.enabled",
                    "moisture diffusion runs in time: set solver.mode = \"dynamic\"".into(),
                );
            }
            if !matches!(
                g.law,
                GrowthLaw::LinearSwelling
                    | GrowthLaw::Bilayer
                    | GrowthLaw::MachineDirection
                    | GrowthLaw::CreaseRelaxation
            ) {
                return ck.inv(
                    "moisture.enabled",
                    format!(
                        "moisture drives the rest forms through a swelling law; growth.law is \
                         {:?} (use linear_swelling, bilayer, machine_direction or crease_relaxation)",
                        g.law
                    ),
                );
            }
            if let Some(rows) = &mo.softening {
                super::values::check_curve("moisture.softening", rows, "moisture")?;
            }
            for (i, r) in mo.regions.iter().enumerate() {
                check_region(
                    &format!("moisture.regions[{i}]"),
                    &r.tags,
                    r.inside.as_ref(),
                    [
                        "diffusivity_along",
                        "diffusivity_across",
                        "diffusivity_through",
                    ],
                    r.values(),
                )?;
            }
            for (i, b) in mo.boundary.iter().enumerate() {
                for v in [b.value, b.k, b.ambient] {
                    if !v.is_finite() {
                        return ck.inv(
                            &format!("moisture.boundary[{i}]"),
                            format!("non-finite value {v_h}", v_h = crate::math::human(v)),
                        );
                    }
                }
                for (what, v) in [("value", b.value), ("ambient", b.ambient)] {
                    if v.abs() > MAX_MOISTURE {
                        return ck.inv(
                            &format!("moisture.boundary[{i}].{what}"),
                            format!(
                                "must lie in ±{MAX_MOISTURE_h}, got {v_h}",
                                MAX_MOISTURE_h = crate::math::human(MAX_MOISTURE),
                                v_h = crate::math::human(v)
                            ),
                        );
                    }
                }
                if b.tape && b.kind != SurfaceKind::Sealed {
                    return ck.inv(
                        &format!("moisture.boundary[{i}].tape"),
                        "tape is a sealed surface: needs kind = \"sealed\"".into(),
                    );
                }
                if b.kind == SurfaceKind::Robin && b.k < 0.0 {
                    return ck.inv(
                        &format!("moisture.boundary[{i}].k"),
                        format!("must be ≥ 0, got {}", crate::math::human(b.k)),
                    );
                }
            }
        }
        Ok(())
    }
}
