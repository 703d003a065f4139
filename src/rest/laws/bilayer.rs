//! Piecewise-constant bilayer (`growth.law = "bilayer"`; van Rees, Vouga & Mahadevan, PNAS
//! 2017; Timoshenko, J. Opt. Soc. Am. 11, 1925): a bottom layer of reference thickness
//! `(1 − φ)h` and modulus `E`, a top layer of thickness `φh` and modulus `nE`. Each layer
//! stretches in-plane by `s± = 1 + μ± m±`, so its metric is `s±²(a⁰ + 2z b⁰)` at reference
//! height `z`; with `growth.isotropic_layers` its thickness also grows by `s±` (a gel), else it
//! is kept. In the grown heights `ζ` the rest forms are the modulus-weighted least-squares
//! projection of that metric onto `ā + 2(ζ − ζₙ) b̄` about the neutral plane
//! `ζₙ = ∫E ζ dζ / ∫E dζ`:
//!
//! `ā = ∫E ḡ dζ / ∫E dζ`,   `b̄ = ∫E (ζ − ζₙ) ḡ dζ / (2 ∫E (ζ − ζₙ)² dζ)`,
//!
//! which decouples the laminate's energy `∫E |a + 2(ζ − ζₙ) b − ḡ|² dζ` into a membrane and a
//! bending part, so a free strip takes the curvature `b̄/ā`. To first order in the mismatch it
//! is Timoshenko's bimetal formula `κ = 6Δε(1 + m)² / (h [3(1 + m)² + (1 + mn)(m² + 1/(mn))])`
//! with `m = φ/(1 − φ)`; with equal layers of one modulus, `ā = (ḡ⁺ + ḡ⁻)/2`,
//! `b̄ = 3(ḡ⁺ − ḡ⁻)/(4h)` (van Rees' equivalence, `κ = 3Δε/(2h)`). The mesh stands for the
//! neutral plane (reference heights `z` are measured from the reference laminate's neutral
//! plane, so a uniform swelling is stress-free for any moduli); the rest thickness is the grown one, `h̄ = (1 − φ)h s⁻ + φh s⁺` with
//! isotropic layers (else `h`, or `growth.mu_through`'s, [`super::through_thickness`]).
//! `material` gives the stiffness of the shell as a whole.
//!
//! A printed layer on top (`growth.print_thickness`, `print_modulus_ratio`: an ethyl-cellulose
//! strip, an ink or a tape) is a third layer that does not swell, part of the face's thickness
//! (the film is the rest); it enters the same projection, so a stiff print pins the neutral plane
//! near itself and keeps the face from curling or growing. Coefficients: `growth.mu_top`,
//! `growth.mu_bottom` (per unit moisture), per face when regions or face fields give them.
//!
//! A layer may swell differently along the machine direction `d` than across it (fibres, a
//! stretched polymer, paper's grain; Armon et al., Science 2011, whose seed pods coil into
//! helices from two such layers crossed): `growth.mu_top_perp`, `growth.mu_bottom_perp` are the
//! coefficients across `d`, and `mu_top`, `mu_bottom` are then along it. Such a layer's metric
//! is `P⁻ᵀ M Pᵀ (a⁰ + 2z b⁰) P M P⁻¹` with `P = [d d⊥]` and `M = diag(1 + μ m, 1 + μ⊥ m)`, as in
//! [`super::machine_direction`]; it enters the same projection. Layers that grow through their
//! thickness (`isotropic_layers`) must swell alike in every direction.
//! Units: ā in m², b̄ in m, h in m.

use super::{
    check_stretch, reference_metric, through_thickness, FaceInput, Grown, GrowthError, LawEntry,
    RestLaw, GAUSS3,
};
use crate::config::growth::{GrowthLaw, GrowthModel, Laminate};
use crate::math::{mat_to_sym, Mat2, Real, Sym2};

/// The bilayer law with its layers and each face's `mu_top`, `mu_bottom` and the coefficients
/// across the machine direction ([`super::Coefficients`]; the direction is read where those are
/// given, [`super::GrowthInputs::gives_across`]).
#[derive(Debug)]
pub struct Bilayer(pub Laminate);

