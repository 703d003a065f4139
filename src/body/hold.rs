//! What the supports hold, per vertex: components along the coordinate axes (pinned DOFs) or
//! along other directions (oblique symmetry planes, the automatic rigid pins), the rigid motions
//! they leave free, and the statically determinate pins that remove those in statics.
//!
//! A vertex held along the orthonormal directions `N` (one to three columns) moves only in the
//! range of the projector `P = I − N Nᵀ`. The solver applies it to the vertex's gradient block
//! and to the Hessian's rows and columns of the vertex (`H ← T H T + s N Nᵀ`, `T` block diagonal
//! with `P` at held vertices and `I` elsewhere, `s` the mean diagonal): the held directions then
//! decouple with a positive pivot and a zero right-hand side, as a pinned DOF does.

use super::SupportGroup;
use crate::math::{Mat3, Real, SMat, SVec, Vec3};
use crate::mesh::Mesh;

/// A vertex held along directions that are not all coordinate axes.
#[derive(Clone, Debug, PartialEq)]
pub struct Skew {
    /// The vertex.
    pub vertex: usize,
    /// The projector `P = I − N Nᵀ` onto the directions the vertex may move in.
    pub free: Mat3,
}

/// A rigid motion of the sheet, `u(x) = t + ω × (x − c) / L` with `c` the centroid of the
/// used vertices and `L` the bounding-box diagonal ([`RigidModes`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RigidMode {
    /// Translation `t` (unit-free; modes are orthonormal in `(t, ω)`).
    pub t: Vec3,
    /// Rotation `ω`.
    pub w: Vec3,
}

/// The rigid motions that the supports leave free (orthonormal in `(t, ω)`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RigidModes {
    /// The centroid `c` of the used vertices (m).
    pub centre: Vec3,
    /// The length `L` that makes rotations commensurate with translations (m).
    pub length: Real,
    /// The free motions.
    pub modes: Vec<RigidMode>,
}

/// One held direction at a vertex: unit direction and the index of the support that holds it.
pub type Held = (Vec3, usize);

/// The row of a held direction `d` at position `p` against the rigid motions `(t, ω)`:
/// `d · (t + ω × r / L) = [d, r × d / L] · (t, ω)`, `r = p − c`.
fn row(d: Vec3, p: Vec3, c: Vec3, l: Real) -> SVec<6> {
    let m = (p - c).cross(&d) / l;
    SVec::<6>::from_column_slice(&[d[0], d[1], d[2], m[0], m[1], m[2]])
}

/// The rigid motions of `mesh` that no held vertex (`fixed`), held component (`comp`) or held
/// direction (`dirs`) resists: the null space of `G = Σ a aᵀ` over the rows `a` of every held
/// direction (eigenvalues below 1e-10 of the largest). With `translations_only`, only the
/// translations among them (the null space of G's translation block). Summed in vertex order,
/// so the result does not depend on the thread count.
pub fn free_modes(
    mesh: &Mesh,
    used: &[bool],
    fixed: &[bool],
    comp: &[[bool; 3]],
    dirs: &[Vec<Held>],
    translations_only: bool,
) -> RigidModes {
    let p = &mesh.positions;
    let n_used = used.iter().filter(|&&u| u).count();
    if n_used == 0 {
        return RigidModes::default();
    }
    let c = (0..p.len())
        .filter(|&v| used[v])
        .map(|v| p[v])
        .sum::<Vec3>()
        / n_used as Real;
    let l = mesh.bbox_diagonal().max(Real::MIN_POSITIVE);
    let mut g = SMat::<6, 6>::zeros();
    for v in (0..p.len()).filter(|&v| used[v]) {
        let mut add = |d: Vec3| {
            let a = row(d, p[v], c, l);
            g += a * a.transpose();
        };
        for (k, &held) in comp[v].iter().enumerate() {
            if fixed[v] || held {
                add(Vec3::ith(k, 1.0));
            }
        }
        if !fixed[v] {
            for &(d, _) in &dirs[v] {
                add(d);
            }
        }
    }
    let k = if translations_only { 3 } else { 6 };
    let gk = nalgebra::DMatrix::from_fn(k, k, |i, j| g[(i, j)]);
    let modes = null_space(gk)
        .into_iter()
        .map(|z| RigidMode {
            t: Vec3::new(z[0], z[1], z[2]),
            w: if k == 6 {
                Vec3::new(z[3], z[4], z[5])
            } else {
                Vec3::zeros()
            },
        })
        .collect();
    RigidModes {
        centre: c,
        length: l,
        modes,
    }
}

