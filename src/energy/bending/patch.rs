//! MorphoShell's quadratic patch-fit second fundamental form (seed 001 §2).
//!
//! Per face: its 3 vertices and 3 nearby nodes, all 6 in the flat reference plane. The quadratic
//! `R(x, y) = c0 + c1 x + c2 y + c3 x² + c4 xy + c5 y²` interpolating the 6 current positions has
//! `∂αβR = Σ_k W_αβ,k x_k`, with weights from the inverse of the 6×6 fit matrix, computed once in
//! the reference state. Then `b_αβ = −N·∂αβR` (N the face's unit normal), which is `a/R` on a
//! sphere of radius R with outward normals, shellsim's convention. Pulled back to the face's
//! barycentric frame, `b = Ŵ`-weighted: `b_q = −N·s_q`, `s_q = Σ_k Ŵ_qk x_k`.
//!
//! DOF order (18): `x[v0], x[v1], x[v2], x[n0], x[n1], x[n2]` (face vertices, patch nodes).

use super::{BendingEval, BendingModel};
use crate::energy::material::FaceDensity;
use crate::geometry::UnitNormal;
use crate::math::{Mat3, Real, SMat, SVec, Sym2, Vec3};
use crate::scene::Scene;

/// Barycentric patch weights `Ŵ` (rows: b11, b12, b22; columns: the 6 stencil nodes), 1/m².
pub type PatchWeights = SMat<3, 6>;

/// Patch-fit second fundamental form of one face (barycentric, m).
pub fn patch_b(x: &[Vec3; 6], w: &PatchWeights) -> Sym2 {
    let n = UnitNormal::new(&[x[0], x[1], x[2]]).n;
    Sym2::from_fn(|q, _| -n.dot(&(0..6).map(|k| x[k] * w[(q, k)]).sum::<Vec3>()))
}

/// Energy (J) of one face with patch-fit bending under density `dens`, optional gradient (N)
/// and Hessian (N/m) in the DOF order of the module doc, through the one shell chain rule
/// ([`crate::energy::shell::shell_element`]). With `GN`, the Hessian is the Gauss–Newton part.
pub fn patch_face<D: FaceDensity, const GN: bool>(
    x: &[Vec3; 6],
    w: &PatchWeights,
    dens: &D,
    grad: Option<&mut SVec<18>>,
    hess: Option<&mut SMat<18, 18>>,
) -> Real {
    crate::energy::shell::shell_element::<D, PatchFit, 18, 6, GN>(&PatchFit, w, x, dens, grad, hess)
}

/// MorphoShell's patch-fit model; the per-face input is the face's weights `Ŵ`.
#[derive(Clone, Copy, Debug, Default)]
pub struct PatchFit;

/// What the gradient and the Hessian contraction need: the light data (the unit normal `N`,
/// twice the area `r = |c|`, the edge vectors `e_a` opposite each face vertex, `∂c/∂x_a =
/// [e_a]×`, and the weighted sums `s_q`), and the normal's full Jacobian when a Hessian is
/// wanted.
pub struct PatchCache {
    light: PatchLight,
    full: Option<UnitNormal>,
}

/// [`BendingModel::light`]'s data: the unit normal, twice the area, the edges opposite each
/// vertex and the weighted sums `s_q`.
pub struct PatchLight {
    n: Vec3,
    r: Real,
    e: [Vec3; 3],
    s: [Vec3; 3],
}

/// `Σ_q W_b,q ∇b_q` (see [`BendingModel::add_gradient`] of [`PatchFit`]).
#[inline(always)]
fn patch_gradient(
    w: &PatchWeights,
    n: &Vec3,
    r: Real,
    e: &[Vec3; 3],
    s: &[Vec3; 3],
    wb: &Sym2,
    g: &mut SVec<18>,
) {
    let lam = s[0] * wb[0] + s[1] * wb[1] + s[2] * wb[2];
    let mu = (lam - n * n.dot(&lam)) / r;
    for a in 0..3 {
        let v = e[a].cross(&mu);
        for c in 0..3 {
            g[3 * a + c] += v[c];
        }
    }
    for k in 0..6 {
        let wk = wb[0] * w[(0, k)] + wb[1] * w[(1, k)] + wb[2] * w[(2, k)];
        for c in 0..3 {
            g[3 * k + c] -= wk * n[c];
        }
    }
}

