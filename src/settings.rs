//! The settings file: a TOML schema with every field's unit and default, strict parsing
//! (unknown keys are errors), `--set key=value` overrides, and validation with messages that
//! name the key. The full reference with examples is `docs/settings.md`.

use crate::config::shell::{HessianProjection, StretchConvention};
use crate::math::Real;
use crate::mesh::io::Format;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Most time steps a dynamic run may need at its largest step (`time.end / time.dt_max`).
pub const MAX_STEPS: Real = 1e9;
/// Most frames a dynamic run may write (`time.end / time.output_interval`).
pub const MAX_FRAMES: Real = 1e6;
/// Largest moisture magnitude accepted (a mass fraction; beyond this swelling overflows).
pub const MAX_MOISTURE: Real = 1e3;
/// Largest density accepted (kg/m³).
pub const MAX_DENSITY: Real = 1e30;
/// Largest Young's modulus accepted (Pa).
pub const MAX_MODULUS: Real = 1e15;
/// Largest gravitational acceleration (m/s², 10¹⁴ g): beyond it the gravity energy of a sheet
/// with the largest accepted density and coordinates overflows.
pub const MAX_GRAVITY: Real = 1e15;
/// Largest load value: forces (N), tractions (N/m), pressures (Pa), moments (N·m/m).
pub const MAX_LOAD: Real = 1e30;
/// Most element layers through the thickness in `[moisture]`.
pub const MAX_LAYERS: usize = 256;
/// Most holds on the dial (`dial.holds`): each is a solve to equilibrium and a frame.
pub const MAX_HOLDS: usize = 10_000;

/// Errors in the settings file or its overrides.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SettingsError {
    /// The file could not be read.
    #[error("{path}: cannot read settings: {reason}")]
    Read {
        /// The file.
        path: String,
        /// Why.
        reason: String,
    },
    /// The TOML is malformed, has an unknown key or a wrong type.
    #[error("{path}: {reason}")]
    Parse {
        /// The file.
        path: String,
        /// The parser's message, with line and key.
        reason: String,
    },
    /// A value is out of range or inconsistent.
    #[error("{path}: invalid '{key}': {reason}")]
    Invalid {
        /// The file.
        path: String,
        /// Dotted key.
        key: String,
        /// Why.
        reason: String,
    },
    /// A `--set` override is malformed.
    #[error("--set {arg}: {reason}")]
    Override {
        /// The argument as given.
        arg: String,
        /// Why.
        reason: String,
    },
}

/// A whole settings file.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Settings {
    /// Material constants.
    pub material: Material,
    /// Rest (programmed) fundamental forms and how they are dialled.
    pub rest: Rest,
    /// Growth and swelling laws that compute the target rest forms (seed 000 §3).
    pub growth: Growth,
    /// Moisture diffusion that drives the swelling laws in time (seed 000 §4).
    pub moisture: Moisture,
    /// What is solved: statics or dynamics, and the Newton solver's controls.
    pub solver: Solver,
    /// Time stepping (dynamic mode).
    pub time: Time,
    /// Explicit damped dynamics (explicit mode): time step, damping, dial and equilibrium test.
    pub explicit: Explicit,
    /// How the rest forms are dialled: order and hold points (every mode).
    pub dial: Dial,
    /// External loads.
    pub loads: Loads,
    /// An enclosed gas (closed meshes): amount, pressure or volume control.
    pub gas: Gas,
    /// Ground contact with friction.
    pub contact: Contact,
    /// Two horizontal glass slides squeezing the sheet (MorphoShell's).
    pub slides: Slides,
    /// Rigid obstacles (`[[obstacles]]`), fixed or moved with the dial.
    pub obstacles: Vec<crate::config::obstacle::ObstacleSettings>,
    /// Fixed vertices.
    pub constraints: Constraints,
    /// Output files.
    pub output: Output,
}

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
#[derive(Clone, Debug, Serialize, Deserialize)]
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
#[derive(Clone, Debug, Serialize, Deserialize)]
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

/// The softening factor of the static solver's membrane continuation.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(untagged)]
pub enum Softening {
    /// A factor ≥ 1 (1 disables the continuation).
    Factor(Real),
    /// `"auto"`: chosen from the mesh size and thickness.
    Auto(Auto),
}

/// The word `"auto"`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Auto {
    /// Automatic.
    Auto,
}

impl Softening {
    /// The factor for a sheet of size `size` (m) and smallest thickness `h` (m).
    pub fn factor(self, size: Real, h: Real) -> Real {
        match self {
            Softening::Factor(c) => c,
            Softening::Auto(_) => ((size / (10.0 * h)).powi(2)).clamp(1.0, 1e8),
        }
    }
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
        }
    }
}

/// Where the target rest forms come from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TargetForms {
    /// No growth: ā = a⁰, b̄ = b⁰ of the input mesh (seed 000 "No Growth").
    #[default]
    None,
    /// `abar`, `bbar` from these settings (numbers or expressions of x, y), in reference
    /// Cartesian coordinates.
    Uniform,
    /// Per-face `abar_info` (required) and `bbar_info` (optional, default 0) mesh fields, in
    /// reference Cartesian coordinates (MorphoShell's files).
    Mesh,
    /// The liquid-crystal director law ([`crate::rest::lce`]): per face a director angle θ, a stretch
    /// λ and a ratio ν, from `[rest.lce]` or from the mesh's `abar_info` read as (θ, λ, ν).
    Lce,
}

impl TargetForms {
    /// Every value, for the registry test.
    pub const ALL: [TargetForms; 4] = [
        TargetForms::None,
        TargetForms::Uniform,
        TargetForms::Mesh,
        TargetForms::Lce,
    ];
}

/// The director law's per-face values, numbers or expressions of the reference x, y (m) at each
/// face's centroid.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LceSettings {
    /// Director angle θ from the reference x axis (rad).
    pub theta: Field,
    /// Target stretch λ along the director (> 0).
    pub lambda: Field,
    /// Opto-thermal Poisson ratio ν (default: `0.5`).
    #[serde(default = "half")]
    pub nu: Field,
}

fn half() -> Field {
    Field::Value(0.5)
}

/// Rest forms.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Rest {
    /// Target forms: `"none"`, `"uniform"` or `"mesh"` (default: `"none"`).
    pub target: TargetForms,
    /// Target ā as `[xx, xy, yy]` in reference Cartesian coordinates, each a number or an
    /// expression of x, y (dimensionless, default: `[1, 0, 1]`).
    pub abar: [Field; 3],
    /// Target b̄ as `[xx, xy, yy]` in reference Cartesian coordinates, numbers or expressions
    /// (1/m, default: `[0, 0, 0]`).
    pub bbar: [Field; 3],
    /// Dynamic mode: time over which the forms are dialled linearly from the input mesh's forms to
    /// the target (s, default: `0` = target from the start).
    pub dial_time: Real,
    /// The director law's values for `target = "lce"` (default: none, read from the mesh).
    pub lce: Option<LceSettings>,
}

impl Default for Rest {
    fn default() -> Self {
        Rest {
            target: TargetForms::None,
            abar: [1.0.into(), 0.0.into(), 1.0.into()],
            bbar: [0.0.into(), 0.0.into(), 0.0.into()],
            dial_time: 0.0,
            lce: None,
        }
    }
}

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
}

impl GrowthLaw {
    /// Every law, `"none"` first (the registry in `rest::laws` has an entry for each other one).
    pub const ALL: [GrowthLaw; 7] = [
        GrowthLaw::None,
        GrowthLaw::Isotropic,
        GrowthLaw::IsotropicInPlane,
        GrowthLaw::IsotropicMetricOnly,
        GrowthLaw::LinearSwelling,
        GrowthLaw::Bilayer,
        GrowthLaw::MachineDirection,
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
        }
    }

    /// The `[growth]` coefficients the law needs (each must be given).
    pub fn coefficients(self) -> &'static [&'static str] {
        match self {
            GrowthLaw::LinearSwelling => &["mu"],
            GrowthLaw::Bilayer => &["mu_top", "mu_bottom"],
            GrowthLaw::MachineDirection => &["mu", "mu_perp"],
            _ => &[],
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
    /// Uniform moisture at the top surface (dimensionless fraction, default `0`).
    pub moisture_top: Real,
    /// Uniform moisture at the bottom surface (default `0`).
    pub moisture_bottom: Real,
    /// Conformal growth factor s of the isotropic laws: a number or an expression of the
    /// reference x, y (the isotropic laws need it or the face field `growth_factor`).
    pub s: Option<Field>,
    /// Uniform machine direction in reference Cartesian coordinates (default `[1, 0, 0]`).
    pub machine_direction: [Real; 3],
}

impl Default for Growth {
    fn default() -> Self {
        Growth {
            law: GrowthLaw::None,
            mu: None,
            mu_perp: None,
            mu_top: None,
            mu_bottom: None,
            moisture_top: 0.0,
            moisture_bottom: 0.0,
            s: None,
            machine_direction: [1.0, 0.0, 0.0],
        }
    }
}

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
    /// Exchange with a moist ground (`[moisture.ground]`, needs `[contact]`), else none.
    pub ground: Option<GroundMoisture>,
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
            ground: None,
        }
    }
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