/// The eigenvectors of the symmetric `g` whose eigenvalues are below 1e-10 of the largest (or
/// all of them when `g` is zero), smallest eigenvalue first.
fn null_space(g: nalgebra::DMatrix<Real>) -> Vec<Vec<Real>> {
    let n = g.nrows();
    let eig = nalgebra::SymmetricEigen::new(g);
    let top = eig
        .eigenvalues
        .iter()
        .fold(0.0, |m: Real, &e| m.max(e.abs()));
    let mut out: Vec<(Real, Vec<Real>)> = (0..n)
        .filter(|&i| top == 0.0 || eig.eigenvalues[i] <= 1e-10 * top)
        .map(|i| {
            (
                eig.eigenvalues[i],
                eig.eigenvectors.column(i).iter().copied().collect(),
            )
        })
        .collect();
    out.sort_by(|a, b| a.0.total_cmp(&b.0));
    out.into_iter().map(|(_, z)| z).collect()
}

/// Statically determinate pins that remove the free rigid motions `modes`: a generalised
/// 3-2-1 support. A is the free vertex nearest the centroid, B the one farthest from A, C the
/// one farthest from the line AB, `n̂` the normal of ABC and `û = n̂ × AB/|AB|`. The candidates,
/// in order, are A along x, y and z; B along `n̂` and `û` (B stays on the line A₀B₀); C along
/// `n̂` (C stays in the plane A₀B₀C₀); then B along AB and C along the axes as fall-backs. Each
/// candidate is kept when its row, restricted to the free motions, is independent of those
/// kept before (a residual above 1e-3 of its norm), until every free motion is held.
///
/// The pins hold one representative of the free rigid motions and carry no reaction: at an
/// equilibrium of a scene whose energy the free motions leave unchanged, the reaction
/// `Σ λᵢ aᵢ` does no work on any free motion, and the rows restricted to them are independent,
/// so every λᵢ is zero. Along these directions a uniform expansion or contraction about A
/// needs no rotation to meet them, so they stay compatible with the inflating balloon or the
/// shrinking sheet however far it goes. Returns (vertex, unit direction) pairs; empty when no
/// motion is free or fewer than three vertices are free.
pub fn rigid_pins(mesh: &Mesh, free: &[bool], modes: &RigidModes) -> Vec<(usize, Vec3)> {
    let m = modes.modes.len();
    let cand: Vec<usize> = (0..free.len()).filter(|&v| free[v]).collect();
    if m == 0 || cand.len() < 3 {
        return Vec::new();
    }
    let p = &mesh.positions;
    let c = cand.iter().map(|&v| p[v]).sum::<Vec3>() / cand.len() as Real;
    let by = |f: &dyn Fn(usize) -> Real| {
        cand.iter()
            .copied()
            .max_by(|&u, &v| f(u).total_cmp(&f(v)).then(v.cmp(&u)))
            .unwrap_or(cand[0])
    };
    let a = by(&|v| -(p[v] - c).norm());
    let b = by(&|v| (p[v] - p[a]).norm());
    let ab = p[b] - p[a];
    let cc = by(&|v| ab.cross(&(p[v] - p[a])).norm());
    let n = ab.cross(&(p[cc] - p[a]));
    if ab.norm() == 0.0 || n.norm() <= 1e-12 * ab.norm_squared() {
        return Vec::new();
    }
    let (n, abu) = (n.normalize(), ab.normalize());
    let u = n.cross(&abu);
    let ax = |k: usize| Vec3::ith(k, 1.0);
    let candidates = [
        (a, ax(0)),
        (a, ax(1)),
        (a, ax(2)),
        (b, n),
        (b, u),
        (cc, n),
        (b, abu),
        (cc, ax(0)),
        (cc, ax(1)),
        (cc, ax(2)),
    ];
    let mut kept: Vec<(usize, Vec3)> = Vec::new();
    let mut basis: Vec<Vec<Real>> = Vec::new();
    for (v, d) in candidates {
        if kept.len() == m {
            break;
        }
        let r = row(d, p[v], modes.centre, modes.length);
        // The row against each free motion.
        let mut q: Vec<Real> = modes
            .modes
            .iter()
            .map(|md| r.fixed_rows::<3>(0).dot(&md.t) + r.fixed_rows::<3>(3).dot(&md.w))
            .collect();
        let norm = r.norm();
        for e in &basis {
            let s: Real = q.iter().zip(e).map(|(x, y)| x * y).sum();
            q.iter_mut().zip(e).for_each(|(x, y)| *x -= s * y);
        }
        let res = q.iter().map(|x| x * x).sum::<Real>().sqrt();
        if res > 1e-3 * norm {
            basis.push(q.iter().map(|x| x / res).collect());
            kept.push((v, d));
        }
    }
    kept
}