/// The registry's entry ([`super::LAWS`]).
pub const ENTRY: LawEntry = LawEntry {
    law: GrowthLaw::Bilayer,
    example: "mu_top = 0.05\nmu_bottom = 0.01\nmoisture_top = 0.4\nmoisture_bottom = 0.3",
    build: |m| match m {
        GrowthModel::Bilayer { laminate, .. } => Some(Box::new(Bilayer(*laminate))),
        _ => None,
    },
};

/// A non-swelling layer printed on top of the film: its thickness (m) and its Young's modulus
/// over the bottom layer's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Print {
    /// Thickness (m).
    pub thickness: Real,
    /// Modulus over the bottom layer's.
    pub modulus_ratio: Real,
}

/// A layer's in-plane stretch along the machine direction and across it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stretch {
    /// Along the machine direction.
    pub along: Real,
    /// Across it.
    pub across: Real,
}

impl Stretch {
    /// The same stretch in every direction.
    pub fn iso(s: Real) -> Stretch {
        Stretch {
            along: s,
            across: s,
        }
    }

    /// `1 + μ m` along and `1 + μ⊥ m` across, for coefficients `(μ, μ⊥)`.
    pub fn of(coefficients: (Real, Real), m: Real) -> Stretch {
        Stretch {
            along: 1.0 + coefficients.0 * m,
            across: 1.0 + coefficients.1 * m,
        }
    }

    /// True when it is the same in every direction.
    pub fn is_iso(&self) -> bool {
        self.along == self.across
    }
}

/// The bilayer's rest forms `(ā, b̄)` and rest thickness over `h`, for in-plane stretches
/// `top`, `bottom` of the two layers about the machine direction `d` (barycentric; unread when
/// both layers stretch alike in every direction), and an optional printed layer on top that
/// does not swell, part of the thickness `h` (see the module doc).
#[allow(clippy::too_many_arguments)]
pub fn bilayer(
    a0: &Sym2,
    b0: &Sym2,
    h: Real,
    top: Stretch,
    bottom: Stretch,
    d: [Real; 2],
    laminate: &Laminate,
    print: Option<Print>,
) -> (Sym2, Sym2, Real) {
    bilayer_jacobian(a0, b0, h, top, bottom, d, laminate, print).0
}

/// The rest data of one face, `(ā, b̄, h̄/h)`.
pub type RestData = (Sym2, Sym2, Real);