/// Static equilibrium or dynamics.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Mode {
    /// Minimise the potential energy, dialling the rest forms in by adaptive continuation.
    #[default]
    Static,
    /// Implicit Euler dynamics with Kelvin–Voigt damping.
    Dynamic,
    /// MorphoShell's explicit damped Newtonian dynamics (symplectic Euler, gradient only), run
    /// until the equilibrium test fires (`[explicit]`).
    Explicit,
}

/// Solver controls.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Solver {
    /// `"static"` or `"dynamic"` (default: `"static"`).
    pub mode: Mode,
    /// Newton converges when ‖∇E‖∞ ≤ tolerance × F, with F = max(E·h) × mean edge length, the
    /// membrane force of a unit strain on one edge (dimensionless, default: `1e-9`).
    pub tolerance: Real,
    /// Newton iterations allowed per solve before the step is cut (default: `40`).
    pub max_newton_iterations: usize,
    /// Hessian used by Newton: `"adaptive"` (exact when it factorises, Gauss–Newton otherwise),
    /// `"none"` (exact + growing diagonal shift), `"gauss_newton"` (always), or per-element
    /// eigenvalue projection `"clamp_zero"` / `"abs"` (default: `"adaptive"`).
    pub hessian_projection: HessianProjection,
    /// Static mode: first continuation increment of the dial factor (dimensionless, (0, 1],
    /// default: `1.0`).
    pub continuation_step: Real,
    /// Static mode: the increment below which continuation gives up (default: `1e-4`).
    pub min_continuation_step: Real,
    /// Static mode: the largest increment of the dial factor (dimensionless, (0, 1], default:
    /// `1.0`); with `output.continuation_frames`, the spacing of the frames along the path.
    pub max_continuation_step: Real,
    /// Static mode: membrane continuation. The dial continuation runs with the stretching
    /// weight divided by a factor c (a sheet √c times thicker, relative to bending), then the
    /// weight is raised to its true value in warm-started solves (×10, ×100, … per solve). Thin
    /// sheets that roll or fold take far fewer Newton iterations this way, and the final state is
    /// a converged, stability-checked equilibrium of the true energy. `"auto"` (default): c =
    /// (L / 10 h)², L the reference mesh's bounding-box diagonal and h its smallest thickness, so
    /// that the softened sheet is as stiff as one of thickness L/10; a number ≥ 1 sets c; 1
    /// disables it.
    pub membrane_continuation: Softening,
    /// Out-of-plane perturbation that breaks the symmetry of a flat start, as a fraction of the
    /// mean edge length (dimensionless, default: `1e-3`; 0 disables). Applied when the sheet is
    /// exactly planar, and again (×10 each time) when a converged state is found to be a saddle.
    pub symmetry_breaking: Real,
    /// Seed of the symmetry-breaking perturbation (default: `1`).
    pub seed: u64,
    /// Check that a static equilibrium is a minimum (Cholesky of H + δI with a tiny δ), and
    /// perturb and re-solve if it is a saddle (default: `true`).
    pub check_stability: bool,
    /// Newton solves allowed to escape a saddle before giving up (default: `4`).
    pub max_saddle_escapes: usize,
}

impl Default for Solver {
    fn default() -> Self {
        Solver {
            mode: Mode::Static,
            tolerance: 1e-9,
            max_newton_iterations: 40,
            hessian_projection: HessianProjection::Adaptive,
            continuation_step: 1.0,
            min_continuation_step: 1e-4,
            max_continuation_step: 1.0,
            membrane_continuation: Softening::Auto(Auto::Auto),
            symmetry_breaking: 1e-3,
            seed: 1,
            check_stability: true,
            max_saddle_escapes: 4,
        }
    }
}

/// Time stepping for dynamic mode.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Time {
    /// End time (s, default: `1.0`).
    pub end: Real,
    /// First time step (s, default: `1e-3`).
    pub dt: Real,
    /// Smallest time step before the run stops unconverged (s, default: `1e-9`).
    pub dt_min: Real,
    /// Largest time step (s, default: `0.1`).
    pub dt_max: Real,
    /// Interval between output frames (s, default: `0.1`).
    pub output_interval: Real,
    /// Kelvin–Voigt retardation time η of seed 000's damping potential (s, default: `0` = off).
    pub damping: Real,
    /// Stop early when the residual without inertia is below tolerance and the kinetic energy is
    /// below `equilibrium_kinetic` × elastic energy (default: `false`).
    pub stop_at_equilibrium: bool,
    /// Relative kinetic-energy threshold for `stop_at_equilibrium` (dimensionless, default: `1e-10`).
    pub equilibrium_kinetic: Real,
}

impl Default for Time {
    fn default() -> Self {
        Time {
            end: 1.0,
            dt: 1e-3,
            dt_min: 1e-9,
            dt_max: 0.1,
            output_interval: 0.1,
            damping: 0.0,
            stop_at_equilibrium: false,
            equilibrium_kinetic: 1e-10,
        }
    }
}

/// Which equilibrium test stops an explicit run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EquilibriumTest {
    /// The force residual relative to the force scale, the kinetic energy, and the changes of
    /// the energy and of the shape over a window of time (cannot fire while the shape moves).
    #[default]
    Window,
    /// MorphoShell's: the largest node force below a fraction of μ t a_min and the largest node
    /// speed below a fraction of √(μ/ρ), checked once per check interval.
    Morphoshell,
}

/// Explicit damped dynamics (MorphoShell's integrator; [`crate::integrate`]'s explicit driver).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Explicit {
    /// The time step's prefactor p in `dt = p · min(0.185 √(ρ/μ) a_min, √(ρt/D) a_min²/2π)`
    /// (default: `0.8`, MorphoShell's common value; the run reports the mesh's stability limit).
    pub time_step_prefactor: Real,
    /// Damping while the forms are dialled, as a multiple of the critical damping of the longest
    /// bending mode (default: `1.0`).
    pub damping_prefactor_dial: Real,
    /// Damping while waiting for equilibrium (default: `1.0`).
    pub damping_prefactor_wait: Real,
    /// Time to dial the forms from 0 to 1, in long times (default: `1.0`).
    pub dial_long_times: Real,
    /// Steps of gradient-descent (overdamped) dynamics before the Newtonian dynamics (default: `0`).
    pub gradient_descent_steps: usize,
    /// Frames per long time (default: `10`).
    pub frames_per_long_time: Real,
    /// The run stops, unconverged, after this many long times (default: `1000`).
    pub max_long_times: Real,
    /// `"window"` (default) or `"morphoshell"`.
    pub equilibrium: EquilibriumTest,
    /// Window test: the force residual ‖∇E‖∞ / F must be below this (default: `1e-7`).
    pub force_tolerance: Real,
    /// Window test: the largest vertex displacement over a window, over the sheet's size, must be
    /// below this (default: `1e-7`).
    pub shape_tolerance: Real,
    /// Window test: the relative change of the elastic energy over a window (default: `1e-7`).
    pub energy_tolerance: Real,
    /// The window (and MorphoShell's check interval), in long times (default: `0.01`).
    pub window_long_times: Real,
    /// MorphoShell's test: largest force / (μ t a_min) (default: `1e-6`).
    pub morphoshell_force_threshold: Real,
    /// MorphoShell's test: largest speed / √(μ/ρ) (default: `1e-5`).
    pub morphoshell_speed_threshold: Real,
}

