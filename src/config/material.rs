//! `[material]`: the moduli, density and thickness, the membrane model and its constants, and
//! the bending model.

use super::limits::{MAX_DENSITY, MAX_MODULUS};
use super::shell::StretchConvention;
use super::solver::Mode;
use super::values::vec_e;
use super::{Check, Invalid};
use crate::math::Real;
use serde::{Deserialize, Serialize};

/// Material constants. Per-face mesh fields (`ref_thicknesses`, `ref_shear_moduli`) override
/// the uniform values when present and enabled.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Material {
    /// Young's modulus E (Pa, default: `1.0e6`).
    pub young: Real,
    /// Poisson's ratio ν (dimensionless, −1 < ν ≤ 0.5, default: `0.3`).
    pub poisson: Real,
    /// Mass density per unit volume ρ (kg/m³, default: `1000.0`).
    pub density: Real,
    /// Shell thickness h (m, default: `0.01`).
    pub thickness: Real,
    /// Use the mesh's per-face `ref_thicknesses` field when present (default: `true`).
    pub use_mesh_thickness: bool,
    /// Use the mesh's per-face `ref_shear_moduli` μ when present, with E = 2μ(1+ν)
    /// (default: `true`).
    pub use_mesh_shear_modulus: bool,
    /// Stretching normalisation: `"koiter"` (standard, seed 000) or `"morphoshell"` (4× larger,
    /// MorphoShell's convention) (default: `"koiter"`).
    pub stretch_convention: StretchConvention,
    /// Discrete second fundamental form: `"midedge_average"` (seed 000), `"patch_fit"`
    /// (MorphoShell's quadratic patch fit, flat reference meshes only), `"midedge_sin"` or
    /// `"midedge_tan"` (mid-edge normals with one rotation DOF per edge), or `"none"` (a pure
    /// membrane: no bending energy) (default: `"midedge_sin"`).
    pub bending: BendingModel,
    /// Membrane material: `"koiter"` (St Venant–Kirchhoff, seed 000), `"neo_hookean"` or
    /// `"mooney_rivlin"` or `"gent"` (incompressible rubber), `"baraff_witkin"` (strain-limiting cloth,
    /// seed 003) (default: `"koiter"`).
    pub model: MaterialModel,
    /// Mooney–Rivlin `c₁` (Pa, default: `0`; required > 0 with `model = "mooney_rivlin"`).
    pub c1: Real,
    /// Mooney–Rivlin `c₂` (Pa, default: `0`, ≥ 0).
    pub c2: Real,
    /// MorphoShell's bend stiffening γ: the bending density `W_b` becomes `W_b + W_b²/(γ μ t)`
    /// (dimensionless, > 0; default: none = off; [`crate::energy::stiffening`]).
    pub bend_stiffening: Option<Real>,
    /// Gent rubber's limiting extensibility.
    pub gent: crate::config::gent::GentSettings,
    /// Baraff–Witkin constants and warp direction.
    pub baraff_witkin: BaraffWitkinSettings,
    /// The prism element's density law and thickness mode.
    pub prism: PrismSettings,
    /// Young's modulus and thickness on regions of faces (a printed strip, a rib), over the
    /// uniform ones; the mesh's `ref_thicknesses` and `ref_shear_moduli` take precedence.
    pub regions: Vec<MaterialRegion>,
}

/// `[[material.regions]]`: Young's modulus and thickness on the faces whose `tri_tags` is one of
/// `tags` (any, when empty) and whose reference centroid lies in `inside` (when given); each
/// given value replaces the uniform one there (later regions over earlier ones).
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MaterialRegion {
    /// Tags (default: `[]`).
    pub tags: Vec<i64>,
    /// Box (m, default: none).
    pub inside: Option<super::selection::FixBox>,
    /// Young's modulus there (Pa).
    pub young: Option<Real>,
    /// Thickness there (m).
    pub thickness: Option<Real>,
}

impl MaterialRegion {
    fn validate(&self, i: usize) -> Result<(), Invalid> {
        let ck = Check;
        let key = format!("material.regions[{i}]");
        ck.region(&key, &self.tags, self.inside.as_ref())?;
        if self.young.is_none() && self.thickness.is_none() {
            return ck.inv(&key, "gives neither young nor thickness".into());
        }
        for (k, v, max) in [
            ("young", self.young, MAX_MODULUS),
            ("thickness", self.thickness, crate::mesh::MAX_COORDINATE),
        ] {
            if let Some(v) = v {
                if !(v.is_finite() && v > 0.0 && v <= max) {
                    return ck.inv(
                        &format!("{key}.{k}"),
                        format!(
                            "must lie in (0, {}], got {}",
                            crate::math::human(max),
                            crate::math::human(v)
                        ),
                    );
                }
            }
        }
        Ok(())
    }
}