/// [`bilayer`] and its derivatives with respect to the top and the bottom layer's stretch,
/// `[∂/∂s⁺, ∂/∂s⁻]`, for layers that stretch alike in every direction (`s = along = across`;
/// for an anisotropic layer the derivative is along a uniform change of both of its stretches
/// only where they are equal, and is not meaningful otherwise). Exact: the Gauss points' heights
/// `ζ`, metrics `s² G(z)` and weights `½ w t s E` (with `isotropic_layers`; fixed heights and
/// weights otherwise) are differentiated through the modulus-weighted projection,
/// `∂ā = (∂Σ ḡW − ā ∂ΣW)/ΣW`, `∂b̄ = (∂Σ ḡW(ζ − ζₙ) − 2b̄ ∂Σ W(ζ − ζₙ)²)/(2 Σ W(ζ − ζₙ)²)`,
/// `∂ζₙ = (∂Σ Wζ − ζₙ ∂ΣW)/ΣW`. Units as [`bilayer`].
#[allow(clippy::too_many_arguments)]
pub fn bilayer_jacobian(
    a0: &Sym2,
    b0: &Sym2,
    h: Real,
    top: Stretch,
    bottom: Stretch,
    d: [Real; 2],
    laminate: &Laminate,
    print: Option<Print>,
) -> (RestData, [RestData; 2]) {
    let phi = laminate.top_fraction;
    let n = laminate.modulus_ratio;
    // Layers that grow through their thickness swell alike in every direction (checked by
    // the law): their thickness stretch is the in-plane one.
    let through = |s: Stretch| if laminate.isotropic { s.along } else { 1.0 };
    let d_through = if laminate.isotropic { 1.0 } else { 0.0 };
    let frame = (!(top.is_iso() && bottom.is_iso()))
        .then(|| super::machine_direction::direction_frame(a0, d));
    // A layer's metric at reference height z.
    let metric = |s: Stretch, z: Real| {
        let g = reference_metric(a0, b0, z);
        match frame {
            Some((p, pinv)) if !s.is_iso() => {
                let m = Mat2::new(s.along, 0.0, 0.0, s.across);
                pinv.transpose() * m * p.transpose() * g * p * m * pinv
            }
            _ => g * (s.along * s.along),
        }
    };
    let tp = print.map_or(0.0, |p| p.thickness);
    let film = h - tp;
    // Each layer: (reference bottom z, reference thickness, in-plane stretch, thickness
    // stretch, modulus weight, which stretch it is: 0 top, 1 bottom, 2 none), bottom to top.
    let mut layers = vec![
        (
            -0.5 * h,
            (1.0 - phi) * film,
            bottom,
            through(bottom),
            1.0,
            1,
        ),
        (
            -0.5 * h + (1.0 - phi) * film,
            phi * film,
            top,
            through(top),
            n,
            0,
        ),
    ];
    if let Some(p) = print.filter(|p| p.thickness > 0.0) {
        layers.push((0.5 * h - tp, tp, Stretch::iso(1.0), 1.0, p.modulus_ratio, 2));
    }
    // The reference laminate's neutral plane, where the mesh lies: heights are measured from it.
    let ref_stiffness: Real = layers.iter().map(|l| l.1 * l.4).sum();
    let z_n = layers
        .iter()
        .map(|l| l.1 * l.4 * (l.0 + 0.5 * l.1))
        .sum::<Real>()
        / ref_stiffness;
    // Gauss points (ζ, metric, weight·E) over the layers, ζ from the grown bottom, and their
    // derivatives with respect to the two stretches.
    let mut points = Vec::with_capacity(3 * layers.len());
    let mut dpoints = Vec::with_capacity(3 * layers.len());
    let mut base = 0.0;
    let mut d_base = [0.0; 2];
    for &(z0, t, s, l, e, which) in &layers {
        let grown = t * l;
        for &(x, w) in &GAUSS3 {
            let u = 0.5 * (x + 1.0);
            let z = z0 + u * t - z_n;
            let g = metric(s, z);
            points.push((base + u * grown, g, 0.5 * w * grown * e));
            let mut dp = [(0.0, Mat2::zeros(), 0.0); 2];
            for (k, dk) in dp.iter_mut().enumerate() {
                *dk = (d_base[k], Mat2::zeros(), 0.0);
                if which == k {
                    let dg = reference_metric(a0, b0, z) * (2.0 * s.along);
                    *dk = (
                        d_base[k] + u * t * d_through,
                        dg,
                        0.5 * w * t * d_through * e,
                    );
                }
            }
            dpoints.push(dp);
        }
        base += grown;
        if which < 2 {
            d_base[which] += t * d_through;
        }
    }
    let stiffness: Real = points.iter().map(|p| p.2).sum();
    let neutral = points.iter().map(|p| p.2 * p.0).sum::<Real>() / stiffness;
    let mut mean = Mat2::zeros();
    let mut moment = Mat2::zeros();
    let mut inertia = 0.0;
    for &(zeta, g, w) in &points {
        let d = zeta - neutral;
        mean += g * w;
        moment += g * (w * d);
        inertia += w * d * d;
    }
    let abar = mean / stiffness;
    let bbar = moment / (2.0 * inertia);
    let ratio = |b: Real| if laminate.isotropic { b / h } else { 0.0 };
    let jac = [0, 1].map(|k| {
        let ds: Real = dpoints.iter().map(|dp| dp[k].2).sum();
        let dn = (points
            .iter()
            .zip(&dpoints)
            .map(|(p, dp)| dp[k].2 * p.0 + p.2 * dp[k].0)
            .sum::<Real>()
            - neutral * ds)
            / stiffness;
        let mut d_mean = Mat2::zeros();
        let mut d_moment = Mat2::zeros();
        let mut d_inertia = 0.0;
        for (&(zeta, g, w), dp) in points.iter().zip(&dpoints) {
            let (dz, dg, dw) = dp[k];
            let arm = zeta - neutral;
            let d_arm = dz - dn;
            d_mean += dg * w + g * dw;
            d_moment += dg * (w * arm) + g * (dw * arm + w * d_arm);
            d_inertia += dw * arm * arm + 2.0 * w * arm * d_arm;
        }
        (
            mat_to_sym(&((d_mean - abar * ds) / stiffness)),
            mat_to_sym(&((d_moment - bbar * (2.0 * d_inertia)) / (2.0 * inertia))),
            ratio(d_base[k]),
        )
    });
    (
        (
            mat_to_sym(&abar),
            mat_to_sym(&bbar),
            if laminate.isotropic { base / h } else { 1.0 },
        ),
        jac,
    )
}