impl Default for Explicit {
    fn default() -> Self {
        Explicit {
            time_step_prefactor: 0.8,
            damping_prefactor_dial: 1.0,
            damping_prefactor_wait: 1.0,
            dial_long_times: 1.0,
            gradient_descent_steps: 0,
            frames_per_long_time: 10.0,
            max_long_times: 1000.0,
            equilibrium: EquilibriumTest::Window,
            force_tolerance: 1e-7,
            shape_tolerance: 1e-7,
            energy_tolerance: 1e-7,
            window_long_times: 0.01,
            morphoshell_force_threshold: 1e-6,
            morphoshell_speed_threshold: 1e-5,
        }
    }
}

/// The order in which ā and b̄ are dialled.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DialOrder {
    /// Both together: dial s takes both from their initial to their target values.
    #[default]
    Together,
    /// b̄ over the first half of the dial (ā at its initial value), then ā over the second half.
    BbarFirst,
}

/// How the rest forms are dialled.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Dial {
    /// `"together"` (default) or `"bbar_first"`.
    pub order: DialOrder,
    /// Dial factors in (0, 1) at which the dial stops until the sheet is at equilibrium, then
    /// goes on (ascending; default: none).
    pub holds: Vec<Real>,
    /// Where the dial starts: `"reference"` (default) or `"start"`.
    pub from: DialFrom,
}

/// The forms at dial 0.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DialFrom {
    /// The reference mesh's own forms.
    #[default]
    Reference,
    /// The forms of the state the run starts from (a `--restart` frame or MorphoShell ansatz,
    /// as MorphoShell's `dialling_from_ansatz_rather_than_ref_state`); the dial starts at 0.
    /// Without a restart this is the reference mesh.
    Start,
}

/// How the upper glass slide moves.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SlideControl {
    /// Down at `speed` until it has moved `travel`.
    #[default]
    Speed,
    /// Pressed down by `force`, moving overdamped against the sheet's push.
    Force,
}

/// Glass slides: two planes z = lower and z = upper (see [`crate::energy::slides`]).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Slides {
    /// Build the slides (default: `false`).
    pub enabled: bool,
    /// Height of the fixed lower slide (m; default: the reference mesh's lowest z).
    pub lower: Option<Real>,
    /// Starting height of the upper slide (m; default: the reference mesh's highest z).
    pub upper: Option<Real>,
    /// MorphoShell's `slide_stiffness_prefactor` p_k: a vertex beyond a slide by d feels
    /// `p_k μ t d` (N), μ and t the smallest shear modulus and thickness (default: `100`).
    pub stiffness_prefactor: Real,
    /// Coulomb friction coefficient of stick/slip friction on vertices in contact (default: `0`;
    /// explicit mode).
    pub friction: Real,
    /// Damping of the contact along the normal, as a fraction of the critical damping
    /// `2√(k m)` of a vertex of mass m on the penalty spring k (default: `1`, critical;
    /// MorphoShell's contact is undamped, `0`; explicit mode). It dissipates only while a vertex
    /// moves into or out of a slide, so equilibria are unchanged.
    pub contact_damping: Option<Real>,
    /// `"speed"` (default) or `"force"` (explicit mode).
    pub control: SlideControl,
    /// Speed control: downward speed of the upper slide (m/s; default: `0`).
    pub speed: Real,
    /// Speed control: the distance it moves before it stops (m; default: `0`).
    pub travel: Real,
    /// Force control: the downward force on the upper slide (N; default: `0`).
    pub force: Real,
    /// Force control: the slide's drag coefficient (N·s/m; default: the sheet's mass times its
    /// waiting drag rate).
    pub drag: Option<Real>,
    /// The upper slide stays still until the dial has reached 1 (default: `false`: it moves
    /// from the start).
    pub after_dial: bool,
}

impl Default for Slides {
    fn default() -> Self {
        Slides {
            enabled: false,
            lower: None,
            upper: None,
            stiffness_prefactor: 100.0,
            friction: 0.0,
            contact_damping: None,
            control: SlideControl::Speed,
            speed: 0.0,
            travel: 0.0,
            force: 0.0,
            drag: None,
            after_dial: false,
        }
    }
}

/// External loads.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Loads {
    /// Gravitational acceleration (m/s², default: `[0, 0, 0]`; Earth: `[0, 0, -9.81]`).
    pub gravity: [Real; 3],
    /// Point forces (`[[loads.point]]`, default: none).
    pub point: Vec<PointLoad>,
    /// Tractions per unit length on boundary edges (`[[loads.traction]]`, default: none).
    pub traction: Vec<TractionLoad>,
    /// Follower pressures on faces (`[[loads.pressure]]`, default: none).
    pub pressure: Vec<PressureLoad>,
    /// Distributed moments along boundaries (`[[loads.moment]]`, default: none).
    pub moment: Vec<MomentLoad>,
}

/// How the enclosed gas is controlled (see [`crate::energy::gas`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GasControl {
    /// No gas.
    #[default]
    None,
    /// A fixed amount of ideal gas (`amount`), dialled from the outside pressure's.
    Amount,
    /// A prescribed gauge pressure (`pressure`), dialled from 0.
    Pressure,
    /// A prescribed enclosed volume (`volume`), the pressure being its multiplier.
    Volume,
}

/// The gas law of amount control.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GasProcess {
    /// `p V = const` (seed 002 Eq. 12).
    #[default]
    Isothermal,
    /// `p V^γ = const`.
    Adiabatic,
}

/// `[gas]`: a gas enclosed by the mesh (seed 002 §5). The mesh must be a closed, consistently
/// oriented surface with outward normals.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Gas {
    /// `"none"`, `"amount"`, `"pressure"` or `"volume"` (default: `"none"`).
    pub control: GasControl,
    /// Amount control: the gas's `p V` at the reference volume when the dial reaches 1, i.e.
    /// its `n R T` (J = Pa·m³, > 0).
    pub amount: Real,
    /// Pressure control: the gauge pressure at dial 1 (Pa; positive inflates).
    pub pressure: Real,
    /// Volume control: the enclosed volume at dial 1 (m³, > 0).
    pub volume: Real,
    /// Pressure outside (Pa, ≥ 0, default: `0`); amount control inflates against it.
    pub external_pressure: Real,
    /// Amount control: `"isothermal"` (p V = const) or `"adiabatic"` (p V^γ = const)
    /// (default: `"isothermal"`).
    pub process: GasProcess,
    /// Heat capacity ratio γ of the adiabatic process (dimensionless, > 1, default: `1.4`).
    pub gamma: Real,
}

impl Default for Gas {
    fn default() -> Self {
        Gas {
            control: GasControl::None,
            amount: 0.0,
            pressure: 0.0,
            volume: 0.0,
            external_pressure: 0.0,
            process: GasProcess::Isothermal,
            gamma: 1.4,
        }
    }
}

/// A distributed moment per unit length along the boundary edges whose two vertices are
/// selected, scaled by the dial; see [`crate::energy::loads::moment`].
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MomentLoad {
    /// Moment per unit length (N·m/m); positive turns the boundary's outward direction toward
    /// the side the face normals point to.
    pub moment: Real,
    /// The boundary vertices.
    #[serde(flatten)]
    pub on: Selection,
}

impl Loads {
    /// Whether any point, traction or pressure load is given (gravity aside).
    pub fn any_external(&self) -> bool {
        !(self.point.is_empty()
            && self.traction.is_empty()
            && self.pressure.is_empty()
            && self.moment.is_empty())
    }
}

/// Which vertices (by `node_tags`) or faces (by `tri_tags`) a load or constraint acts on: those
/// whose tag is in `tags` (any, when empty) and, when `inside` is given, whose reference position
/// (a face: its centroid) lies in that box. At least one of the two must be given.
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct Selection {
    /// Tags (default: `[]`).
    pub tags: Vec<i64>,
    /// Box (m, default: none).
    pub inside: Option<FixBox>,
}

/// A dead point force, scaled by the dial (the load factor).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PointLoad {
    /// Total force on the selected vertices, shared equally among them (N).
    pub force: [Real; 3],
    /// The vertices.
    #[serde(flatten)]
    pub on: Selection,
}

/// A dead traction per unit reference length on the boundary edges whose two vertices are
/// selected, scaled by the dial; each edge gives half of `traction × length` to each end.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TractionLoad {
    /// Force per unit length (N/m).
    pub traction: [Real; 3],
    /// The boundary vertices.
    #[serde(flatten)]
    pub on: Selection,
}

