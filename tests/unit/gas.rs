//! The enclosed gas and the prism membrane: LDLᵀ inertia against dense eigenvalues, the gas
//! term's gradient and whole Hessian (sparse + rank-one) against finite differences for every
//! control, the volume's invariance under rigid motions, the Sherman–Morrison solve against a
//! dense solve with a positive definite and an indefinite sparse part, Newton's quadratic
//! convergence with the rank-one part (and its loss without it), and the prism element against
//! its 3D deformation gradient rebuilt from the vertices (seed 002 Eq. 4).

use nalgebra::{DMatrix, DVector};
use shellsim::assembly::{ElementMap, Pattern, Want};
use shellsim::body::Body;
use shellsim::energy::membrane::neo_hookean::NeoHookeanFace;
use shellsim::energy::membrane::prism::PrismFace;
use shellsim::energy::membrane::MembraneLaw;
use shellsim::energy::term::{Stencil, Term, Terms};
use shellsim::energy::HessianProjection;
use shellsim::energy::Potential;
use shellsim::geometry::first_fundamental_form;
use shellsim::math::{Mat3, Real, SVec, Sym2, Vec3};
use shellsim::mesh::generate::{icosphere, Rng};
use shellsim::model::Scene;
use shellsim::settings::{PrismLaw, Settings};
use shellsim::solve::low_rank::Woodbury;
use shellsim::solve::{newton, LinearSolver, NewtonOptions, State};

/// A balloon scene: an icosphere of radius 1 with `n` subdivisions, membrane only (static: 6
/// position DOFs pinned against rigid motions).
fn balloon(n: usize, extra: &str) -> Scene {
    let s = Settings::from_str_with(
        &format!(
            "[material]\nbending = \"none\"\nmodel = \"neo_hookean\"\npoisson = 0.5\n\
             young = 3e6\nthickness = 0.01\n{extra}"
        ),
        "test",
        &[],
    )
    .unwrap();
    Scene::build(icosphere(1.0, n), s).unwrap()
}

/// Positions scaled by `lambda` about the origin plus a random offset of `noise`.
fn inflated(sc: &Scene, lambda: Real, noise: Real, seed: u64) -> Vec<Vec3> {
    let mut rng = Rng::new(seed);
    sc.body
        .mesh
        .positions
        .iter()
        .map(|p| p * lambda + Vec3::new(rng.symmetric(), rng.symmetric(), rng.symmetric()) * noise)
        .collect()
}

/// The dense matrix of a lower-triangle pattern's values.
fn dense(p: &Pattern, values: &[Real]) -> DMatrix<Real> {
    let mut m = DMatrix::zeros(p.n, p.n);
    for c in 0..p.n {
        for k in p.col_ptr[c]..p.col_ptr[c + 1] {
            let r = p.row_idx[k];
            m[(r, c)] = values[k];
            m[(c, r)] = values[k];
        }
    }
    m
}

/// [`balloon`] in dynamic mode: nothing pinned (the potentials here carry no inertia).
fn free_balloon(n: usize, extra: &str) -> Scene {
    balloon(n, &format!("{extra}\n[solver]\nmode = \"dynamic\"\n"))
}

fn gas_index(sc: &Scene) -> usize {
    sc.terms.iter().position(|t| t.name() == "gas").unwrap()
}

/// A lower-triangle CSC pattern and values of the 3D grid Laplacian on `k³` nodes with
/// diagonal `6 + shift_i`, some shifts negative: a sparse symmetric indefinite matrix.
fn grid(k: usize, shifts: &[(usize, Real)]) -> (usize, Vec<usize>, Vec<usize>, Vec<Real>) {
    let n = k * k * k;
    let (mut cp, mut ri, mut v) = (vec![0], Vec::new(), Vec::new());
    for j in 0..n {
        let (x, y, z) = (j % k, (j / k) % k, j / (k * k));
        ri.push(j);
        v.push(
            6.0 + shifts
                .iter()
                .filter(|s| s.0 == j)
                .map(|s| s.1)
                .sum::<Real>(),
        );
        for (ok, step) in [(x + 1 < k, 1), (y + 1 < k, k), (z + 1 < k, k * k)] {
            if ok {
                ri.push(j + step);
                v.push(-1.0);
            }
        }
        cp.push(ri.len());
    }
    (n, cp, ri, v)
}