impl BendingModel<18, 6> for PatchFit {
    type Face = PatchWeights;
    type Cache = PatchCache;
    const NAME: &'static str = "patch_fit";
    type Light = PatchLight;

    /// `b_q = −N·s_q` with the normal, twice the area, the edges and `s_q`: nothing else.
    #[inline(always)]
    fn light(&self, w: &PatchWeights, x: &[Vec3; 6]) -> (Sym2, PatchLight) {
        let c = (x[1] - x[0]).cross(&(x[2] - x[0]));
        let r = c.norm();
        let n = c / r;
        let s: [Vec3; 3] = std::array::from_fn(|q| {
            let mut acc = x[0] * w[(q, 0)];
            for k in 1..6 {
                acc += x[k] * w[(q, k)];
            }
            acc
        });
        let b = Sym2::new(-n.dot(&s[0]), -n.dot(&s[1]), -n.dot(&s[2]));
        (
            b,
            PatchLight {
                n,
                r,
                e: [x[2] - x[1], x[0] - x[2], x[1] - x[0]],
                s,
            },
        )
    }

    /// As [`BendingModel::add_gradient`], from the light data.
    #[inline(always)]
    fn add_gradient_light(&self, w: &PatchWeights, l: &PatchLight, wb: &Sym2, g: &mut SVec<18>) {
        patch_gradient(w, &l.n, l.r, &l.e, &l.s, wb, g);
    }

    #[inline(always)]
    fn face(&self, scene: &Scene, f: usize, _: &[usize], _: &[Real]) -> PatchWeights {
        scene.patches[f].weights
    }

    /// `b_q = −N·s_q`; with a Hessian, also `G = ∇b` (node k gets `−Ŵ_qk N`; face vertex a
    /// also gets `−(∂N/∂x_a)ᵀ s_q`). A gradient alone needs no `G`: see
    /// [`BendingModel::add_gradient`] below.
    #[inline(always)]
    fn eval(
        &self,
        w: &PatchWeights,
        x: &[Vec3; 6],
        _grad: bool,
        hess: bool,
    ) -> BendingEval<18, PatchCache> {
        let (b, light) = self.light(w, x);
        let (n, s) = (light.n, light.s);
        let full = hess.then(|| UnitNormal::new(&[x[0], x[1], x[2]]));
        let jac = full.as_ref().map(|nf| {
            let mut jac = SMat::<18, 3>::zeros();
            for q in 0..3 {
                for k in 0..6 {
                    for c in 0..3 {
                        jac[(3 * k + c, q)] -= w[(q, k)] * n[c];
                    }
                }
                for av in 0..3 {
                    let v = nf.dn[av].transpose() * s[q];
                    for c in 0..3 {
                        jac[(3 * av + c, q)] -= v[c];
                    }
                }
            }
            jac
        });
        BendingEval {
            b,
            jac,
            cache: PatchCache { light, full },
        }
    }

    /// `Σ_q W_b,q ∇b_q` without forming `G`: node k gets `−(Σ_q W_b,q Ŵ_qk) N`, and with
    /// `λ = Σ_q W_b,q s_q` and `μ = (I − N Nᵀ) λ / r`, face vertex a gets
    /// `−(∂N/∂x_a)ᵀ λ = −[e_a]×ᵀ μ = e_a × μ`.
    #[inline(always)]
    fn add_gradient(
        &self,
        w: &PatchWeights,
        ev: &BendingEval<18, PatchCache>,
        wb: &Sym2,
        g: &mut SVec<18>,
    ) {
        self.add_gradient_light(w, &ev.cache.light, wb, g);
    }

