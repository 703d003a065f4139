//! `[temperature]`: heat conduction through the sheet's layers and along it, its surface
//! conditions (each for a time window), and moving heat sources, which drive the thermal shrink
//! law in time.

use super::growth::{Growth, GrowthLaw};
use super::limits::MAX_LAYERS;
use super::moisture::{SurfaceKind, SurfaceSide};
use super::selection::FixBox;
use super::solver::Mode;
use super::{Check, Invalid};
use crate::math::{human, Real};
use serde::{Deserialize, Serialize};

/// The largest absolute temperature accepted anywhere (K): well above any polymer's or paper's
/// decomposition; a larger value is a unit mistake.
pub const MAX_TEMPERATURE: Real = 1e4;

/// `[temperature]`: the same prism-FEM diffusion as `[moisture]` (see [`crate::diffusion`]),
/// for the heat equation `ρ c ∂T/∂t = ∇·(k ∇T)` divided by `ρ c`: the diffusivity is
/// `α = k/(ρ c)` with `ρ` = `material.density`. Each time step conducts heat, updates the
/// highest temperature each node has reached, and sets the rest forms from it with
/// `growth.law = "thermal_shrink"`.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Temperature {
    /// Solve the heat conduction (dynamic mode with `growth.law = "thermal_shrink"`; default
    /// `false`).
    pub enabled: bool,
    /// Thermal conductivity along the machine direction (W/(m·K), default `0.22`, polypropylene).
    pub conductivity_along: Real,
    /// Conductivity across it, in the plane (W/(m·K), default `0.22`).
    pub conductivity_across: Real,
    /// Conductivity through the thickness (W/(m·K), default `0.22`).
    pub conductivity_through: Real,
    /// Specific heat capacity c (J/(kg·K), default `1900`, polypropylene).
    pub specific_heat: Real,
    /// Element layers through the thickness, each quadratic through its height (default `5`).
    pub layers: usize,
    /// Thickness ratio of neighbouring layers from the two surfaces inwards (≥ 1, default `1.5`).
    pub grading: Real,
    /// Local error allowed per conduction sub-step, relative to the scene's largest temperature
    /// difference (default `1e-4`: 0.01 K when a surface is heated by 100 K).
    pub tolerance: Real,
    /// Initial temperature everywhere (K, default `293.15`).
    pub initial: Real,
    /// Largest change of a nodal temperature in one time step (K, default `5`): a step that
    /// exceeds it is halved before the mechanical solve.
    pub max_change: Real,
    /// Surface conditions by region and time window; faces without one are insulated.
    pub boundary: Vec<HeatBoundary>,
    /// Moving heat sources (a flame, a laser spot).
    pub source: Vec<HeatSource>,
    /// Conductivities on regions of faces, over the uniform ones.
    pub regions: Vec<HeatRegion>,
    /// Softening E(T): rows `[T (K), factor]`, the moduli of each face times the factor at its
    /// mean temperature through the thickness (the current one, not the highest; linear between
    /// rows, constant beyond; default none).
    pub softening: Option<Vec<[Real; 2]>>,
}

/// `[[temperature.regions]]`: conductivities (W/(m·K)) of the faces whose `tri_tags` is one of
/// `tags` (any, when empty) and whose reference centroid lies in `inside` (when given).
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct HeatRegion {
    /// Tags (default: `[]`).
    pub tags: Vec<i64>,
    /// Box (m, default: none).
    pub inside: Option<FixBox>,
    /// Along the machine direction (W/(m·K)).
    pub conductivity_along: Option<Real>,
    /// Across it, in the plane (W/(m·K)).
    pub conductivity_across: Option<Real>,
    /// Through the thickness (W/(m·K)).
    pub conductivity_through: Option<Real>,
}

impl HeatRegion {
    /// The values along, across and through (the given ones).
    pub fn values(&self) -> [Option<Real>; 3] {
        [
            self.conductivity_along,
            self.conductivity_across,
            self.conductivity_through,
        ]
    }
}