/// LDLᵀ's count of negative pivots is the number of negative eigenvalues (Sylvester), for a
/// small matrix (simplicial factor) and a large one (supernodal), and its solves match dense
/// ones.
#[test]
fn ldlt_inertia_matches_dense_eigenvalues() {
    for (k, shifts) in [
        (4usize, vec![(3usize, -8.0), (20, -7.5)]),
        (12, vec![(100, -9.0), (800, -8.5), (1500, -11.0)]),
    ] {
        let (n, cp, ri, v) = grid(k, &shifts);
        let mut lin = LinearSolver::from_csc(n, cp.clone(), ri.clone()).unwrap();
        let negative = lin.factor_indefinite(&v).unwrap();
        let mut a = DMatrix::zeros(n, n);
        for c in 0..n {
            for p in cp[c]..cp[c + 1] {
                a[(ri[p], c)] = v[p];
                a[(c, ri[p])] = v[p];
            }
        }
        let eig = a.clone().symmetric_eigen();
        let dense_negative = eig.eigenvalues.iter().filter(|&&l| l < 0.0).count();
        println!(
            "n {n}: supernodal {}, negative pivots {negative}, eigenvalues {dense_negative}",
            lin.is_supernodal()
        );
        assert!(dense_negative >= 1);
        assert_eq!(negative, dense_negative);
        assert_eq!(
            lin.is_supernodal(),
            k == 12,
            "both factor layouts are covered"
        );
        let b: Vec<Real> = (0..n).map(|i| (i as Real * 0.37).sin()).collect();
        let mut x = b.clone();
        lin.solve_in_place(&mut x);
        let r = &a * DVector::from_vec(x) - DVector::from_vec(b);
        assert!(r.amax() < 1e-10, "LDLᵀ solve residual {}", r.amax());
        // A positive definite matrix has no negative pivot.
        let (n, cp, ri, v) = grid(k, &[]);
        let mut lin = LinearSolver::from_csc(n, cp, ri).unwrap();
        assert_eq!(lin.factor_indefinite(&v).unwrap(), 0);
    }
}

/// The gas term's gradient against central differences of its energy, and its whole Hessian,
/// sparse part plus the rank-one part `G'' ∇V∇Vᵀ`, against central differences of the
/// gradient, at 1e-6 of the largest entry, for every control; the rank-one part alone would
/// miss the follower part `G' ∇²V` (seed 002's Eq. 16), which is what the sparse part is.
#[test]
fn gas_term_matches_finite_differences_for_every_control() {
    for gas in [
        "control = \"amount\"\namount = 2e4\nexternal_pressure = 1e3",
        "control = \"amount\"\namount = 2e4\nexternal_pressure = 1e3\nprocess = \"adiabatic\"",
        "control = \"pressure\"\npressure = 5e3",
        "control = \"volume\"\nvolume = 6.0",
    ] {
        let sc = free_balloon(1, &format!("[gas]\n{gas}\n"));
        let p = Pattern::for_scene(&sc);
        let i = gas_index(&sc);
        let term = &sc.terms[i];
        let map: &ElementMap = &p.maps[i];
        let x = inflated(&sc, 1.15, 0.03, 4);
        // Volume control: a non-zero multiplier (one plain update); the other controls have
        // no multiplier.
        let mut states = sc.initial_states.clone();
        let at_start = Potential {
            dial: 0.7,
            ..Potential::new(&sc, &p)
        };
        assert_eq!(
            term.updates().is_some(),
            gas.contains("\"volume\""),
            "{gas}"
        );
        if let Some(m) = term.updates() {
            m.update(&at_start, &x, &[], states.get_mut("gas"), &mut |_| None);
        }
        let pot = Potential {
            dial: 0.7,
            states: &states,
            ..Potential::new(&sc, &p)
        };
        let eval = |x: &[Vec3], g: &mut Vec<Real>, h: &mut Vec<Real>, want: Want| {
            g.iter_mut().for_each(|v| *v = 0.0);
            h.iter_mut().for_each(|v| *v = 0.0);
            term.eval(&pot, map, x, &[], want, HessianProjection::None, g, h)
        };
        let (mut g, mut h) = (vec![0.0; p.n], vec![0.0; p.nnz()]);
        eval(&x, &mut g, &mut h, Want::Hessian);
        let mut full = dense(&p, &h);
        let mut lr = Vec::new();
        term.low_rank().unwrap().low_rank(&pot, &x, &[], &mut lr);
        for part in &lr {
            let u = DVector::from_column_slice(&part.u);
            full += &u * u.transpose() * part.c;
        }
        let gmax = g.iter().fold(0.0 as Real, |m, v| m.max(v.abs()));
        let hmax = full.amax();
        let eps = 1e-6;
        let (mut gp, mut gm, mut s) = (vec![0.0; p.n], vec![0.0; p.n], vec![0.0; p.nnz()]);
        let mut sparse_only = 0.0 as Real;
        for k in 0..p.n {
            let (mut xp, mut xm) = (x.clone(), x.clone());
            xp[k / 3][k % 3] += eps;
            xm[k / 3][k % 3] -= eps;
            let ep = eval(&xp, &mut gp, &mut s, Want::Gradient);
            let em = eval(&xm, &mut gm, &mut s, Want::Gradient);
            let fd = (ep - em) / (2.0 * eps);
            assert!(
                (fd - g[k]).abs() < 1e-6 * gmax,
                "{gas}: grad {k}: {} vs {fd}",
                g[k]
            );
            for r in 0..p.n {
                let fd = (gp[r] - gm[r]) / (2.0 * eps);
                assert!(
                    (fd - full[(r, k)]).abs() < 1e-6 * hmax,
                    "{gas}: H({r},{k}): {} vs {fd}",
                    full[(r, k)]
                );
                sparse_only = sparse_only.max((fd - dense(&p, &h)[(r, k)]).abs());
            }
            if k > 6 {
                break;
            }
        }
        let has_rank_one = !gas.contains("control = \"pressure\"");
        assert_eq!(!lr.is_empty(), has_rank_one, "{gas}");
        if has_rank_one {
            assert!(
                sparse_only > 1e-3 * hmax,
                "{gas}: the rank-one part must matter"
            );
        }
    }
}