/// A follower pressure on the selected faces (all faces when neither tags nor a box is given),
/// pushing along each face's normal, scaled by the dial.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PressureLoad {
    /// Pressure (Pa); positive pushes toward the side the face normals point to.
    pub pressure: Real,
    /// The faces (by `tri_tags` or centroid box).
    #[serde(flatten, default)]
    pub on: Selection,
}

/// A number, or an expression of the reference coordinates x, y (m) as a string (see
/// `src/expr.rs`), evaluated at each face's reference centroid.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(untagged)]
pub enum Field {
    /// A constant.
    Value(Real),
    /// An expression of x and y.
    Expr(String),
}

impl Field {
    /// The parsed expression (a constant for a number).
    pub fn compile(&self) -> Result<crate::expr::Expr, crate::expr::ExprError> {
        match self {
            Field::Value(v) => Ok(crate::expr::Expr::Num(*v)),
            Field::Expr(s) => crate::expr::Expr::parse(s),
        }
    }

    /// The constant, if this is one.
    pub fn constant(&self) -> Option<Real> {
        match self {
            Field::Value(v) => Some(*v),
            Field::Expr(_) => None,
        }
    }
}

impl From<Real> for Field {
    fn from(v: Real) -> Self {
        Field::Value(v)
    }
}

/// A number or the word `"auto"`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(untagged)]
pub enum AutoOr {
    /// A value.
    Value(Real),
    /// `"auto"`: chosen by the solver (each use documents how).
    Auto(Auto),
}

impl AutoOr {
    /// The value, or `auto` when automatic.
    pub fn or(self, auto: Real) -> Real {
        match self {
            AutoOr::Value(v) => v,
            AutoOr::Auto(_) => auto,
        }
    }
}

/// `[contact]`: a rigid ground plane the sheet rests on and lifts off from, with Coulomb
/// friction, inside the Newton solve (see [`crate::solve::contact`]).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Contact {
    /// Build the ground (default `false`).
    pub enabled: bool,
    /// A point on the plane (m, default `[0, 0, 0]`).
    pub point: [Real; 3],
    /// The plane's normal, pointing to the side the sheet is on (default `[0, 0, 1]`).
    pub normal: [Real; 3],
    /// Penalty stiffness k: contact pressure per unit penetration (Pa/m). `"auto"`: E/h, the
    /// sheet's own through-thickness stiffness (default).
    pub stiffness: AutoOr,
    /// Smoothing length δ of the penalty (m): the pressure grows as k p²/(2δ) for a penetration
    /// p < δ, and as k (p − δ/2) beyond. `"auto"`: h/100 (default).
    pub smoothing: AutoOr,
    /// Coulomb friction coefficient μ (default `0`; dynamics only).
    pub friction: Real,
    /// Slip speed ε_v (m/s) below which friction is smoothed (sticking creeps at most this fast;
    /// default `1e-5`).
    pub slip_speed: Real,
}

impl Default for Contact {
    fn default() -> Self {
        Contact {
            enabled: false,
            point: [0.0; 3],
            normal: [0.0, 0.0, 1.0],
            stiffness: AutoOr::Auto(Auto::Auto),
            smoothing: AutoOr::Auto(Auto::Auto),
            friction: 0.0,
            slip_speed: 1e-5,
        }
    }
}

/// An axis-aligned box of vertices to hold fixed.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FixBox {
    /// Lower corner (m).
    pub min: [Real; 3],
    /// Upper corner (m).
    pub max: [Real; 3],
}

/// Fixed vertices: the union of all the selections below.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Constraints {
    /// Fix vertices whose `constraint_indicators` mesh field is non-zero (default: `true`).
    pub use_constraint_indicators: bool,
    /// Fix vertices whose `node_tags` value is in this list (default: `[]`).
    pub fix_tags: Vec<i64>,
    /// Fix vertices inside any of these boxes (default: none).
    pub fix_boxes: Vec<FixBox>,
    /// Clamped boundaries (`[[constraints.clamp]]`): on the boundary edges whose two vertices
    /// are selected, those vertices and their edge neighbours (one ring) are held, and with
    /// edge DOFs the boundary edges' rotations too: positions and rotation (default: none).
    pub clamp: Vec<Selection>,
    /// Prescribed displacements (`[[constraints.displacement]]`): selected vertices move to
    /// `reference + dial × displacement` (default: none).
    pub displacement: Vec<Prescribed>,
}

/// A prescribed displacement path.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Prescribed {
    /// Displacement at dial 1 (m).
    pub displacement: [Real; 3],
    /// The vertices.
    #[serde(flatten)]
    pub on: Selection,
}

impl Default for Constraints {
    fn default() -> Self {
        Constraints {
            use_constraint_indicators: true,
            fix_tags: Vec::new(),
            fix_boxes: Vec::new(),
            clamp: Vec::new(),
            displacement: Vec::new(),
        }
    }
}

/// Output files.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Output {
    /// Frame format: `"vtu"` (XML), `"vtk"` (legacy binary) or `"vtk_ascii"` (default: `"vtu"`).
    pub format: Format,
    /// Static mode: also write a frame after every accepted continuation step, each solved to the
    /// full tolerance (default: `false`).
    pub continuation_frames: bool,
    /// Basename of frame files, `{prefix}_{index:05}.{ext}` (default: `"frame"`).
    pub prefix: String,
    /// Also write MorphoShell's derived fields: angle deficits and their Gauss curvature per
    /// vertex, its strain measure and the principal Cauchy stresses per face
    /// (`src/fields.rs`; default: `false`).
    pub morphoshell_fields: bool,
    /// `.vtu` frames: compression of every array, `"zlib"`, `"lz4"` or `"none"` (default:
    /// `"zlib"`).
    pub compression: Option<crate::mesh::vtu::Compression>,
    /// `.vtu` frames: `"appended"` (raw bytes after the XML, ParaView's default) or `"base64"`
    /// (inline, valid XML) (default: `"appended"`).
    pub encoding: Option<crate::mesh::vtu::Encoding>,
    /// `"single"` or `"double"`: the precision of derived fields (curvatures, forms, stresses,
    /// energy densities, …). Positions, the displacement (which gives the reference positions)
    /// and the fields a restart reads are always double (default: `"single"`).
    pub precision: Precision,
    /// The fields frames carry: names, and the keywords `"default"` (every field but the
    /// current forms `a` and `b`, which the positions determine) and `"all"` (default:
    /// `["default"]`). The fields a restart reads (velocity in the dynamic modes, edge angles,
    /// term states) are always written.
    pub fields: Vec<String>,
    /// PNG pictures beside frames (`src/render.rs`): `"none"`, `"all"` (beside every frame) or
    /// `"final"` (beside the last one) (default: `"none"`).
    pub snapshots: Snapshots,
    /// The field the snapshots are coloured by (default: `mean_curvature`).
    pub snapshot_field: Option<String>,
    /// The snapshots' view: `iso`, `top`, `bottom`, `front`, `back`, `side` or `"AZ,EL"`
    /// (default: `"iso"`).
    pub snapshot_view: String,
    /// The snapshots' size in pixels (default: `[1024, 768]`).
    pub snapshot_size: [usize; 2],
}

/// Which frames get a PNG snapshot.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Snapshots {
    /// None.
    None,
    /// Every frame.
    All,
    /// The last frame, written when the run ends.
    Final,
}

/// The fields `output.fields = ["default"]` leaves out: the current fundamental forms, which
/// the positions determine.
pub const NOT_DEFAULT_FIELDS: [&str; 2] = ["a", "b"];

/// Floating-point precision of derived output fields.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Precision {
    /// Float64.
    Double,
    /// Float32: half the bytes, 7 significant digits.
    Single,
}

impl Default for Output {
    fn default() -> Self {
        Output {
            format: Format::Vtu,
            continuation_frames: false,
            prefix: "frame".into(),
            morphoshell_fields: false,
            compression: None,
            encoding: None,
            precision: Precision::Single,
            fields: vec!["default".into()],
            snapshots: Snapshots::None,
            snapshot_field: None,
            snapshot_view: "iso".into(),
            snapshot_size: [1024, 768],
        }
    }
}

impl Output {
    /// Whether frames carry every field.
    pub fn all_fields(&self) -> bool {
        self.fields.iter().any(|f| f == "all")
    }

    /// Whether a field named `name` is written (the restart's fields aside).
    pub fn selects(&self, name: &str) -> bool {
        self.all_fields()
            || self.fields.iter().any(|f| f == name)
            || (self.fields.iter().any(|f| f == "default") && !NOT_DEFAULT_FIELDS.contains(&name))
    }
}

