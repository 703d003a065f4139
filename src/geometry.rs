//! Discrete fundamental forms of a triangle and their derivatives.
//!
//! Conventions (DESIGN.md, seed 000 §3):
//! * A face `[v0, v1, v2]` is parameterised over the unit triangle by `e1 = v1 − v0`,
//!   `e2 = v2 − v0`; its first fundamental form is `a = [e1·e1, e1·e2; e1·e2, e2·e2]`, stored as
//!   `[a11, a12, a22]`.
//! * Edge `i` is the edge opposite vertex `i`. Across it lies the neighbouring face, whose vertex
//!   not on the edge is `p_i`.
//! * The second fundamental form `b` has the sign for which, with outward normals, a sphere of
//!   radius R has `b = a/R`; a positive `b` bulges toward the side the normal points to
//!   (`b_αβ = −N·∂αβr`, MorphoShell's convention, seed 001 §2).
//!
//! ## Mid-edge second fundamental form, derived from the offset definition
//! Offset each edge midpoint `m_i` by `ε n_i` along its mid-edge normal. A triangle's vertices
//! are `v_i = m_j + m_k − m_i`, so the offset triangle has `e1^ε = e1 + 2ε(n_0 − n_1)`,
//! `e2^ε = e2 + 2ε(n_0 − n_2)` and `a^ε = a + 2ε b + O(ε²)` (offset toward the normal) with
//!
//! `b = 2 [q0 + q1, q0; q0, q0 + q2]`, where `q_i = (v_j − v_i)·n_i` for either `j ≠ i`
//! (the same value, because `n_i ⟂` edge `i`).
//!
//! For the mid-edge *average* normal `n_i = (N_f + N_g)/|N_f + N_g|`, since `N_f ⟂ (v_j − v_i)`,
//! `q_i = (v_j − v_i)·N_g / |N_f + N_g| = h_i sin(θ_i/2)`, with `h_i` the height of `v_i` over
//! edge `i` and `θ_i` the signed dihedral angle. On a boundary edge `n_i = N_f` and `q_i = 0`.
//! Check (tests/geometry): on a sphere `b → a/R` face by face as a regular mesh is refined.
//!
//! The seed's displayed matrix (`½[(n_i − n_j)·(v_i − v_j) ...]`) has the opposite sign and a
//! factor 1/4 relative to its own offset definition; shellsim uses the derivation above.

use crate::config::shell::AngleVariant;
use crate::math::{skew, Mat2, Mat3, Real, SMat, SVec, Sym2, Vec3};

/// First fundamental form `[e1·e1, e1·e2, e2·e2]` of a triangle (m²).
#[inline]
pub fn first_fundamental_form(x: &[Vec3; 3]) -> Sym2 {
    let e1 = x[1] - x[0];
    let e2 = x[2] - x[0];
    Sym2::new(e1.dot(&e1), e1.dot(&e2), e2.dot(&e2))
}

/// Jacobian of `a` with respect to `[v0, v1, v2]` (3×9).
#[inline]
pub fn first_fundamental_form_jacobian(x: &[Vec3; 3]) -> SMat<3, 9> {
    let e1 = x[1] - x[0];
    let e2 = x[2] - x[0];
    let mut j = SMat::<3, 9>::zeros();
    for c in 0..3 {
        // a11 = e1·e1
        j[(0, c)] = -2.0 * e1[c];
        j[(0, 3 + c)] = 2.0 * e1[c];
        // a12 = e1·e2
        j[(1, c)] = -e1[c] - e2[c];
        j[(1, 3 + c)] = e2[c];
        j[(1, 6 + c)] = e1[c];
        // a22 = e2·e2
        j[(2, c)] = -2.0 * e2[c];
        j[(2, 6 + c)] = 2.0 * e2[c];
    }
    j
}