/// The membrane material.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MaterialModel {
    /// St Venant–Kirchhoff / Koiter.
    #[default]
    Koiter,
    /// Incompressible neo-Hookean, μ = E/(2(1+ν)).
    NeoHookean,
    /// Incompressible Mooney–Rivlin with `c1`, `c2`.
    MooneyRivlin,
    /// Incompressible Gent rubber, μ = E/(2(1+ν)), with `[material.gent] jm`.
    Gent,
    /// Strain-limiting Baraff–Witkin (seed 003).
    BaraffWitkin,
    /// Seed 002's three-prism element with a thickness (`[material.prism]`).
    Prism,
}

impl MaterialModel {
    /// Every material, in declaration order (the registry must have an entry for each; a test
    /// in `energy::registry` checks it).
    pub const ALL: [MaterialModel; 6] = [
        MaterialModel::Koiter,
        MaterialModel::NeoHookean,
        MaterialModel::MooneyRivlin,
        MaterialModel::Gent,
        MaterialModel::BaraffWitkin,
        MaterialModel::Prism,
    ];
}

/// The membrane material with the constants its model reads: `material.model` and its own keys
/// as one value, so that no material's constants are read under another model.
#[derive(Clone, Debug, PartialEq)]
pub enum MembraneMaterial {
    /// St Venant–Kirchhoff / Koiter.
    Koiter,
    /// Incompressible neo-Hookean.
    NeoHookean,
    /// Incompressible Mooney–Rivlin, `W = c1 (I₁ − 3) + c2 (I₂ − 3)` (Pa).
    MooneyRivlin {
        /// `c1` (Pa).
        c1: Real,
        /// `c2` (Pa).
        c2: Real,
    },
    /// Incompressible Gent rubber.
    Gent {
        /// The limiting extensibility `J_m` (dimensionless).
        jm: Real,
    },
    /// Strain-limiting Baraff–Witkin cloth, `[material.baraff_witkin]`.
    BaraffWitkin(BaraffWitkinSettings),
    /// Seed 002's prism element, `[material.prism]`.
    Prism(PrismSettings),
}

impl MembraneMaterial {
    /// Its `material.model`.
    pub fn model(&self) -> MaterialModel {
        match self {
            MembraneMaterial::Koiter => MaterialModel::Koiter,
            MembraneMaterial::NeoHookean => MaterialModel::NeoHookean,
            MembraneMaterial::MooneyRivlin { .. } => MaterialModel::MooneyRivlin,
            MembraneMaterial::Gent { .. } => MaterialModel::Gent,
            MembraneMaterial::BaraffWitkin(_) => MaterialModel::BaraffWitkin,
            MembraneMaterial::Prism(_) => MaterialModel::Prism,
        }
    }
}

/// The 3D strain energy of the prism element.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PrismLaw {
    /// St Venant–Kirchhoff, `ψ = μ E:E + λ/2 tr²E` (seed 002 Eqs. 6–7).
    #[default]
    Stvk,
    /// Compressible neo-Hookean, `ψ = μ/2 (I₁ − 3) − μ ln J + λ/2 ln²J`.
    NeoHookean,
}

/// How the prism element's thickness follows the deformation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PrismThickness {
    /// `h = h̄ Ā/A` inside the energy: exact incompressibility.
    #[default]
    Incompressible,
    /// Seed 002's position-based volume preservation after each step (dynamics).
    Pbd,
}

/// `[material.prism]`: seed 002's three-prism membrane.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PrismSettings {
    /// `"stvk"` or `"neo_hookean"` (default: `"stvk"`, the seed's).
    pub law: PrismLaw,
    /// `"incompressible"` (h = h̄ Ā/A inside the energy) or `"pbd"` (the seed's position-based
    /// volume preservation after each implicit step; dynamic mode) (default:
    /// `"incompressible"`).
    pub thickness: PrismThickness,
    /// `"pbd"`: projections per step (default: `1`, the seed's Algorithm 2).
    pub pbd_iterations: usize,
}

impl Default for PrismSettings {
    fn default() -> Self {
        PrismSettings {
            law: PrismLaw::Stvk,
            thickness: PrismThickness::Incompressible,
            pbd_iterations: 1,
        }
    }
}

