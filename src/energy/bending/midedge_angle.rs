//! The mid-edge shell with one rotation degree of freedom per edge: the mid-edge normal of each
//! edge is free to turn about the edge, away from the average of the two face normals.
//!
//! ## Formula
//! For face `f` and its edge `i` (opposite vertex `i`), with `h_i` the height of `v_i` over the
//! edge, `θ_i` the signed dihedral angle between `f` and its neighbour across the edge, `φ_e` the
//! edge's DOF (rad) and `σ = ±1` the face's orientation relative to the edge (+1 for the edge's
//! first face, −1 for the second):
//!
//! `q_i = h_i g(θ_i/2 + σ φ_e)`, `g = sin` (variant `sin`) or `g = tan` (variant `tan`),
//!
//! and `b = 2 [q0 + q1, q0; q0, q0 + q2]` as for the average ([`crate::geometry`]). This is the
//! per-edge quantity `2 h_e sin(θ_e/2 + σφ_e)` of the angle-based mid-edge shells that followed
//! seed 000 (Chen, Sastry, van Rees & Vouga 2018, "Physical simulation of environmentally
//! induced thin shell deformation", and its libshell "MidedgeAngleSin/Tan" formulations); the
//! factor 2 is the one in `b = 2[…]`. With `φ = 0` the `sin` variant *is* the mid-edge average
//! (`h sin(θ/2) = (v_j − v_i)·N_g/|N_f + N_g|`). Rotating the normal by `+φ` from one face is a
//! rotation by `−φ` seen from the other, hence `σ`.
//!
//! ## How the derivatives are organised
//! Write `α_i = θ_i/2`. With the average's `q̃_i = h_i sin α_i` (already differentiated in
//! [`crate::geometry::midedge_average_q`]) and `w_i = h_i cos α_i = √(h_i² − q̃_i²)`,
//! `α_i = atan2(q̃_i, w_i)`, and `h_i² = det a / ℓ_i²(a)` is a function of the first fundamental
//! form only (`ℓ_0² = a11 − 2a12 + a22`, `ℓ_1² = a22`, `ℓ_2² = a11`). So the face energy is a
//! function of 9 intermediate variables `y = (a[3], q̃[3], φ[3])`,
//! `Ẽ(y) = W(a, B F(q̃, h(a), σφ))` with `F(q̃, h, ψ) = h g(α(q̃, h) + ψ)`; its 9-gradient and
//! 9×9 Hessian are formed in closed form and pulled back through `J = ∂y/∂x` (21 DOFs), plus the
//! second-derivative terms of `a` and `q̃`.
//!
//! ## Boundary edges
//! An edge with one face has no dihedral angle: `θ = 0`, `q_i = h_i g(σφ_e)`. Its DOF is free, so
//! the boundary normal settles where the face's bending moment vanishes: the natural (free-edge)
//! boundary condition. (The mid-edge average instead pins `q = 0`, a spurious clamp that is the
//! source of its corner error on curved shapes.)
//!
//! A boundary edge whose mid-edge normal `t` is set in space ([`EdgeNormal`]: a clamp holds its
//! reference normal, a symmetry plane keeps it in the plane) has no rotation of its own: it
//! takes `u = (m − v_i)·t = h_i sin ψ` ([`set_edge_u`]) in the place of the average's `q̃_i`
//! and `ψ = 0`, so `q_i = h_i g(asin(u/h_i))`, with `u`'s derivatives in the positions. Its DOF
//! is held.
//!
//! DOF order (21): `x[v0], x[v1], x[v2], x[p0], x[p1], x[p2]` (18, as [`crate::energy::shell`]), then
//! `φ_{e0}, φ_{e1}, φ_{e2}` (rad), the DOFs of the edges opposite `v0, v1, v2`. Units: energy J,
//! gradient N (positions) and N·m (angles).

use super::{BendingEval, BendingModel};
use crate::body::Body;
use crate::energy::material::FaceDensity;
use crate::geometry::{
    b_from_q, b_from_q_matrix, edge_slots, first_fundamental_form,
    first_fundamental_form_hessian_pattern, first_fundamental_form_jacobian, set_edge_u,
    set_edge_u_hessian, AverageQs, EdgeNormal, UnitNormal,
};
use crate::math::{Mat3, Real, SMat, SVec, Sym2, Vec3};

