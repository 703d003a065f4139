//! `[growth]`: the growth and swelling law that computes the target rest forms, and its
//! constants.

use super::limits::MAX_MOISTURE;
use super::rest::TargetForms;
use super::values::Field;
use super::{Check, Invalid};
use crate::math::Real;
use serde::{Deserialize, Serialize};

/// Which rest-form law computes the target forms (see [`crate::rest::laws`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GrowthLaw {
    /// No growth law: the targets come from `[rest]`.
    #[default]
    None,
    /// Uniform volumetric growth: `ā = e^{2s} a⁰`, `b̄ = e^s b⁰`, `h̄ = e^s h`, s from the face
    /// field `growth_factor` or `growth.s`.
    Isotropic,
    /// In-plane growth at fixed thickness: `ā = e^{2s} a⁰`, `b̄ = e^{2s} b⁰`.
    IsotropicInPlane,
    /// Seed 000's law as printed: `ā = e^{2s} a⁰`, `b̄ = b⁰`.
    IsotropicMetricOnly,
    /// Linear differential swelling from the top and bottom moisture, coefficient `mu`.
    LinearSwelling,
    /// Piecewise-constant bilayer, coefficients `mu_top` and `mu_bottom`.
    Bilayer,
    /// Linear swelling with a machine direction: `mu` along it, `mu_perp` across it.
    MachineDirection,
    /// Irreversible shrink set by the highest temperature reached, from the table `shrink`,
    /// along and across the machine direction and through the thickness.
    ThermalShrink,
    /// Crease relaxation: rest forms blended from the mesh's creased state toward the stored
    /// original shape (vertex field `original_positions`) as the moisture rises through
    /// `relax_moisture`.
    CreaseRelaxation,
}

impl GrowthLaw {
    /// Every law, `"none"` first (the registry in `rest::laws` has an entry for each other one).
    pub const ALL: [GrowthLaw; 9] = [
        GrowthLaw::None,
        GrowthLaw::Isotropic,
        GrowthLaw::IsotropicInPlane,
        GrowthLaw::IsotropicMetricOnly,
        GrowthLaw::LinearSwelling,
        GrowthLaw::Bilayer,
        GrowthLaw::MachineDirection,
        GrowthLaw::ThermalShrink,
        GrowthLaw::CreaseRelaxation,
    ];

    /// The law's settings value, as in the settings file.
    pub fn name(self) -> &'static str {
        match self {
            GrowthLaw::None => "none",
            GrowthLaw::Isotropic => "isotropic",
            GrowthLaw::IsotropicInPlane => "isotropic_in_plane",
            GrowthLaw::IsotropicMetricOnly => "isotropic_metric_only",
            GrowthLaw::LinearSwelling => "linear_swelling",
            GrowthLaw::Bilayer => "bilayer",
            GrowthLaw::MachineDirection => "machine_direction",
            GrowthLaw::ThermalShrink => "thermal_shrink",
            GrowthLaw::CreaseRelaxation => "crease_relaxation",
        }
    }

    /// The `[growth]` coefficients the law needs (each must be given).
    pub fn coefficients(self) -> &'static [&'static str] {
        match self {
            GrowthLaw::LinearSwelling => &["mu"],
            GrowthLaw::Bilayer => &["mu_top", "mu_bottom"],
            GrowthLaw::MachineDirection => &["mu", "mu_perp"],
            GrowthLaw::ThermalShrink => &["shrink"],
            GrowthLaw::CreaseRelaxation => &["relax_moisture"],
            _ => &[],
        }
    }
}