/// The held DOFs after every support and pin is known.
pub struct Final {
    /// Coordinate components held at vertices held along no other direction (`3v + k`), sorted.
    pub pinned_dofs: Vec<usize>,
    /// Vertices held along directions that are not all coordinate axes, ascending.
    pub skew: Vec<Skew>,
}

/// Splits the held components and directions of the vertices not `fixed` into pinned DOFs and
/// [`Skew`] vertices. A vertex with a held direction off the axes becomes a skew vertex with
/// every constraint it has: its held components move from their supports' DOFs to their
/// directions ([`SupportGroup::directions`]), and a direction in the span of those before it
/// (a plane held twice) is dropped. Directions at fixed vertices are dropped: the support that
/// fixes the vertex carries its reaction.
pub fn finalise(
    fixed: &[bool],
    comp: &[[bool; 3]],
    dirs: &[Vec<Held>],
    groups: &mut [SupportGroup],
) -> Final {
    let nv = fixed.len();
    let mut pinned_dofs = Vec::new();
    let mut skew = Vec::new();
    for g in groups.iter_mut() {
        g.directions.retain(|&(v, _)| !fixed[v]);
    }
    for v in (0..nv).filter(|&v| !fixed[v]) {
        if dirs[v].is_empty() {
            pinned_dofs.extend((0..3).filter(|&k| comp[v][k]).map(|k| 3 * v + k));
            continue;
        }
        // Every held direction at v, with its support: the components first.
        let mut all: Vec<Held> = Vec::new();
        for k in (0..3).filter(|&k| comp[v][k]) {
            let d = 3 * v + k;
            if let Some(gi) = groups.iter().position(|g| g.dofs.binary_search(&d).is_ok()) {
                groups[gi].dofs.retain(|&x| x != d);
                all.push((Vec3::ith(k, 1.0), gi));
            }
        }
        all.extend(dirs[v].iter().copied());
        for g in groups.iter_mut() {
            g.directions.retain(|&(u, _)| u != v);
        }
        let mut q: Vec<Vec3> = Vec::new();
        for (d, gi) in all {
            let mut r = d;
            for e in &q {
                r -= e * e.dot(&r);
            }
            if r.norm() > 1e-6 && q.len() < 3 {
                q.push(r.normalize());
                groups[gi].directions.push((v, d));
            }
        }
        let free = Mat3::identity() - q.iter().map(|e| e * e.transpose()).sum::<Mat3>();
        skew.push(Skew { vertex: v, free });
    }
    pinned_dofs.sort_unstable();
    Final { pinned_dofs, skew }
}

/// Splits the reaction `r` at a skew vertex (in the span of its held directions) among the
/// directions `d` that hold it: `r = Σ λᵢ dᵢ`, `λ = (DᵀD)⁻¹ Dᵀ r`. Returns `λᵢ dᵢ` per
/// direction.
pub fn split_reaction(r: Vec3, d: &[Vec3]) -> Vec<Vec3> {
    let k = d.len();
    let mut g = nalgebra::DMatrix::<Real>::zeros(k, k);
    let mut b = nalgebra::DVector::<Real>::zeros(k);
    for i in 0..k {
        b[i] = d[i].dot(&r);
        for j in 0..k {
            g[(i, j)] = d[i].dot(&d[j]);
        }
    }
    match g.lu().solve(&b) {
        Some(l) => (0..k).map(|i| d[i] * l[i]).collect(),
        None => vec![Vec3::zeros(); k],
    }
}