/// `Σ_k g_k ∇²a_k` as a 3×3 vertex-block pattern `S` (the 9×9 Hessian is `S ⊗ I₃`).
#[inline]
pub fn first_fundamental_form_hessian_pattern(g: &Sym2) -> Mat3 {
    let (g0, g1, g2) = (g[0], g[1], g[2]);
    Mat3::new(
        2.0 * g0 + 2.0 * g1 + 2.0 * g2,
        -2.0 * g0 - g1,
        -g1 - 2.0 * g2,
        -2.0 * g0 - g1,
        2.0 * g0,
        g1,
        -g1 - 2.0 * g2,
        g1,
        2.0 * g2,
    )
}

/// Unnormalised face normal `(v1 − v0) × (v2 − v0)` (twice the area vector).
#[inline]
pub fn area_normal(x: &[Vec3; 3]) -> Vec3 {
    (x[1] - x[0]).cross(&(x[2] - x[0]))
}

/// Unit normal of a triangle with its first derivatives, and the means to contract its second
/// derivatives with a covector.
#[derive(Clone, Copy, Debug)]
pub struct UnitNormal {
    /// The unit normal `N = c/|c|`.
    pub n: Vec3,
    /// `|c|` = twice the area.
    pub r: Real,
    /// `∂c/∂v_a` for a = 0, 1, 2.
    pub dc: [Mat3; 3],
    /// `∂N/∂v_a = (I − N Nᵀ)/|c| · ∂c/∂v_a`.
    pub dn: [Mat3; 3],
}

impl UnitNormal {
    /// Unit normal of `[v0, v1, v2]` and its Jacobian.
    #[inline]
    pub fn new(x: &[Vec3; 3]) -> Self {
        let c = area_normal(x);
        let r = c.norm();
        let n = c / r;
        let p = (Mat3::identity() - n * n.transpose()) / r;
        let dc = [
            skew(&(x[2] - x[1])),
            skew(&(x[0] - x[2])),
            skew(&(x[1] - x[0])),
        ];
        let dn = [p * dc[0], p * dc[1], p * dc[2]];
        UnitNormal { n, r, dc, dn }
    }

    /// The 9×9 Hessian of `λ·N` with respect to `[v0, v1, v2]`.
    ///
    /// With `g(c) = λ·c/|c|`: `∂²g/∂c² = [−λNᵀ − Nλᵀ − (λ·N)I + 3(λ·N)NNᵀ]/|c|²`, plus the
    /// constant second derivative of the bilinear `c` contracted with `μ = ∂g/∂c = Pλ/|c|`:
    /// `μ·(Δ1 × Δ2)` gives blocks `±M`, `M = −[μ]×`.
    #[inline]
    pub fn hessian_contract(&self, lambda: &Vec3) -> SMat<9, 9> {
        let n = self.n;
        let ln = lambda.dot(&n);
        let r2 = self.r * self.r;
        let g = (-(lambda * n.transpose()) - n * lambda.transpose() - Mat3::identity() * ln
            + n * n.transpose() * (3.0 * ln))
            / r2;
        let mu = (lambda - n * ln) / self.r;
        let m = -skew(&mu);
        let mt = m.transpose();
        let mut h = SMat::<9, 9>::zeros();
        for a in 0..3 {
            let ga = g * self.dc[a];
            for b in a..3 {
                let mut blk = self.dc[b].transpose() * ga;
                blk = blk.transpose(); // dc_aᵀ G dc_b
                let extra = match (a, b) {
                    (0, 1) => -mt,
                    (0, 2) => -m,
                    (1, 2) => m,
                    _ => Mat3::zeros(),
                };
                blk += extra;
                h.fixed_view_mut::<3, 3>(3 * a, 3 * b).copy_from(&blk);
                if a != b {
                    h.fixed_view_mut::<3, 3>(3 * b, 3 * a)
                        .copy_from(&blk.transpose());
                }
            }
        }
        h
    }
}