/// A growth law with the coefficients it reads: `[growth]` once validated ([`Growth::model`]).
/// The isotropic laws' factor `s` and the moisture are per-face inputs
/// ([`crate::rest::laws::GrowthInputs`]), not coefficients.
#[derive(Clone, Debug, PartialEq)]
pub enum GrowthModel {
    /// No growth law.
    None,
    /// Uniform volumetric growth.
    Isotropic,
    /// In-plane growth at fixed thickness.
    IsotropicInPlane,
    /// Seed 000's law as printed.
    IsotropicMetricOnly,
    /// Linear differential swelling.
    LinearSwelling {
        /// Moisture–length coefficient (per unit moisture).
        mu: Real,
    },
    /// Piecewise-constant bilayer.
    Bilayer {
        /// Coefficient of the top layer (per unit moisture).
        mu_top: Real,
        /// Coefficient of the bottom layer (per unit moisture).
        mu_bottom: Real,
        /// The layers' thicknesses and moduli.
        laminate: Laminate,
    },
    /// Linear swelling with a machine direction.
    MachineDirection {
        /// Coefficient along the machine direction (per unit moisture).
        mu: Real,
        /// Coefficient across it (per unit moisture).
        mu_perp: Real,
    },
    /// Crease relaxation with moisture.
    CreaseRelaxation {
        /// The mean moisture where the creases start to relax and where they are fully relaxed.
        relax: [Real; 2],
    },
    /// Irreversible thermal shrink.
    ThermalShrink {
        /// Shrink against the highest temperature reached.
        table: ShrinkTable,
    },
}

/// The bilayer's two layers: their thicknesses, moduli and whether each swells through its
/// thickness as it does in-plane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Laminate {
    /// The top layer's share φ of the reference thickness, in (0, 1).
    pub top_fraction: Real,
    /// Young's modulus of the top layer over the bottom layer's, `n > 0`.
    pub modulus_ratio: Real,
    /// Each layer's thickness grows by its own in-plane stretch (a gel's isotropic swelling).
    pub isotropic: bool,
}

impl Default for Laminate {
    fn default() -> Self {
        Laminate {
            top_fraction: 0.5,
            modulus_ratio: 1.0,
            isotropic: false,
        }
    }
}

/// `[[growth.regions]]`: coefficients on the faces whose `tri_tags` is one of `tags` (any, when
/// empty) and whose reference centroid lies in `inside` (when given); each given coefficient
/// replaces the uniform one there (later regions over earlier ones).
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GrowthRegion {
    /// Tags (default: `[]`).
    pub tags: Vec<i64>,
    /// Box (m, default: none).
    pub inside: Option<super::selection::FixBox>,
    /// See [`Growth::mu`].
    pub mu: Option<Real>,
    /// See [`Growth::mu_perp`].
    pub mu_perp: Option<Real>,
    /// See [`Growth::mu_top`].
    pub mu_top: Option<Real>,
    /// See [`Growth::mu_bottom`].
    pub mu_bottom: Option<Real>,
    /// See [`Growth::mu_top_perp`].
    pub mu_top_perp: Option<Real>,
    /// See [`Growth::mu_bottom_perp`].
    pub mu_bottom_perp: Option<Real>,
    /// See [`Growth::mu_through`].
    pub mu_through: Option<Real>,
    /// See [`Growth::print_thickness`].
    pub print_thickness: Option<Real>,
    /// See [`Growth::print_modulus_ratio`].
    pub print_modulus_ratio: Option<Real>,
}

