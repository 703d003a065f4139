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
//! Units: ā in m², b̄ in m, h in m.

use super::{
    check_stretch, reference_metric, through_thickness, FaceInput, Grown, GrowthError, LawEntry,
    RestLaw, GAUSS3,
};
use crate::config::growth::{GrowthLaw, GrowthModel, Laminate};
use crate::math::{mat_to_sym, Mat2, Real, Sym2};

/// The bilayer law with its layers and each face's `mu_top` and `mu_bottom`
/// ([`super::Coefficients`]).
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

/// The bilayer's rest forms `(ā, b̄)` and rest thickness over `h`, for in-plane stretches
/// `s_top`, `s_bottom` of the two layers, and an optional printed layer on top that does not
/// swell, part of the thickness `h` (see the module doc).
pub fn bilayer(
    a0: &Sym2,
    b0: &Sym2,
    h: Real,
    s_top: Real,
    s_bottom: Real,
    laminate: &Laminate,
    print: Option<Print>,
) -> (Sym2, Sym2, Real) {
    let phi = laminate.top_fraction;
    let n = laminate.modulus_ratio;
    let through = |s: Real| if laminate.isotropic { s } else { 1.0 };
    let tp = print.map_or(0.0, |p| p.thickness);
    let film = h - tp;
    // Each layer: (reference bottom z, reference thickness, in-plane stretch, thickness
    // stretch, modulus weight), bottom to top.
    let mut layers = vec![
        (
            -0.5 * h,
            (1.0 - phi) * film,
            s_bottom,
            through(s_bottom),
            1.0,
        ),
        (
            -0.5 * h + (1.0 - phi) * film,
            phi * film,
            s_top,
            through(s_top),
            n,
        ),
    ];
    if let Some(p) = print.filter(|p| p.thickness > 0.0) {
        layers.push((0.5 * h - tp, tp, 1.0, 1.0, p.modulus_ratio));
    }
    // The reference laminate's neutral plane, where the mesh lies: heights are measured from it.
    let ref_stiffness: Real = layers.iter().map(|l| l.1 * l.4).sum();
    let z_n = layers
        .iter()
        .map(|l| l.1 * l.4 * (l.0 + 0.5 * l.1))
        .sum::<Real>()
        / ref_stiffness;
    // Gauss points (ζ, metric, weight·E) over the layers, ζ from the grown bottom.
    let mut points = Vec::with_capacity(3 * layers.len());
    let mut base = 0.0;
    for &(z0, t, s, l, e) in &layers {
        let grown = t * l;
        for &(x, w) in &GAUSS3 {
            let u = 0.5 * (x + 1.0);
            let metric = reference_metric(a0, b0, z0 + u * t - z_n) * (s * s);
            points.push((base + u * grown, metric, 0.5 * w * grown * e));
        }
        base += grown;
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
    (
        mat_to_sym(&(mean / stiffness)),
        mat_to_sym(&(moment / (2.0 * inertia))),
        if laminate.isotropic { base / h } else { 1.0 },
    )
}

impl RestLaw for Bilayer {
    fn grow(&self, i: &FaceInput) -> Result<Grown, GrowthError> {
        let (mt, mb) = (i.coef.mu_top, i.coef.mu_bottom);
        check_stretch(i, mt, true, false)?;
        check_stretch(i, mb, false, true)?;
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
        let (st, sb) = (1.0 + mt * i.m_top, 1.0 + mb * i.m_bottom);
        let (abar, bbar, ratio) = bilayer(&i.a0, &i.b0, i.h, st, sb, &self.0, print);
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
            1.0 + de / 2.0,
            1.0 - de / 2.0,
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
                let (a, b, _) = bilayer(&a0, &Sym2::zeros(), h, 1.0 + de, 1.0, &lam, None);
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
                    1.0 + de,
                    1.0 + de,
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
        let (a, b, _) = bilayer(&a0, &Sym2::zeros(), h, 1.3, 1.1, &equal(), Some(stiff));
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
        let (a, b, r) = bilayer(&a0, &b0, 0.01, s, s, &lam, None);
        assert!((r - s).abs() < 1e-15);
        // Heights from the neutral plane grow by s: ḡ = s²(a⁰ + 2(ζ/s) b⁰), ā = s² a⁰, b̄ = s b⁰.
        assert!(close(&a, &(a0 * (s * s)), 1e-13), "{a:?}");
        assert!(close(&b, &(b0 * s), 1e-12), "{b:?}");
        // At a kept thickness the lever arms keep their length: b̄ = s² b⁰.
        let kept = Laminate {
            isotropic: false,
            ..lam
        };
        let (a, b, r) = bilayer(&a0, &b0, 0.01, s, s, &kept, None);
        assert!(close(&a, &(a0 * (s * s)), 1e-13) && close(&b, &(b0 * (s * s)), 1e-12));
        assert_eq!(r, 1.0);
    }

    #[test]
    fn isotropic_layers_thicken_the_swollen_side() {
        let a0 = Sym2::new(1.0, 0.0, 1.0);
        let h = 1.0;
        let iso = Laminate {
            isotropic: true,
            ..equal()
        };
        let (a, b, r) = bilayer(&a0, &Sym2::zeros(), h, 1.5, 1.0, &iso, None);
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
        let (a2, b2, _) = bilayer(&a0, &Sym2::zeros(), h, 1.5, 1.0, &equal(), None);
        assert!(b[0] / a[0] < b2[0] / a2[0]);
    }
}