/// Derivatives of one edge quantity `q` with respect to its 12 local DOFs
/// `[v_i, v_j, v_k, p]` (the face's vertex opposite the edge, the edge's two ends in face order,
/// and the neighbour's far vertex).
#[derive(Clone, Copy, Debug)]
pub struct EdgeQ {
    /// The value of `q_i` (m).
    pub q: Real,
    /// `∂q/∂x`, 12 entries.
    pub grad: SVec<12>,
}

/// Mid-edge-average `q_i = (v_j − v_i)·N_g / |N_f + N_g|` with its gradient, and (when `hess` is
/// given) its Hessian excluding the `N_f` second-derivative term, which the caller contracts once
/// per face; the `N_f` covector `∂q/∂N_f` is returned for that.
///
/// `xf = [v_i, v_j, v_k]` in the face's cyclic order, `p` the neighbour's far vertex; the
/// neighbour is oriented `[p, v_k, v_j]`.
#[inline]
pub fn midedge_average_q(
    nf: &UnitNormal,
    slots: [usize; 3],
    xf: &[Vec3; 3],
    p: &Vec3,
    hess: Option<&mut SMat<12, 12>>,
) -> (EdgeQ, Vec3) {
    let (vi, vj, vk) = (xf[0], xf[1], xf[2]);
    let ng_data = UnitNormal::new(&[*p, vk, vj]);
    let ng = ng_data.n;
    let nfv = nf.n;
    let w = vj - vi;
    let u = nfv + ng;
    let s = u.norm();
    let s3 = s * s * s;
    let t = w.dot(&ng);
    let q = t / s;
    let f_w = ng / s;
    let f_ng = w / s - u * (t / s3);
    let f_nf = -u * (t / s3);

    // Jacobians into local slots [v_i(0), v_j(1), v_k(2), p(3)].
    // Nf: face slots are given by `slots` (which of nf.dn corresponds to v_i, v_j, v_k).
    let jnf = [nf.dn[slots[0]], nf.dn[slots[1]], nf.dn[slots[2]]];
    // Ng over [p, v_k, v_j] → local [3, 2, 1].
    let jng = [
        (1usize, ng_data.dn[2]),
        (2usize, ng_data.dn[1]),
        (3usize, ng_data.dn[0]),
    ];
    let mut grad = SVec::<12>::zeros();
    {
        let gw = f_w;
        for c in 0..3 {
            grad[c] -= gw[c];
            grad[3 + c] += gw[c];
        }
        for (a, j) in jnf.iter().enumerate() {
            let v = j.transpose() * f_nf;
            for c in 0..3 {
                grad[3 * a + c] += v[c];
            }
        }
        for (slot, j) in &jng {
            let v = j.transpose() * f_ng;
            for c in 0..3 {
                grad[3 * slot + c] += v[c];
            }
        }
    }
    if let Some(h) = hess {
        // Hessian of F(w, Nf, Ng) (9×9).
        let i3 = Mat3::identity();
        let uu = u * u.transpose();
        let k = (i3 / s3 - uu * (3.0 / (s3 * s * s))) * t;
        let fw_nf = -(ng * u.transpose()) / s3;
        let fw_ng = i3 / s - (ng * u.transpose()) / s3;
        let fnf_nf = -k;
        let fnf_ng = -(u * w.transpose()) / s3 - k;
        let fng_ng = -(w * u.transpose()) / s3 - (u * w.transpose()) / s3 - k;
        // H = Jᵀ F'' J with J (9×12, rows [w; Nf; Ng], columns the slots [v_i, v_j, v_k, p])
        // block-sparse: w = v_j − v_i has −I, +I at slots 0, 1; N_f has `jnf` at slots 0–2;
        // N_g has `jng` at slots 1–3. Column block b: M_b = F'' J_b (three 3×3 row blocks),
        // then H_ab = Σ_r J_raᵀ M_rb over the blocks present, for a ≤ b, mirrored: 33 products
        // of 3×3 matrices instead of the dense 9×12 products' 84.
        let wcoef: [Real; 4] = [-1.0, 1.0, 0.0, 0.0];
        let mut fblk: [Option<Mat3>; 4] = [None; 4];
        for (a, j) in jnf.iter().enumerate() {
            fblk[a] = Some(*j);
        }
        let mut gblk: [Option<Mat3>; 4] = [None; 4];
        for &(slot, j) in &jng {
            gblk[slot] = Some(j);
        }
        let (fnf_w, fng_w, fng_nf) = (fw_nf.transpose(), fw_ng.transpose(), fnf_ng.transpose());
        let mut m = [[Mat3::zeros(); 3]; 4];
        for b in 0..4 {
            let (mut mw, mut mf, mut mg) = (Mat3::zeros(), fnf_w * wcoef[b], fng_w * wcoef[b]);
            if let Some(f) = &fblk[b] {
                mw += fw_nf * f;
                mf += fnf_nf * f;
                mg += fng_nf * f;
            }
            if let Some(g) = &gblk[b] {
                mw += fw_ng * g;
                mf += fnf_ng * g;
                mg += fng_ng * g;
            }
            m[b] = [mw, mf, mg];
        }
        for (b, [mw, mf, mg]) in m.iter().enumerate() {
            for a in 0..=b {
                let mut blk = mw * wcoef[a];
                if let Some(f) = &fblk[a] {
                    blk += f.transpose() * mf;
                }
                if let Some(g) = &gblk[a] {
                    blk += g.transpose() * mg;
                }
                h.fixed_view_mut::<3, 3>(3 * a, 3 * b).copy_from(&blk);
                if a != b {
                    h.fixed_view_mut::<3, 3>(3 * b, 3 * a)
                        .copy_from(&blk.transpose());
                }
            }
        }
        // Ng second derivative contracted with ∂F/∂Ng, over [p, v_k, v_j] → local [3, 2, 1].
        let hg = ng_data.hessian_contract(&f_ng);
        let map = [3usize, 2, 1];
        for a in 0..3 {
            for b in 0..3 {
                let blk = hg.fixed_view::<3, 3>(3 * a, 3 * b);
                let mut dst = h.fixed_view_mut::<3, 3>(3 * map[a], 3 * map[b]);
                dst += blk;
            }
        }
    }
    (EdgeQ { q, grad }, f_nf)
}