impl GrowthRegion {
    /// The coefficients as `(key, value)` in the order mu, mu_perp, mu_top, mu_bottom,
    /// mu_top_perp, mu_bottom_perp, mu_through, print_thickness, print_modulus_ratio (`None`:
    /// not given).
    pub fn values(&self) -> [(&'static str, Option<Real>); 9] {
        [
            ("mu", self.mu),
            ("mu_perp", self.mu_perp),
            ("mu_top", self.mu_top),
            ("mu_bottom", self.mu_bottom),
            ("mu_top_perp", self.mu_top_perp),
            ("mu_bottom_perp", self.mu_bottom_perp),
            ("mu_through", self.mu_through),
            ("print_thickness", self.print_thickness),
            ("print_modulus_ratio", self.print_modulus_ratio),
        ]
    }

    fn validate(&self, i: usize) -> Result<(), Invalid> {
        let ck = Check;
        ck.region(
            &format!("growth.regions[{i}]"),
            &self.tags,
            self.inside.as_ref(),
        )?;
        for (k, v) in self.values().into_iter().filter_map(|(k, v)| Some((k, v?))) {
            print_range(&format!("growth.regions[{i}].{k}"), k, v)?;
            if !k.starts_with("print_") && (!v.is_finite() || v.abs() > MAX_MOISTURE) {
                return ck.inv(
                    &format!("growth.regions[{i}].{k}"),
                    format!(
                        "must lie in ±{}, got {}",
                        crate::math::human(MAX_MOISTURE),
                        crate::math::human(v)
                    ),
                );
            }
        }
        Ok(())
    }
}

/// Checks a printed layer's thickness (≥ 0, m) or modulus ratio (in [1e-6, 1e6]) given under
/// `key` (other coefficients pass).
pub fn print_range(key: &str, name: &str, v: Real) -> Result<(), Invalid> {
    // A region's key or a face field's name (`growth_` before it).
    let ok = match name.trim_start_matches("growth_") {
        "print_thickness" => v.is_finite() && v >= 0.0,
        "print_modulus_ratio" => v.is_finite() && (1e-6..=1e6).contains(&v),
        _ => true,
    };
    if ok {
        return Ok(());
    }
    Check.inv(
        key,
        format!(
            "a printed layer's thickness is ≥ 0 (m) and its modulus ratio lies in [1e-6, 1e6]; \
             got {}",
            crate::math::human(v)
        ),
    )
}

/// The thermal shrink law's table, validated ([`Growth::validate`]): at each temperature
/// (K, strictly increasing) the shrink strains along the machine direction, across it and
/// through the thickness (fractions of the length lost; negative: expansion). Linear between
/// rows, constant beyond the first and the last.
#[derive(Clone, Debug, PartialEq)]
pub struct ShrinkTable {
    /// Temperatures (K).
    pub temperature: Vec<Real>,
    /// Shrink along, across and through at each temperature.
    pub shrink: Vec<[Real; 3]>,
}

impl ShrinkTable {
    /// The shrink strains `[along, across, through]` at temperature `t` (K).
    pub fn at(&self, t: Real) -> [Real; 3] {
        let ts = &self.temperature;
        let n = ts.len();
        if n == 0 {
            return [0.0; 3];
        }
        if t.is_nan() || t <= ts[0] {
            return self.shrink[0];
        }
        if t >= ts[n - 1] {
            return self.shrink[n - 1];
        }
        let k = ts.partition_point(|&x| x <= t);
        let s = (t - ts[k - 1]) / (ts[k] - ts[k - 1]);
        let (a, b) = (self.shrink[k - 1], self.shrink[k]);
        std::array::from_fn(|i| a[i] + s * (b[i] - a[i]))
    }

