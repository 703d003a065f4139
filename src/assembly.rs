//! Global assembly of energy, gradient and sparse Hessian.
//!
//! The sparsity pattern (lower triangle, compressed sparse columns, 3 DOFs per vertex in the
//! order `x, y, z`) is built once per mesh from each face's 6-vertex stencil. Element kernels run
//! in parallel (rayon) over fixed-size chunks of faces into per-element buffers; the buffers are
//! then scattered serially in face order. No floating-point atomics, no per-thread accumulators:
//! results are bitwise identical for any number of threads.

use crate::energy::projection::{project, HessianProjection};
use crate::energy::shell::shell_face;
use crate::energy::KoiterDensity;
use crate::math::{Real, SMat, SVec, Vec3};
use crate::mesh::topology::NONE;
use rayon::prelude::*;

/// Faces per parallel chunk (fixed, so the evaluation order never depends on the threads).
const CHUNK: usize = 2048;

/// The Hessian's sparsity pattern and, per face, where its entries go.
#[derive(Clone, Debug)]
pub struct Pattern {
    /// Number of DOFs (3 × vertices).
    pub n: usize,
    /// CSC column pointers (lower triangle).
    pub col_ptr: Vec<usize>,
    /// CSC row indices.
    pub row_idx: Vec<usize>,
    /// Per face: vertex ids of its 18-DOF stencil `[v0, v1, v2, p0, p1, p2]` (`NONE` if absent).
    pub stencil: Vec<[usize; 6]>,
    /// Per face and slot pair (s, t) with `u_s > u_t`: rank of `u_s` among the neighbours of
    /// `u_t` with larger index.
    ranks: Vec<[u16; 36]>,
}

impl Pattern {
    /// Builds the pattern for faces and their opposite vertices.
    pub fn new(nv: usize, faces: &[[usize; 3]], opposite: &[[usize; 3]]) -> Pattern {
        let stencil: Vec<[usize; 6]> = faces
            .iter()
            .zip(opposite)
            .map(|(f, o)| [f[0], f[1], f[2], o[0], o[1], o[2]])
            .collect();
        let mut hi: Vec<Vec<usize>> = vec![Vec::new(); nv];
        for st in &stencil {
            for &u in st {
                for &v in st {
                    if u != NONE && v != NONE && u > v {
                        hi[v].push(u);
                    }
                }
            }
        }
        for h in &mut hi {
            h.sort_unstable();
            h.dedup();
        }
        let n = 3 * nv;
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut row_idx = Vec::new();
        col_ptr.push(0);
        for (v, hv) in hi.iter().enumerate() {
            for d in 0..3 {
                for c in d..3 {
                    row_idx.push(3 * v + c);
                }
                for &u in hv {
                    for c in 0..3 {
                        row_idx.push(3 * u + c);
                    }
                }
                col_ptr.push(row_idx.len());
            }
        }
        let ranks = stencil
            .iter()
            .map(|st| {
                let mut r = [0u16; 36];
                for s in 0..6 {
                    for t in 0..6 {
                        let (u, v) = (st[s], st[t]);
                        if u != NONE && v != NONE && u > v {
                            r[6 * s + t] = hi[v].binary_search(&u).unwrap_or(0) as u16;
                        }
                    }
                }
                r
            })
            .collect();
        Pattern {
            n,
            col_ptr,
            row_idx,
            stencil,
            ranks,
        }
    }