    /// `∇²b_q`: the cross blocks `−Ŵ_qk ∂N/∂x_a` (node k, face vertex a) and their transposes,
    /// and `−∇²(s_q·N)` with `s_q` fixed on the face vertices.
    #[inline(always)]
    fn add_hessian(
        &self,
        w: &PatchWeights,
        _: &[Vec3; 6],
        ev: &BendingEval<18, PatchCache>,
        lambda: &Sym2,
        h: &mut SMat<18, 18>,
    ) {
        let PatchCache { full, light } = &ev.cache;
        let s = &light.s;
        let Some(nf) = full else {
            return; // evaluated without a Hessian
        };
        let lam: Vec3 = s.iter().zip(lambda.iter()).map(|(sq, g)| sq * *g).sum();
        let hn = nf.hessian_contract(&lam);
        let mut top = h.fixed_view_mut::<9, 9>(0, 0);
        top -= hn;
        for k in 0..6 {
            let wk: Real = (0..3).map(|q| lambda[q] * w[(q, k)]).sum();
            if wk == 0.0 {
                continue;
            }
            for av in 0..3 {
                let blk: Mat3 = -nf.dn[av] * wk; // ∂²/∂x_k ∂x_a
                let mut dst = h.fixed_view_mut::<3, 3>(3 * k, 3 * av);
                dst += blk;
                let mut dst_t = h.fixed_view_mut::<3, 3>(3 * av, 3 * k);
                dst_t += blk.transpose();
            }
        }
    }
}

/// The patch of one face: its 3 extra nodes, barycentric weights, and the fit's condition number.
#[derive(Clone, Debug)]
pub struct Patch {
    /// The 3 nearby nodes.
    pub nodes: [usize; 3],
    /// Barycentric weights `Ŵ`.
    pub weights: PatchWeights,
    /// 2-norm condition number of the (scaled) 6×6 fit matrix.
    pub condition: Real,
}

/// A patch whose fit matrix is this well conditioned is taken at once.
pub const GOOD_CONDITION: Real = 30.0;
/// Patches worse than this are reported (they amplify the O(h³) interpolation error).
pub const MAX_CONDITION: Real = 1e3;