/// The mid-edge-average `q_i` of a face's three edges, from its 6 stencil positions
/// `[v0, v1, v2, p0, p1, p2]` (`has[i]`: edge `i` has a neighbour; otherwise `q_i = 0`).
#[derive(Clone, Copy, Debug)]
pub struct AverageQs {
    /// `q_i` (m).
    pub q: [Real; 3],
    /// `∇q_i` over the local slots [`edge_slots`]`(i)` (12 entries each).
    pub grad: [SVec<12>; 3],
    /// `∇²q_i` without the `N_f` second-derivative part (filled only when asked).
    pub hess: [SMat<12, 12>; 3],
    /// `∂q_i/∂N_f`, contracted once per face by [`AverageQs::add_hessians`].
    pub dnf: [Vec3; 3],
}

/// The 4 face-local vertex slots of edge `i`'s quantity: `[v_i, v_j, v_k, p_i]`.
#[inline(always)]
pub fn edge_slots(i: usize) -> [usize; 4] {
    [i, (i + 1) % 3, (i + 2) % 3, 3 + i]
}

impl AverageQs {
    /// Evaluates every edge of a face; Hessians only with `hess`.
    #[inline]
    pub fn new(nf: &UnitNormal, x: &[Vec3; 6], has: [bool; 3], hess: bool) -> Self {
        let mut out = Self::zeros();
        out.fill(nf, x, has, hess);
        out
    }

