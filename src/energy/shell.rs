//! The shell face term: a membrane material × a bending model, composed by one chain rule.
//!
//! A face's energy is `E = W(a(x), b(x))`, with `a` the first fundamental form of the face's
//! own vertices (local DOFs 0..9) and `b` the bending model's second fundamental form over the
//! model's stencil ([`super::bending`]). With `Ja = ∂a/∂x` and `G = ∂b/∂x`:
//!
//! `∇E = Jaᵀ W_a + G W_b`,
//! `∇²E = Jaᵀ W_aa Ja + Σ_k (W_a)_k ∇²a_k + G W_bb Gᵀ + Σ_q (W_b)_q ∇²b_q`
//!
//! (stretching and bending are uncoupled: no `W_ab`). The Gauss–Newton Hessian keeps
//! `Jaᵀ W_aa⁺ Ja + Σ_k (W_a⁺)_k ∇²a_k + G W_bb Gᵀ` with the density's positive semi-definite
//! parts ([`FaceDensity::gauss_newton`]).
//!
//! Units: energy J, gradient N (positions) and N·m (edge angles), Hessian N/m. DOF order: that
//! of the bending model (`x[v0], x[v1], x[v2]` first).

use super::bending::average::MidedgeAverage;
use super::bending::BendingModel;
use super::material::{DensityDerivs, FaceDensity};
use super::membrane::Membrane;
use super::term::{ElementKernel, Projection, Reports, StateError, Stateful, Stencil, Tracked};
use crate::body::Body;
use crate::energy::Potential;
use crate::geometry::{
    first_fundamental_form, first_fundamental_form_hessian_pattern, first_fundamental_form_jacobian,
};
use crate::math::{Real, SMat, SVec, Sym2, Vec3};
use crate::mesh::topology::NONE;

/// Fundamental forms of one face under the mid-edge average (for output and the damping term's
/// previous state).
pub fn face_forms(x: &[Vec3; 6], has: [bool; 3]) -> (Sym2, Sym2) {
    let xf = [x[0], x[1], x[2]];
    let opp = [0, 1, 2].map(|i| has[i].then_some(x[3 + i]));
    (
        first_fundamental_form(&xf),
        crate::geometry::midedge_average_b(&xf, &opp),
    )
}

/// The one shell chain rule (module doc): energy (J) of a face under density `dens` with
/// bending model `model` (per-face input `face`), stencil positions `x`, optional gradient and
/// Hessian over the model's `N` DOFs. `GN` selects the Gauss–Newton Hessian.
#[inline(always)]
pub fn shell_element<
    D: FaceDensity,
    B: BendingModel<N, S>,
    const N: usize,
    const S: usize,
    const GN: bool,
>(
    model: &B,
    face: &B::Face,
    x: &[Vec3; 6],
    dens: &D,
    grad: Option<&mut SVec<N>>,
    hess: Option<&mut SMat<N, N>>,
) -> Real {
    let want_h = hess.is_some();
    let want_g = grad.is_some() || want_h;
    let grad = match grad {
        Some(gout) if !want_h => return shell_gradient::<D, B, N, S>(model, face, x, dens, gout),
        other => other,
    };
    // The bending evaluation (with its cache) stays in this frame: passed by reference, never
    // moved into an `Option`.
    if N > 9 && dens.uses_b() {
        let ev = model.eval(face, x, want_g, want_h && !GN);
        shell_element_with::<D, B, N, S, GN>(model, face, x, dens, Some(&ev), grad, hess)
    } else {
        shell_element_with::<D, B, N, S, GN>(model, face, x, dens, None, grad, hess)
    }
}