    /// Whether the in-plane shrink is the same along and across at every row (no machine
    /// direction needed).
    pub fn isotropic_in_plane(&self) -> bool {
        self.shrink.iter().all(|r| r[0] == r[1])
    }
}

impl GrowthModel {
    /// The law's settings value.
    pub fn law(&self) -> GrowthLaw {
        match self {
            GrowthModel::None => GrowthLaw::None,
            GrowthModel::Isotropic => GrowthLaw::Isotropic,
            GrowthModel::IsotropicInPlane => GrowthLaw::IsotropicInPlane,
            GrowthModel::IsotropicMetricOnly => GrowthLaw::IsotropicMetricOnly,
            GrowthModel::LinearSwelling { .. } => GrowthLaw::LinearSwelling,
            GrowthModel::Bilayer { .. } => GrowthLaw::Bilayer,
            GrowthModel::MachineDirection { .. } => GrowthLaw::MachineDirection,
            GrowthModel::ThermalShrink { .. } => GrowthLaw::ThermalShrink,
            GrowthModel::CreaseRelaxation { .. } => GrowthLaw::CreaseRelaxation,
        }
    }
}

/// `[growth]`: the rest-form laws of seed 000 §3. Per-face mesh fields take precedence over the
/// uniform values here: `moisture_top`, `moisture_bottom` (dimensionless moisture fractions),
/// `growth_factor` (s), `machine_direction` (3 components, reference Cartesian coordinates).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Growth {
    /// The law (default: `"none"`).
    pub law: GrowthLaw,
    /// Moisture–length coefficient μ along the machine direction, or isotropic (per unit
    /// moisture; required by `"linear_swelling"` and `"machine_direction"`).
    pub mu: Option<Real>,
    /// Moisture–length coefficient μ⊥ across the machine direction (required by
    /// `"machine_direction"`).
    pub mu_perp: Option<Real>,
    /// Bilayer: coefficient of the top layer (required by `"bilayer"`).
    pub mu_top: Option<Real>,
    /// Bilayer: coefficient of the bottom layer (required by `"bilayer"`).
    pub mu_bottom: Option<Real>,
    /// Bilayer: coefficient of the top layer across the machine direction (default
    /// `mu_top`: the layer swells alike in every direction); `mu_top` is then along it.
    pub mu_top_perp: Option<Real>,
    /// Bilayer: coefficient of the bottom layer across the machine direction (default
    /// `mu_bottom`).
    pub mu_bottom_perp: Option<Real>,
    /// Moisture–thickness coefficient of the moisture laws (per unit moisture, default `0`:
    /// the thickness is kept): the rest thickness is `h (1 + μ_n (m⁺ + m⁻)/2)`.
    pub mu_through: Option<Real>,
    /// Bilayer: the top layer's share of the thickness, in (0, 1) (default `0.5`).
    pub top_fraction: Option<Real>,
    /// Bilayer: Young's modulus of the top layer over the bottom layer's (default `1`). The
    /// rest forms are projected about the laminate's neutral plane; `material` gives the
    /// stiffness of the shell as a whole.
    pub modulus_ratio: Option<Real>,
    /// Bilayer: each layer's thickness grows by the same stretch as its length (isotropic
    /// swelling, as in a gel; default `false`: the thickness is kept). Excludes `mu_through` and
    /// the coefficients across the machine direction.
    pub isotropic_layers: Option<bool>,
    /// Bilayer: thickness of a printed layer on top that does not swell (m, default `0`: none),
    /// included in the face's thickness (the film is the rest).
    pub print_thickness: Option<Real>,
    /// Bilayer: Young's modulus of the printed layer over the bottom layer's (default `1`).
    pub print_modulus_ratio: Option<Real>,
    /// Crease relaxation (required by `"crease_relaxation"`): the mean moisture `[m₀, m₁]`
    /// (m₀ < m₁) over which the rest forms go from the mesh's creased state to the stored
    /// original one, linearly.
    pub relax_moisture: Option<[Real; 2]>,
    /// Coefficients on regions of faces (veins, a printed layer), over the uniform ones; the
    /// face fields `growth_mu`, `growth_mu_perp`, `growth_mu_top`, `growth_mu_bottom`,
    /// `growth_mu_top_perp`, `growth_mu_bottom_perp`, `growth_mu_through` and the print's take
    /// precedence over both. A region or field that gives `mu_top` without `mu_top_perp` keeps
    /// the uniform `mu_top_perp` where `[growth]` gives one, else that layer swells alike in
    /// every direction (the same for the bottom).
    pub regions: Vec<GrowthRegion>,
    /// Uniform moisture at the top surface (dimensionless fraction, default `0`).
    pub moisture_top: Real,
    /// Uniform moisture at the bottom surface (default `0`).
    pub moisture_bottom: Real,
    /// Conformal growth factor s of the isotropic laws: a number or an expression of the
    /// reference x, y (the isotropic laws need it or the face field `growth_factor`).
    pub s: Option<Field>,
    /// Uniform machine direction in reference Cartesian coordinates (default `[1, 0, 0]`).
    pub machine_direction: [Real; 3],
    /// Thermal shrink table (required by `"thermal_shrink"`): rows `[T, along, across]` or
    /// `[T, along, across, through]`, T in kelvin strictly increasing, the shrink strains
    /// (fractions) each monotone in T; `through` is 0 with three columns.
    pub shrink: Option<Vec<Vec<Real>>>,
    /// Highest temperature reached at the top surface, without `[temperature]` (K, default
    /// `293.15`); linear through the thickness to `temperature_bottom`.
    pub temperature_top: Real,
    /// See `temperature_top` (K, default `293.15`).
    pub temperature_bottom: Real,
}

