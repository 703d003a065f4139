//! Rest-form laws (seed 000 §3, "Choosing Rest Fundamental Forms"), one file each behind
//! [`RestLaw`], with the registry [`LAWS`]: pure functions from per-face inputs to the rest forms
//! `(ā, b̄)` of a face, in its barycentric frame, and its rest thickness.
//!
//! ## One derivation for every law
//! Each law prescribes the rest *metric of the 3D shell* at every height `z ∈ [−h/2, h/2]` above
//! the mid-surface, `ḡ(z)` (a 2×2 tensor in the face's barycentric frame). The Koiter energy
//! only sees the part of `ḡ` linear in `z`, `ḡ(z) ≈ ā + 2z b̄` (shellsim's sign: offsetting
//! toward the normal by `z` turns `a` into `a + 2z b`, so that a positive `b̄` bulges toward the
//! normal). shellsim takes the least-squares projection of `ḡ` onto linear functions of `z`:
//!
//! `ā = (1/h) ∫ ḡ(z) dz`,   `b̄ = (6/h³) ∫ z ḡ(z) dz`,
//!
//! evaluated with 3-point Gauss–Legendre quadrature on each half `[−h/2, 0]`, `[0, h/2]`, which
//! is exact for every law below (each is a polynomial of degree ≤ 3 in `z` on each half).
//!
//! The reference shell's own metric at height `z` is `a⁰ + 2z b⁰`.
//!
//! * **No growth**: `ḡ = a⁰ + 2z b⁰`, so `(ā, b̄) = (a⁰, b⁰)`.
//! * **Isotropic growth** with conformal factor `s`, three laws (see `REFERENCES.md`, "Growth
//!   of a curved shell"), which agree on flat sheets except for the thickness:
//!   - [`isotropic`] (`"isotropic"`, the default): uniform volumetric growth. Every length grows by
//!     `e^s`, the thickness included, so the grown shell is a scaled copy: at grown height
//!     `z' = e^s z` its metric is `e^{2s}(a⁰ + 2z b⁰) = e^{2s} a⁰ + 2z' e^s b⁰`, hence
//!     `ā = e^{2s} a⁰`, `b̄ = e^s b⁰`, `h̄ = e^s h`. A curved shell grows stress-free.
//!   - [`isotropic_in_plane`] (`"isotropic_in_plane"`): every layer grows in-plane by `e^s` at
//!     fixed thickness, `ḡ = e^{2s}(a⁰ + 2z b⁰)`, so `ā = e^{2s} a⁰`, `b̄ = e^{2s} b⁰`: the
//!     reference curvature `ā⁻¹b̄` is kept, the thickness is not scaled, and a curved shell is
//!     frustrated (a 60° cap of radius 1 m grown by s = ln 0.9 at h = 0.1 m and E = 1 MPa
//!     keeps 2.6 J).
//!   - [`isotropic_metric_only`] (`"isotropic_metric_only"`): seed 000 as printed,
//!     `ā = e^{2s} a⁰`, `b̄ = b⁰`.
//! * **Linear differential swelling**: moisture varies linearly from `m⁻` (bottom, `z = −h/2`)
//!   to `m⁺` (top, `z = +h/2`), and lengths scale by `1 + μ m(z)`:
//!   `ḡ = (1 + μ m(z))² (a⁰ + 2z b⁰)`. With `s₀ = 1 + μ(m⁺ + m⁻)/2` and `s₁ = μ(m⁺ − m⁻)/h`:
//!   `ā = (s₀² + s₁²h²/12) a⁰ + (s₀ s₁ h²/3) b⁰`, `b̄ = s₀ s₁ a⁰ + (s₀² + 3 s₁²h²/20) b⁰`.
//!   Seed 000 gives two different expressions: `ā` from the end values `(ḡ⁺ + ḡ⁻)/2` (which
//!   weights the `z²` term by h²/4 instead of h²/12) and `b̄ = (ḡ⁻ − ḡ⁺)/(2h)` (the same `s₀s₁`
//!   term, opposite sign convention); the projection is the one consistent with the energy.
//!   `m⁺ = m⁻` leaves a flat sheet flat; a wetter top (`m⁺ > m⁻`, μ > 0) gives `b̄ > 0`: the
//!   sheet bulges toward the wet side's normal, i.e. curls away from the water.
//! * **Piecewise-constant bilayer** (van Rees et al. 2017): the top layer has metric
//!   `(1 + μ⁺ m⁺)²(a⁰ + 2z b⁰)`, the bottom layer `(1 + μ⁻ m⁻)²(a⁰ + 2z b⁰)`. For equal halves
//!   of one modulus on a flat reference, `ā = (ḡ⁺ + ḡ⁻)/2`, `b̄ = 3(ḡ⁺ − ḡ⁻)/(4h)`: van Rees'
//!   equivalence, which reproduces Timoshenko's κ = 3Δε/(2h). Unequal layers, thickening
//!   layers and a printed layer weight the projection by the modulus about the neutral plane
//!   ([`bilayer`]).
//! * **Linear differential swelling with a machine direction** `d` (a barycentric vector): with
//!   `d⊥` its `a⁰`-orthogonal complement, `P = [d d⊥]` and
//!   `M(z) = diag(1 + μ m(z), 1 + μ⊥ m(z))` in the `(d, d⊥)` basis,
//!   `ḡ(z) = P⁻ᵀ M(z) Pᵀ (a⁰ + 2z b⁰) P M(z) P⁻¹` (seed 000's `TᵀMT⁻ᵀ(·)T⁻¹MT` with
//!   `T = P⁻¹`). With `μ⊥ = μ` it is the isotropic linear swelling above.
//!
//! The moisture laws ([`linear_swelling`], [`bilayer`], [`machine_direction`]) keep the thickness:
//! seed 000's paper scenes use them, and its model swells the paper in-plane only (the
//! through-thickness swelling of paper does not enter the Koiter energy of a flat sheet).
//!
//! ## Target laws
//! The forms at dial 1 come first from a [`TargetLaw`] (`rest.target`, registry [`TARGETS`]), which
//! replaces the reference forms by forms given outright, and then from the growth law above,
//! which transforms them face by face:
//!
//! * [`uniform_forms`] (`"uniform"`): `rest.abar`, `rest.bbar` from the settings, numbers or
//!   expressions of the reference x, y;
//! * [`mesh_forms`] (`"mesh"`): the face fields `abar_info`, `bbar_info` of MorphoShell's files;
//! * [`lce`] (`"lce"`): the liquid-crystal director law, which also dials ā through its own
//!   stretch rather than linearly ([`RestForms::at`]).
//!
//! `"none"` keeps the reference forms.
//!
//! Units: `a`, `ā` in m² (barycentric), `b`, `b̄` in m, `h` in m, moisture `m` dimensionless
//! (seed 000 uses percent; shellsim uses fractions), `μ` per unit moisture.