impl RestLaw for Bilayer {
    fn grow(&self, i: &FaceInput) -> Result<Grown, GrowthError> {
        let (top, bottom) = (i.coef.top_layer(), i.coef.bottom_layer());
        for mu in [top.0, top.1] {
            check_stretch(i, mu, true, false)?;
        }
        for mu in [bottom.0, bottom.1] {
            check_stretch(i, mu, false, true)?;
        }
        if self.0.isotropic && (top.0 != top.1 || bottom.0 != bottom.1) {
            return Err(GrowthError::AnisotropicGel { face: i.face });
        }
        let tp = i.coef.print_thickness;
        if tp >= i.h {
            return Err(GrowthError::Print {
                face: i.face,
                print: tp,
                thickness: i.h,
            });
        }
        let print = (tp > 0.0).then_some(Print {
            thickness: tp,
            modulus_ratio: i.coef.print_modulus_ratio,
        });
        let (st, sb) = (Stretch::of(top, i.m_top), Stretch::of(bottom, i.m_bottom));
        let (abar, bbar, ratio) = bilayer(&i.a0, &i.b0, i.h, st, sb, i.direction, &self.0, print);
        if self.0.isotropic {
            return Ok(Grown {
                abar,
                bbar,
                thickness_ratio: ratio,
            });
        }
        through_thickness(i, (abar, bbar))
    }
}

#[cfg(test)]
mod tests {
    use super::super::close;
    use super::*;

    const D: [Real; 2] = [1.0, 0.0];

    fn iso(s: Real) -> Stretch {
        Stretch::iso(s)
    }

    fn equal() -> Laminate {
        Laminate::default()
    }

    #[test]
    fn bilayer_is_van_rees_and_timoshenko() {
        let a0 = Sym2::new(1.0, 0.0, 1.0);
        let (h, de) = (0.002, 0.002);
        // Layers stretched by 1 ± Δε/2.
        let (a, b, r) = bilayer(
            &a0,
            &Sym2::zeros(),
            h,
            iso(1.0 + de / 2.0),
            iso(1.0 - de / 2.0),
            D,
            &equal(),
            None,
        );
        let (gp, gm) = ((1.0 + de / 2.0).powi(2), (1.0 - de / 2.0).powi(2));
        assert!(close(&a, &(a0 * ((gp + gm) / 2.0)), 1e-14));
        assert!(close(&b, &(a0 * (3.0 * (gp - gm) / (4.0 * h))), 1e-13));
        assert_eq!(r, 1.0);
        // Timoshenko, equal layers: κ = 3Δε/(2h) (to O(Δε²)).
        let kappa = b[0] / a[0];
        assert!((kappa / (1.5 * de / h) - 1.0).abs() < 1e-5, "{kappa}");
    }