/// The enclosed volume is invariant under rigid motions to 1e-12 (relative), and so is the gas
/// energy; its gradient rotates with the motion.
#[test]
fn volume_is_invariant_under_rigid_motions() {
    let sc = free_balloon(2, "[gas]\ncontrol = \"amount\"\namount = 1e4\n");
    let x = inflated(&sc, 1.3, 0.05, 9);
    let rot = nalgebra::Rotation3::from_euler_angles(0.3, -1.1, 2.0);
    let t = Vec3::new(3.0, -7.0, 11.0);
    let y: Vec<Vec3> = x.iter().map(|p| rot * p + t).collect();
    let v = shellsim::mesh::closed::enclosed_volume(&x, &sc.body.mesh.faces);
    let w = shellsim::mesh::closed::enclosed_volume(&y, &sc.body.mesh.faces);
    assert!(((v - w) / v).abs() < 1e-12, "{v} vs {w}");
    let p = Pattern::for_scene(&sc);
    let pot = Potential::new(&sc, &p);
    let (mut gx, mut gy) = (vec![0.0; p.n], vec![0.0; p.n]);
    let ex = pot.eval(&x, &[], Want::Gradient, &mut gx, &mut []);
    let ey = pot.eval(&y, &[], Want::Gradient, &mut gy, &mut []);
    assert!(((ex - ey) / ex).abs() < 1e-12, "{ex} vs {ey}");
    let gmax = gx.iter().fold(0.0 as Real, |m, v| m.max(v.abs()));
    for v in 0..sc.body.num_vertices() {
        let a = rot * Vec3::new(gx[3 * v], gx[3 * v + 1], gx[3 * v + 2]);
        let b = Vec3::new(gy[3 * v], gy[3 * v + 1], gy[3 * v + 2]);
        assert!((a - b).amax() < 1e-10 * gmax);
    }
}

/// The Sherman–Morrison solve on the sparse factor equals a dense solve of the whole Hessian
/// to 1e-10, before the limit point (Cholesky of a positive definite sparse part) and past it
/// (LDLᵀ of a sparse part with a negative eigenvalue, made positive definite by the rank-one
/// part, as the inertia says).
#[test]
fn sherman_morrison_equals_a_dense_solve() {
    // λ = 1.15 is before the neo-Hookean limit point (7^(1/6) = 1.383), λ = 2 past it.
    for (lambda, indefinite) in [(1.15 as Real, false), (2.0, true)] {
        // The gas at the membrane's pressure for this stretch, 2μH/R (1/λ − 1/λ⁷): near an
        // equilibrium.
        let v0 = shellsim::mesh::closed::enclosed_volume(
            &icosphere(1.0, 2).positions,
            &icosphere(1.0, 2).faces,
        );
        let p_el = 2e4 * (1.0 / lambda - 1.0 / lambda.powi(7));
        let amount = p_el * v0 * lambda.powi(3);
        let sc = balloon(
            2,
            &format!("[gas]\ncontrol = \"amount\"\namount = {amount}\n"),
        );
        let p = Pattern::for_scene(&sc);
        let x = inflated(&sc, lambda, 0.0, 1);
        let pot = Potential::new(&sc, &p);
        let (mut g, mut h) = (vec![0.0; p.n], vec![0.0; p.nnz()]);
        pot.eval(&x, &[], Want::Hessian, &mut g, &mut h);
        let lr = pot.low_rank(&x, &[]);
        assert_eq!(lr.len(), 1);
        let mut lin = LinearSolver::new(&p).unwrap();
        let negative = match lin.factor(&h) {
            Ok(()) => 0,
            Err(_) => lin.factor_indefinite(&h).unwrap(),
        };
        assert_eq!(
            negative > 0,
            indefinite,
            "λ = {lambda}: {negative} negative pivots"
        );
        let wb = Woodbury::new(&mut lin, &lr);
        let mut full = dense(&p, &h);
        let u = DVector::from_column_slice(&lr[0].u);
        full += &u * u.transpose() * lr[0].c;
        let eig = full.clone().symmetric_eigen();
        let dense_negative = eig.eigenvalues.iter().filter(|&&l| l < 0.0).count();
        assert_eq!(wb.negative_eigenvalues(negative), Some(dense_negative));
        let mut y = g.clone();
        assert!(wb.solve_in_place(&mut lin, &mut y));
        let yd = full.lu().solve(&DVector::from_column_slice(&g)).unwrap();
        let err = (DVector::from_vec(y) - &yd).amax() / yd.amax();
        println!("λ {lambda}: {negative} negative pivots, whole {dense_negative}, error {err:e}");
        assert!(err < 1e-10, "λ {lambda}: {err}");
    }
}