impl Default for Growth {
    fn default() -> Self {
        Growth {
            law: GrowthLaw::None,
            mu: None,
            mu_perp: None,
            mu_top: None,
            mu_bottom: None,
            mu_top_perp: None,
            mu_bottom_perp: None,
            mu_through: None,
            top_fraction: None,
            modulus_ratio: None,
            isotropic_layers: None,
            print_thickness: None,
            print_modulus_ratio: None,
            relax_moisture: None,
            regions: Vec::new(),
            moisture_top: 0.0,
            moisture_bottom: 0.0,
            s: None,
            machine_direction: [1.0, 0.0, 0.0],
            shrink: None,
            temperature_top: 293.15,
            temperature_bottom: 293.15,
        }
    }
}

impl Growth {
    /// The law with its own coefficients. On validated settings every coefficient the law
    /// needs is given ([`Growth::validate`]); a missing one reads as 0.
    pub fn model(&self) -> GrowthModel {
        let c = |v: Option<Real>| v.unwrap_or(0.0);
        match self.law {
            GrowthLaw::None => GrowthModel::None,
            GrowthLaw::Isotropic => GrowthModel::Isotropic,
            GrowthLaw::IsotropicInPlane => GrowthModel::IsotropicInPlane,
            GrowthLaw::IsotropicMetricOnly => GrowthModel::IsotropicMetricOnly,
            GrowthLaw::LinearSwelling => GrowthModel::LinearSwelling { mu: c(self.mu) },
            GrowthLaw::Bilayer => GrowthModel::Bilayer {
                mu_top: c(self.mu_top),
                mu_bottom: c(self.mu_bottom),
                laminate: self.laminate(),
            },
            GrowthLaw::MachineDirection => GrowthModel::MachineDirection {
                mu: c(self.mu),
                mu_perp: c(self.mu_perp),
            },
            GrowthLaw::ThermalShrink => GrowthModel::ThermalShrink {
                table: self.shrink_table(),
            },
            GrowthLaw::CreaseRelaxation => GrowthModel::CreaseRelaxation {
                relax: self.relax_moisture.unwrap_or([0.0, 1.0]),
            },
        }
    }

    /// True when `[growth]` or a region gives a bilayer layer's coefficient across the machine
    /// direction (`mu_top_perp`, `mu_bottom_perp`).
    pub fn anisotropic_layers(&self) -> bool {
        self.mu_top_perp.is_some()
            || self.mu_bottom_perp.is_some()
            || self
                .regions
                .iter()
                .any(|r| r.mu_top_perp.is_some() || r.mu_bottom_perp.is_some())
    }

    /// The bilayer's layers (defaults where not given).
    pub fn laminate(&self) -> Laminate {
        let d = Laminate::default();
        Laminate {
            top_fraction: self.top_fraction.unwrap_or(d.top_fraction),
            modulus_ratio: self.modulus_ratio.unwrap_or(d.modulus_ratio),
            isotropic: self.isotropic_layers.unwrap_or(d.isotropic),
        }
    }