    /// Timoshenko's bimetal formula (1925, eq. 4) with `m` = top over bottom thickness and `n`
    /// = top over bottom modulus, for a top layer strained `Δε` more than the bottom.
    fn timoshenko(de: Real, h: Real, m: Real, n: Real) -> Real {
        6.0 * de * (1.0 + m).powi(2)
            / (h * (3.0 * (1.0 + m).powi(2) + (1.0 + m * n) * (m * m + 1.0 / (m * n))))
    }

    #[test]
    fn unequal_layers_follow_timoshenko() {
        let a0 = Sym2::new(1.0, 0.0, 1.0);
        let (h, de) = (0.001, 1e-6);
        for (phi, n) in [(0.5, 1.0), (0.3, 3.0), (0.7, 0.2), (0.1, 10.0), (0.5, 5.0)] {
            for isotropic in [false, true] {
                let lam = Laminate {
                    top_fraction: phi,
                    modulus_ratio: n,
                    isotropic,
                };
                let (a, b, _) = bilayer(
                    &a0,
                    &Sym2::zeros(),
                    h,
                    iso(1.0 + de),
                    iso(1.0),
                    D,
                    &lam,
                    None,
                );
                let kappa = b[0] / a[0];
                let t = timoshenko(de, h, phi / (1.0 - phi), n);
                // First order in Δε: the error is O(Δε) relative.
                assert!((kappa / t - 1.0).abs() < 1e-5, "{phi} {n}: {kappa} vs {t}");
                // Isotropic curvature: b̄ ∝ a⁰.
                assert!(b[1].abs() < 1e-12 * b[0].abs() && (b[2] - b[0]).abs() < 1e-9 * b[0]);
            }
        }
    }

    /// A film swelling uniformly under a print that does not: a bilayer of film and print, whose
    /// top (the print) is strained −Δε against the film, as Timoshenko's formula says.
    #[test]
    fn a_print_on_a_swelling_film_is_a_bilayer() {
        let a0 = Sym2::new(1.0, 0.0, 1.0);
        let (h, de) = (0.001, 1e-6);
        for (tp, np) in [(0.1e-3, 1000.0), (0.3e-3, 1.0), (0.5e-3, 0.3)] {
            for lam in [
                equal(),
                Laminate {
                    top_fraction: 0.3,
                    modulus_ratio: 1.0,
                    isotropic: true,
                },
            ] {
                let print = Print {
                    thickness: tp,
                    modulus_ratio: np,
                };
                let (a, b, _) = bilayer(
                    &a0,
                    &Sym2::zeros(),
                    h,
                    iso(1.0 + de),
                    iso(1.0 + de),
                    D,
                    &lam,
                    Some(print),
                );
                let kappa = b[0] / a[0];
                let t = timoshenko(-de, h, tp / (h - tp), np);
                assert!((kappa / t - 1.0).abs() < 1e-5, "{tp} {np}: {kappa} vs {t}");
            }
        }
        // A print much stiffer than the film keeps the face from growing and curling.
        let stiff = Print {
            thickness: 0.1e-3,
            modulus_ratio: 1e6,
        };
        let (a, b, _) = bilayer(
            &a0,
            &Sym2::zeros(),
            h,
            iso(1.3),
            iso(1.1),
            D,
            &equal(),
            Some(stiff),
        );
        assert!(
            (a[0] - 1.0).abs() < 1e-3 && b[0].abs() * h < 1e-3,
            "{a:?} {b:?}"
        );
    }

    #[test]
    fn a_uniform_swelling_is_stress_free() {
        // Both layers stretched alike: a scaled copy, whatever the moduli; isotropic layers
        // scale the thickness and the reference curvature's lever arm with it.
        let (a0, b0) = (Sym2::new(1.0, 0.1, 0.9), Sym2::new(0.3, -0.1, 0.2));
        let lam = Laminate {
            top_fraction: 0.3,
            modulus_ratio: 4.0,
            isotropic: true,
        };
        let s = 1.4;
        let (a, b, r) = bilayer(&a0, &b0, 0.01, iso(s), iso(s), D, &lam, None);
        assert!((r - s).abs() < 1e-15);
        // Heights from the neutral plane grow by s: ḡ = s²(a⁰ + 2(ζ/s) b⁰), ā = s² a⁰, b̄ = s b⁰.
        assert!(close(&a, &(a0 * (s * s)), 1e-13), "{a:?}");
        assert!(close(&b, &(b0 * s), 1e-12), "{b:?}");
        // At a kept thickness the lever arms keep their length: b̄ = s² b⁰.
        let kept = Laminate {
            isotropic: false,
            ..lam
        };
        let (a, b, r) = bilayer(&a0, &b0, 0.01, iso(s), iso(s), D, &kept, None);
        assert!(close(&a, &(a0 * (s * s)), 1e-13) && close(&b, &(b0 * (s * s)), 1e-12));
        assert_eq!(r, 1.0);
    }