/// A term that hides another's low-rank part (Newton without the gas's rank-one stiffness).
struct WithoutLowRank(Terms, usize);

impl Term for WithoutLowRank {
    fn name(&self) -> &'static str {
        self.0[self.1].name()
    }
    fn stencil(&self, body: &Body) -> Stencil {
        self.0[self.1].stencil(body)
    }
    fn eval(
        &self,
        pot: &Potential,
        map: &ElementMap,
        x: &[Vec3],
        phi: &[Real],
        want: Want,
        projection: HessianProjection,
        grad: &mut [Real],
        values: &mut [Real],
    ) -> Real {
        self.0[self.1].eval(pot, map, x, phi, want, projection, grad, values)
    }
}

/// Residuals of Newton from `x0` after 0, 1, 2, … iterations (each run afresh, capped).
fn residuals(sc: &Scene, x0: &[Vec3], projection: HessianProjection, n: usize) -> Vec<Real> {
    let p = Pattern::for_scene(sc);
    let pot = Potential::new(sc, &p);
    let mut lin = LinearSolver::new(&p).unwrap();
    let mut ws = shellsim::solve::newton::Workspace::new(&p);
    (0..=n)
        .map(|k| {
            let mut st = State {
                x: x0.to_vec(),
                dofs: Vec::new(),
                terms: sc.initial_states.clone(),
            };
            let opts = NewtonOptions {
                tol: 1e-300,
                max_iter: k,
                projection,
                chord: false,
            };
            newton(&pot, &mut lin, &mut ws, &mut st, opts).residual
        })
        .collect()
}

/// The gas-controlled balloon's equilibrium (solved from a 20% inflation), scaled by 1.01 and
/// perturbed by 1e-3 per coordinate: a start near it.
fn near_equilibrium(sc: &Scene) -> Vec<Vec3> {
    let p = Pattern::for_scene(sc);
    let pot = Potential::new(sc, &p);
    let mut lin = LinearSolver::new(&p).unwrap();
    let mut ws = shellsim::solve::newton::Workspace::new(&p);
    let mut st = State {
        x: inflated(sc, 1.2, 0.0, 1),
        dofs: Vec::new(),
        terms: sc.initial_states.clone(),
    };
    let rep = newton(&pot, &mut lin, &mut ws, &mut st, NewtonOptions::default());
    assert!(rep.converged, "{rep:?}");
    let mut rng = Rng::new(8);
    st.x.iter()
        .map(|p| p * 1.01 + Vec3::new(rng.symmetric(), rng.symmetric(), rng.symmetric()) * 1e-3)
        .collect()
}

/// Near an equilibrium of the gas-controlled balloon, Newton with the exact Hessian (sparse +
/// rank-one) converges quadratically; without the rank-one part it converges only linearly, and
/// with the seed's tangent (the rank-one part without the follower part, Eq. 16) too.
#[test]
fn newton_is_quadratic_with_the_rank_one_part() {
    let sc = balloon(2, "[gas]\ncontrol = \"amount\"\namount = 6e4\n");
    let x0 = near_equilibrium(&sc);
    let exact = residuals(&sc, &x0, HessianProjection::None, 5);
    let seed = residuals(&sc, &x0, HessianProjection::GaussNewton, 5);
    let mut without = sc.clone();
    let gi = gas_index(&sc);
    let fresh = Terms(std::sync::Arc::new(
        shellsim::energy::registry::terms(&sc.body, &sc.settings).unwrap(),
    ));
    let mut list: Vec<Box<dyn Term>> =
        shellsim::energy::registry::terms(&sc.body, &sc.settings).unwrap();
    list[gi] = Box::new(WithoutLowRank(fresh, gi));
    without.terms = Terms(std::sync::Arc::new(list));
    let no_rank_one = residuals(&without, &x0, HessianProjection::None, 5);
    let show = |r: &[Real]| {
        r.iter()
            .map(|v| format!("{v:.1e}"))
            .collect::<Vec<_>>()
            .join(" ")
    };
    println!("exact (sparse + rank-one): {}", show(&exact));
    println!("seed's tangent (rank-one only): {}", show(&seed));
    println!("without the rank-one part: {}", show(&no_rank_one));
    // Quadratic: round-off after 4 iterations, and a step above round-off that squares the
    // residual (r_{k+1} ≤ 10 r_k², which the linear alternatives below never do; which step
    // depends on the start, the first steps being pre-asymptotic).
    let r = &exact;
    assert!(r[4] < 1e-14, "exact Newton: {r:?}");
    assert!(
        (0..4).any(|k| r[k] < 1e-2 && r[k + 1] > 1e-14 && r[k + 1] < 10.0 * r[k] * r[k]),
        "not quadratic: {r:?}"
    );
    // The others: linear (ratios 0.5–0.9), far from converged after 5 iterations.
    assert!(no_rank_one[5] > 1e-4, "{no_rank_one:?}");
    assert!(seed[5] > 1e-6, "{seed:?}");
    for q in [&no_rank_one, &seed] {
        assert!(q[5] / q[4] > 0.2, "linear convergence expected: {q:?}");
    }
}