impl Default for Temperature {
    fn default() -> Self {
        Temperature {
            enabled: false,
            conductivity_along: 0.22,
            conductivity_across: 0.22,
            conductivity_through: 0.22,
            specific_heat: 1900.0,
            layers: 5,
            grading: 1.5,
            tolerance: 1e-4,
            initial: 293.15,
            max_change: 5.0,
            boundary: Vec::new(),
            source: Vec::new(),
            regions: Vec::new(),
            softening: None,
        }
    }
}

/// One surface condition on a region of faces, during a time window.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct HeatBoundary {
    /// Faces whose `tri_tags` is one of these (empty: every face).
    pub tags: Vec<i64>,
    /// Only faces whose reference centroid lies in this box (m).
    pub inside: Option<FixBox>,
    /// `"top"` (the normal side) or `"bottom"`.
    pub side: SurfaceSide,
    /// `"value"` (prescribed temperature), `"flux"` (inward heat flux), `"robin"` (exchange
    /// with an ambient temperature: a heat gun, air) or `"sealed"` (insulated).
    pub kind: SurfaceKind,
    /// Temperature (K) for `"value"`, inward heat flux (W/m²) for `"flux"`.
    pub value: Real,
    /// Heat transfer coefficient h (W/(m²·K)) for `"robin"`: the outward flux is `h (T − ambient)`.
    pub h: Real,
    /// Ambient temperature (K) for `"robin"`.
    pub ambient: Real,
    /// Start of the window (s, default `0`).
    pub from: Real,
    /// End of the window (s, default: never). Windows need `kind = "flux"` or `"robin"`.
    pub until: Option<Real>,
}

impl Default for HeatBoundary {
    fn default() -> Self {
        HeatBoundary {
            tags: Vec::new(),
            inside: None,
            side: SurfaceSide::Top,
            kind: SurfaceKind::Sealed,
            value: 0.0,
            h: 0.0,
            ambient: 0.0,
            from: 0.0,
            until: None,
        }
    }
}

impl HeatBoundary {
    /// Whether the condition applies at time `t` (s): `from ≤ t < until`.
    pub fn active(&self, t: Real) -> bool {
        t >= self.from && self.until.is_none_or(|u| t < u)
    }

    /// Whether the condition holds for the whole run.
    pub fn permanent(&self) -> bool {
        self.from <= 0.0 && self.until.is_none()
    }
}

/// A heat source moving on a path: a Gaussian spot of total power `power` (W) and standard
/// deviation `radius` (m) on one side of the sheet, `q(r) = P/(2π σ²) exp(−r²/(2σ²))` (W/m²)
/// with r the distance of a face's reference centroid from the spot's centre.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct HeatSource {
    /// `"top"` or `"bottom"`.
    pub side: SurfaceSide,
    /// Total power into the sheet (W).
    pub power: Real,
    /// Standard deviation σ of the spot (m).
    pub radius: Real,
    /// Waypoints `[t, x, y, z]` (s, m, reference coordinates), times strictly increasing; the
    /// centre moves linearly between them. Outside the first and last time the source is off.
    pub path: Vec<[Real; 4]>,
}

impl Default for HeatSource {
    fn default() -> Self {
        HeatSource {
            side: SurfaceSide::Top,
            power: 0.0,
            radius: 0.0,
            path: Vec::new(),
        }
    }
}

impl HeatSource {
    /// The spot's centre at time `t` (s), `None` outside its path's times.
    pub fn centre(&self, t: Real) -> Option<[Real; 3]> {
        let p = &self.path;
        let (first, last) = (p.first()?, p.last()?);
        if t < first[0] || t > last[0] {
            return None;
        }
        let k = p
            .partition_point(|w| w[0] <= t)
            .clamp(1, p.len().max(2) - 1);
        if p.len() == 1 {
            return Some([first[1], first[2], first[3]]);
        }
        let (a, b) = (p[k - 1], p[k]);
        let s = ((t - a[0]) / (b[0] - a[0])).clamp(0.0, 1.0);
        Some(std::array::from_fn(|i| {
            a[i + 1] + s * (b[i + 1] - a[i + 1])
        }))
    }
}