pub mod bilayer;
pub mod crease_relaxation;
pub mod inputs;
pub mod isotropic;
pub mod isotropic_in_plane;
pub mod isotropic_metric_only;
pub mod lce;
pub mod linear_swelling;
pub mod machine_direction;
pub mod mesh_forms;
pub mod thermal_shrink;
pub mod uniform_forms;

pub use inputs::GrowthInputs;

use super::RestForms;
use crate::config::growth::GrowthModel;
use crate::math::{mat_to_sym, sym_to_mat, Mat2, Real, Sym2};
use crate::mesh::{Mesh, MeshError};
use crate::settings::{GrowthLaw, Rest, Settings, TargetForms};

/// What a law reads for one face.
#[derive(Clone, Copy, Debug)]
pub struct FaceInput {
    /// The face (for errors).
    pub face: usize,
    /// The reference forms `(a⁰, b⁰)` (m², m).
    pub a0: Sym2,
    /// See `a0`.
    pub b0: Sym2,
    /// The reference thickness (m).
    pub h: Real,
    /// Moisture at the top surface (`z = +h/2`).
    pub m_top: Real,
    /// Moisture at the bottom surface.
    pub m_bottom: Real,
    /// The conformal factor `s` of the isotropic laws.
    pub s: Real,
    /// The machine direction (barycentric; `[1, 0]` when no law needs it).
    pub direction: [Real; 2],
    /// The highest temperature reached (K) at the six heights [`sample_heights`] of the
    /// through-thickness projection, bottom to top (the thermal shrink law's input).
    pub heat: [Real; 6],
    /// The face's swelling coefficients.
    pub coef: Coefficients,
    /// The stored original forms `(â, b̂)` of a law that relaxes toward them
    /// ([`crease_relaxation`]), else `None`.
    pub relaxed: Option<(Sym2, Sym2)>,
}