    /// All zero (no edge).
    #[inline]
    pub fn zeros() -> Self {
        AverageQs {
            q: [0.0; 3],
            grad: [SVec::<12>::zeros(); 3],
            hess: [SMat::<12, 12>::zeros(); 3],
            dnf: [Vec3::zeros(); 3],
        }
    }

    /// [`Self::new`] in place, on a value from [`Self::zeros`] (an edge without a neighbour
    /// keeps its zeros; the Hessians are written only with `hess`): a kernel that keeps the
    /// result in a larger value fills it there instead of copying 3.5 kB in.
    #[inline(always)]
    pub fn fill(&mut self, nf: &UnitNormal, x: &[Vec3; 6], has: [bool; 3], hess: bool) {
        for i in 0..3 {
            if !has[i] {
                continue;
            }
            let (j, k) = ((i + 1) % 3, (i + 2) % 3);
            let (eq, f) = midedge_average_q(
                nf,
                [i, j, k],
                &[x[i], x[j], x[k]],
                &x[3 + i],
                hess.then_some(&mut self.hess[i]),
            );
            self.q[i] = eq.q;
            self.grad[i] = eq.grad;
            self.dnf[i] = f;
        }
    }

    /// Adds `Σ_i μ_i ∇²q_i` to the position block (the first 18 rows and columns) of an element
    /// Hessian, the face-normal part contracted once with `Σ_i μ_i ∂q_i/∂N_f`.
    #[inline]
    pub fn add_hessians<const N: usize>(
        &self,
        nf: &UnitNormal,
        has: [bool; 3],
        mu: [Real; 3],
        h: &mut SMat<N, N>,
    ) {
        let mut lam_f = Vec3::zeros();
        for i in 0..3 {
            if !has[i] || mu[i] == 0.0 {
                continue;
            }
            lam_f += self.dnf[i] * mu[i];
            let sl = edge_slots(i);
            for (la, &sa) in sl.iter().enumerate() {
                for (lb, &sb) in sl.iter().enumerate() {
                    let blk = self.hess[i].fixed_view::<3, 3>(3 * la, 3 * lb) * mu[i];
                    let mut dst = h.fixed_view_mut::<3, 3>(3 * sa, 3 * sb);
                    dst += blk;
                }
            }
        }
        let hn = nf.hessian_contract(&lam_f);
        let mut dst = h.fixed_view_mut::<9, 9>(0, 0);
        dst += hn;
    }
}

/// `b = 2 [q0 + q1, q0; q0, q0 + q2]` as `[b11, b12, b22]` (1/m · m² = m).
#[inline]
pub fn b_from_q(q: &SVec<3>) -> Sym2 {
    Sym2::new(2.0 * (q[0] + q[1]), 2.0 * q[0], 2.0 * (q[0] + q[2]))
}

/// The constant map `∂b/∂q` (3×3).
#[inline]
pub fn b_from_q_matrix() -> Mat3 {
    Mat3::new(2.0, 2.0, 0.0, 2.0, 0.0, 0.0, 2.0, 0.0, 2.0)
}

/// Mid-edge-average second fundamental form of one face from its vertices and the (optional)
/// far vertices of its neighbours. Value only.
pub fn midedge_average_b(x: &[Vec3; 3], opp: &[Option<Vec3>; 3]) -> Sym2 {
    let nf = UnitNormal::new(x);
    let mut q = SVec::<3>::zeros();
    for i in 0..3 {
        if let Some(p) = opp[i] {
            let (j, k) = ((i + 1) % 3, (i + 2) % 3);
            let ng = UnitNormal::new(&[p, x[k], x[j]]).n;
            q[i] = (x[j] - x[i]).dot(&ng) / (nf.n + ng).norm();
        }
    }
    b_from_q(&q)
}