pub use crate::config::shell::AngleVariant;
pub use crate::geometry::{height_from_a, midedge_angle_b};

/// `F(q̃, h, ψ) = h g(α + ψ)`, `α = atan2(q̃, √(h² − q̃²))`, with its gradient and Hessian in
/// `(q̃, h, ψ)`.
#[inline]
pub fn edge_q(variant: AngleVariant, qt: Real, h: Real, psi: Real) -> (Real, SVec<3>, Mat3) {
    let w = (h * h - qt * qt).max(0.0).sqrt();
    let alpha = qt.atan2(w);
    let (g, g1, g2) = variant.eval(alpha + psi);
    // α's derivatives: α_q = 1/w, α_h = −q/(h w), and their second derivatives.
    let (aq, ah) = (1.0 / w, -qt / (h * w));
    let w3 = w * w * w;
    let aqq = qt / w3;
    let aqh = -h / w3;
    let ahh = qt * (w * w + h * h) / (h * h * w3);
    let f = h * g;
    let grad = SVec::<3>::new(h * g1 * aq, g + h * g1 * ah, h * g1);
    let fqq = h * (g2 * aq * aq + g1 * aqq);
    let fqh = g1 * aq + h * (g2 * aq * ah + g1 * aqh);
    let fhh = 2.0 * g1 * ah + h * (g2 * ah * ah + g1 * ahh);
    let fqp = h * g2 * aq;
    let fhp = g1 + h * g2 * ah;
    let fpp = h * g2;
    let hess = Mat3::new(fqq, fqh, fqp, fqh, fhh, fhp, fqp, fhp, fpp);
    (f, grad, hess)
}

/// Energy (J) of one face of the mid-edge shell with edge DOFs, with optional gradient and
/// Hessian in the 21-DOF order of the module doc, through the one shell chain rule
/// ([`crate::energy::shell::shell_element`]). `GN` selects the Gauss–Newton Hessian
/// `Jᵀ W'' J` (positive semi-definite for the Koiter density), dropping second derivatives of
/// `a`, `q̃`, `h` and `F`.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub fn midedge_angle_face<D: FaceDensity, const GN: bool>(
    x: &[Vec3; 6],
    has: [bool; 3],
    phi: &[Real; 3],
    sigma: [Real; 3],
    variant: AngleVariant,
    dens: &D,
    grad: Option<&mut SVec<21>>,
    hess: Option<&mut SMat<21, 21>>,
) -> Real {
    midedge_angle_face_with::<D, GN>(x, has, phi, sigma, [None; 3], variant, dens, grad, hess)
}

/// [`midedge_angle_face`] with the mid-edge normals of some boundary edges set in space
/// (`set[i]` for the edge opposite `v_i`; see the module doc).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub fn midedge_angle_face_with<D: FaceDensity, const GN: bool>(
    x: &[Vec3; 6],
    has: [bool; 3],
    phi: &[Real; 3],
    sigma: [Real; 3],
    set: [Option<EdgeNormal>; 3],
    variant: AngleVariant,
    dens: &D,
    grad: Option<&mut SVec<21>>,
    hess: Option<&mut SMat<21, 21>>,
) -> Real {
    let face = AngleFace {
        has,
        phi: *phi,
        sigma,
        set,
    };
    crate::energy::shell::shell_element::<D, MidedgeAngle, 21, 9, GN>(
        &MidedgeAngle(variant),
        &face,
        x,
        dens,
        grad,
        hess,
    )
}

/// The edge-DOF model (`sin` or `tan`).
#[derive(Clone, Copy, Debug)]
pub struct MidedgeAngle(pub AngleVariant);

/// Per-face input: boundary flags, the three edge DOFs (rad), the face's orientation signs and
/// the boundary edges whose mid-edge normal is set in space.
#[derive(Clone, Copy, Debug)]
pub struct AngleFace {
    /// Whether edge `i` has a neighbour.
    pub has: [bool; 3],
    /// `φ` of the edges opposite `v0, v1, v2` (rad).
    pub phi: [Real; 3],
    /// The face's orientation sign `σ` on each edge.
    pub sigma: [Real; 3],
    /// The set mid-edge normal of a boundary edge (a clamp, a symmetry plane), if any.
    pub set: [Option<EdgeNormal>; 3],
}