/// The swelling coefficients of one face (per unit moisture): the uniform `[growth]` ones, or a
/// region's, or the face fields' ([`GrowthInputs::coef`]). Each law reads those it uses.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Coefficients {
    /// μ: in every direction (`linear_swelling`) or along the machine direction.
    pub mu: Real,
    /// μ⊥ across the machine direction.
    pub mu_perp: Real,
    /// The bilayer's top layer.
    pub mu_top: Real,
    /// The bilayer's bottom layer.
    pub mu_bottom: Real,
    /// The bilayer's top layer across the machine direction (`None`: `mu_top`, the layer
    /// swells alike in every direction).
    pub mu_top_perp: Option<Real>,
    /// The bilayer's bottom layer across the machine direction (`None`: `mu_bottom`).
    pub mu_bottom_perp: Option<Real>,
    /// μ_n through the thickness: `h̄ = h (1 + μ_n (m⁺ + m⁻)/2)`.
    pub mu_through: Real,
    /// The bilayer's printed top layer: its thickness (m, 0: none), part of the face's.
    pub print_thickness: Real,
    /// The printed layer's Young's modulus over the bottom layer's.
    pub print_modulus_ratio: Real,
}

impl Coefficients {
    /// The bilayer's top layer's coefficients `(along, across)` the machine direction.
    pub fn top_layer(&self) -> (Real, Real) {
        (self.mu_top, self.mu_top_perp.unwrap_or(self.mu_top))
    }

    /// The bilayer's bottom layer's coefficients `(along, across)` the machine direction.
    pub fn bottom_layer(&self) -> (Real, Real) {
        (
            self.mu_bottom,
            self.mu_bottom_perp.unwrap_or(self.mu_bottom),
        )
    }

    /// True when a layer's coefficient across the machine direction is given (by `[growth]`, a
    /// region or a face field), whatever its value.
    pub fn gives_across(&self) -> bool {
        self.mu_top_perp.is_some() || self.mu_bottom_perp.is_some()
    }
}

/// The forms `(ā, b̄)` of a moisture law at the reference thickness, with the thickness grown
/// by `1 + μ_n m̄` (m̄ the mean of the surface moistures): heights map `z ↦ λ z`, so `b̄`
/// divides by λ (as for the thermal shrink; exact for a swelling uniform through the
/// thickness). Errors when the thickness would vanish.
pub fn through_thickness(i: &FaceInput, forms: (Sym2, Sym2)) -> Result<Grown, GrowthError> {
    let mu_n = i.coef.mu_through;
    if mu_n == 0.0 {
        return Ok(Grown::at_fixed_thickness(forms));
    }
    let lambda = 1.0 + mu_n * 0.5 * (i.m_top + i.m_bottom);
    if lambda.is_nan() || lambda <= 0.0 {
        return Err(GrowthError::Stretch {
            face: i.face,
            worst: lambda - 1.0,
            mu: mu_n,
            top: i.m_top,
            bottom: i.m_bottom,
        });
    }
    Ok(Grown {
        abar: forms.0,
        bbar: forms.1 / lambda,
        thickness_ratio: lambda,
    })
}