    /// Checks the bilayer's layer keys: given only with `"bilayer"`, a fraction in (0, 1), a
    /// positive finite modulus ratio, and isotropic layers without `mu_through`.
    fn validate_laminate(&self) -> Result<(), Invalid> {
        let ck = Check;
        let region_print = self.regions.iter().enumerate().find_map(|(i, r)| {
            (r.print_thickness.is_some() || r.print_modulus_ratio.is_some())
                .then(|| format!("growth.regions[{i}]"))
        });
        let region_perp = self.regions.iter().enumerate().find_map(|(i, r)| {
            (r.mu_top_perp.is_some() || r.mu_bottom_perp.is_some())
                .then(|| format!("growth.regions[{i}]"))
        });
        let given = [
            ("growth.mu_top_perp", self.mu_top_perp.is_some()),
            ("growth.mu_bottom_perp", self.mu_bottom_perp.is_some()),
            (region_perp.as_deref().unwrap_or(""), region_perp.is_some()),
            ("growth.top_fraction", self.top_fraction.is_some()),
            ("growth.modulus_ratio", self.modulus_ratio.is_some()),
            ("growth.isotropic_layers", self.isotropic_layers.is_some()),
            ("growth.print_thickness", self.print_thickness.is_some()),
            (
                "growth.print_modulus_ratio",
                self.print_modulus_ratio.is_some(),
            ),
            (
                region_print.as_deref().unwrap_or(""),
                region_print.is_some(),
            ),
        ];
        if self.law != GrowthLaw::Bilayer {
            if let Some((k, _)) = given.iter().find(|(_, g)| *g) {
                return ck.inv(
                    k,
                    format!(
                        "describes the layers of growth.law = \"bilayer\" (print keys and \
                         mu_top_perp, mu_bottom_perp too), not of \"{}\"",
                        self.law.name()
                    ),
                );
            }
            return Ok(());
        }
        for (k, v) in [
            ("print_thickness", self.print_thickness),
            ("print_modulus_ratio", self.print_modulus_ratio),
        ] {
            if let Some(v) = v {
                print_range(&format!("growth.{k}"), k, v)?;
            }
        }
        if let Some(f) = self.top_fraction {
            if !(f > 0.0 && f < 1.0) {
                return ck.inv(
                    "growth.top_fraction",
                    format!(
                        "is the top layer's share of the thickness, in (0, 1); got {}",
                        crate::math::human(f)
                    ),
                );
            }
        }
        if let Some(n) = self.modulus_ratio {
            if !(n.is_finite() && (1e-6..=1e6).contains(&n)) {
                return ck.inv(
                    "growth.modulus_ratio",
                    format!(
                        "is E_top / E_bottom, in [1e-6, 1e6]; got {}",
                        crate::math::human(n)
                    ),
                );
            }
        }
        let region = self
            .regions
            .iter()
            .position(|r| r.mu_through.is_some())
            .map(|i| format!("growth.regions[{i}].mu_through"));
        if self.isotropic_layers == Some(true) && self.anisotropic_layers() {
            let key = match (self.mu_top_perp, self.mu_bottom_perp) {
                (Some(_), _) => "growth.mu_top_perp".to_string(),
                (None, Some(_)) => "growth.mu_bottom_perp".to_string(),
                _ => region_perp.unwrap_or_default(),
            };
            return ck.inv(
                &key,
                "isotropic_layers grows each layer's thickness by its in-plane stretch, which \
                 must then be the same in every direction; give isotropic_layers or the \
                 coefficients across the machine direction, not both"
                    .into(),
            );
        }
        if self.isotropic_layers == Some(true) && (self.mu_through.is_some() || region.is_some()) {
            return ck.inv(
                &region.unwrap_or_else(|| "growth.mu_through".into()),
                "isotropic_layers already grows each layer's thickness by its own stretch; \
                 give one or the other"
                    .into(),
            );
        }
        Ok(())
    }