/// Curvatures of a face from its forms: the shape operator `S = a⁻¹ b`; mean curvature
/// `H = tr S / 2`, Gauss curvature `K = det S`, principal curvatures (eigenvalues, ascending),
/// all in 1/m or 1/m².
pub fn curvatures(a: &Sym2, b: &Sym2) -> (Real, Real, Real, Real) {
    let am = crate::math::sym_to_mat(a);
    let bm = crate::math::sym_to_mat(b);
    let s = am.try_inverse().unwrap_or_else(Mat2::zeros) * bm;
    let h = 0.5 * s.trace();
    let k = s.determinant();
    let (k1, k2) = crate::math::eig2(&s);
    (h, k, k1, k2)
}

/// `w` times the signed volume of the cone from the origin over triangle `x`,
/// `w V_f = w x₀·(x₁ × x₂)/6` (m³ × w), with optional gradient and Hessian (9 DOFs:
/// `x0, x1, x2`). Summed over a closed surface's faces, `V = Σ V_f` is the enclosed volume
/// (exact for the polyhedron, see [`crate::mesh::closed`]).
///
/// `∂V_f/∂x₀ = (x₁ × x₂)/6` (cyclically): summed around a vertex, `(1/3) Σ A n̂`, the seed's
/// Eq. 15 nodal force direction. `∇²V_f` has zero 3×3 diagonal blocks and
/// `∂²V_f/∂x_i∂x_j = −[x_k]×/6` for `(i, j, k)` cyclic, with the transpose for `(j, i)`: the
/// derivative of the area and normal that seed 002's Eq. 16 drops. It depends on the origin
/// (only the sum over a closed surface does not), so it must never be projected face by face.
pub fn cone_volume(
    x: &[Vec3; 3],
    w: Real,
    grad: Option<&mut SVec<9>>,
    hess: Option<&mut SMat<9, 9>>,
) -> Real {
    let w6 = w / 6.0;
    let [x0, x1, x2] = *x;
    if let Some(g) = grad {
        let gs = [x1.cross(&x2), x2.cross(&x0), x0.cross(&x1)];
        for (i, gi) in gs.iter().enumerate() {
            g.fixed_rows_mut::<3>(3 * i).copy_from(&(gi * w6));
        }
    }
    if let Some(h) = hess {
        h.fill(0.0);
        for i in 0..3 {
            let (j, k) = ((i + 1) % 3, (i + 2) % 3);
            let b = -crate::math::skew(&x[k]) * w6;
            h.fixed_view_mut::<3, 3>(3 * i, 3 * j).copy_from(&b);
            h.fixed_view_mut::<3, 3>(3 * j, 3 * i)
                .copy_from(&b.transpose());
        }
    }
    w6 * x0.dot(&x1.cross(&x2))
}

impl AngleVariant {
    /// `(g, g', g'')` at `t`.
    #[inline(always)]
    pub fn eval(self, t: Real) -> (Real, Real, Real) {
        match self {
            AngleVariant::Sin => {
                let (s, c) = t.sin_cos();
                (s, c, -s)
            }
            AngleVariant::Tan => {
                let tn = t.tan();
                let sec2 = 1.0 + tn * tn;
                (tn, sec2, 2.0 * tn * sec2)
            }
        }
    }
}

/// `ℓ_i²` as a linear form in `a = [a11, a12, a22]` for the edge opposite vertex `i`.
const EDGE_LENGTH2: [[Real; 3]; 3] = [[1.0, -2.0, 1.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]];