/// Intermediate-variable derivatives kept for the Hessian contraction.
pub struct AngleCache {
    nf: UnitNormal,
    qs: AverageQs,
    /// `∂q/∂y` (3×9), `y = (a, q̃, φ)`.
    jq: SMat<3, 9>,
    /// `∂y/∂x` (9×21).
    jy: SMat<9, 21>,
    /// `(∇_a h_i, ∇²_a h_i)`.
    dh: [(SVec<3>, Mat3); 3],
    /// `(∇F_i, ∇²F_i)` in `(q̃, h, ψ)`.
    df: [(SVec<3>, Mat3); 3],
}

impl BendingModel<21, 9> for MidedgeAngle {
    type Face = AngleFace;
    type Cache = AngleCache;
    const NAME: &'static str = "midedge_angle";
    crate::light_via_eval!(21);

    #[inline(always)]
    fn face(&self, body: &Body, f: usize, nodes: &[usize], phi: &[Real]) -> AngleFace {
        let nv = body.num_vertices();
        let e = [nodes[6] - nv, nodes[7] - nv, nodes[8] - nv];
        AngleFace {
            has: super::has_extra(nodes),
            phi: [phi[e[0]], phi[e[1]], phi[e[2]]],
            sigma: body.edge_sign[f],
            set: if body.edge_normal.is_empty() {
                [None; 3]
            } else {
                e.map(|e| body.edge_normal[e])
            },
        }
    }

    /// `G = Jyᵀ Jqᵀ Bᵀ` through the 9 intermediate variables of the module doc.
    #[inline(always)]
    fn eval(
        &self,
        face: &AngleFace,
        x: &[Vec3; 6],
        grad: bool,
        hess: bool,
    ) -> BendingEval<21, AngleCache> {
        let AngleFace {
            has,
            phi,
            sigma,
            set,
        } = *face;
        let xf = [x[0], x[1], x[2]];
        let a = first_fundamental_form(&xf);
        // Built where it is returned and filled in place: the cache is about 6 kB, and
        // assembling it from locals copied it (3% of a cone's run).
        let mut ev = BendingEval {
            b: Sym2::zeros(),
            // G is never formed: the gradient and Hessian go through the y variables.
            jac: None,
            cache: AngleCache {
                nf: UnitNormal::new(&xf),
                qs: AverageQs::zeros(),
                jq: SMat::<3, 9>::zeros(),
                jy: SMat::<9, 21>::zeros(),
                dh: [(SVec::<3>::zeros(), Mat3::zeros()); 3],
                df: [(SVec::<3>::zeros(), Mat3::zeros()); 3],
            },
        };
        let c = &mut ev.cache;
        c.qs.fill(&c.nf, x, has, hess);
        // A set edge's `u` takes the average's `q̃` slot, with no rotation of its own.
        let mut qt = c.qs.q;
        let mut set_grad = [None; 3];
        for i in 0..3 {
            if let Some(en) = &set[i] {
                let (u, g) = set_edge_u(en, &xf, i);
                qt[i] = u;
                set_grad[i] = Some(g);
            }
        }
        let mut q = SVec::<3>::zeros();
        for i in 0..3 {
            let (h, gh, hh) = height_from_a(&a, i);
            let psi = if set[i].is_some() {
                0.0
            } else {
                sigma[i] * phi[i]
            };
            let (f, gf, hf) = edge_q(self.0, qt[i], h, psi);
            q[i] = f;
            c.dh[i] = (gh, hh);
            c.df[i] = (gf, hf);
        }
        if grad {
            let (jq, jy) = (&mut c.jq, &mut c.jy);
            for i in 0..3 {
                let (gf, _) = c.df[i];
                for k in 0..3 {
                    jq[(i, k)] = gf[1] * c.dh[i].0[k];
                }
                jq[(i, 3 + i)] = if has[i] || set[i].is_some() {
                    gf[0]
                } else {
                    0.0
                };
                jq[(i, 6 + i)] = if set[i].is_some() {
                    0.0
                } else {
                    gf[2] * sigma[i]
                };
            }
            jy.fixed_view_mut::<3, 9>(0, 0)
                .copy_from(&first_fundamental_form_jacobian(&xf));
            for i in 0..3 {
                if has[i] {
                    for (l, &s) in edge_slots(i).iter().enumerate() {
                        for k in 0..3 {
                            jy[(3 + i, 3 * s + k)] = c.qs.grad[i][3 * l + k];
                        }
                    }
                }
                if let Some(g) = &set_grad[i] {
                    for k in 0..9 {
                        jy[(3 + i, k)] = g[k];
                    }
                }
                jy[(6 + i, 18 + i)] = 1.0;
            }
        }
        ev.b = b_from_q(&q);
        ev
    }

