//! Finite-difference checks of every kernel: gradient against energy, Hessian against gradient,
//! central differences, on random non-degenerate configurations including boundary faces.

use shellsim::energy::{material::sv_matrix, shell_face, KoiterDensity, Lame2d};
use shellsim::math::{Real, SMat, SVec, Sym2, Vec3};
use shellsim::mesh::generate::Rng;

/// A face with its three neighbours' far vertices, randomly bent and sheared.
pub fn random_patch(rng: &mut Rng, amp: Real) -> [Vec3; 6] {
    let base = [
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.3, 0.9, 0.0),
        // p0 across edge (v1, v2), p1 across (v2, v0), p2 across (v0, v1)
        Vec3::new(1.2, 1.0, 0.0),
        Vec3::new(-0.6, 0.5, 0.0),
        Vec3::new(0.5, -0.8, 0.0),
    ];
    base.map(|p| p + Vec3::new(rng.symmetric(), rng.symmetric(), rng.symmetric()) * amp)
}

pub fn random_density(rng: &mut Rng, damping: bool) -> KoiterDensity {
    let abar = Sym2::new(
        1.0 + 0.2 * rng.uniform(),
        0.1 * rng.symmetric(),
        0.8 + 0.2 * rng.uniform(),
    );
    let bbar = Sym2::new(rng.symmetric(), rng.symmetric(), rng.symmetric()) * 0.5;
    let lame = Lame2d::from_young_poisson(1.0 + rng.uniform(), 0.45 * rng.uniform());
    let h = 0.1;
    let (ws, wb) = KoiterDensity::weights(&abar, h, 1.0);
    let mut d = KoiterDensity {
        c: sv_matrix(&abar, lame),
        stretch: [(ws, abar), (0.0, Sym2::zeros())],
        bend: [(wb, bbar), (0.0, Sym2::zeros())],
        stiffen: 0.0,
    };
    if damping {
        d.stretch[1] = (0.3 * ws, Sym2::new(1.1, 0.05, 0.9));
        d.bend[1] = (0.3 * wb, Sym2::new(0.1, -0.2, 0.3));
    }
    d
}

fn flat(x: &[Vec3; 6]) -> SVec<18> {
    SVec::<18>::from_iterator(x.iter().flat_map(|p| [p.x, p.y, p.z]))
}
fn unflat(v: &SVec<18>) -> [Vec3; 6] {
    std::array::from_fn(|i| Vec3::new(v[3 * i], v[3 * i + 1], v[3 * i + 2]))
}

/// Max relative errors (gradient, Hessian) of central differences with step `eps`.
pub fn fd_errors(x: &[Vec3; 6], has: [bool; 3], d: &KoiterDensity, eps: Real) -> (Real, Real) {
    let mut g = SVec::<18>::zeros();
    let mut h = SMat::<18, 18>::zeros();
    shell_face(x, has, d, Some(&mut g), Some(&mut h));
    let x0 = flat(x);
    let mut gfd = SVec::<18>::zeros();
    let mut hfd = SMat::<18, 18>::zeros();
    for k in 0..18 {
        let mut xp = x0;
        xp[k] += eps;
        let mut xm = x0;
        xm[k] -= eps;
        let mut gp = SVec::<18>::zeros();
        let mut gm = SVec::<18>::zeros();
        let ep = shell_face(&unflat(&xp), has, d, Some(&mut gp), None);
        let em = shell_face(&unflat(&xm), has, d, Some(&mut gm), None);
        gfd[k] = (ep - em) / (2.0 * eps);
        hfd.set_column(k, &((gp - gm) / (2.0 * eps)));
    }
    let ge = (g - gfd).amax() / g.amax().max(1e-300);
    let he = (h - hfd).amax() / h.amax().max(1e-300);
    (ge, he)
}

#[test]
fn shell_face_derivatives_match_finite_differences() {
    let mut rng = Rng::new(7);
    let patterns = [
        [true, true, true],
        [false, true, true],
        [true, false, false],
        [false, false, false],
    ];
    for trial in 0..40 {
        let x = random_patch(&mut rng, 0.25);
        let d = random_density(&mut rng, trial % 2 == 1);
        let has = patterns[trial % patterns.len()];
        let (ge, he) = fd_errors(&x, has, &d, 1e-6);
        assert!(ge < 1e-6, "trial {trial}: gradient rel. error {ge:e}");
        assert!(he < 1e-6, "trial {trial}: Hessian rel. error {he:e}");
    }
}