/// `Ok` when `v` (K) is an absolute temperature: finite, above 0 K and at most
/// [`MAX_TEMPERATURE`].
pub(crate) fn absolute(key: &str, v: Real) -> Result<(), Invalid> {
    if v.is_finite() && v > 0.0 && v <= MAX_TEMPERATURE {
        return Ok(());
    }
    let hint = if v.is_finite() && v <= 0.0 {
        format!(
            " (temperatures are absolute, in kelvin: {} °C is {:.2} K)",
            human(v),
            v + 273.15
        )
    } else {
        String::new()
    };
    Err(Invalid::new(
        key,
        format!(
            "must be a temperature above 0 K and at most {} K, got {}{hint}",
            human(MAX_TEMPERATURE),
            human(v)
        ),
    ))
}

impl Temperature {
    /// Validates `[temperature]` (when enabled): conductivities, heat capacity, layers, the
    /// temperatures, the surfaces and their windows, the sources, and the dynamic mode and
    /// thermal law it needs. `moisture` is whether `[moisture]` is enabled.
    pub fn validate(&self, growth: &Growth, moisture: bool, mode: Mode) -> Result<(), Invalid> {
        let ck = Check;
        let t = self;
        if !t.enabled {
            return Ok(());
        }
        for (k, v) in [
            ("temperature.conductivity_along", t.conductivity_along),
            ("temperature.conductivity_across", t.conductivity_across),
            ("temperature.conductivity_through", t.conductivity_through),
            ("temperature.specific_heat", t.specific_heat),
            ("temperature.max_change", t.max_change),
        ] {
            ck.pos(k, v)?;
        }
        if t.layers == 0 || t.layers > MAX_LAYERS {
            return ck.inv(
                "temperature.layers",
                format!("must lie in 1..={MAX_LAYERS}, got {}", t.layers),
            );
        }
        let half = (t.layers / 2) as i32;
        if !(t.grading >= 1.0 && t.grading <= 10.0) || t.grading.powi(half) > 1e6 {
            return ck.inv(
                "temperature.grading",
                format!(
                    "must lie in 1..=10 with grading^(layers/2) ≤ 1e6, got {} with {} layers",
                    human(t.grading),
                    t.layers
                ),
            );
        }
        if !(t.tolerance >= 1e-10 && t.tolerance <= 0.1) {
            return ck.inv(
                "temperature.tolerance",
                format!("must lie in 1e-10..=0.1, got {}", human(t.tolerance)),
            );
        }
        absolute("temperature.initial", t.initial)?;
        if let Some(rows) = &t.softening {
            super::values::check_curve("temperature.softening", rows, "temperature (K)")?;
            for (i, r) in rows.iter().enumerate() {
                absolute(&format!("temperature.softening[{i}]"), r[0])?;
            }
        }
        for (i, r) in t.regions.iter().enumerate() {
            super::moisture::check_region(
                &format!("temperature.regions[{i}]"),
                &r.tags,
                r.inside.as_ref(),
                [
                    "conductivity_along",
                    "conductivity_across",
                    "conductivity_through",
                ],
                r.values(),
            )?;
        }
        for (i, b) in t.boundary.iter().enumerate() {
            let key = |k: &str| format!("temperature.boundary[{i}].{k}");
            ck.inside(&format!("temperature.boundary[{i}]"), b.inside.as_ref())?;
            match b.kind {
                SurfaceKind::Value => absolute(&key("value"), b.value)?,
                SurfaceKind::Flux => {
                    if !b.value.is_finite() {
                        return ck.inv(
                            &key("value"),
                            format!("must be a finite heat flux (W/m²), got {}", human(b.value)),
                        );
                    }
                }
                SurfaceKind::Robin => {
                    ck.nonneg(&key("h"), b.h)?;
                    absolute(&key("ambient"), b.ambient)?;
                }
                SurfaceKind::Sealed => {}
            }
            if !b.from.is_finite() || b.from < 0.0 {
                return ck.inv(
                    &key("from"),
                    format!("must be a time ≥ 0 s, got {}", human(b.from)),
                );
            }
            if let Some(u) = b.until {
                if !(u.is_finite() && u > b.from) {
                    return ck.inv(
                        &key("until"),
                        format!(
                            "must be a time after from = {} s, got {}",
                            human(b.from),
                            human(u)
                        ),
                    );
                }
            }
            if !b.permanent() && !matches!(b.kind, SurfaceKind::Flux | SurfaceKind::Robin) {
                return ck.inv(
                    &key("from"),
                    format!(
                        "a time window needs kind = \"flux\" or \"robin\" (a prescribed \
                         temperature or an insulated side holds for the whole run); got {:?}",
                        b.kind
                    ),
                );
            }
        }
        for (i, s) in t.source.iter().enumerate() {
            let key = |k: &str| format!("temperature.source[{i}].{k}");
            if !s.power.is_finite() {
                return ck.inv(
                    &key("power"),
                    format!("must be a finite power (W), got {}", human(s.power)),
                );
            }
            ck.pos(&key("radius"), s.radius)?;
            if s.path.is_empty() {
                return ck.inv(
                    &key("path"),
                    "needs at least one waypoint [t, x, y, z]".into(),
                );
            }
            for (j, w) in s.path.iter().enumerate() {
                if w.iter().any(|v| !v.is_finite()) {
                    return ck.inv(
                        &format!("temperature.source[{i}].path[{j}]"),
                        "must be finite [t (s), x, y, z (m)]".into(),
                    );
                }
                if j > 0 && w[0] <= s.path[j - 1][0] {
                    return ck.inv(
                        &format!("temperature.source[{i}].path[{j}]"),
                        format!(
                            "times must increase strictly: {} s after {} s",
                            human(w[0]),
                            human(s.path[j - 1][0])
                        ),
                    );
                }
            }
        }
        if mode != Mode::Dynamic {
            return ck.inv(
                "temperature.enabled",
                "heat conduction runs in time: set solver.mode = \"dynamic\" (a static scene \
                 reads growth.temperature_top and temperature_bottom instead)"
                    .into(),
            );
        }
        if moisture {
            return ck.inv(
                "temperature.enabled",
                "one field drives the rest forms: enable [moisture] or [temperature], not both"
                    .into(),
            );
        }
        if growth.law != GrowthLaw::ThermalShrink {
            return ck.inv(
                "temperature.enabled",
                format!(
                    "temperature drives the rest forms through growth.law = \"thermal_shrink\"; \
                     it is \"{}\"",
                    growth.law.name()
                ),
            );
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_source_moves_linearly_between_its_waypoints_and_is_off_outside_them() {
        let s = HeatSource {
            path: vec![
                [1.0, 0.0, 0.0, 0.0],
                [3.0, 2.0, 0.0, 0.0],
                [4.0, 2.0, 1.0, 0.0],
            ],
            ..Default::default()
        };
        assert_eq!(s.centre(0.5), None);
        assert_eq!(s.centre(1.0), Some([0.0, 0.0, 0.0]));
        assert_eq!(s.centre(2.0), Some([1.0, 0.0, 0.0]));
        assert_eq!(s.centre(3.5), Some([2.0, 0.5, 0.0]));
        assert_eq!(s.centre(4.0), Some([2.0, 1.0, 0.0]));
        assert_eq!(s.centre(4.5), None);
        let fixed = HeatSource {
            path: vec![[0.0, 1.0, 2.0, 3.0]],
            ..Default::default()
        };
        assert_eq!(fixed.centre(0.0), Some([1.0, 2.0, 3.0]));
    }

    #[test]
    fn a_temperature_below_absolute_zero_names_the_key_and_the_celsius_reading() {
        let e = absolute("temperature.initial", -20.0).unwrap_err();
        assert_eq!(e.key, "temperature.initial");
        assert!(
            e.reason.contains("above 0 K") && e.reason.contains("253.15"),
            "{}",
            e.reason
        );
        assert!(absolute("k", 0.0).is_err());
        assert!(absolute("k", Real::NAN).is_err());
        assert!(absolute("k", 293.15).is_ok());
    }
}