    /// With `μ = Bᵀλ`: `Σ_i μ_i ∇²q_i = Jyᵀ [Σ_i μ_i (Kᵢᵀ F_i'' Kᵢ + F_i,h ∇²_a h_i)] Jy`
    /// `+ Σ_k (Jqᵀμ)_{a_k} ∇²a_k + Σ_i (Jqᵀμ)_{q̃_i} ∇²q̃_i`.
    #[inline(always)]
    fn add_hessian(
        &self,
        face: &AngleFace,
        x: &[Vec3; 6],
        ev: &BendingEval<21, AngleCache>,
        lambda: &Sym2,
        h: &mut SMat<21, 21>,
    ) {
        self.add_y_hessian(face, x, ev, SMat::<9, 9>::zeros(), Some(lambda), false, h);
    }

    /// Both bending parts in the intermediate variables `y`, then one product `Jyᵀ H_y Jy`:
    /// `G W_bb Gᵀ = Jyᵀ (Jqᵀ Bᵀ W_bb B Jq) Jy`.
    #[inline(always)]
    fn add_bending_hessian(
        &self,
        face: &AngleFace,
        x: &[Vec3; 6],
        ev: &BendingEval<21, AngleCache>,
        hbb: &Mat3,
        lambda: Option<&Sym2>,
        h: &mut SMat<21, 21>,
    ) {
        let bq = b_from_q_matrix();
        let jq = &ev.cache.jq;
        let hy = jq.transpose() * (bq.transpose() * hbb * bq) * jq;
        self.add_y_hessian(face, x, ev, hy, lambda, false, h);
    }

    /// `G W_b = Jyᵀ (Jqᵀ (Bᵀ W_b))`: three products of a vector, never the 21×3 `G`.
    #[inline(always)]
    fn add_gradient(
        &self,
        _face: &Self::Face,
        ev: &BendingEval<21, AngleCache>,
        wb: &Sym2,
        g: &mut SVec<21>,
    ) {
        let c = &ev.cache;
        *g += c.jy.transpose() * (c.jq.transpose() * (b_from_q_matrix().transpose() * wb));
    }

    /// The membrane's `W_aa` joins the y-space Hessian (`a` is the first block of `y`), so
    /// one product `Jyᵀ hy Jy` sets the whole Hessian.
    #[inline(always)]
    fn set_shell_hessian(
        &self,
        face: &AngleFace,
        x: &[Vec3; 6],
        ev: &BendingEval<21, AngleCache>,
        haa: &Mat3,
        hbb: &Mat3,
        lambda: Option<&Sym2>,
        h: &mut SMat<21, 21>,
    ) -> bool {
        let bq = b_from_q_matrix();
        let jq = &ev.cache.jq;
        let mut hy = jq.transpose() * (bq.transpose() * hbb * bq) * jq;
        {
            let mut aa = hy.fixed_view_mut::<3, 3>(0, 0);
            aa += haa;
        }
        self.add_y_hessian(face, x, ev, hy, lambda, true, h);
        true
    }
}