/// Builds every face's patch on a flat reference mesh (z = const). Candidates are the 8 vertices
/// nearest to the face centroid among the vertices of faces sharing a vertex with the face (then
/// their neighbours, if too few). Triples are tried in order of distance; the first whose
/// (scaled) fit matrix has a condition number ≤ [`GOOD_CONDITION`] is taken, otherwise the
/// best-conditioned triple. The error of the fitted curvature grows with the condition number
/// (measured: cond ≈ 10 gives ~1% on a jittered mesh, cond ≈ 1000 gives ~100%), hence the search.
/// A face whose best patch is still worse than [`MAX_CONDITION`] is reported in the returned
/// warnings and uses that patch (the documented fallback).
pub fn build_patches(
    mesh: &crate::mesh::Mesh,
) -> Result<(Vec<Patch>, Vec<String>), crate::mesh::MeshError> {
    use nalgebra::{SMatrix, SVD};
    if !mesh.is_flat_xy() {
        return Err(mesh
            .invalid("bending = \"patch_fit\" needs a flat reference mesh in a plane z = const"));
    }
    let nv = mesh.positions.len();
    let mut vf: Vec<Vec<usize>> = vec![Vec::new(); nv];
    for (f, face) in mesh.faces.iter().enumerate() {
        for &v in face {
            vf[v].push(f);
        }
    }
    let mut patches = Vec::with_capacity(mesh.faces.len());
    let mut warnings = Vec::new();
    for (f, face) in mesh.faces.iter().enumerate() {
        let c = (mesh.positions[face[0]] + mesh.positions[face[1]] + mesh.positions[face[2]]) / 3.0;
        let ell = ((mesh.positions[face[1]] - mesh.positions[face[0]]).norm()
            + (mesh.positions[face[2]] - mesh.positions[face[1]]).norm()
            + (mesh.positions[face[0]] - mesh.positions[face[2]]).norm())
            / 3.0;
        let mut cand: Vec<usize> = Vec::new();
        let mut ring: Vec<usize> = face.to_vec();
        for _ in 0..3 {
            let mut next = Vec::new();
            for &v in &ring {
                for &g in &vf[v] {
                    for &u in &mesh.faces[g] {
                        if !face.contains(&u) && !cand.contains(&u) {
                            cand.push(u);
                            next.push(u);
                        }
                    }
                }
            }
            if cand.len() >= 8 || next.is_empty() {
                break;
            }
            ring = next;
        }
        if cand.len() < 3 {
            return Err(mesh.invalid(format!(
                "patch_fit: face {f} has only {} nearby vertices; a quadratic patch needs 3",
                cand.len()
            )));
        }
        let dist = |u: usize| (mesh.positions[u] - c).norm_squared();
        cand.sort_by(|&p, &q| dist(p).total_cmp(&dist(q)).then(p.cmp(&q)));
        cand.truncate(8);
        let row = |u: usize| {
            let p = (mesh.positions[u] - c) / ell;
            [1.0, p.x, p.y, p.x * p.x, p.x * p.y, p.y * p.y]
        };
        let mut best: Option<(Real, [usize; 3], SMatrix<Real, 6, 6>)> = None;
        'search: for i in 0..cand.len() {
            for j in i + 1..cand.len() {
                for k in j + 1..cand.len() {
                    let nodes = [cand[i], cand[j], cand[k]];
                    let all = [face[0], face[1], face[2], nodes[0], nodes[1], nodes[2]];
                    let m = SMatrix::<Real, 6, 6>::from_fn(|r, col| row(all[r])[col]);
                    let sv = SVD::new(m, false, false).singular_values;
                    let cond = sv.max() / sv.min().max(Real::MIN_POSITIVE);
                    if best.as_ref().is_none_or(|b| cond < b.0) {
                        best = Some((cond, nodes, m));
                    }
                    if cond <= GOOD_CONDITION {
                        break 'search;
                    }
                }
            }
        }
        let Some((cond, nodes, m)) = best else {
            return Err(mesh.invalid(format!("patch_fit: no patch for face {f}")));
        };
        let Some(minv) = m.try_inverse() else {
            return Err(mesh.invalid(format!(
                "patch_fit: face {f}: every candidate patch is singular (nodes collinear or on a conic)"
            )));
        };
        if cond > MAX_CONDITION {
            warnings.push(format!(
                "patch_fit: face {f}: best patch {nodes:?} has condition number {cond_h} > {MAX_CONDITION_h}; used anyway"
            , cond_h = crate::math::human(cond), MAX_CONDITION_h = crate::math::human(MAX_CONDITION)));
        }
        // Cartesian weights: ∂xx R = 2 c3/ℓ², ∂xy R = c4/ℓ², ∂yy R = 2 c5/ℓ², c = M⁻¹ R.
        let l2 = ell * ell;
        let wc = SMat::<3, 6>::from_fn(|p, k| match p {
            0 => 2.0 * minv[(3, k)] / l2,
            1 => minv[(4, k)] / l2,
            _ => 2.0 * minv[(5, k)] / l2,
        });
        // Pull back to the face's frame: b_bary = Tᵀ B T with T = [e1 e2].
        let t = crate::rest::reference_frame(mesh, f);
        let (t00, t01, t10, t11) = (t[(0, 0)], t[(0, 1)], t[(1, 0)], t[(1, 1)]);
        let l = Mat3::new(
            t00 * t00,
            2.0 * t00 * t10,
            t10 * t10,
            t00 * t01,
            t00 * t11 + t10 * t01,
            t10 * t11,
            t01 * t01,
            2.0 * t01 * t11,
            t11 * t11,
        );
        patches.push(Patch {
            nodes,
            weights: l * wc,
            condition: cond,
        });
    }
    Ok((patches, warnings))
}