/// What a law gives for one face.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grown {
    /// ā (m²).
    pub abar: Sym2,
    /// b̄ (m).
    pub bbar: Sym2,
    /// The rest thickness over the reference thickness, `h̄/h`.
    pub thickness_ratio: Real,
}

impl Grown {
    /// Rest forms `(ā, b̄)` of a law that keeps the thickness.
    pub fn at_fixed_thickness((abar, bbar): (Sym2, Sym2)) -> Grown {
        Grown {
            abar,
            bbar,
            thickness_ratio: 1.0,
        }
    }
}

/// A rest-form law with its coefficients (built from [`GrowthModel`] by its registry entry):
/// a face's inputs → its rest forms.
pub trait RestLaw: Send + Sync + std::fmt::Debug {
    /// The grown forms of one face. Errors name the face.
    fn grow(&self, input: &FaceInput) -> Result<Grown, GrowthError>;
    /// True when the law reads a stored original state (the vertex field
    /// `original_positions`, [`GrowthInputs::relaxed`]).
    fn needs_stored_state(&self) -> bool {
        false
    }
    /// True when the law reads the machine direction.
    fn needs_direction(&self) -> bool {
        false
    }
    /// True when the law reads the conformal factor `s` (`growth.s` or the face field
    /// `growth_factor`, one of which must be given).
    fn needs_s(&self) -> bool {
        false
    }
}

/// A registered rest-form law: its settings value, a valid example, and how it is built from
/// its own variant of [`GrowthModel`].
pub struct LawEntry {
    /// `growth.law`.
    pub law: GrowthLaw,
    /// The `[growth]` keys besides `law` of a valid example on a flat sheet, for the tests that
    /// every registered law passes (restarts).
    pub example: &'static str,
    /// The law with its coefficients; `None` for another law's variant (never asked: [`law`]
    /// picks the entry by the law).
    pub build: fn(&GrowthModel) -> Option<Box<dyn RestLaw>>,
}

/// Every rest-form law, one line each.
pub const LAWS: &[LawEntry] = &[
    isotropic::ENTRY,
    isotropic_in_plane::ENTRY,
    isotropic_metric_only::ENTRY,
    linear_swelling::ENTRY,
    bilayer::ENTRY,
    machine_direction::ENTRY,
    thermal_shrink::ENTRY,
    crease_relaxation::ENTRY,
];

/// The law of `model` with its coefficients (`None` for `"none"`).
pub fn law(model: &GrowthModel) -> Option<std::sync::Arc<dyn RestLaw>> {
    LAWS.iter()
        .find(|e| e.law == model.law())
        .and_then(|e| (e.build)(model))
        .map(std::sync::Arc::from)
}

/// The grown forms of a face under `law` (`which` names it in errors), checked: ā positive
/// definite, b̄ and the thickness finite and positive. No law keeps the reference forms.
pub fn grow_face(
    law: Option<&dyn RestLaw>,
    which: GrowthLaw,
    input: &FaceInput,
) -> Result<Grown, GrowthError> {
    let Some(l) = law else {
        return Ok(Grown {
            abar: input.a0,
            bbar: input.b0,
            thickness_ratio: 1.0,
        });
    };
    let out = l.grow(input)?;
    let a = out.abar;
    if !(a[0] > 0.0
        && crate::math::sym_det(&a) > 0.0
        && out.bbar.iter().all(|v| v.is_finite())
        && out.thickness_ratio.is_finite()
        && out.thickness_ratio > 0.0)
    {
        return Err(GrowthError::NotPositiveDefinite {
            face: input.face,
            law: which,
            top: input.m_top,
            bottom: input.m_bottom,
        });
    }
    Ok(out)
}

/// What a target law gives: per face the forms at dial 1 (barycentric, m² and m), and the
/// director data of a law that dials ā through its own stretch (else empty).
#[derive(Clone, Debug, Default)]
pub struct Targets {
    /// ā at dial 1 (m²).
    pub abar: Vec<Sym2>,
    /// b̄ at dial 1 (m).
    pub bbar: Vec<Sym2>,
    /// The director law per face ([`lce`]), else empty.
    pub lce: Vec<lce::LceFace>,
}