/// `[material.baraff_witkin]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BaraffWitkinSettings {
    /// Stretch stiffness λ (Pa, default: `E/2`).
    pub lambda: Option<Real>,
    /// Shear stiffness μ (Pa, default: `E/(4(1+ν))`).
    pub mu: Option<Real>,
    /// Cubic strain-limiting coefficient r (dimensionless, ≥ 0, default: `100`).
    pub r: Real,
    /// Warp direction in reference Cartesian coordinates, projected on each rest face; the
    /// face field `warp_direction` overrides it (default: `[1, 0, 0]`).
    pub direction: [Real; 3],
}

impl Default for BaraffWitkinSettings {
    fn default() -> Self {
        BaraffWitkinSettings {
            lambda: None,
            mu: None,
            r: 100.0,
            direction: [1.0, 0.0, 0.0],
        }
    }
}

/// The discrete second fundamental form.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BendingModel {
    /// Seed 000's mid-edge average normals.
    MidedgeAverage,
    /// MorphoShell's quadratic patch fit through the face and 3 nearby nodes.
    PatchFit,
    /// Mid-edge normals with one rotation DOF per edge, `q = h sin(θ/2 + σφ)`.
    #[default]
    MidedgeSin,
    /// As `MidedgeSin` with `q = h tan(θ/2 + σφ)`.
    MidedgeTan,
    /// No bending energy (a pure membrane).
    None,
}

impl BendingModel {
    /// The edge-DOF variant, if this model has edge DOFs.
    pub fn angle_variant(self) -> Option<crate::config::shell::AngleVariant> {
        use crate::config::shell::AngleVariant;
        match self {
            BendingModel::MidedgeSin => Some(AngleVariant::Sin),
            BendingModel::MidedgeTan => Some(AngleVariant::Tan),
            _ => None,
        }
    }
}

impl Default for Material {
    fn default() -> Self {
        Material {
            young: 1.0e6,
            poisson: 0.3,
            density: 1000.0,
            thickness: 0.01,
            use_mesh_thickness: true,
            use_mesh_shear_modulus: true,
            stretch_convention: StretchConvention::Koiter,
            bending: BendingModel::default(),
            model: MaterialModel::default(),
            c1: 0.0,
            c2: 0.0,
            bend_stiffening: None,
            gent: Default::default(),
            baraff_witkin: BaraffWitkinSettings::default(),
            prism: PrismSettings::default(),
            regions: Vec::new(),
        }
    }
}

impl Material {
    /// The membrane material `model` names, with the constants it reads.
    pub fn membrane(&self) -> MembraneMaterial {
        match self.model {
            MaterialModel::Koiter => MembraneMaterial::Koiter,
            MaterialModel::NeoHookean => MembraneMaterial::NeoHookean,
            MaterialModel::MooneyRivlin => MembraneMaterial::MooneyRivlin {
                c1: self.c1,
                c2: self.c2,
            },
            MaterialModel::Gent => MembraneMaterial::Gent { jm: self.gent.jm() },
            MaterialModel::BaraffWitkin => {
                MembraneMaterial::BaraffWitkin(self.baraff_witkin.clone())
            }
            MaterialModel::Prism => MembraneMaterial::Prism(self.prism.clone()),
        }
    }

    /// Validates `[material]`: moduli, density, thickness, Poisson's ratio, the membrane model and its constants.
    /// `mode` is the run's mode (`solver.mode`): the position-based prism needs dynamics.
    pub fn validate(&self, mode: Mode) -> Result<(), Invalid> {
        let ck = Check;
        let m = self;
        ck.pos("material.young", m.young)?;
        if let Some(g) = m.bend_stiffening {
            ck.pos("material.bend_stiffening", g)?;
        }
        if m.young > MAX_MODULUS {
            return ck.inv(
                "material.young",
                format!(
                    "{} Pa is beyond {MAX_MODULUS_h} Pa (diamond is 1.2e12): energies of such a \
                     sheet overflow",
                    crate::math::human(m.young),
                    MAX_MODULUS_h = crate::math::human(MAX_MODULUS)
                ),
            );
        }
        ck.pos("material.density", m.density)?;
        ck.pos("material.thickness", m.thickness)?;
        for (key, v, max, unit) in [
            ("material.density", m.density, MAX_DENSITY, "kg/m³"),
            (
                "material.thickness",
                m.thickness,
                crate::mesh::MAX_COORDINATE,
                "m",
            ),
        ] {
            if v > max {
                return ck.inv(
                    key,
                    format!(
                        "{v_h} {unit} is beyond {max_h} {unit}: energies of such a sheet overflow",
                        v_h = crate::math::human(v),
                        max_h = crate::math::human(max)
                    ),
                );
            }
        }
        if !(m.poisson > -1.0 && m.poisson <= 0.5) {
            return ck.inv(
                "material.poisson",
                format!(
                    "must lie in (-1, 0.5], got {}",
                    crate::math::human(m.poisson)
                ),
            );
        }
        for (i, r) in m.regions.iter().enumerate() {
            r.validate(i)?;
        }
        self.validate_model(mode)?;
        Ok(())
    }