    /// Number of stored entries.
    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }

    /// Position of the diagonal entry of DOF `i`.
    #[inline]
    pub fn diag(&self, i: usize) -> usize {
        self.col_ptr[i]
    }

    /// Adds an element Hessian (lower parts) into `values`, skipping fixed vertices.
    #[inline]
    fn scatter_hessian(&self, f: usize, h: &SMat<18, 18>, fixed: &[bool], values: &mut [Real]) {
        let st = &self.stencil[f];
        let rk = &self.ranks[f];
        for t in 0..6 {
            let v = st[t];
            if v == NONE || fixed[v] {
                continue;
            }
            for s in 0..6 {
                let u = st[s];
                if u == NONE || fixed[u] || u < v {
                    continue;
                }
                for d in 0..3 {
                    let base = self.col_ptr[3 * v + d];
                    if u == v {
                        for c in d..3 {
                            values[base + c - d] += h[(3 * s + c, 3 * t + d)];
                        }
                    } else {
                        let off = base + (3 - d) + 3 * rk[6 * s + t] as usize;
                        for c in 0..3 {
                            values[off + c] += h[(3 * s + c, 3 * t + d)];
                        }
                    }
                }
            }
        }
    }
}

/// What to compute.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Want {
    /// Energy only.
    Energy,
    /// Energy and gradient.
    Gradient,
    /// Energy, gradient and Hessian.
    Hessian,
}

/// Per-face element evaluation: energy, and the local gradient and Hessian when wanted.
struct Local {
    e: Real,
    g: SVec<18>,
    h: SMat<18, 18>,
}

/// Assembles face terms. `density(f)` gives the face's energy density; `fixed` is per vertex.
/// Returns the total face energy; fills `grad` (len n) and `values` (len nnz) when wanted
/// (they are overwritten, not accumulated).
#[allow(clippy::too_many_arguments)]
pub fn assemble_faces<F>(
    pattern: &Pattern,
    x: &[Vec3],
    density: F,
    fixed: &[bool],
    projection: HessianProjection,
    want: Want,
    grad: &mut [Real],
    values: &mut [Real],
) -> Real
where
    F: Fn(usize) -> KoiterDensity + Sync,
{
    let nf = pattern.stencil.len();
    if want != Want::Energy {
        grad.fill(0.0);
    }
    if want == Want::Hessian {
        values.fill(0.0);
    }
    let mut total = 0.0;
    let mut buf: Vec<Local> = Vec::new();
    let mut start = 0;
    while start < nf {
        let end = (start + CHUNK).min(nf);
        if want == Want::Energy {
            let es: Vec<Real> = (start..end)
                .into_par_iter()
                .map(|f| {
                    let (xs, has) = gather(pattern, x, f);
                    shell_face(&xs, has, &density(f), None, None)
                })
                .collect();
            total += es.iter().sum::<Real>();
        } else {
            (start..end)
                .into_par_iter()
                .map(|f| {
                    let (xs, has) = gather(pattern, x, f);
                    let d = density(f);
                    let mut l = Local {
                        e: 0.0,
                        g: SVec::zeros(),
                        h: SMat::zeros(),
                    };
                    l.e = shell_face(
                        &xs,
                        has,
                        &d,
                        Some(&mut l.g),
                        (want == Want::Hessian).then_some(&mut l.h),
                    );
                    if want == Want::Hessian {
                        project(&mut l.h, projection);
                    }
                    l
                })
                .collect_into_vec(&mut buf);
            for (k, l) in buf.iter().enumerate() {
                let f = start + k;
                total += l.e;
                for (s, &u) in pattern.stencil[f].iter().enumerate() {
                    if u == NONE || fixed[u] {
                        continue;
                    }
                    for c in 0..3 {
                        grad[3 * u + c] += l.g[3 * s + c];
                    }
                }
                if want == Want::Hessian {
                    pattern.scatter_hessian(f, &l.h, fixed, values);
                }
            }
        }
        start = end;
    }
    total
}

/// The face's 6 stencil positions (absent neighbours get the face's own first vertex, unused).
#[inline]
fn gather(pattern: &Pattern, x: &[Vec3], f: usize) -> ([Vec3; 6], [bool; 3]) {
    let st = &pattern.stencil[f];
    let has = [st[3] != NONE, st[4] != NONE, st[5] != NONE];
    let xs = std::array::from_fn(|s| if st[s] == NONE { x[st[0]] } else { x[st[s]] });
    (xs, has)
}