/// A 3D deformation gradient's St Venant–Kirchhoff and compressible neo-Hookean densities
/// (Pa), straight from seed 002's Eqs. 6–7 and the standard neo-Hookean law.
fn psi_3d(f: &Mat3, law: PrismLaw, mu: Real, lambda: Real) -> Real {
    let c = f.transpose() * f;
    match law {
        PrismLaw::Stvk => {
            let e = (c - Mat3::identity()) * 0.5;
            mu * e.component_mul(&e).sum() + 0.5 * lambda * e.trace() * e.trace()
        }
        PrismLaw::NeoHookean => {
            let j = f.determinant();
            0.5 * mu * (c.trace() - 3.0) - mu * j.ln() + 0.5 * lambda * j.ln() * j.ln()
        }
    }
}

/// The prism law through `a` equals `V̄ ψ(F)` with `F = [e₁₂ e₁₃ d h][ē₁₂ ē₁₃ d̄ h̄]⁻¹` built
/// from random rest and current triangles in 3D (Eq. 4), for both densities and both thickness
/// modes, to 1e-12; its derivatives match central differences; the incompressible neo-Hookean
/// prism is the incompressible neo-Hookean membrane.
#[test]
fn prism_law_is_seed_002s_element() {
    let mut rng = Rng::new(17);
    let mut tri =
        || [0; 3].map(|_| Vec3::new(rng.symmetric(), rng.symmetric(), rng.symmetric()) * 0.5);
    let (young, nu) = (2e6, 0.45);
    let mu = young / (2.0 * (1.0 + nu));
    let lambda = young * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
    for trial in 0..20 {
        let (rest, cur) = (tri(), tri());
        let hbar = 0.01;
        let frame = |t: &[Vec3; 3], h: Real| {
            let (e1, e2) = (t[1] - t[0], t[2] - t[0]);
            let d = e1.cross(&e2).normalize();
            Mat3::from_columns(&[e1, e2, d * h])
        };
        let abar = first_fundamental_form(&rest);
        let a = first_fundamental_form(&cur);
        let det = |s: &Sym2| s[0] * s[2] - s[1] * s[1];
        let area_bar = 0.5 * det(&abar).sqrt();
        for law in [PrismLaw::Stvk, PrismLaw::NeoHookean] {
            // Position-based mode: a given thickness.
            let h = hbar * (0.7 + 0.02 * trial as Real);
            let f = frame(&cur, h) * frame(&rest, hbar).try_inverse().unwrap();
            let want = hbar * area_bar * psi_3d(&f, law, mu, lambda);
            let face = PrismFace::new(law, &abar, hbar, young, nu, Some((h / hbar).powi(2)), 1.0);
            let got = face.eval(&a, None);
            assert!(
                (got - want).abs() < 1e-12 * want.abs().max(1e-30),
                "{law:?}: {got} vs {want}"
            );
            // Incompressible: h = h̄ Ā/A.
            let h = hbar * (det(&abar) / det(&a)).sqrt();
            let f = frame(&cur, h) * frame(&rest, hbar).try_inverse().unwrap();
            assert!((f.determinant() - 1.0).abs() < 1e-10);
            let want = hbar * area_bar * psi_3d(&f, law, mu, lambda);
            let face = PrismFace::new(law, &abar, hbar, young, nu, None, 1.0);
            let got = face.eval(&a, None);
            assert!(
                (got - want).abs() < 1e-12 * want.abs().max(1e-30),
                "{law:?}: {got} vs {want}"
            );
            if law == PrismLaw::NeoHookean {
                let nh = NeoHookeanFace::new(&abar, hbar, mu, 1.0);
                let (mut g1, mut h1, mut g2, mut h2) =
                    (Sym2::zeros(), Mat3::zeros(), Sym2::zeros(), Mat3::zeros());
                let e1 = face.eval(&a, Some((&mut g1, &mut h1)));
                let e2 = nh.eval(&a, Some((&mut g2, &mut h2)));
                assert!((e1 - e2).abs() < 1e-12 * e2.abs());
                assert!((g1 - g2).amax() < 1e-12 * g2.amax());
                assert!((h1 - h2).amax() < 1e-12 * h2.amax());
            }
            // Derivatives in a, both modes.
            for c in [None, Some(0.8)] {
                let face = PrismFace::new(law, &abar, hbar, young, nu, c, 1.0);
                let (mut g, mut hh) = (Sym2::zeros(), Mat3::zeros());
                face.eval(&a, Some((&mut g, &mut hh)));
                let eps = 1e-7 * a.amax();
                for k in 0..3 {
                    let (mut ap, mut am) = (a, a);
                    ap[k] += eps;
                    am[k] -= eps;
                    let fd = (face.eval(&ap, None) - face.eval(&am, None)) / (2.0 * eps);
                    assert!((fd - g[k]).abs() < 1e-6 * g.amax(), "{law:?} {c:?}: g{k}");
                    let (mut gp, mut gm, mut s) = (Sym2::zeros(), Sym2::zeros(), Mat3::zeros());
                    face.eval(&ap, Some((&mut gp, &mut s)));
                    face.eval(&am, Some((&mut gm, &mut s)));
                    let col: SVec<3> = (gp - gm) / (2.0 * eps);
                    assert!(
                        (col - hh.column(k)).amax() < 1e-6 * hh.amax(),
                        "{law:?} {c:?}: H col {k}"
                    );
                }
            }
        }
    }
}