    #[test]
    fn isotropic_layers_thicken_the_swollen_side() {
        let a0 = Sym2::new(1.0, 0.0, 1.0);
        let h = 1.0;
        let gel = Laminate {
            isotropic: true,
            ..equal()
        };
        let (a, b, r) = bilayer(&a0, &Sym2::zeros(), h, iso(1.5), iso(1.0), D, &gel, None);
        assert!((r - 1.25).abs() < 1e-15);
        // Closed form: layers of grown thickness 0.75 (ḡ = 2.25) over 0.5 (ḡ = 1), neutral
        // plane at the centroid ζₙ = (0.5·0.25 + 0.75·0.875)/1.25 = 0.625.
        let (zn, t1, t2): (Real, Real, Real) = (0.625, 0.5, 0.75);
        let m1 = 1.0 * t1 * (0.25 - zn) + 2.25 * t2 * (0.875 - zn);
        let i = (t1.powi(3) + t2.powi(3)) / 12.0
            + t1 * (0.25 - zn).powi(2)
            + t2 * (0.875f64 - zn).powi(2);
        assert!((a[0] - (t1 + 2.25 * t2) / 1.25).abs() < 1e-14);
        assert!(
            (b[0] - m1 / (2.0 * i)).abs() < 1e-13,
            "{} vs {}",
            b[0],
            m1 / (2.0 * i)
        );
        // Thicker: less curvature than at a kept thickness.
        let (a2, b2, _) = bilayer(
            &a0,
            &Sym2::zeros(),
            h,
            iso(1.5),
            iso(1.0),
            D,
            &equal(),
            None,
        );
        assert!(b[0] / a[0] < b2[0] / a2[0]);
    }

