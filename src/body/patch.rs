//! MorphoShell's quadratic patches (seed 001 §2): per face, 3 nearby nodes and the barycentric
//! weights that give the fitted quadratic's second derivatives, found once on the flat
//! reference mesh. The bending kernel that uses them is [`crate::energy::patch`].

use crate::geometry::UnitNormal;
use crate::math::{Mat3, Real, SMat, Sym2, Vec3};

/// Barycentric patch weights `Ŵ` (rows: b11, b12, b22; columns: the 6 stencil nodes), 1/m².
pub type PatchWeights = SMat<3, 6>;

/// Patch-fit second fundamental form of one face (barycentric, m).
pub fn patch_b(x: &[Vec3; 6], w: &PatchWeights) -> Sym2 {
    let n = UnitNormal::new(&[x[0], x[1], x[2]]).n;
    Sym2::from_fn(|q, _| -n.dot(&(0..6).map(|k| x[k] * w[(q, k)]).sum::<Vec3>()))
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