/// Seed 002's position-based projection restores the skin's volume: one pass to second order in
/// the violation; repeated passes converge linearly (the mass-weighted correction of a single
/// constraint is not exactly the linearised one: ten passes from a 20% violation leave ~1e-8).
/// It reads the thickness back from the virtual vertices and leaves fixed vertices where they
/// are.
#[test]
fn position_based_projection_restores_the_skin_volume() {
    for iterations in [1usize, 10] {
        let sc = {
            let s = Settings::from_str_with(
                &format!(
                    "[material]\nbending = \"none\"\nmodel = \"prism\"\npoisson = 0.45\n\
                     thickness = 0.01\nprism = {{ thickness = \"pbd\", pbd_iterations = \
                     {iterations} }}\n[solver]\nmode = \"dynamic\"\n[constraints]\nfix_boxes = \
                     [{{ min = [-2, -2, 0.95], max = [2, 2, 2] }}]\n"
                ),
                "test",
                &[],
            )
            .unwrap();
            Scene::build(icosphere(1.0, 2), s).unwrap()
        };
        let p = Pattern::for_scene(&sc);
        let pot = Potential::new(&sc, &p);
        let mut x = inflated(&sc, 1.0, 0.0, 1);
        for (v, q) in x.iter_mut().enumerate() {
            if !sc.body.fixed[v] {
                *q *= 1.1;
            }
        }
        let before = x.clone();
        let shell = &sc.terms[0];
        let ratio = |pot: &Potential, x: &[Vec3]| {
            shellsim::energy::term::observables(shell.as_ref(), pot, x, &[])
                .into_iter()
                .find(|o| o.0 == "skin_volume_ratio")
                .unwrap()
                .1
        };
        let r0 = ratio(&pot, &x);
        let projection = shell.projection().expect("the prism projects");
        let tracked = shell.tracked().expect("the prism tracks its thickness");
        let mut own = sc.initial_states.get("shell").to_vec();
        let c = projection
            .project(&pot, &mut x, &[], &mut own)
            .unwrap()
            .unwrap();
        let mut states = sc.initial_states.clone();
        states.set("shell", own.clone());
        let pot = Potential {
            states: &states,
            ..pot
        };
        let r1 = ratio(&pot, &x);
        println!("{iterations} projections: ratio {r0} → {r1} (C/V₀ = {c:e})");
        assert!((c - (r0 - 1.0)).abs() < 1e-12);
        if iterations == 1 {
            // Second order: the linearised constraint leaves about C².
            assert!((r1 - 1.0).abs() < 1.5 * (r0 - 1.0).powi(2), "{r1}");
        } else {
            assert!((r1 - 1.0).abs() < 1e-6, "{r1}");
        }
        for v in 0..sc.body.num_vertices() {
            if sc.body.fixed[v] {
                assert_eq!(x[v], before[v]);
            }
        }
        // A collapsed face has no normal: the projection refuses (its thickness would not be a
        // number), naming a face, and leaves the thickness state as it was.
        if iterations == 1 {
            let mut y = x.clone();
            let f0 = sc.body.mesh.faces[0];
            y[f0[1]] = y[f0[0]];
            let state = tracked.field(&x, &[], &own);
            let err = projection.project(&pot, &mut y, &[], &mut own).unwrap_err();
            assert!(err.to_string().contains("thickness not finite"), "{err}");
            assert_eq!(
                tracked.field(&x, &[], &own),
                state,
                "the state is left as it was"
            );
        }
        // The frame's thickness field is the projected thickness: thinner than at rest.
        let fields = shell.reports().unwrap().face_fields(&pot, &x, &[]);
        let h = &fields.iter().find(|f| f.0 == "thickness").unwrap().1;
        assert!(h.iter().all(|&h| h > 0.0 && h < 0.01));
    }
}