    /// Checks `relax_moisture`: given exactly with `"crease_relaxation"`, two finite moistures
    /// within ±`MAX_MOISTURE`, the first below the second.
    fn validate_relax(&self) -> Result<(), Invalid> {
        let ck = Check;
        let key = "growth.relax_moisture";
        match (self.law, self.relax_moisture) {
            (GrowthLaw::CreaseRelaxation, None) => ck.inv(
                key,
                "growth.law = \"crease_relaxation\" needs relax_moisture = [m0, m1]: the mean \
                 moisture where the creases start to relax and where they are fully relaxed"
                    .into(),
            ),
            (GrowthLaw::CreaseRelaxation, Some([m0, m1])) => {
                if !(m0.is_finite()
                    && m1.is_finite()
                    && m0.abs() <= MAX_MOISTURE
                    && m1.abs() <= MAX_MOISTURE
                    && m0 < m1)
                {
                    return ck.inv(
                        key,
                        format!(
                            "needs finite moistures m0 < m1, got [{}, {}]",
                            crate::math::human(m0),
                            crate::math::human(m1)
                        ),
                    );
                }
                Ok(())
            }
            (_, Some(_)) => ck.inv(
                key,
                format!(
                    "belongs to growth.law = \"crease_relaxation\", not \"{}\"",
                    self.law.name()
                ),
            ),
            _ => Ok(()),
        }
    }

    /// `shrink` as a table (empty when not given; validated settings have one).
    pub fn shrink_table(&self) -> ShrinkTable {
        let rows = self.shrink.as_deref().unwrap_or(&[]);
        ShrinkTable {
            temperature: rows
                .iter()
                .map(|r| r.first().copied().unwrap_or(0.0))
                .collect(),
            shrink: rows
                .iter()
                .map(|r| std::array::from_fn(|i| r.get(i + 1).copied().unwrap_or(0.0)))
                .collect(),
        }
    }

    /// Checks `shrink`: at least two rows of 3 or 4 finite numbers, all of one length,
    /// temperatures above 0 K strictly increasing, shrink strains in (−1, 1) and each column
    /// monotone in temperature (the shrink set free by heating never reverses on further
    /// heating).
    fn validate_shrink(&self) -> Result<(), Invalid> {
        let ck = Check;
        let Some(rows) = &self.shrink else {
            return Ok(());
        };
        if rows.len() < 2 {
            return ck.inv(
                "growth.shrink",
                format!(
                    "needs at least two rows [T, along, across(, through)], got {}",
                    rows.len()
                ),
            );
        }
        let width = rows[0].len();
        for (i, r) in rows.iter().enumerate() {
            let key = format!("growth.shrink[{i}]");
            if !(r.len() == 3 || r.len() == 4) || r.len() != width {
                return ck.inv(
                    &key,
                    format!(
                        "rows are [T (K), along, across] or [T, along, across, through], all of \
                         one length; this one has {} numbers, the first {width}",
                        r.len()
                    ),
                );
            }
            super::temperature::absolute(&key, r[0])?;
            if let Some(v) = r[1..].iter().find(|v| !(v.is_finite() && v.abs() < 1.0)) {
                return ck.inv(
                    &key,
                    format!(
                        "shrink strains are fractions in (−1, 1) (a length cannot vanish), got \
                         {}",
                        crate::math::human(*v)
                    ),
                );
            }
            if i > 0 && r[0] <= rows[i - 1][0] {
                return ck.inv(
                    &key,
                    format!(
                        "the table is not monotone in temperature: {} K after {} K (temperatures \
                         must increase strictly)",
                        crate::math::human(r[0]),
                        crate::math::human(rows[i - 1][0])
                    ),
                );
            }
        }
        let names = ["along", "across", "through"];
        for c in 1..width {
            let mut dir = 0.0;
            for i in 1..rows.len() {
                let d = rows[i][c] - rows[i - 1][c];
                if d * dir < 0.0 {
                    return ck.inv(
                        &format!("growth.shrink[{i}]"),
                        format!(
                            "the {} shrink is not monotone in temperature: it turns at {} K \
                             (the shrink set free by heating cannot reverse on further heating)",
                            names[c - 1],
                            crate::math::human(rows[i - 1][0])
                        ),
                    );
                }
                if d != 0.0 {
                    dir = d;
                }
            }
        }
        Ok(())
    }