/// Parses a `--set key=value` value with TOML's rules (number, bool, array, inline table,
/// quoted string); a bare word (letters, digits, `_`, `-`, not starting with a digit or sign)
/// is taken as a string, so `--set solver.mode=dynamic` works. Anything else that TOML rejects
/// (an integer beyond 64 bits, say) is an error with TOML's reason.
fn parse_override_value(v: &str) -> Result<toml::Value, String> {
    let doc = format!("v = {v}");
    match doc.parse::<toml::Table>() {
        Ok(mut t) => Ok(t.remove("v").unwrap_or(toml::Value::String(v.into()))),
        Err(e) => {
            let word = v.chars().next().is_some_and(|c| c.is_ascii_alphabetic())
                && v.chars()
                    .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
            if word {
                Ok(toml::Value::String(v.into()))
            } else {
                Err(format!(
                    "'{v}' is not a TOML value: {}",
                    e.message().trim_end()
                ))
            }
        }
    }
}

/// Applies `key=value` overrides (dotted keys) to a TOML table.
pub fn apply_overrides(table: &mut toml::Table, overrides: &[String]) -> Result<(), SettingsError> {
    for arg in overrides {
        let oerr = |reason: &str| SettingsError::Override {
            arg: arg.clone(),
            reason: reason.into(),
        };
        let (key, value) = arg
            .split_once('=')
            .ok_or_else(|| oerr("expected key=value"))?;
        let parts: Vec<&str> = key.trim().split('.').collect();
        if parts.iter().any(|p| p.is_empty()) {
            return Err(oerr("empty key segment"));
        }
        let mut cur = &mut *table;
        for p in &parts[..parts.len() - 1] {
            let entry = cur
                .entry(p.to_string())
                .or_insert_with(|| toml::Value::Table(toml::Table::new()));
            cur = entry
                .as_table_mut()
                .ok_or_else(|| oerr(&format!("'{p}' is not a table")))?;
        }
        let value = parse_override_value(value.trim()).map_err(|e| oerr(&e))?;
        cur.insert(parts[parts.len() - 1].to_string(), value);
    }
    Ok(())
}