/// The gas's multiplier lives in the run's state, not in the scene: one scene run twice, and
/// its clone, take the same steps and end on the same positions bitwise, and the scene's
/// initial multiplier stays 0. (With the multiplier kept in the term, the second run started
/// from the first one's final pressure and took other iterations.)
#[test]
fn a_volume_controlled_run_leaves_the_scene_as_it_was() {
    let sc = balloon(
        2,
        "[gas]\ncontrol = \"volume\"\nvolume = 6.0\n[solver]\nmode = \"static\"\n",
    );
    let dir = tempfile::tempdir().unwrap();
    let mut runs = Vec::new();
    let copy = sc.clone();
    for (k, run_on) in [&sc, &copy, &sc].into_iter().enumerate() {
        let out = dir.path().join(format!("run{k}"));
        let mut writer = shellsim::output::Writer::new(&out, run_on, false).unwrap();
        let summary = shellsim::integrate::run(
            run_on,
            &mut writer,
            &mut shellsim::integrate::Quiet,
            1,
            None,
        )
        .unwrap();
        assert!(summary.converged, "{}", summary.reason);
        let last = out.join(&summary.final_frame);
        let frame = shellsim::mesh::io::read_mesh(&last).unwrap();
        runs.push((summary.newton_iterations, summary.steps, frame.positions));
    }
    assert_eq!(sc.initial_states.get("gas"), &[0.0][..]);
    assert_eq!(runs[0], runs[1], "the clone's run differs");
    assert_eq!(runs[0], runs[2], "the scene's second run differs");
    let volume = shellsim::energy::gas::Gas::volume(&sc.body, &runs[0].2);
    assert!((volume / 6.0 - 1.0).abs() < 1e-8, "volume {volume}");
}

/// On a free balloon, held by the automatic pins (one vertex along the axes, two along
/// directions off them: skew vertices), the Hessian the solver factorises (sparse part with
/// the skew projection, plus the gas's rank-one parts) applied to random directions equals the
/// central difference of the projected gradient, to 1e-6 of its size: the held directions and
/// the projection are consistent, so Newton on the held system is exact.
#[test]
fn projected_hessian_matches_the_projected_gradient() {
    let sc = balloon(2, "[gas]\ncontrol = \"amount\"\namount = 6e4\n");
    assert!(
        !sc.body.skew.is_empty(),
        "no skew vertex: {:?}",
        sc.body.supports
    );
    let p = Pattern::for_scene(&sc);
    let pot = Potential::new(&sc, &p);
    let x = inflated(&sc, 1.2, 0.02, 3);
    let n = p.n;
    let mut g = vec![0.0; n];
    let mut values = vec![0.0; p.nnz()];
    pot.eval(&x, &[], Want::Hessian, &mut g, &mut values);
    let h = dense(&p, &values);
    let lr = pot.low_rank(&x, &[]);
    let mut rng = Rng::new(11);
    let mut worst: Real = 0.0;
    for _ in 0..3 {
        let mut v: Vec<Real> = (0..n).map(|_| rng.symmetric()).collect();
        pot.mask_fixed(&mut v);
        let mut hv = &h * DVector::from_column_slice(&v);
        for part in &lr {
            let uv: Real = part.u.iter().zip(&v).map(|(a, b)| a * b).sum();
            for (k, u) in part.u.iter().enumerate() {
                hv[k] += part.c * uv * u;
            }
        }
        // The held directions: the factorised matrix has the pivot there, the gradient none.
        let eps = 1e-6;
        let at = |s: Real| {
            let y: Vec<Vec3> = (0..x.len())
                .map(|i| x[i] + Vec3::new(v[3 * i], v[3 * i + 1], v[3 * i + 2]) * s)
                .collect();
            let mut gy = vec![0.0; n];
            pot.eval(&y, &[], Want::Gradient, &mut gy, &mut []);
            gy
        };
        let (gp, gm) = (at(eps), at(-eps));
        let size = hv.iter().fold(0.0, |m: Real, a| m.max(a.abs()));
        for k in 0..n {
            worst = worst.max(((gp[k] - gm[k]) / (2.0 * eps) - hv[k]).abs() / size);
        }
    }
    println!("projected Hessian against the projected gradient: {worst:.2e}");
    assert!(worst < 1e-6, "{worst:e}");
}