/// Bend stiffening `E_b + s E_b²` (MorphoShell's `W_b + W_b²/(γμt)`): the face's gradient and
/// Hessian against central differences, with `s E_b` of order one so that the squared term
/// matters, and its energy against the formula.
#[test]
fn stiffened_bending_derivatives_match_finite_differences() {
    use shellsim::energy::material::FaceDensity;
    let mut rng = Rng::new(17);
    for trial in 0..20 {
        let x = random_patch(&mut rng, 0.25);
        let mut d = random_density(&mut rng, trial % 2 == 1);
        let (_, eb) = d.elastic_parts(
            &shellsim::geometry::first_fundamental_form(&[x[0], x[1], x[2]]),
            &shell_face_b(&x),
        );
        d.stiffen = 2.0 / eb.max(1e-12);
        let (ge, he) = fd_errors(&x, [true; 3], &d, 1e-6);
        assert!(ge < 1e-6, "trial {trial}: gradient rel. error {ge:e}");
        assert!(he < 1e-6, "trial {trial}: Hessian rel. error {he:e}");
        let (_, es) = d.elastic_parts(
            &shellsim::geometry::first_fundamental_form(&[x[0], x[1], x[2]]),
            &shell_face_b(&x),
        );
        assert!(
            (es - 3.0 * eb).abs() <= 1e-12 * es,
            "E_b + s E_b² = 3 E_b, got {es} vs {eb}"
        );
    }
}

fn shell_face_b(x: &[Vec3; 6]) -> Sym2 {
    shellsim::energy::shell::face_forms(x, [true; 3]).1
}

#[test]
fn hessian_is_symmetric() {
    let mut rng = Rng::new(11);
    for _ in 0..10 {
        let x = random_patch(&mut rng, 0.3);
        let d = random_density(&mut rng, true);
        let mut h = SMat::<18, 18>::zeros();
        shell_face(&x, [true; 3], &d, None, Some(&mut h));
        let asym = (h - h.transpose()).amax() / h.amax();
        assert!(asym < 1e-13, "asymmetry {asym:e}");
    }
}

/// Prints the error-vs-step table for h = 1e-2 … 1e-6 (run with `--ignored --nocapture`).
#[test]
#[ignore]
fn fd_error_table() {
    let mut rng = Rng::new(3);
    let x = random_patch(&mut rng, 0.25);
    let d = random_density(&mut rng, true);
    println!("{:>8} {:>12} {:>12}", "h", "grad err", "hess err");
    for p in 2..=6 {
        let eps = 10f64.powi(-p);
        let (ge, he) = fd_errors(&x, [true; 3], &d, eps);
        println!("{eps:>8.0e} {ge:>12.3e} {he:>12.3e}");
    }
}

/// Patch-fit kernel: gradient and Hessian against central differences, exact and Gauss–Newton
/// gradients equal.
#[test]
fn patch_face_derivatives_match_finite_differences() {
    use shellsim::energy::patch::{patch_face, PatchWeights};
    let mut rng = Rng::new(21);
    for trial in 0..20 {
        let x = random_patch(&mut rng, 0.25);
        let d = random_density(&mut rng, trial % 2 == 1);
        let w = PatchWeights::from_fn(|_, _| rng.symmetric());
        let mut g = SVec::<18>::zeros();
        let mut h = SMat::<18, 18>::zeros();
        patch_face::<_, false>(&x, &w, &d, Some(&mut g), Some(&mut h));
        // The gradient alone (the explicit path) forms Jaᵀ W_a in closed form: equal to the
        // Hessian path's gradient up to round-off.
        let mut ggn = SVec::<18>::zeros();
        patch_face::<_, true>(&x, &w, &d, Some(&mut ggn), None);
        assert!(
            (g - ggn).amax() <= 1e-14 * g.amax(),
            "{:e}",
            (g - ggn).amax()
        );
        let x0 = flat(&x);
        let eps = 1e-6;
        let mut gfd = SVec::<18>::zeros();
        let mut hfd = SMat::<18, 18>::zeros();
        for k in 0..18 {
            let (mut xp, mut xm) = (x0, x0);
            xp[k] += eps;
            xm[k] -= eps;
            let (mut gp, mut gm) = (SVec::<18>::zeros(), SVec::<18>::zeros());
            let ep = patch_face::<_, false>(&unflat(&xp), &w, &d, Some(&mut gp), None);
            let em = patch_face::<_, false>(&unflat(&xm), &w, &d, Some(&mut gm), None);
            gfd[k] = (ep - em) / (2.0 * eps);
            hfd.set_column(k, &((gp - gm) / (2.0 * eps)));
        }
        let ge = (g - gfd).amax() / g.amax();
        let he = (h - hfd).amax() / h.amax();
        assert!(ge < 1e-6 && he < 1e-6, "trial {trial}: {ge:e} {he:e}");
        assert!((h - h.transpose()).amax() < 1e-12 * h.amax());
    }
}