/// A target law: the `[rest]` settings and the mesh → the forms at dial 1 of every face.
pub trait TargetLaw: Sync {
    /// The targets. Errors name the key or field and the face.
    fn targets(&self, mesh: &Mesh, rest: &Rest) -> Result<Targets, MeshError>;
}

/// Every target law, one line each (`"none"` has none: the reference forms stay).
pub const TARGETS: &[(TargetForms, &dyn TargetLaw)] = &[
    (TargetForms::Uniform, &uniform_forms::UniformForms),
    (TargetForms::Mesh, &mesh_forms::MeshForms),
    (TargetForms::Lce, &lce::Director),
];

/// The target law of `rest.target` (`None` for `"none"`).
pub fn target_law(which: TargetForms) -> Option<&'static dyn TargetLaw> {
    TARGETS.iter().find(|(l, _)| *l == which).map(|(_, r)| *r)
}

/// The forms at dial 1: `rest`'s dial-0 forms replaced by the target law's, then transformed by
/// the growth law face by face (at the reference thickness `thickness` and, with `[moisture]`,
/// its initial moisture on both sides), with the stored original forms `relaxed` of a law that
/// needs them ([`RestLaw::needs_stored_state`], else empty). Returns the growth inputs (the moisture driver grows
/// from them again each step) and, per face, the rest thickness over the reference one when
/// the law scales it (else empty).
pub fn targets(
    rest: &mut RestForms,
    mesh: &Mesh,
    settings: &Settings,
    thickness: &[Real],
    relaxed: Vec<(Sym2, Sym2)>,
) -> Result<(GrowthInputs, Vec<Real>), MeshError> {
    if let Some(law) = target_law(settings.rest.target) {
        let t = law.targets(mesh, &settings.rest)?;
        rest.abar1 = t.abar;
        rest.bbar1 = t.bbar;
        rest.lce = t.lce;
    }
    rest.order = settings.dial.order;
    let mut growth = GrowthInputs::read(mesh, settings)?;
    growth.relaxed = relaxed;
    let mut grown_thickness = Vec::new();
    if settings.growth.law != GrowthLaw::None {
        for (f, &h) in thickness.iter().enumerate() {
            let m = if settings.moisture.enabled {
                (settings.moisture.initial, settings.moisture.initial)
            } else {
                (growth.moisture_top[f], growth.moisture_bottom[f])
            };
            let reference = (rest.abar0[f], rest.bbar0[f]);
            let g = growth_face(&growth, f, reference, h, m, None)
                .map_err(|e| mesh.invalid(e.to_string()))?;
            rest.abar1[f] = g.abar;
            rest.bbar1[f] = g.bbar;
            if g.thickness_ratio != 1.0 {
                grown_thickness.resize(thickness.len(), 1.0);
                grown_thickness[f] = g.thickness_ratio;
            }
        }
    }
    Ok((growth, grown_thickness))
}

/// The rest forms and thickness ratio of face `f` under `growth.law`, from its reference forms,
/// thickness, surface moisture `(m_top, m_bottom)` and the highest temperatures reached at the
/// heights [`sample_heights`] (K; `None`: `growth.temperature_top` and `temperature_bottom`,
/// linear between them). Errors name the face: a stretch `1 + μ m ≤ 0`, or an ā that is not
/// positive definite.
pub fn growth_face(
    inputs: &GrowthInputs,
    f: usize,
    reference: (Sym2, Sym2),
    h: Real,
    moisture: (Real, Real),
    heat: Option<[Real; 6]>,
) -> Result<Grown, GrowthError> {
    let heat = heat.unwrap_or_else(|| {
        let (top, bottom) = inputs.temperature;
        sample_heights(1.0).map(|z| 0.5 * (top + bottom) + (top - bottom) * z)
    });
    let input = FaceInput {
        face: f,
        a0: reference.0,
        b0: reference.1,
        h,
        m_top: moisture.0,
        m_bottom: moisture.1,
        s: inputs.s.get(f).copied().unwrap_or(0.0),
        direction: inputs.direction.get(f).map_or([1.0, 0.0], |d| d.0),
        heat,
        coef: inputs.coef.get(f).copied().unwrap_or(inputs.uniform),
        relaxed: inputs.relaxed.get(f).copied(),
    };
    grow_face(inputs.law.as_deref(), inputs.which, &input)
}