    /// Layers that swell along the machine direction only curl the face along it alone; crossed
    /// layers (Armon et al. 2011) program a saddle along `d` and `d⊥`. Equal layers on a flat
    /// face: each layer's metric is `diag(s², 1)` in the `(d, d⊥)` frame, so van Rees'
    /// equivalence is exact: `ā = (ḡ⁺ + ḡ⁻)/2`, `b̄ = 3(ḡ⁺ − ḡ⁻)/(4h)`.
    #[test]
    fn anisotropic_layers_curl_along_their_direction() {
        let a0 = Sym2::new(1.0, 0.0, 1.0);
        let h = 0.002;
        let (c, s) = (0.3f64.cos(), 0.3f64.sin());
        let d = [2.0 * c, 2.0 * s]; // its length does not matter
        let dd = Sym2::new(c * c, c * s, s * s);
        let pp = Sym2::new(s * s, -c * s, c * c);
        let e: Real = 0.01;
        let along = |v: Real| Stretch {
            along: v,
            across: 1.0,
        };
        let across = |v: Real| Stretch {
            along: 1.0,
            across: v,
        };
        let (gp, gm) = ((1.0 + e).powi(2), (1.0 - e).powi(2));
        // Both layers along d, one swelling, one shrinking.
        let (a, b, _) = bilayer(
            &a0,
            &Sym2::zeros(),
            h,
            along(1.0 + e),
            along(1.0 - e),
            d,
            &equal(),
            None,
        );
        let a_want = dd * ((gp + gm) / 2.0) + pp;
        assert!(close(&a, &a_want, 1e-14), "{a:?} vs {a_want:?}");
        let b_want = dd * (3.0 * (gp - gm) / (4.0 * h));
        assert!(close(&b, &b_want, 1e-12), "{b:?} vs {b_want:?}");
        // Crossed: the top along d, the bottom across it, both swelling by e.
        let (a, b, _) = bilayer(
            &a0,
            &Sym2::zeros(),
            h,
            along(1.0 + e),
            across(1.0 + e),
            d,
            &equal(),
            None,
        );
        let a_want = a0 * ((gp + 1.0) / 2.0);
        assert!(close(&a, &a_want, 1e-14), "{a:?}");
        let b_want = (dd - pp) * (3.0 * (gp - 1.0) / (4.0 * h));
        assert!(close(&b, &b_want, 1e-12), "{b:?} vs {b_want:?}");
        // On a curved, sheared face the law is the machine-direction law's metric per layer:
        // with both layers alike it is a single layer swelling by a uniform moisture, at any
        // direction, and it differs from the isotropic layer.
        let (a0, b0) = (Sym2::new(1.0, 0.3, 1.2), Sym2::new(0.2, 0.05, -0.1));
        let layer = Stretch {
            along: 1.02,
            across: 1.07,
        };
        let (a, b, _) = bilayer(&a0, &b0, h, layer, layer, [0.3, 0.7], &equal(), None);
        let (am, bm) = super::super::machine_direction::machine_direction(
            &a0,
            &b0,
            h,
            1.0,
            1.0,
            0.02,
            0.07,
            [0.3, 0.7],
        );
        assert!(
            close(&a, &am, 1e-13) && close(&b, &bm, 1e-10),
            "{a:?} {am:?} {b:?} {bm:?}"
        );
        let (ai, _, _) = bilayer(
            &a0,
            &b0,
            h,
            iso(1.02),
            iso(1.02),
            [0.3, 0.7],
            &equal(),
            None,
        );
        assert!((a - ai).amax() > 1e-3);
    }

    /// The derivatives with respect to the layers' stretches against central differences of
    /// the law: gel layers (heights, weights and the thickness move) and layers that keep their
    /// thickness, unequal, on a curved face, with a print. Differences with step 1e-5 have error
    /// ~1e-10 relative; the test asks for 1e-7.
    #[test]
    fn the_stretch_derivatives_are_the_laws() {
        let (a0, b0) = (Sym2::new(1.1, 0.2, 0.9), Sym2::new(0.3, -0.1, 0.5));
        let h = 0.05;
        let print = Some(Print {
            thickness: 0.005,
            modulus_ratio: 3.0,
        });
        for isotropic in [true, false] {
            let lam = Laminate {
                top_fraction: 0.35,
                modulus_ratio: 2.5,
                isotropic,
            };
            let (st, sb) = (1.3, 0.9);
            let law = |st: Real, sb: Real| bilayer(&a0, &b0, h, iso(st), iso(sb), D, &lam, print);
            let (_, jac) = bilayer_jacobian(&a0, &b0, h, iso(st), iso(sb), D, &lam, print);
            let e = 1e-5;
            for (k, (p, m)) in [
                (law(st + e, sb), law(st - e, sb)),
                (law(st, sb + e), law(st, sb - e)),
            ]
            .into_iter()
            .enumerate()
            {
                let da = (p.0 - m.0) / (2.0 * e);
                let db = (p.1 - m.1) / (2.0 * e);
                let dr = (p.2 - m.2) / (2.0 * e);
                assert!(
                    close(&jac[k].0, &da, 1e-7),
                    "{isotropic} {k}: {:?} vs {da:?}",
                    jac[k].0
                );
                assert!(
                    close(&jac[k].1, &db, 1e-7),
                    "{isotropic} {k}: {:?} vs {db:?}",
                    jac[k].1
                );
                assert!(
                    (jac[k].2 - dr).abs() < 1e-8,
                    "{isotropic} {k}: {} vs {dr}",
                    jac[k].2
                );
            }
            // Gel layers thicken and move the neutral plane; kept ones do not.
            assert_eq!(jac[0].2 == 0.0, !isotropic);
        }
    }
}