/// The gradient and Hessian of `eval` at `v0` by central differences of its energy and its
/// gradient (step `eps`), for the 21 DOFs of an edge-DOF face.
fn central_differences_21<F>(eval: &F, v0: &SVec<21>, eps: Real) -> (SVec<21>, SMat<21, 21>)
where
    F: Fn(&SVec<21>, Option<&mut SVec<21>>, Option<&mut SMat<21, 21>>) -> Real,
{
    let mut gfd = SVec::<21>::zeros();
    let mut hfd = SMat::<21, 21>::zeros();
    for k in 0..21 {
        let (mut vp, mut vm) = (*v0, *v0);
        vp[k] += eps;
        vm[k] -= eps;
        let (mut gp, mut gm) = (SVec::<21>::zeros(), SVec::<21>::zeros());
        let ep = eval(&vp, Some(&mut gp), None);
        let em = eval(&vm, Some(&mut gm), None);
        gfd[k] = (ep - em) / (2.0 * eps);
        hfd.set_column(k, &((gp - gm) / (2.0 * eps)));
    }
    (gfd, hfd)
}

/// Mid-edge shell with edge DOFs (both variants, every boundary pattern): gradient and Hessian
/// against central differences in all 21 DOFs; Gauss–Newton gradient equal to the exact one;
/// the `sin` variant at φ = 0 equals the mid-edge average.
#[test]
fn midedge_angle_derivatives_match_finite_differences() {
    use shellsim::energy::midedge_angle::{midedge_angle_face, AngleVariant};
    let mut rng = Rng::new(31);
    let patterns = [
        [true, true, true],
        [false, true, true],
        [true, false, false],
        [false, false, false],
    ];
    for trial in 0..40 {
        let variant = if trial % 2 == 0 {
            AngleVariant::Sin
        } else {
            AngleVariant::Tan
        };
        let x = random_patch(&mut rng, 0.25);
        let d = random_density(&mut rng, trial % 3 == 1);
        let has = patterns[trial % patterns.len()];
        let phi = [0.0; 3].map(|_: Real| 0.3 * rng.symmetric());
        let sigma = [0.0; 3].map(|_: Real| if rng.uniform() < 0.5 { -1.0 } else { 1.0 });
        let pack = |x: &[Vec3; 6], p: &[Real; 3]| {
            let mut v = SVec::<21>::zeros();
            v.fixed_rows_mut::<18>(0).copy_from(&flat(x));
            for i in 0..3 {
                v[18 + i] = p[i];
            }
            v
        };
        let unpack = |v: &SVec<21>| {
            let x = unflat(&v.fixed_rows::<18>(0).into_owned());
            (x, [v[18], v[19], v[20]])
        };
        let eval = |v: &SVec<21>, g: Option<&mut SVec<21>>, h: Option<&mut SMat<21, 21>>| {
            let (x, p) = unpack(v);
            midedge_angle_face::<_, false>(&x, has, &p, sigma, variant, &d, g, h)
        };
        let v0 = pack(&x, &phi);
        let mut g = SVec::<21>::zeros();
        let mut h = SMat::<21, 21>::zeros();
        eval(&v0, Some(&mut g), Some(&mut h));
        let mut ggn = SVec::<21>::zeros();
        let mut hgn = SMat::<21, 21>::zeros();
        midedge_angle_face::<_, true>(
            &x,
            has,
            &phi,
            sigma,
            variant,
            &d,
            Some(&mut ggn),
            Some(&mut hgn),
        );
        assert!(
            (g - ggn).amax() <= 1e-14 * g.amax(),
            "trial {trial}: GN gradient differs"
        );
        let ev = hgn.symmetric_eigenvalues();
        assert!(
            ev.min() >= -1e-12 * ev.amax(),
            "trial {trial}: GN Hessian not PSD"
        );
        let (gfd, hfd) = central_differences_21(&eval, &v0, 1e-6);
        let ge = (g - gfd).amax() / g.amax();
        let he = (h - hfd).amax() / h.amax();
        assert!(
            ge < 1e-6,
            "trial {trial} {variant:?} {has:?}: gradient rel. error {ge:e}"
        );
        assert!(
            he < 1e-6,
            "trial {trial} {variant:?} {has:?}: Hessian rel. error {he:e}"
        );
        assert!((h - h.transpose()).amax() < 1e-12 * h.amax());
        // The sin variant at φ = 0 is the mid-edge average.
        if variant == AngleVariant::Sin {
            let e0 =
                midedge_angle_face::<_, false>(&x, has, &[0.0; 3], sigma, variant, &d, None, None);
            let ea = shell_face(&x, has, &d, None, None);
            assert!(
                (e0 - ea).abs() <= 1e-12 * ea.abs(),
                "trial {trial}: {e0} vs {ea}"
            );
        }
    }
}