    /// Checks ranges and consistency.
    /// Validates `[material]`'s membrane model and its constants.
    fn validate_model(&self, mode: Mode) -> Result<(), Invalid> {
        let inv =
            |key: &str, reason: String| -> Result<(), Invalid> { Err(Invalid::new(key, reason)) };
        let m = self;
        if let Err(e) = m.gent.validate(m.model == MaterialModel::Gent) {
            return inv(&e.key, e.reason);
        }
        if m.model == MaterialModel::MooneyRivlin {
            if !(m.c1.is_finite() && m.c1 > 0.0) {
                return inv(
                    "material.c1",
                    format!(
                        "model = \"mooney_rivlin\" needs c1 > 0 (Pa), got {}",
                        crate::math::human(m.c1)
                    ),
                );
            }
            if !(m.c2.is_finite() && m.c2 >= 0.0) {
                return inv(
                    "material.c2",
                    format!("must be ≥ 0 (Pa), got {}", crate::math::human(m.c2)),
                );
            }
        }
        if m.model == MaterialModel::Prism {
            let p = &m.prism;
            let needs_lambda = p.law == PrismLaw::Stvk || p.thickness == PrismThickness::Pbd;
            if needs_lambda && m.poisson >= 0.5 {
                return inv(
                    "material.poisson",
                    format!(
                        "the prism element with law = {:?} and thickness = {:?} uses the 3D Lamé \
                         λ = Eν/((1+ν)(1−2ν)), infinite at ν = 0.5: use ν < 0.5 (e.g. 0.49), or \
                         law = \"neo_hookean\" with thickness = \"incompressible\"",
                        p.law, p.thickness
                    ),
                );
            }
            if p.thickness == PrismThickness::Pbd && mode != Mode::Dynamic {
                return inv(
                    "material.prism.thickness",
                    "\"pbd\" is seed 002's projection after each implicit step: it needs \
                     solver.mode = \"dynamic\" (use \"incompressible\" in static mode)"
                        .into(),
                );
            }
            if p.pbd_iterations == 0 || p.pbd_iterations > 100 {
                return inv(
                    "material.prism.pbd_iterations",
                    format!("must lie in 1..=100, got {}", p.pbd_iterations),
                );
            }
        }
        let bw = &m.baraff_witkin;
        if !(bw.r.is_finite() && bw.r >= 0.0) {
            return inv(
                "material.baraff_witkin.r",
                format!(
                    "must be ≥ 0 (a negative cubic term softens the strain limit), got {}",
                    crate::math::human(bw.r)
                ),
            );
        }
        for (key, v) in [("lambda", bw.lambda), ("mu", bw.mu)] {
            if let Some(v) = v {
                if !(v.is_finite() && v > 0.0) {
                    return inv(
                        &format!("material.baraff_witkin.{key}"),
                        format!(
                            "must be a positive number (Pa), got {v_h}",
                            v_h = crate::math::human(v)
                        ),
                    );
                }
            }
        }
        let d = bw.direction;
        if !d.iter().all(|c| c.is_finite()) || d.iter().all(|&c| c == 0.0) {
            return inv(
                "material.baraff_witkin.direction",
                format!("must be a finite non-zero vector, got {}", vec_e(&d)),
            );
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every model gives its own variant, which names the model back, with the constants that
    /// model reads and no other.
    #[test]
    fn each_model_carries_its_own_constants() {
        for model in MaterialModel::ALL {
            let m = Material {
                model,
                ..Material::default()
            };
            assert_eq!(m.membrane().model(), model);
        }
        let mr = Material {
            model: MaterialModel::MooneyRivlin,
            c1: 3e5,
            c2: 1e5,
            ..Material::default()
        };
        assert_eq!(
            mr.membrane(),
            MembraneMaterial::MooneyRivlin { c1: 3e5, c2: 1e5 }
        );
        let gent = Material {
            model: MaterialModel::Gent,
            gent: crate::config::gent::GentSettings { jm: Some(0.5) },
            ..Material::default()
        };
        assert_eq!(gent.membrane(), MembraneMaterial::Gent { jm: 0.5 });
        // The Mooney–Rivlin constants are not part of another model's material.
        let koiter = Material {
            c1: 3e5,
            ..Material::default()
        };
        assert_eq!(koiter.membrane(), MembraneMaterial::Koiter);
    }
}