/// The gradient alone (the explicit dynamics' path): `b` and the bending model's light data,
/// the density's first derivatives, and `∇E = Jaᵀ W_a + Σ_q W_b,q ∇b_q` with `Jaᵀ W_a` in closed
/// form (`e₁ = x₁ − x₀`, `e₂ = x₂ − x₀`: `∂E/∂x₁ = 2W_a,11 e₁ + W_a,12 e₂`,
/// `∂E/∂x₂ = W_a,12 e₁ + 2W_a,22 e₂`, `∂E/∂x₀ = −∂E/∂x₁ − ∂E/∂x₂`). Returns the energy (J).
#[inline(always)]
fn shell_gradient<D: FaceDensity, B: BendingModel<N, S>, const N: usize, const S: usize>(
    model: &B,
    face: &B::Face,
    x: &[Vec3; 6],
    dens: &D,
    gout: &mut SVec<N>,
) -> Real {
    let xf = [x[0], x[1], x[2]];
    let a = first_fundamental_form(&xf);
    let mut d = DensityDerivs::default();
    let (e1, e2) = (x[1] - x[0], x[2] - x[0]);
    *gout = SVec::<N>::zeros();
    let e = if N > 9 && dens.uses_b() {
        let (b, light) = model.light(face, x);
        let e = dens.eval_gradient(&a, &b, &mut d);
        model.add_gradient_light(face, &light, &d.gb, gout);
        e
    } else {
        dens.eval_gradient(&a, &Sym2::zeros(), &mut d)
    };
    let g1 = e1 * (2.0 * d.ga[0]) + e2 * d.ga[1];
    let g2 = e1 * d.ga[1] + e2 * (2.0 * d.ga[2]);
    let g0 = -(g1 + g2);
    for (k, v) in [g0, g1, g2].iter().enumerate() {
        for c in 0..3 {
            gout[3 * k + c] += v[c];
        }
    }
    e
}

/// [`shell_element`] after the bending model's evaluation `ev` (`None` without bending).
#[inline(always)]
fn shell_element_with<
    D: FaceDensity,
    B: BendingModel<N, S>,
    const N: usize,
    const S: usize,
    const GN: bool,
>(
    model: &B,
    face: &B::Face,
    x: &[Vec3; 6],
    dens: &D,
    ev: Option<&super::bending::BendingEval<N, B::Cache>>,
    grad: Option<&mut SVec<N>>,
    hess: Option<&mut SMat<N, N>>,
) -> Real {
    let xf = [x[0], x[1], x[2]];
    let a = first_fundamental_form(&xf);
    let want_h = hess.is_some();
    let want_g = grad.is_some() || want_h;
    let b = ev.map_or(Sym2::zeros(), |ev| ev.b);
    let mut d = DensityDerivs::default();
    if !want_g {
        return dens.eval(&a, &b, &mut d);
    }
    let e = if want_h {
        dens.eval(&a, &b, &mut d)
    } else {
        dens.eval_gradient(&a, &b, &mut d)
    };
    if GN && want_h {
        dens.gauss_newton(&a, &b, &mut d);
    }
    let ja = first_fundamental_form_jacobian(&xf);
    let mut g = SVec::<N>::zeros();
    g.fixed_rows_mut::<9>(0).copy_from(&(ja.transpose() * d.ga));
    if let Some(ev) = ev {
        model.add_gradient(face, ev, &d.gb, &mut g);
    }
    if let Some(h) = hess {
        let lambda = (!GN).then_some(&d.gb);
        // A model that forms membrane and bending in one product sets `h`; else both apart.
        let set =
            ev.is_some_and(|ev| model.set_shell_hessian(face, x, ev, &d.haa, &d.hbb, lambda, h));
        if !set {
            *h = SMat::zeros();
            h.fixed_view_mut::<9, 9>(0, 0)
                .copy_from(&(ja.transpose() * d.haa * ja));
            if let Some(ev) = ev {
                model.add_bending_hessian(face, x, ev, &d.hbb, lambda, h);
            }
        }
        let coef = if GN { d.ga_psd } else { d.ga };
        if coef != Sym2::zeros() {
            let pat = first_fundamental_form_hessian_pattern(&coef);
            for r in 0..3 {
                for s in 0..3 {
                    for c in 0..3 {
                        h[(3 * r + c, 3 * s + c)] += pat[(r, s)];
                    }
                }
            }
        }
    }
    if let Some(gout) = grad {
        *gout = g;
    }
    e
}

/// Energy (J) of one shell face with the mid-edge average (seed 000 §3) under density `dens`,
/// with optional gradient (+∂E/∂x, N) and Hessian (N/m), 18 DOFs in the order of
/// [`super::bending::average`].
pub fn shell_face<D: FaceDensity>(
    x: &[Vec3; 6],
    has: [bool; 3],
    dens: &D,
    grad: Option<&mut SVec<18>>,
    hess: Option<&mut SMat<18, 18>>,
) -> Real {
    shell_element::<D, MidedgeAverage, 18, 6, false>(&MidedgeAverage, &has, x, dens, grad, hess)
}

/// As [`shell_face`], but the Hessian is the Gauss–Newton part only,
/// `Jaᵀ W_aa Ja + G W_bb Gᵀ`, dropping the terms with second derivatives of `a` and `b`.
/// For the Koiter density (`W_aa`, `W_bb` multiples of the positive semi-definite `C`) it is
/// positive semi-definite by construction: a descent direction without an eigendecomposition.
pub fn shell_face_gauss_newton<D: FaceDensity>(
    x: &[Vec3; 6],
    has: [bool; 3],
    dens: &D,
    grad: Option<&mut SVec<18>>,
    hess: Option<&mut SMat<18, 18>>,
) -> Real {
    shell_element::<D, MidedgeAverage, 18, 6, true>(&MidedgeAverage, &has, x, dens, grad, hess)
}