    /// Validates `[growth]`: finite coefficients, a valid `s`, and no growth law together with `rest.target`.
    /// `target` is `rest.target`: a growth law computes the targets, so none may be given.
    pub fn validate(&self, target: TargetForms) -> Result<(), Invalid> {
        let ck = Check;
        let g = self;
        for (k, v) in [
            ("mu", g.mu),
            ("mu_perp", g.mu_perp),
            ("mu_top", g.mu_top),
            ("mu_bottom", g.mu_bottom),
        ] {
            if v.is_none() && g.law.coefficients().contains(&k) {
                return ck.inv(
                    &format!("growth.{k}"),
                    format!(
                        "growth.law = \"{}\" needs its coefficient {k} (per unit moisture); \
                         it needs {}",
                        g.law.name(),
                        g.law.coefficients().join(" and ")
                    ),
                );
            }
        }
        for (k, v) in [
            ("growth.mu", g.mu.unwrap_or(0.0)),
            ("growth.mu_perp", g.mu_perp.unwrap_or(0.0)),
            ("growth.mu_top", g.mu_top.unwrap_or(0.0)),
            ("growth.mu_bottom", g.mu_bottom.unwrap_or(0.0)),
            ("growth.mu_top_perp", g.mu_top_perp.unwrap_or(0.0)),
            ("growth.mu_bottom_perp", g.mu_bottom_perp.unwrap_or(0.0)),
            ("growth.mu_through", g.mu_through.unwrap_or(0.0)),
            ("growth.moisture_top", g.moisture_top),
            ("growth.moisture_bottom", g.moisture_bottom),
        ] {
            if !v.is_finite() || v.abs() > MAX_MOISTURE {
                return ck.inv(
                    k,
                    format!(
                        "must lie in ±{MAX_MOISTURE_h}, got {v_h}",
                        MAX_MOISTURE_h = crate::math::human(MAX_MOISTURE),
                        v_h = crate::math::human(v)
                    ),
                );
            }
        }
        for (i, r) in g.regions.iter().enumerate() {
            r.validate(i)?;
        }
        if g.shrink.is_none() && g.law == GrowthLaw::ThermalShrink {
            return ck.inv(
                "growth.shrink",
                "growth.law = \"thermal_shrink\" needs its table shrink = [[T (K), along, \
                 across], ...]"
                    .into(),
            );
        }
        g.validate_shrink()?;
        g.validate_laminate()?;
        g.validate_relax()?;
        super::temperature::absolute("growth.temperature_top", g.temperature_top)?;
        super::temperature::absolute("growth.temperature_bottom", g.temperature_bottom)?;
        match &g.s {
            Some(Field::Value(v)) if !v.is_finite() => {
                return ck.inv(
                    "growth.s",
                    format!("must be finite, got {v_h}", v_h = crate::math::human(v)),
                )
            }
            Some(s @ Field::Expr(_)) => {
                if let Err(e) = s.compile() {
                    return ck.inv("growth.s", e.to_string());
                }
            }
            _ => {}
        }
        if g.law != GrowthLaw::None && target != TargetForms::None {
            return ck.inv(
                "growth.law",
                format!(
                    "a growth law computes the target forms, so rest.target must be \"none\" \
                     (it is {:?}); use one or the other",
                    target
                ),
            );
        }
        Ok(())
    }
}