/// A rest form that a growth law cannot produce.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum GrowthError {
    /// A swelling stretch `1 + μ m` that is not positive.
    #[error(
        "growth at face {face}: the stretch 1 + mu m = 1 + {worst_h} is not positive (mu {mu_h}, \
         moisture top {top_h}, bottom {bottom_h}): a length cannot become ≤ 0"
    , worst_h = crate::math::human(*.worst), mu_h = crate::math::human(*.mu), top_h = crate::math::human(*.top), bottom_h = crate::math::human(*.bottom))]
    Stretch {
        /// The face.
        face: usize,
        /// The most negative `μ m`.
        worst: Real,
        /// The coefficient.
        mu: Real,
        /// Moisture on the top side.
        top: Real,
        /// Moisture on the bottom side.
        bottom: Real,
    },
    /// A printed layer as thick as the face or thicker.
    #[error(
        "growth at face {face}: the printed layer ({print_h} m) must be thinner than the face \
         ({thickness_h} m), which includes it",
        print_h = crate::math::human(*.print),
        thickness_h = crate::math::human(*.thickness)
    )]
    Print {
        /// The face.
        face: usize,
        /// The print's thickness (m).
        print: Real,
        /// The face's thickness (m).
        thickness: Real,
    },
    /// A gel bilayer's layer that swells differently across the machine direction.
    #[error(
        "growth at face {face}: growth.isotropic_layers grows each layer's thickness by its \
         in-plane stretch, so a layer must swell alike along and across the machine direction \
         (mu_top_perp = mu_top, mu_bottom_perp = mu_bottom)"
    )]
    AnisotropicGel {
        /// The face.
        face: usize,
    },
    /// The law's `ā` is not positive definite (or `b̄` or the thickness is not finite).
    #[error(
        "growth at face {face}: growth.law {law:?} makes abar non-positive-definite (moisture \
         top {}, bottom {})",
        crate::math::human(*.top),
        crate::math::human(*.bottom)
    )]
    NotPositiveDefinite {
        /// The face.
        face: usize,
        /// The law.
        law: GrowthLaw,
        /// Moisture on the top side.
        top: Real,
        /// Moisture on the bottom side.
        bottom: Real,
    },
}

/// `Ok` when the stretch `1 + μ m` is positive for the moisture the coefficient applies to
/// (`top`, `bottom`: whether it acts on that side).
pub(crate) fn check_stretch(
    input: &FaceInput,
    mu: Real,
    top: bool,
    bottom: bool,
) -> Result<(), GrowthError> {
    let (mt, mb) = (input.m_top, input.m_bottom);
    let worst = match (top, bottom) {
        (true, true) => (mu * mt).min(mu * mb),
        (true, false) => mu * mt,
        _ => mu * mb,
    };
    if 1.0 + worst <= 0.0 || worst.is_nan() {
        return Err(GrowthError::Stretch {
            face: input.face,
            worst,
            mu,
            top: mt,
            bottom: mb,
        });
    }
    Ok(())
}

/// Gauss–Legendre nodes and weights on [−1, 1] (3 points, exact to degree 5).
pub(crate) const GAUSS3: [(Real, Real); 3] = [
    (-0.774_596_669_241_483_4, 5.0 / 9.0),
    (0.0, 8.0 / 9.0),
    (0.774_596_669_241_483_4, 5.0 / 9.0),
];