/// The name of the shell face term, and of its state when its membrane has one.
pub const NAME: &str = "shell";

/// The shell face term of a membrane material `M` and a bending model `B` with `N` local DOFs.
pub struct Shell<M, B, const N: usize, const S: usize> {
    /// The membrane material.
    pub membrane: M,
    /// The bending model.
    pub bending: B,
}

/// A face's 6 stencil positions (absent slots get the face's own first vertex, unused).
#[inline(always)]
pub fn gather(nodes: &[usize], x: &[Vec3]) -> [Vec3; 6] {
    std::array::from_fn(|s| match nodes.get(s) {
        Some(&u) if u != NONE => x[u],
        _ => x[nodes[0]],
    })
}

impl<M: Membrane, B: BendingModel<N, S>, const N: usize, const S: usize> ElementKernel<N, S>
    for Shell<M, B, N, S>
{
    #[inline(always)]
    fn eval(
        &self,
        pot: &Potential,
        f: usize,
        nodes: &[usize],
        x: &[Vec3],
        phi: &[Real],
        gauss_newton: bool,
        grad: Option<&mut SVec<N>>,
        hess: Option<&mut SMat<N, N>>,
    ) -> Real {
        let xs = gather(nodes, x);
        let face = self.bending.face(pot.body, f, nodes, phi);
        let dens = self.membrane.density(pot, f);
        if gauss_newton {
            shell_element::<_, B, N, S, true>(&self.bending, &face, &xs, &dens, grad, hess)
        } else {
            shell_element::<_, B, N, S, false>(&self.bending, &face, &xs, &dens, grad, hess)
        }
    }
}

impl<M: Membrane, B: BendingModel<N, S>, const N: usize, const S: usize> Shell<M, B, N, S> {
    /// The stencil `[v0, v1, v2, p0, p1, p2, e0, e1, e2]` truncated to the model's slots.
    pub fn stencil(body: &Body, _: &Self) -> Stencil {
        let slots = S;
        let extra = body.stencil_extra();
        let nv = body.num_vertices();
        let mut nodes = Vec::with_capacity(slots * body.num_faces());
        let mut anchors = Vec::with_capacity(body.num_faces());
        for (f, face) in body.mesh.faces.iter().enumerate() {
            let o = extra[f];
            let e = if slots > 6 {
                body.topo.face_edges[f].map(|e| nv + e)
            } else {
                [NONE; 3]
            };
            let all = [
                face[0], face[1], face[2], o[0], o[1], o[2], e[0], e[1], e[2],
            ];
            nodes.extend_from_slice(&all[..slots]);
            let p = &body.mesh.positions;
            anchors.push((p[face[0]] + p[face[1]] + p[face[2]]) / 3.0);
        }
        let slot_dofs = (0..slots).map(|s| if s < 6 { 3 } else { 1 }).collect();
        Stencil {
            slot_dofs,
            nodes,
            anchors,
        }
    }

    /// `out(f, stencil, positions, bending input)` of every face at `x`, `phi` (in parallel, in
    /// face order).
    fn each_face<T: Send>(
        &self,
        pot: &Potential,
        x: &[Vec3],
        phi: &[Real],
        out: impl Fn(usize, &[usize], &[Vec3; 6], &B::Face) -> T + Sync,
    ) -> Vec<T> {
        use rayon::prelude::*;
        let pattern = pot.pattern.faces();
        (0..pot.body.num_faces())
            .into_par_iter()
            .map(|f| {
                let nodes = pattern.element(f);
                let xs = gather(nodes, x);
                let face = self.bending.face(pot.body, f, nodes, phi);
                out(f, nodes, &xs, &face)
            })
            .collect()
    }

    /// `out(density, a, b)` of every face at `x`, `phi` (in parallel, in face order).
    fn per_face<T: Send>(
        &self,
        pot: &Potential,
        x: &[Vec3],
        phi: &[Real],
        out: impl Fn(&M::Density, &Sym2, &Sym2) -> T + Sync,
    ) -> Vec<T> {
        self.each_face(pot, x, phi, |f, _, xs, face| {
            let dens = self.membrane.density(pot, f);
            let a = first_fundamental_form(&[xs[0], xs[1], xs[2]]);
            let b = if N > 9 {
                self.bending.eval(face, xs, false, false).b
            } else {
                Sym2::zeros()
            };
            out(&dens, &a, &b)
        })
    }