/// Height `h_i = √(det a / ℓ_i²)` of vertex `i` over its opposite edge (m), with its gradient
/// and Hessian with respect to `a`.
#[inline]
pub fn height_from_a(a: &Sym2, i: usize) -> (Real, SVec<3>, Mat3) {
    let l = SVec::<3>::from(EDGE_LENGTH2[i]);
    let det = a[0] * a[2] - a[1] * a[1];
    let len2 = l.dot(a);
    let u = det / len2;
    let h = u.max(0.0).sqrt();
    let gd = SVec::<3>::new(a[2], -2.0 * a[1], a[0]);
    let hd = Mat3::new(0.0, 0.0, 1.0, 0.0, -2.0, 0.0, 1.0, 0.0, 0.0);
    let gu = gd / len2 - l * (det / (len2 * len2));
    let hu = hd / len2 - (gd * l.transpose() + l * gd.transpose()) / (len2 * len2)
        + l * l.transpose() * (2.0 * det / (len2 * len2 * len2));
    let gh = gu / (2.0 * h);
    let hh = hu / (2.0 * h) - gu * gu.transpose() / (4.0 * h * h * h);
    (h, gh, hh)
}

/// Second fundamental form of one face (value only), 6 stencil positions as in the module doc;
/// a boundary edge with its mid-edge normal set in space (`set[i]`) takes [`set_edge_u`].
pub fn midedge_angle_b(
    x: &[Vec3; 6],
    has: [bool; 3],
    phi: &[Real; 3],
    sigma: [Real; 3],
    set: [Option<EdgeNormal>; 3],
    variant: AngleVariant,
) -> Sym2 {
    let xf = [x[0], x[1], x[2]];
    let a = first_fundamental_form(&xf);
    let nf = UnitNormal::new(&xf);
    let mut q = SVec::<3>::zeros();
    for i in 0..3 {
        let (j, k) = ((i + 1) % 3, (i + 2) % 3);
        let (qt, psi) = if let Some(en) = &set[i] {
            (set_edge_u(en, &xf, i).0, 0.0)
        } else if has[i] {
            let ng = UnitNormal::new(&[x[3 + i], xf[k], xf[j]]).n;
            (
                (xf[j] - xf[i]).dot(&ng) / (nf.n + ng).norm(),
                sigma[i] * phi[i],
            )
        } else {
            (0.0, sigma[i] * phi[i])
        };
        let h = height_from_a(&a, i).0;
        let w = (h * h - qt * qt).max(0.0).sqrt();
        q[i] = h * variant.eval(qt.atan2(w) + psi).0;
    }
    b_from_q(&q)
}

/// A boundary edge's mid-edge normal set in space, for the bending models with edge DOFs: the
/// second-order clamp and the symmetry plane. The edge's own rotation DOF is then unused (and
/// held); its `q` follows from the normal ([`set_edge_u`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum EdgeNormal {
    /// The normal is this fixed unit vector: a clamp holds the reference face normal (its rest
    /// angle), whatever the face does.
    Fixed(Vec3),
    /// The normal lies in the symmetry plane of unit normal `normal`, across the edge:
    /// `t = sign · N × e / |N × e|` (`e` the edge in the face's order, `sign` making `t` point
    /// to the face's side at the reference), so that the surface meets the plane at a right
    /// angle as mirror symmetry requires.
    Plane {
        /// The plane's unit normal `N`.
        normal: Vec3,
        /// ±1.
        sign: Real,
    },
}