/// `h = Jyᵀ hy Jy` (with `set`) or `h += Jyᵀ hy Jy`, through the block structure of `Jy`
/// (9×21, [`BendingModel::eval`]): the rows of `a` and `q̃` reach the face's 9 vertex DOFs
/// (`F`, 6×9), row `q̃_i` also the 3 DOFs of the far vertex `p_i` (`g_i`, a 3-vector), and row
/// `φ_i` is the unit vector of DOF `18 + i`. With `U = hy Jy` (9×21): `U_F = hy[:, 0..6] F`,
/// `U_{p_i} = hy[:, 3+i] g_iᵀ`, `U_{φ_i} = hy[:, 6+i]`; then `H_F = Fᵀ U[0..6]`,
/// `H_{p_i} = g_i U[3+i]`, `H_{φ_i} = U[6+i]`. About 1.9k multiply-adds against the dense
/// products' 5.7k.
#[inline(always)]
fn jy_congruence(jy: &SMat<9, 21>, hy: &SMat<9, 9>, set: bool, h: &mut SMat<21, 21>) {
    let f = jy.fixed_view::<6, 9>(0, 0).into_owned();
    let g: [Vec3; 3] = std::array::from_fn(|i| {
        Vec3::new(
            jy[(3 + i, 9 + 3 * i)],
            jy[(3 + i, 10 + 3 * i)],
            jy[(3 + i, 11 + 3 * i)],
        )
    });
    let mut u = SMat::<9, 21>::zeros();
    u.fixed_view_mut::<9, 9>(0, 0)
        .copy_from(&(hy.fixed_view::<9, 6>(0, 0) * f));
    for i in 0..3 {
        for r in 0..9 {
            let w = hy[(r, 3 + i)];
            for k in 0..3 {
                u[(r, 9 + 3 * i + k)] = w * g[i][k];
            }
            u[(r, 18 + i)] = hy[(r, 6 + i)];
        }
    }
    let top = f.transpose() * u.fixed_view::<6, 21>(0, 0);
    if set {
        h.fixed_view_mut::<9, 21>(0, 0).copy_from(&top);
    } else {
        let mut dst = h.fixed_view_mut::<9, 21>(0, 0);
        dst += top;
    }
    for i in 0..3 {
        for col in 0..21 {
            let w = u[(3 + i, col)];
            for k in 0..3 {
                let e = &mut h[(9 + 3 * i + k, col)];
                *e = if set { g[i][k] * w } else { *e + g[i][k] * w };
            }
            let e = &mut h[(18 + i, col)];
            *e = if set {
                u[(6 + i, col)]
            } else {
                *e + u[(6 + i, col)]
            };
        }
    }
}

impl MidedgeAngle {
    /// Adds (or, with `set`, assigns) `Jyᵀ (hy + Σ_i μ_i (Kᵢᵀ F_i'' Kᵢ + F_i,h ∇²_a h_i)) Jy`
    /// and, with `lambda`, adds the second-derivative terms of `a` and `q̃` contracted with
    /// `Jqᵀμ` (`μ = Bᵀλ`).
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn add_y_hessian(
        &self,
        face: &AngleFace,
        x: &[Vec3; 6],
        ev: &BendingEval<21, AngleCache>,
        mut hy: SMat<9, 9>,
        lambda: Option<&Sym2>,
        set: bool,
        h: &mut SMat<21, 21>,
    ) {
        let AngleFace {
            has,
            sigma,
            set: set_normal,
            ..
        } = *face;
        let c = &ev.cache;
        let mu = lambda.map(|l| b_from_q_matrix().transpose() * l);
        if let Some(mu) = &mu {
            for i in 0..3 {
                let (gf, hf) = c.df[i];
                let mut kmat = SMat::<3, 9>::zeros();
                if has[i] || set_normal[i].is_some() {
                    kmat[(0, 3 + i)] = 1.0;
                }
                for k in 0..3 {
                    kmat[(1, k)] = c.dh[i].0[k];
                }
                if set_normal[i].is_none() {
                    kmat[(2, 6 + i)] = sigma[i];
                }
                hy += kmat.transpose() * hf * kmat * mu[i];
                let mut aa = hy.fixed_view_mut::<3, 3>(0, 0);
                aa += c.dh[i].1 * (mu[i] * gf[1]);
            }
        }
        jy_congruence(&c.jy, &hy, set, h);
        if let Some(mu) = &mu {
            let gy = c.jq.transpose() * mu;
            let pat = first_fundamental_form_hessian_pattern(&Sym2::new(gy[0], gy[1], gy[2]));
            for r in 0..3 {
                for s in 0..3 {
                    for k in 0..3 {
                        h[(3 * r + k, 3 * s + k)] += pat[(r, s)];
                    }
                }
            }
            c.qs.add_hessians(&c.nf, has, [gy[3], gy[4], gy[5]], h);
            // A set edge's `u`: its second derivative (zero for a fixed normal).
            for i in 0..3 {
                if let Some(en @ EdgeNormal::Plane { .. }) = &set_normal[i] {
                    let xf = [x[0], x[1], x[2]];
                    let mut dst = h.fixed_view_mut::<9, 9>(0, 0);
                    dst += set_edge_u_hessian(en, &xf, i) * gy[3 + i];
                }
            }
        }
    }
}