    /// Per-face elastic (stretching, bending) energies (J) at `x`, `phi`, without damping.
    pub fn face_energies(&self, pot: &Potential, x: &[Vec3], phi: &[Real]) -> Vec<(Real, Real)> {
        self.per_face(pot, x, phi, |dens, a, b| dens.elastic_parts(a, b))
    }
}

impl<M: Membrane, B: BendingModel<N, S>, const N: usize, const S: usize> super::term::Term
    for Shell<M, B, N, S>
{
    fn name(&self) -> &'static str {
        NAME
    }

    fn stencil(&self, body: &Body) -> Stencil {
        Self::stencil(body, self)
    }

    fn eval(
        &self,
        pot: &Potential,
        map: &crate::elements::ElementMap,
        x: &[Vec3],
        phi: &[Real],
        want: crate::elements::Want,
        projection: super::HessianProjection,
        grad: &mut [Real],
        values: &mut [Real],
    ) -> Real {
        let gn = projection == super::HessianProjection::GaussNewton;
        crate::elements::assemble_elements_owned::<N, S, _>(
            map,
            |e, nodes, g, h| ElementKernel::<N, S>::eval(self, pot, e, nodes, x, phi, gn, g, h),
            pot.node_fixed,
            projection,
            want,
            grad,
            values,
            &pot.pattern.col_ptr,
            pot.owned,
        )
    }

    /// A membrane with a state of its own (the prism's position-based thickness).
    fn tracked(&self) -> Option<&dyn Tracked> {
        self.membrane.state_field().is_some().then_some(self)
    }

    fn stateful(&self) -> Option<&dyn Stateful> {
        self.membrane.state_field().is_some().then_some(self)
    }

    fn projection(&self) -> Option<&dyn Projection> {
        self.membrane.projects().then_some(self)
    }

    fn reports(&self) -> Option<&dyn Reports> {
        Some(self)
    }

    fn rest_sensitivity(&self) -> Option<&dyn super::term::RestSensitivity> {
        Some(self)
    }
}

impl<M: Membrane, B: BendingModel<N, S>, const N: usize, const S: usize>
    super::term::RestSensitivity for Shell<M, B, N, S>
{
    /// Per face: `λ` gathered over the stencil (slots 0..6 three DOFs each, edge slots one),
    /// `δa = Ja λ`, `δb_q = ∇b_qᵀ λ` (the bending model's gradient with `W_b` the unit
    /// vector `e_q`), then [`super::sensitivity::koiter_rest_adjoint`]. In parallel, in face
    /// order.
    fn rest_adjoint(
        &self,
        pot: &Potential,
        x: &[Vec3],
        phi: &[Real],
        lambda: &[Real],
    ) -> Result<Vec<super::sensitivity::RestAdjoint>, String> {
        self.each_face(pot, x, phi, |f, nodes, xs, face| {
            let rest = self.membrane.rest_face(pot, f)?;
            let mut l = SVec::<N>::zeros();
            let mut k = 0;
            for (s, &u) in nodes.iter().enumerate().take(S) {
                let nd = if s < 6 { 3 } else { 1 };
                if u != NONE && k + nd <= N {
                    let (d0, _) = pot.pattern.node_dofs(u);
                    for c in 0..nd {
                        l[k + c] = lambda[d0 + c];
                    }
                }
                k += nd;
            }
            let xf = [xs[0], xs[1], xs[2]];
            let a = first_fundamental_form(&xf);
            let da: Sym2 = first_fundamental_form_jacobian(&xf) * l.fixed_rows::<9>(0);
            let (b, db) = if N > 9 && rest.bending {
                let ev = self.bending.eval(face, xs, true, false);
                let mut db = Sym2::zeros();
                for q in 0..3 {
                    let mut g = SVec::<N>::zeros();
                    self.bending
                        .add_gradient(face, &ev, &Sym2::ith(q, 1.0), &mut g);
                    db[q] = g.dot(&l);
                }
                (ev.b, db)
            } else {
                (Sym2::zeros(), Sym2::zeros())
            };
            Ok(super::sensitivity::koiter_rest_adjoint(
                &rest, &a, &b, &da, &db,
            ))
        })
        .into_iter()
        .collect()
    }
}