/// The six heights `z ∈ (−h/2, h/2)` (m) at which [`project_through_thickness`] samples, bottom
/// to top: 3-point Gauss–Legendre on each half.
pub fn sample_heights(h: Real) -> [Real; 6] {
    std::array::from_fn(|k| {
        let (c, r) = if k < 3 {
            (-0.25 * h, 0.25 * h)
        } else {
            (0.25 * h, 0.25 * h)
        };
        c + r * GAUSS3[k % 3].0
    })
}

/// The weights of [`sample_heights`] over the thickness: each height's share of the mean, summing
/// to 1.
pub fn sample_weights() -> [Real; 6] {
    std::array::from_fn(|k| 0.25 * GAUSS3[k % 3].1)
}

/// Projects a through-thickness metric `g(z)` onto `ā + 2z b̄` (see the module doc). `g` may be
/// discontinuous at `z = 0`; it is sampled strictly inside each half.
pub fn project_through_thickness(h: Real, g: impl Fn(Real) -> Mat2) -> (Sym2, Sym2) {
    project_samples(h, |_, z| g(z))
}

/// [`project_through_thickness`] with `g(k, z)` told the index `k` of the height
/// [`sample_heights`]`(h)[k]` it is sampled at.
pub fn project_samples(h: Real, g: impl Fn(usize, Real) -> Mat2) -> (Sym2, Sym2) {
    let mut mean = Mat2::zeros();
    let mut moment = Mat2::zeros();
    for (k, (z, w)) in sample_heights(h)
        .into_iter()
        .zip(sample_weights())
        .enumerate()
    {
        let gz = g(k, z);
        mean += gz * (w * h);
        moment += gz * (w * h * z);
    }
    let abar = mean / h;
    let bbar = moment * (6.0 / (h * h * h));
    (mat_to_sym(&abar), mat_to_sym(&bbar))
}

/// The reference shell's metric at height `z`: `a⁰ + 2z b⁰`.
#[inline]
pub(crate) fn reference_metric(a0: &Sym2, b0: &Sym2, z: Real) -> Mat2 {
    sym_to_mat(a0) + sym_to_mat(b0) * (2.0 * z)
}

/// Moisture at height `z`, linear between `m_bottom` at `−h/2` and `m_top` at `+h/2`.
#[inline]
pub(crate) fn moisture_at(z: Real, h: Real, m_top: Real, m_bottom: Real) -> Real {
    0.5 * (m_top + m_bottom) + (m_top - m_bottom) * z / h
}

#[cfg(test)]
pub(crate) fn close(a: &Sym2, b: &Sym2, tol: Real) -> bool {
    (a - b).amax() <= tol * (1.0 + b.amax())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every law the settings accept (but `"none"`) has exactly one entry.
    #[test]
    fn every_law_is_registered_once() {
        for l in GrowthLaw::ALL {
            let n = LAWS.iter().filter(|e| e.law == l).count();
            assert_eq!(n, usize::from(l != GrowthLaw::None), "{l:?}");
        }
        for l in TargetForms::ALL {
            let n = TARGETS.iter().filter(|(k, _)| *k == l).count();
            assert_eq!(n, usize::from(l != TargetForms::None), "{l:?}");
        }
    }

    /// Each entry's example is valid settings, and its law builds from that example's
    /// coefficients and from no other law's.
    #[test]
    fn every_law_builds_from_its_own_coefficients_only() {
        for e in LAWS {
            let text = format!("[growth]\nlaw = \"{}\"\n{}\n", e.law.name(), e.example);
            let s = Settings::from_str_with(&text, "example", &[]).unwrap();
            let model = s.growth.model();
            assert_eq!(model.law(), e.law);
            assert!((e.build)(&model).is_some(), "{:?}", e.law);
            for other in LAWS.iter().filter(|o| o.law != e.law) {
                assert!(
                    (other.build)(&model).is_none(),
                    "{:?} from {:?}",
                    other.law,
                    e.law
                );
            }
        }
    }
}