/// `u = (m − v_i)·t` (m) of the face's edge `i` (opposite `v_i`, from `v_j` to `v_k` in face
/// order, midpoint `m`) whose mid-edge normal `t` is set in space ([`EdgeNormal`]), with its
/// gradient over the face's three vertices (9 entries, `[v0, v1, v2]`). With `t` a unit vector
/// normal to the edge, `u = h_i sin ψ` for the angle ψ from the face normal to `t` about the
/// edge, the same quantity as the mid-edge average's `q_i = (v_j − v_i)·n_e` with `n_e = t`
/// ([`midedge_average_q`]); so the edge-DOF models take `u` in place of the average's `q̃_i`
/// with no rotation of their own (`q_i = h_i g(asin(u/h_i))`).
///
/// Fixed `t`: `∇u = (−t at v_i, t/2 at v_j and v_k)`, no second derivative. Plane: with
/// `p = v_i − m`, `e = v_k − v_j`, `c = N × e`, `r = |c|` and `P = I − N Nᵀ`,
/// `u = −sign · p·c / r`, `∂/∂p = c/r`, `∂/∂e = (p × N)/r − (p·c) P e / r³` (times `−sign`).
#[inline]
pub fn set_edge_u(en: &EdgeNormal, xf: &[Vec3; 3], i: usize) -> (Real, SVec<9>) {
    let (j, k) = ((i + 1) % 3, (i + 2) % 3);
    let p = xf[i] - (xf[j] + xf[k]) * 0.5;
    let mut g = SVec::<9>::zeros();
    let (u, gp, ge) = match *en {
        EdgeNormal::Fixed(t) => (-p.dot(&t), -t, Vec3::zeros()),
        EdgeNormal::Plane { normal: n, sign } => {
            let e = xf[k] - xf[j];
            let c = n.cross(&e);
            let r = c.norm();
            let pc = p.dot(&c);
            let pe = e - n * n.dot(&e);
            (
                -sign * pc / r,
                c * (-sign / r),
                (p.cross(&n) / r - pe * (pc / (r * r * r))) * (-sign),
            )
        }
    };
    // p = v_i − (v_j + v_k)/2, e = v_k − v_j.
    for c in 0..3 {
        g[3 * i + c] = gp[c];
        g[3 * j + c] = -0.5 * gp[c] - ge[c];
        g[3 * k + c] = -0.5 * gp[c] + ge[c];
    }
    (u, g)
}

/// The Hessian of [`set_edge_u`] over `[v0, v1, v2]` (9×9): zero for a fixed normal; for a
/// plane, `−sign` times the second derivatives of `p·c/r` in `(p, e)`:
/// `H_pp = 0`, `H_pe = [N]ₓ/r − c (Pe)ᵀ/r³`,
/// `H_ee = −((p×N)(Pe)ᵀ + (Pe)(p×N)ᵀ + (p·c) P)/r³ + 3 (p·c)(Pe)(Pe)ᵀ/r⁵`,
/// pulled back through `p = v_i − (v_j + v_k)/2`, `e = v_k − v_j`.
#[inline]
pub fn set_edge_u_hessian(en: &EdgeNormal, xf: &[Vec3; 3], i: usize) -> SMat<9, 9> {
    let mut h = SMat::<9, 9>::zeros();
    let EdgeNormal::Plane { normal: n, sign } = *en else {
        return h;
    };
    let (j, k) = ((i + 1) % 3, (i + 2) % 3);
    let p = xf[i] - (xf[j] + xf[k]) * 0.5;
    let e = xf[k] - xf[j];
    let c = n.cross(&e);
    let r = c.norm();
    let (r3, r5) = (r * r * r, r * r * r * r * r);
    let pc = p.dot(&c);
    let pe = e - n * n.dot(&e);
    let pxn = p.cross(&n);
    let nx = skew(&n);
    let proj = Mat3::identity() - n * n.transpose();
    let hpe = (nx / r - c * pe.transpose() / r3) * (-sign);
    let hee = ((pxn * pe.transpose() + pe * pxn.transpose() + proj * pc) * (-1.0 / r3)
        + pe * pe.transpose() * (3.0 * pc / r5))
        * (-sign);
    // Coefficients of p and e per vertex (i, j, k).
    let mut cp = [0.0; 3];
    let mut ce = [0.0; 3];
    cp[i] = 1.0;
    cp[j] = -0.5;
    cp[k] = -0.5;
    ce[j] = -1.0;
    ce[k] = 1.0;
    for a in 0..3 {
        for b in 0..3 {
            let blk =
                hpe * (cp[a] * ce[b]) + hpe.transpose() * (ce[a] * cp[b]) + hee * (ce[a] * ce[b]);
            h.fixed_view_mut::<3, 3>(3 * a, 3 * b).copy_from(&blk);
        }
    }
    h
}