impl<M: Membrane, B: BendingModel<N, S>, const N: usize, const S: usize> Reports
    for Shell<M, B, N, S>
{
    /// Stretching and bending, elastic parts only (Kelvin–Voigt damping is dissipation, not
    /// stored energy).
    fn energies(
        &self,
        pot: &Potential,
        _: &crate::elements::ElementMap,
        x: &[Vec3],
        phi: &[Real],
    ) -> Option<Vec<(&'static str, Real)>> {
        Some(totals(&self.face_energies(pot, x, phi)))
    }

    /// `stretching_energy_density` and `bending_energy_density` (J/m² of rest area), and the
    /// material's own fields.
    fn face_fields(&self, pot: &Potential, x: &[Vec3], phi: &[Real]) -> Vec<(String, Vec<Real>)> {
        let mut f = densities(pot, &self.face_energies(pot, x, phi));
        f.extend(self.membrane.face_fields(pot, x));
        f
    }

    fn observables(&self, pot: &Potential, x: &[Vec3], _phi: &[Real]) -> Vec<(String, Real)> {
        self.membrane.observables(pot, x)
    }

    /// `∂W/∂a` of each face's density at the potential's rest forms (its elastic part: frames
    /// are evaluated without the damping wells).
    fn membrane_stress(&self, pot: &Potential, x: &[Vec3], phi: &[Real]) -> Option<Vec<Sym2>> {
        Some(self.per_face(pot, x, phi, |dens, a, b| {
            let mut d = crate::energy::material::DensityDerivs::default();
            dens.eval_gradient(a, b, &mut d);
            d.ga
        }))
    }

    /// The face energies once for both the totals and the densities.
    fn report(
        &self,
        pot: &Potential,
        _: &crate::elements::ElementMap,
        x: &[Vec3],
        phi: &[Real],
    ) -> (Option<Vec<(&'static str, Real)>>, Vec<(String, Vec<Real>)>) {
        let fe = self.face_energies(pot, x, phi);
        let mut f = densities(pot, &fe);
        f.extend(self.membrane.face_fields(pot, x));
        (Some(totals(&fe)), f)
    }
}

impl<M: Membrane, B: BendingModel<N, S>, const N: usize, const S: usize> Tracked
    for Shell<M, B, N, S>
{
    fn state_field(&self) -> &'static str {
        self.membrane.state_field().unwrap_or("membrane_state")
    }

    fn state_components(&self) -> usize {
        1
    }

    fn field(&self, _x: &[Vec3], _phi: &[Real], own: &[Real]) -> Vec<Real> {
        own.to_vec()
    }

    fn restore(
        &self,
        _x: &[Vec3],
        _phi: &[Real],
        field: Option<&[Real]>,
        own: &mut [Real],
    ) -> Result<Option<String>, StateError> {
        self.membrane.restore(field, own)
    }
}

impl<M: Membrane, B: BendingModel<N, S>, const N: usize, const S: usize> Stateful
    for Shell<M, B, N, S>
{
    fn initial_state(&self) -> Vec<Real> {
        self.membrane.initial_state().unwrap_or_default()
    }

    fn check_state(&self, state: &[Real]) -> Result<(), String> {
        self.membrane.check_state(state).map_err(|e| e.to_string())
    }
}

impl<M: Membrane, B: BendingModel<N, S>, const N: usize, const S: usize> Projection
    for Shell<M, B, N, S>
{
    fn project(
        &self,
        pot: &Potential,
        x: &mut [Vec3],
        _phi: &[Real],
        own: &mut [Real],
    ) -> Result<Option<Real>, StateError> {
        self.membrane.project(pot, x, own)
    }
}

/// Total stretching and bending energies (J) of per-face `(stretching, bending)`.
fn totals(fe: &[(Real, Real)]) -> Vec<(&'static str, Real)> {
    let (s, b) = fe
        .iter()
        .fold((0.0, 0.0), |(s, b), (fs, fb)| (s + fs, b + fb));
    vec![("stretching", s), ("bending", b)]
}

/// Per-face energy densities (J/m² of rest area) of per-face `(stretching, bending)`.
fn densities(pot: &Potential, fe: &[(Real, Real)]) -> Vec<(String, Vec<Real>)> {
    let area: Vec<Real> = (0..fe.len())
        .map(|f| 0.5 * crate::math::sym_det(&pot.rest_forms(f).0).max(0.0).sqrt())
        .collect();
    vec![
        (
            "stretching_energy_density".into(),
            fe.iter().zip(&area).map(|(e, a)| e.0 / a).collect(),
        ),
        (
            "bending_energy_density".into(),
            fe.iter().zip(&area).map(|(e, a)| e.1 / a).collect(),
        ),
    ]
}