impl Settings {
    /// Reads, overrides, parses and validates a settings file.
    pub fn load(path: &Path, overrides: &[String]) -> Result<Settings, SettingsError> {
        let name = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| SettingsError::Read {
            path: name.clone(),
            reason: e.to_string(),
        })?;
        Self::from_str_with(&text, &name, overrides)
    }

    /// Parses settings from text (`name` is used in messages).
    pub fn from_str_with(
        text: &str,
        name: &str,
        overrides: &[String],
    ) -> Result<Settings, SettingsError> {
        let perr = |reason: String| SettingsError::Parse {
            path: name.to_string(),
            reason,
        };
        // Parse directly first, for messages with line numbers.
        let direct: Result<Settings, _> = toml::from_str(text);
        let settings = if overrides.is_empty() {
            direct.map_err(|e| perr(e.to_string().trim_end().to_string()))?
        } else {
            let mut table: toml::Table = text
                .parse()
                .map_err(|e: toml::de::Error| perr(e.to_string().trim_end().to_string()))?;
            apply_overrides(&mut table, overrides)?;
            toml::Value::Table(table)
                .try_into()
                .map_err(|e: toml::de::Error| {
                    perr(format!(
                        "after --set overrides: {}",
                        e.to_string().trim_end()
                    ))
                })?
        };
        settings.validate(name)?;
        Ok(settings)
    }

    /// Checks ranges and consistency.
    /// Validates `[material]`'s membrane model and its constants.
    fn validate_material_model(&self, name: &str) -> Result<(), SettingsError> {
        let inv = |key: &str, reason: String| {
            Err(SettingsError::Invalid {
                path: name.to_string(),
                key: key.into(),
                reason,
            })
        };
        let m = &self.material;
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
            if p.thickness == PrismThickness::Pbd && self.solver.mode != Mode::Dynamic {
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

    /// Validates every section, each by its own function (errors name the file and key).
    pub fn validate(&self, name: &str) -> Result<(), SettingsError> {
        self.validate_material(name)?;
        self.validate_rest(name)?;
        self.validate_solver(name)?;
        self.validate_growth(name)?;
        self.validate_moisture(name)?;
        self.validate_time(name)?;
        self.validate_explicit(name)?;
        self.validate_slides(name)?;
        self.validate_loads(name)?;
        self.validate_gas(name)?;
        self.validate_contact(name)?;
        for (i, o) in self.obstacles.iter().enumerate() {
            if let Err(e) = o.shape(i) {
                return Err(SettingsError::Invalid {
                    path: name.to_string(),
                    key: e.key,
                    reason: e.reason,
                });
            }
            let control = o.control(i).map_err(|e| SettingsError::Invalid {
                path: name.to_string(),
                key: e.key,
                reason: e.reason,
            })?;
            let invalid = |key: &str, reason: &str| SettingsError::Invalid {
                path: name.to_string(),
                key: format!("obstacles[{i}].{key}"),
                reason: reason.to_string(),
            };
            if let crate::config::obstacle::Control::Pressed { mass, .. } = control {
                if self.solver.mode == Mode::Explicit {
                    return Err(invalid(
                        "force",
                        "force control needs solver.mode = \"static\" or \"dynamic\" (the \
                         explicit driver moves vertices only; [slides] offer a pressed plane \
                         there)",
                    ));
                }
                if self.solver.mode == Mode::Dynamic && mass.is_none() {
                    return Err(invalid(
                        "mass",
                        "is required by a force-controlled obstacle in dynamic mode (kg, its \
                         inertia)",
                    ));
                }
            }
            if o.friction > 0.0 && self.solver.mode == Mode::Static {
                return Err(invalid(
                    "friction",
                    "friction needs solver.mode = \"dynamic\" or \"explicit\": a static solve \
                     has no slip over a time for friction to resist",
                ));
            }
            if o.friction > 0.0
                && self.solver.mode == Mode::Explicit
                && o.displacement.iter().any(|&c| c != 0.0)
            {
                return Err(invalid(
                    "friction",
                    "friction on a moving obstacle needs solver.mode = \"dynamic\" (explicit \
                     stick/slip acts against fixed obstacles only)",
                ));
            }
        }
        self.validate_constraints(name)?;
        self.validate_output(name)?;
        Ok(())
    }

    /// Validates `[material]`: moduli, density, thickness, Poisson's ratio, the membrane model and its constants.
    pub fn validate_material(&self, name: &str) -> Result<(), SettingsError> {
        let ck = Check(name);
        let m = &self.material;
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
        self.validate_material_model(name)?;
        Ok(())
    }

    /// Validates `[rest]`: finite (or parseable) target forms, a positive definite uniform ā, the dial time.
    pub fn validate_rest(&self, name: &str) -> Result<(), SettingsError> {
        let ck = Check(name);
        let r = &self.rest;
        for (name, form) in [("abar", &r.abar), ("bbar", &r.bbar)] {
            for (i, v) in form.iter().enumerate() {
                let key = format!("rest.{name}[{i}]");
                match v {
                    Field::Value(v) if !v.is_finite() => {
                        return ck.inv(
                            &key,
                            format!("must be finite, got {v_h}", v_h = crate::math::human(v)),
                        )
                    }
                    Field::Expr(_) => {
                        if let Err(e) = v.compile() {
                            return ck.inv(&key, e.to_string());
                        }
                    }
                    _ => {}
                }
            }
        }
        if let [Some(a0), Some(a1), Some(a2)] = r.abar.clone().map(|f| f.constant()) {
            if r.target == TargetForms::Uniform && !(a0 > 0.0 && a0 * a2 - a1 * a1 > 0.0) {
                return ck.inv(
                    "rest.abar",
                    format!("must be positive definite, got [{a0}, {a1}, {a2}]"),
                );
            }
        }
        ck.nonneg("rest.dial_time", r.dial_time)?;
        if let Some(l) = &r.lce {
            for (key, f) in [("theta", &l.theta), ("lambda", &l.lambda), ("nu", &l.nu)] {
                let key = format!("rest.lce.{key}");
                if let Err(e) = f.compile() {
                    return ck.inv(&key, e.to_string());
                }
                if let Some(v) = f.constant() {
                    if !v.is_finite() {
                        return ck.inv(
                            &key,
                            format!("must be finite, got {v_h}", v_h = crate::math::human(v)),
                        );
                    }
                }
            }
            if let Some(v) = l.lambda.constant() {
                if v <= 0.0 {
                    return ck.inv("rest.lce.lambda", format!("must be positive, got {v}"));
                }
            }
            if r.target != TargetForms::Lce {
                return ck.inv("rest.lce", "is used only with rest.target = \"lce\"".into());
            }
        }
        Ok(())
    }

    /// Validates `[solver]`: tolerance, iteration and continuation controls.
    pub fn validate_solver(&self, name: &str) -> Result<(), SettingsError> {
        let ck = Check(name);
        let s = &self.solver;
        ck.pos("solver.tolerance", s.tolerance)?;
        if s.max_newton_iterations == 0 {
            return ck.inv("solver.max_newton_iterations", "must be at least 1".into());
        }
        if !(s.continuation_step > 0.0 && s.continuation_step <= 1.0) {
            return ck.inv(
                "solver.continuation_step",
                format!(
                    "must lie in (0, 1], got {}",
                    crate::math::human(s.continuation_step)
                ),
            );
        }
        ck.pos("solver.min_continuation_step", s.min_continuation_step)?;
        if !(s.max_continuation_step > 0.0 && s.max_continuation_step <= 1.0) {
            return ck.inv(
                "solver.max_continuation_step",
                format!(
                    "must lie in (0, 1], got {}",
                    crate::math::human(s.max_continuation_step)
                ),
            );
        }
        if let Softening::Factor(c) = s.membrane_continuation {
            if !(c >= 1.0 && c.is_finite()) {
                return ck.inv(
                    "solver.membrane_continuation",
                    format!(
                        "must be \"auto\" or a finite number ≥ 1, got {c_h}",
                        c_h = crate::math::human(c)
                    ),
                );
            }
        }
        ck.nonneg("solver.symmetry_breaking", s.symmetry_breaking)?;
        Ok(())
    }

    /// Validates `[growth]`: finite coefficients, a valid `s`, and no growth law together with `rest.target`.
    pub fn validate_growth(&self, name: &str) -> Result<(), SettingsError> {
        let ck = Check(name);
        let g = &self.growth;
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
        if g.law != GrowthLaw::None && self.rest.target != TargetForms::None {
            return ck.inv(
                "growth.law",
                format!(
                    "a growth law computes the target forms, so rest.target must be \"none\" \
                     (it is {:?}); use one or the other",
                    self.rest.target
                ),
            );
        }
        Ok(())
    }

    /// Validates `[moisture]` (when enabled): diffusivities, layers, the surfaces, the ground exchange, and the dynamic mode and swelling law it needs.
    pub fn validate_moisture(&self, name: &str) -> Result<(), SettingsError> {
        let ck = Check(name);
        let g = &self.growth;
        let mo = &self.moisture;
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
                if !self.contact.enabled {
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
            if self.solver.mode != Mode::Dynamic {
                return ck.inv(
                    "moisture.enabled",
                    "moisture diffusion runs in time: set solver.mode = \"dynamic\"".into(),
                );
            }
            if !matches!(
                g.law,
                GrowthLaw::LinearSwelling | GrowthLaw::Bilayer | GrowthLaw::MachineDirection
            ) {
                return ck.inv(
                    "moisture.enabled",
                    format!(
                        "moisture drives the rest forms through a swelling law; growth.law is \
                         {:?} (use linear_swelling, bilayer or machine_direction)",
                        g.law
                    ),
                );
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

    /// Validates `[time]`: positive times, `dt_min ≤ dt ≤ dt_max`.
    pub fn validate_time(&self, name: &str) -> Result<(), SettingsError> {
        let ck = Check(name);
        let t = &self.time;
        ck.pos("time.end", t.end)?;
        ck.pos("time.dt", t.dt)?;
        ck.pos("time.dt_min", t.dt_min)?;
        ck.pos("time.dt_max", t.dt_max)?;
        ck.pos("time.output_interval", t.output_interval)?;
        ck.nonneg("time.damping", t.damping)?;
        ck.pos("time.equilibrium_kinetic", t.equilibrium_kinetic)?;
        if t.dt_min > t.dt || t.dt > t.dt_max {
            return ck.inv(
                "time.dt",
                format!(
                    "need dt_min ≤ dt ≤ dt_max, got {} ≤ {} ≤ {}",
                    crate::math::human(t.dt_min),
                    crate::math::human(t.dt),
                    crate::math::human(t.dt_max)
                ),
            );
        }
        // Bounds on the work a run can ask for: steps at the largest step, and frames.
        let steps = t.end / t.dt_max;
        if steps > MAX_STEPS {
            return ck.inv(
                "time.end",
                format!(
                    "{} s at steps of at most time.dt_max = {} s is {steps_h} steps, more \
                     than {MAX_STEPS_h}; raise time.dt_max or lower time.end",
                    crate::math::human(t.end),
                    crate::math::human(t.dt_max),
                    steps_h = crate::math::human(steps),
                    MAX_STEPS_h = crate::math::human(MAX_STEPS)
                ),
            );
        }
        let frames = t.end / t.output_interval;
        if frames > MAX_FRAMES {
            return ck.inv(
                "time.output_interval",
                format!(
                    "{} s between frames over {} s is {frames_h} frames, more than \
                     {MAX_FRAMES_h}",
                    crate::math::human(t.output_interval),
                    crate::math::human(t.end),
                    frames_h = crate::math::human(frames),
                    MAX_FRAMES_h = crate::math::human(MAX_FRAMES)
                ),
            );
        }
        if t.output_interval < t.dt_min {
            return ck.inv(
                "time.output_interval",
                format!(
                    "{} s is below time.dt_min = {} s: frames cannot be closer than the \
                     smallest step",
                    crate::math::human(t.output_interval),
                    crate::math::human(t.dt_min)
                ),
            );
        }
        Ok(())
    }

    /// Validates `[slides]`.
    pub fn validate_slides(&self, name: &str) -> Result<(), SettingsError> {
        let ck = Check(name);
        let sl = &self.slides;
        ck.pos("slides.stiffness_prefactor", sl.stiffness_prefactor)?;
        ck.nonneg("slides.friction", sl.friction)?;
        if let Some(z) = sl.contact_damping {
            ck.nonneg("slides.contact_damping", z)?;
        }
        ck.nonneg("slides.travel", sl.travel)?;
        let coordinate = crate::mesh::MAX_COORDINATE;
        for (k, v, max, unit) in [
            ("slides.speed", sl.speed, coordinate, "m/s"),
            ("slides.force", sl.force, MAX_LOAD, "N"),
            ("slides.travel", sl.travel, coordinate, "m"),
        ] {
            if !(v.is_finite() && v.abs() <= max) {
                return ck.inv(
                    k,
                    format!(
                        "must be finite within ±{max_h} {unit}, got {v_h}",
                        max_h = crate::math::human(max),
                        v_h = crate::math::human(v)
                    ),
                );
            }
        }
        for (k, v) in [("slides.lower", sl.lower), ("slides.upper", sl.upper)] {
            if let Some(v) = v {
                if !(v.is_finite() && v.abs() <= coordinate) {
                    return ck.inv(
                        k,
                        format!(
                            "must be a finite height within ±{coordinate_h} m, got {v_h}",
                            coordinate_h = crate::math::human(coordinate),
                            v_h = crate::math::human(v)
                        ),
                    );
                }
            }
        }
        if let Some(d) = sl.drag {
            ck.pos("slides.drag", d)?;
        }
        if let (Some(l), Some(u)) = (sl.lower, sl.upper) {
            if u <= l {
                return ck.inv(
                    "slides.upper",
                    format!("the upper slide ({u}) must be above the lower one ({l})"),
                );
            }
        }
        if sl.enabled && self.solver.mode != Mode::Explicit {
            let moving = (sl.control == SlideControl::Speed && sl.speed != 0.0 && sl.travel > 0.0)
                || sl.control == SlideControl::Force;
            if sl.friction > 0.0 {
                return ck.inv(
                    "slides.friction",
                    "slide friction needs solver.mode = \"explicit\" (the implicit modes hold \
                     frictionless slides still)"
                        .into(),
                );
            }
            if sl.contact_damping.is_some_and(|z| z > 0.0) {
                return ck.inv(
                    "slides.contact_damping",
                    "contact damping needs solver.mode = \"explicit\" (the implicit modes hold \
                     the slides still, without damping)"
                        .into(),
                );
            }
            if moving {
                return ck.inv(
                    "slides.control",
                    "moving slides need solver.mode = \"explicit\" (the implicit modes hold the \
                     slides still)"
                        .into(),
                );
            }
        }
        Ok(())
    }

    /// Validates `[explicit]` and `[dial]`.
    pub fn validate_explicit(&self, name: &str) -> Result<(), SettingsError> {
        let ck = Check(name);
        let e = &self.explicit;
        ck.pos("explicit.time_step_prefactor", e.time_step_prefactor)?;
        ck.nonneg("explicit.damping_prefactor_dial", e.damping_prefactor_dial)?;
        ck.nonneg("explicit.damping_prefactor_wait", e.damping_prefactor_wait)?;
        ck.nonneg("explicit.dial_long_times", e.dial_long_times)?;
        ck.pos("explicit.frames_per_long_time", e.frames_per_long_time)?;
        ck.pos("explicit.max_long_times", e.max_long_times)?;
        ck.pos("explicit.force_tolerance", e.force_tolerance)?;
        ck.pos("explicit.shape_tolerance", e.shape_tolerance)?;
        ck.pos("explicit.energy_tolerance", e.energy_tolerance)?;
        ck.pos("explicit.window_long_times", e.window_long_times)?;
        ck.pos(
            "explicit.morphoshell_force_threshold",
            e.morphoshell_force_threshold,
        )?;
        ck.pos(
            "explicit.morphoshell_speed_threshold",
            e.morphoshell_speed_threshold,
        )?;
        if e.window_long_times > e.max_long_times {
            return ck.inv(
                "explicit.window_long_times",
                format!(
                    "a window of {} long times is longer than the run's limit, \
                     explicit.max_long_times = {}: the equilibrium test could never run",
                    crate::math::human(e.window_long_times),
                    crate::math::human(e.max_long_times)
                ),
            );
        }
        if e.gradient_descent_steps as Real > MAX_STEPS {
            return ck.inv(
                "explicit.gradient_descent_steps",
                format!(
                    "{} steps is more than {MAX_STEPS_h}",
                    e.gradient_descent_steps,
                    MAX_STEPS_h = crate::math::human(MAX_STEPS)
                ),
            );
        }
        if e.max_long_times * e.frames_per_long_time > MAX_FRAMES {
            return ck.inv(
                "explicit.frames_per_long_time",
                format!(
                    "{} frames per long time over {} long times is more than {MAX_FRAMES_h} frames",
                    e.frames_per_long_time,
                    e.max_long_times,
                    MAX_FRAMES_h = crate::math::human(MAX_FRAMES)
                ),
            );
        }
        if self.dial.holds.len() > MAX_HOLDS {
            return ck.inv(
                "dial.holds",
                format!(
                    "{} holds is more than {MAX_HOLDS}: each hold is a solve to equilibrium \
                     and a frame",
                    self.dial.holds.len()
                ),
            );
        }
        let mut last = 0.0;
        for (i, &h) in self.dial.holds.iter().enumerate() {
            if !(h.is_finite() && h > last && h < 1.0) {
                return ck.inv(
                    &format!("dial.holds[{i}]"),
                    format!("holds must ascend strictly inside (0, 1), got {h}"),
                );
            }
            last = h;
        }
        if self.dial.from == DialFrom::Start
            && (self.growth.law != GrowthLaw::None || self.moisture.enabled)
        {
            return ck.inv(
                "dial.from",
                "\"start\" dials rest.target's forms from the starting state; growth laws and \
                 moisture set the rest forms from the reference mesh, so the two do not combine"
                    .into(),
            );
        }
        if self.solver.mode == Mode::Explicit && self.material.bending.angle_variant().is_some() {
            return ck.inv(
                "material.bending",
                "explicit mode integrates vertex positions only; the mid-edge angle models carry \
                 edge rotations without inertia. Use \"patch_fit\" (MorphoShell's), \
                 \"midedge_average\" or \"none\""
                    .into(),
            );
        }
        Ok(())
    }

    /// Validates `[loads]`: finite gravity and finite load values with well-formed selections.
    pub fn validate_loads(&self, name: &str) -> Result<(), SettingsError> {
        let ck = Check(name);
        let g = &self.loads.gravity;
        if g.iter().any(|c| !c.is_finite() || c.abs() > MAX_GRAVITY) {
            return ck.inv(
                "loads.gravity",
                format!(
                    "must be finite with components within ±{MAX_GRAVITY_h} m/s², got {}",
                    vec_e(g),
                    MAX_GRAVITY_h = crate::math::human(MAX_GRAVITY)
                ),
            );
        }
        let l = &self.loads;
        let finite3 = |key: String, v: &[Real; 3]| -> Result<(), SettingsError> {
            if v.iter().all(|c| c.is_finite() && c.abs() <= MAX_LOAD) {
                Ok(())
            } else {
                ck.inv(
                    &key,
                    format!(
                        "must be finite within ±{MAX_LOAD_h}, got {}",
                        vec_e(v),
                        MAX_LOAD_h = crate::math::human(MAX_LOAD)
                    ),
                )
            }
        };
        for (i, p) in l.point.iter().enumerate() {
            finite3(format!("loads.point[{i}].force"), &p.force)?;
            ck.selection(&format!("loads.point[{i}]"), &p.on)?;
        }
        for (i, t) in l.traction.iter().enumerate() {
            finite3(format!("loads.traction[{i}].traction"), &t.traction)?;
            ck.selection(&format!("loads.traction[{i}]"), &t.on)?;
        }
        for (i, p) in l.pressure.iter().enumerate() {
            if !(p.pressure.is_finite() && p.pressure.abs() <= MAX_LOAD) {
                return ck.inv(
                    &format!("loads.pressure[{i}].pressure"),
                    format!(
                        "must be finite within ±{MAX_LOAD_h} Pa, got {}",
                        crate::math::human(p.pressure),
                        MAX_LOAD_h = crate::math::human(MAX_LOAD)
                    ),
                );
            }
            ck.selection(&format!("loads.pressure[{i}]"), &p.on)?;
        }
        for (i, m) in l.moment.iter().enumerate() {
            if !(m.moment.is_finite() && m.moment.abs() <= MAX_LOAD) {
                return ck.inv(
                    &format!("loads.moment[{i}].moment"),
                    format!(
                        "must be finite within ±{MAX_LOAD_h} N·m/m, got {}",
                        crate::math::human(m.moment),
                        MAX_LOAD_h = crate::math::human(MAX_LOAD)
                    ),
                );
            }
            ck.selection(&format!("loads.moment[{i}]"), &m.on)?;
        }
        Ok(())
    }

    /// Validates `[gas]`: the control's value (a positive amount or volume, a finite
    /// pressure), the external pressure and γ.
    pub fn validate_gas(&self, name: &str) -> Result<(), SettingsError> {
        let ck = Check(name);
        let g = &self.gas;
        if g.control == GasControl::None {
            return Ok(());
        }
        let within = |key: &str, v: Real, unit: &str| {
            if v.is_finite() && v.abs() <= MAX_LOAD {
                Ok(())
            } else {
                ck.inv(
                    key,
                    format!(
                        "must be finite within ±{MAX_LOAD_h} {unit}, got {v_h}",
                        MAX_LOAD_h = crate::math::human(MAX_LOAD),
                        v_h = crate::math::human(v)
                    ),
                )
            }
        };
        match g.control {
            GasControl::Amount => {
                if g.amount.is_nan() || g.amount <= 0.0 {
                    return ck.inv(
                        "gas.amount",
                        format!(
                            "amount control needs a positive amount of gas (p V at the reference \
                             volume, J), got {}",
                            crate::math::human(g.amount)
                        ),
                    );
                }
                within("gas.amount", g.amount, "J")?;
            }
            GasControl::Pressure => within("gas.pressure", g.pressure, "Pa")?,
            GasControl::Volume => {
                if g.volume.is_nan() || g.volume <= 0.0 {
                    return ck.inv(
                        "gas.volume",
                        format!(
                            "volume control needs a positive enclosed volume (m³), got {}",
                            crate::math::human(g.volume)
                        ),
                    );
                }
                within("gas.volume", g.volume, "m³")?;
            }
            GasControl::None => {}
        }
        ck.nonneg("gas.external_pressure", g.external_pressure)?;
        within("gas.external_pressure", g.external_pressure, "Pa")?;
        if !(g.gamma > 1.0 && g.gamma <= 10.0) {
            return ck.inv(
                "gas.gamma",
                format!(
                    "must lie in (1, 10] (1.4 for air), got {}",
                    crate::math::human(g.gamma)
                ),
            );
        }
        Ok(())
    }

    /// Validates `[contact]` (when enabled): the plane, stiffness, smoothing, friction.
    pub fn validate_contact(&self, name: &str) -> Result<(), SettingsError> {
        let ck = Check(name);
        let c = &self.contact;
        if c.enabled {
            if c.point.iter().any(|v| !v.is_finite()) {
                return ck.inv("contact.point", "must be finite".into());
            }
            let n2: Real = c.normal.iter().map(|v| v * v).sum();
            if !(n2.is_finite() && n2 > 0.0) {
                return ck.inv(
                    "contact.normal",
                    format!("must be a finite non-zero vector, got {}", vec_e(&c.normal)),
                );
            }
            if let AutoOr::Value(k) = c.stiffness {
                ck.pos("contact.stiffness", k)?;
            }
            if let AutoOr::Value(d) = c.smoothing {
                ck.pos("contact.smoothing", d)?;
            }
            ck.nonneg("contact.friction", c.friction)?;
            ck.pos("contact.slip_speed", c.slip_speed)?;
        }
        Ok(())
    }

    /// Validates `[constraints]`: well-formed boxes and selections, finite displacements.
    pub fn validate_constraints(&self, name: &str) -> Result<(), SettingsError> {
        let ck = Check(name);
        for (i, b) in self.constraints.fix_boxes.iter().enumerate() {
            if b.min.iter().chain(b.max.iter()).any(|v| !v.is_finite())
                || (0..3).any(|k| b.min[k] > b.max[k])
            {
                return ck.inv(
                    &format!("constraints.fix_boxes[{i}]"),
                    "needs finite min ≤ max".into(),
                );
            }
        }
        let cs = &self.constraints;
        for (i, sel) in cs.clamp.iter().enumerate() {
            ck.selection(&format!("constraints.clamp[{i}]"), sel)?;
        }
        for (i, d) in cs.displacement.iter().enumerate() {
            // A displacement moves vertices: it is bounded like the coordinates themselves.
            let max = crate::mesh::MAX_COORDINATE;
            if !d
                .displacement
                .iter()
                .all(|c| c.is_finite() && c.abs() <= max)
            {
                return ck.inv(
                    &format!("constraints.displacement[{i}].displacement"),
                    format!(
                        "must be finite with components within ±{max_h} m, got {}",
                        vec_e(&d.displacement),
                        max_h = crate::math::human(max)
                    ),
                );
            }
            ck.selection(&format!("constraints.displacement[{i}]"), &d.on)?;
        }
        Ok(())
    }

    /// Validates `[output]`: a plain file-name prefix.
    pub fn validate_output(&self, name: &str) -> Result<(), SettingsError> {
        let ck = Check(name);
        if self.output.prefix.is_empty() || self.output.prefix.contains(['/', '\\']) {
            return ck.inv(
                "output.prefix",
                "must be a plain, non-empty file name".into(),
            );
        }
        let o = &self.output;
        if o.format != Format::Vtu {
            for (key, set) in [
                ("output.compression", o.compression.is_some()),
                ("output.encoding", o.encoding.is_some()),
            ] {
                if set {
                    return ck.inv(
                        key,
                        format!(
                            "applies to .vtu frames only (output.format = \"{}\")",
                            o.format.name()
                        ),
                    );
                }
            }
        }
        if o.snapshots != Snapshots::None {
            crate::config::view::angles(&o.snapshot_view)
                .map(|_| ())
                .or_else(|e| ck.inv("output.snapshot_view", e))?;
            let [w, h] = o.snapshot_size;
            let max = crate::config::view::MAX_SIDE;
            if !(64..=max).contains(&w) || !(64..=max).contains(&h) {
                return ck.inv(
                    "output.snapshot_size",
                    format!("[{w}, {h}]: each side must lie in 64–{max} pixels"),
                );
            }
        }
        if o.fields.is_empty() {
            return ck.inv(
                "output.fields",
                "is empty: list field names, or [\"all\"]".into(),
            );
        }
        if o.all_fields() && o.fields.len() > 1 {
            return ck.inv(
                "output.fields",
                "\"all\" cannot be combined with other entries".into(),
            );
        }
        Ok(())
    }
}

/// The error helpers of the section validators for one settings file.
#[derive(Clone, Copy)]
struct Check<'a>(&'a str);

impl Check<'_> {
    fn inv(&self, key: &str, reason: String) -> Result<(), SettingsError> {
        Err(SettingsError::Invalid {
            path: self.0.to_string(),
            key: key.into(),
            reason,
        })
    }
    fn pos(&self, key: &str, v: Real) -> Result<(), SettingsError> {
        if !(v.is_finite() && v > 0.0) {
            return self.inv(
                key,
                format!(
                    "must be a positive number, got {v_h}",
                    v_h = crate::math::human(v)
                ),
            );
        }
        Ok(())
    }
    fn nonneg(&self, key: &str, v: Real) -> Result<(), SettingsError> {
        if !(v.is_finite() && v >= 0.0) {
            return self.inv(
                key,
                format!(
                    "must be a non-negative number, got {v_h}",
                    v_h = crate::math::human(v)
                ),
            );
        }
        Ok(())
    }
    /// A selection's box must be finite with min ≤ max.
    fn selection(&self, key: &str, sel: &Selection) -> Result<(), SettingsError> {
        if let Some(b) = &sel.inside {
            if b.min.iter().chain(b.max.iter()).any(|v| !v.is_finite())
                || (0..3).any(|k| b.min[k] > b.max[k])
            {
                return self.inv(&format!("{key}.inside"), "needs finite min ≤ max".into());
            }
        }
        Ok(())
    }
}

/// A settings value that is a number or a string, for the enums that accept either; their
/// errors say what they accept instead of serde's "untagged enum".
enum NumOrStr {
    Num(Real),
    Str(String),
}

fn num_or_str<'de, D: serde::Deserializer<'de>>(
    d: D,
    expecting: &'static str,
) -> Result<NumOrStr, D::Error> {
    struct V(&'static str);
    impl serde::de::Visitor<'_> for V {
        type Value = NumOrStr;
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            f.write_str(self.0)
        }
        fn visit_f64<E>(self, v: f64) -> Result<NumOrStr, E> {
            Ok(NumOrStr::Num(v))
        }
        fn visit_i64<E>(self, v: i64) -> Result<NumOrStr, E> {
            Ok(NumOrStr::Num(v as Real))
        }
        fn visit_u64<E>(self, v: u64) -> Result<NumOrStr, E> {
            Ok(NumOrStr::Num(v as Real))
        }
        fn visit_str<E>(self, v: &str) -> Result<NumOrStr, E> {
            Ok(NumOrStr::Str(v.into()))
        }
    }
    d.deserialize_any(V(expecting))
}

/// Number-or-`"auto"` settings.
fn number_or_auto<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<Real>, D::Error> {
    use serde::de::Error;
    match num_or_str(d, "a number or \"auto\"")? {
        NumOrStr::Num(v) => Ok(Some(v)),
        NumOrStr::Str(s) if s == "auto" => Ok(None),
        NumOrStr::Str(s) => Err(D::Error::custom(format!(
            "expected a number or \"auto\", got \"{s}\""
        ))),
    }
}

impl<'de> Deserialize<'de> for AutoOr {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        Ok(number_or_auto(d)?.map_or(AutoOr::Auto(Auto::Auto), AutoOr::Value))
    }
}

impl<'de> Deserialize<'de> for Softening {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        Ok(number_or_auto(d)?.map_or(Softening::Auto(Auto::Auto), Softening::Factor))
    }
}

impl<'de> Deserialize<'de> for Field {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        Ok(
            match num_or_str(d, "a number or an expression of x and y in quotes")? {
                NumOrStr::Num(v) => Field::Value(v),
                NumOrStr::Str(s) => Field::Expr(s),
            },
        )
    }
}

/// `[a, b, c]` with every number as [`crate::math::human`] writes it, for messages.
fn vec_e(v: &[Real]) -> String {
    let parts: Vec<String> = v.iter().map(crate::math::human).collect();
    format!("[{}]", parts.join(", "))
}