/// Mid-edge shell with a boundary edge's normal set in space (a clamp's fixed normal, a
/// symmetry plane's): gradient and Hessian against central differences in all 21 DOFs, both
/// variants; the set edge's rotation DOF does not enter; and `u` with the average's normal is
/// the average's `q` (the convention that makes `u` the edge's `h sin ψ`).
#[test]
fn set_edge_normals_match_finite_differences() {
    use shellsim::energy::midedge_angle::{midedge_angle_face_with, AngleVariant};
    use shellsim::geometry::{set_edge_u, AverageQs, EdgeNormal, UnitNormal};
    let mut rng = Rng::new(47);
    for trial in 0..40 {
        let variant = if trial % 2 == 0 {
            AngleVariant::Sin
        } else {
            AngleVariant::Tan
        };
        let x = random_patch(&mut rng, 0.25);
        let d = random_density(&mut rng, trial % 3 == 1);
        // Edge 0 (v1 → v2) on the boundary with its normal set; edge 1 interior or boundary.
        let has = [false, trial % 4 < 2, true];
        let xf = [x[0], x[1], x[2]];
        let nf = (xf[1] - xf[0]).cross(&(xf[2] - xf[0])).normalize();
        let e = (xf[2] - xf[1]).normalize();
        let m = e.cross(&nf);
        let set0 = if trial % 3 == 0 {
            // A clamp: a fixed unit normal across the edge, 0.3 rad off the face's.
            EdgeNormal::Fixed((nf * 0.3f64.cos() + m * 0.3f64.sin()).normalize())
        } else {
            // A symmetry plane through the edge, tilted 0.2 rad from the face's perpendicular.
            let n = (m * 0.2f64.cos() + nf * 0.2f64.sin()).normalize();
            EdgeNormal::Plane {
                normal: n,
                sign: if n.cross(&(xf[2] - xf[1])).dot(&nf) >= 0.0 {
                    1.0
                } else {
                    -1.0
                },
            }
        };
        let set = [Some(set0), None, None];
        let phi = [0.0; 3].map(|_: Real| 0.3 * rng.symmetric());
        let sigma = [1.0, -1.0, 1.0];
        let eval = |v: &SVec<21>, g: Option<&mut SVec<21>>, h: Option<&mut SMat<21, 21>>| {
            let x = unflat(&v.fixed_rows::<18>(0).into_owned());
            let p = [v[18], v[19], v[20]];
            midedge_angle_face_with::<_, false>(&x, has, &p, sigma, set, variant, &d, g, h)
        };
        let mut v0 = SVec::<21>::zeros();
        v0.fixed_rows_mut::<18>(0).copy_from(&flat(&x));
        for i in 0..3 {
            v0[18 + i] = phi[i];
        }
        let mut g = SVec::<21>::zeros();
        let mut h = SMat::<21, 21>::zeros();
        let e0 = eval(&v0, Some(&mut g), Some(&mut h));
        assert!(e0.is_finite() && g.amax() > 0.0);
        assert_eq!(
            g[18], 0.0,
            "trial {trial}: the set edge's own DOF does not enter"
        );
        let (gfd, hfd) = central_differences_21(&eval, &v0, 1e-6);
        let ge = (g - gfd).amax() / g.amax();
        let he = (h - hfd).amax() / h.amax();
        assert!(
            ge < 1e-6,
            "trial {trial} {variant:?} {set0:?}: gradient {ge:e}"
        );
        assert!(
            he < 1e-6,
            "trial {trial} {variant:?} {set0:?}: Hessian {he:e}"
        );
        assert!((h - h.transpose()).amax() < 1e-12 * h.amax());
    }
    // The convention: with the mid-edge average's normal (N_f + N_g)/|N_f + N_g| set on an
    // interior edge, u is the average's q.
    for _ in 0..20 {
        let x = random_patch(&mut rng, 0.25);
        let xf = [x[0], x[1], x[2]];
        let nf = UnitNormal::new(&xf);
        let qs = AverageQs::new(&nf, &x, [true; 3], false);
        for i in 0..3 {
            let (j, k) = ((i + 1) % 3, (i + 2) % 3);
            let ng = (x[k] - x[3 + i]).cross(&(x[j] - x[3 + i])).normalize();
            let t = (nf.n + ng).normalize();
            let (u, _) = set_edge_u(&EdgeNormal::Fixed(t), &xf, i);
            assert!(
                (u - qs.q[i]).abs() < 1e-14,
                "edge {i}: u {u} against q {}",
                qs.q[i]
            );
        }
    }
}