/// A rejected exact model is remembered: the next solve from the same state starts with the
/// Gauss–Newton model without the failed factorisations, and takes the same step.
#[test]
fn a_rejected_exact_model_is_not_retried_by_the_next_solve() {
    let sc = balloon(2, "[gas]\ncontrol = \"amount\"\namount = 6e4\n");
    let p = Pattern::for_scene(&sc);
    let pot = Potential::new(&sc, &p);
    // Crushed to 70%: the compressed membrane's exact Hessian is indefinite.
    let x0 = inflated(&sc, 0.7, 1e-3, 3);
    let opts = NewtonOptions {
        tol: 1e-300,
        max_iter: 1,
        projection: HessianProjection::Adaptive,
        chord: false,
    };
    let one_iteration = |ws: &mut shellsim::solve::newton::Workspace| {
        let mut lin = LinearSolver::new(&p).unwrap();
        let mut st = State {
            x: x0.clone(),
            dofs: Vec::new(),
            terms: sc.initial_states.clone(),
        };
        let rep = newton(&pot, &mut lin, ws, &mut st, opts);
        (rep, lin.counts(), st.x)
    };
    let mut ws = shellsim::solve::newton::Workspace::new(&p);
    assert_eq!(ws.model_hints(), [false, false]);
    let (first, c1, x1) = one_iteration(&mut ws);
    assert_eq!(first.gauss_newton_iterations, 1, "{first:?}");
    assert!(
        c1.failed >= 1,
        "the exact model was tried and refused: {c1:?}"
    );
    assert!(ws.model_hints()[1], "{:?}", ws.model_hints());
    let (second, c2, x2) = one_iteration(&mut ws);
    assert_eq!(second.gauss_newton_iterations, 1, "{second:?}");
    assert_eq!(c2.failed, 0, "{c2:?}");
    assert_eq!(c2.factorisations, 1, "{c2:?}");
    // The same Gauss–Newton step either way.
    assert!(x1
        .iter()
        .zip(&x2)
        .all(|(a, b)| (0..3).all(|k| a[k].to_bits() == b[k].to_bits())));
}

/// A Newton solve that converges quadratically ends with an evaluation of the gradient alone:
/// the residual predicted from the last full step's rate is below the tolerance, so the
/// Hessian is not assembled for the check that ends the solve. The check tells the truth (an
/// independent gradient at the result meets the tolerance), and a solve whose prediction
/// misses still converges to the same state as the other (the Hessian is then assembled).
#[test]
fn a_predicted_convergence_is_checked_without_the_hessian() {
    let sc = balloon(2, "[gas]\ncontrol = \"amount\"\namount = 6e4\n");
    let p = Pattern::for_scene(&sc);
    let pot = Potential::new(&sc, &p);
    let mut lin = LinearSolver::new(&p).unwrap();
    let mut ws = shellsim::solve::newton::Workspace::new(&p);
    let state = |x: Vec<Vec3>| State {
        x,
        dofs: Vec::new(),
        terms: sc.initial_states.clone(),
    };
    let opts = NewtonOptions::default();
    let x0 = near_equilibrium(&sc);
    let mut a = state(x0.clone());
    let rep = newton(&pot, &mut lin, &mut ws, &mut a, opts);
    assert!(rep.converged, "{rep:?}");
    assert_eq!(rep.gradient_only_checks, 1, "{rep:?}");
    let mut g = vec![0.0; p.n];
    pot.eval(&a.x, &a.dofs, Want::Gradient, &mut g, &mut []);
    assert!(pot.residual(&g) <= opts.tol, "{}", pot.residual(&g));
    assert_eq!(pot.residual(&g).to_bits(), rep.residual.to_bits());
    // Stopping one iteration short and going on from there: the second solve has no history
    // to predict from, assembles the Hessian for every check, and lands on the same bits.
    let mut b = state(x0);
    let short = newton(
        &pot,
        &mut lin,
        &mut ws,
        &mut b,
        NewtonOptions {
            max_iter: rep.iterations - 1,
            ..opts
        },
    );
    assert!(
        !short.converged && short.gradient_only_checks <= 1,
        "{short:?}"
    );
    let rest = newton(&pot, &mut lin, &mut ws, &mut b, opts);
    assert!(rest.converged && rest.gradient_only_checks == 0, "{rest:?}");
    assert!(a.x.iter().zip(&b.x).all(|(p, q)| p
        .iter()
        .zip(q.iter())
        .all(|(u, v)| u.to_bits() == v.to_bits())));
}
