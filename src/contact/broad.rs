//! The broad phase: every point–triangle and edge–edge pair of a surface whose primitives'
//! axis-aligned boxes, inflated by a radius, overlap — the candidates that the exact distance
//! then filters.
//!
//! A uniform grid: each face's (each edge's) box, inflated by the radius, is listed under every
//! cell it overlaps, in a table sorted by cell (and primitive, so the table is the same on any
//! thread count), with a hash index from each occupied cell to its rows; each vertex looks up the
//! one cell it lies in, each edge the cells its own box overlaps. The cell is twice the median
//! inflated box's longest side, at most the largest's (so a box of a mesh of even size spans at
//! most two or three cells per axis), doubled while the boxes would be listed under more than 16
//! cells each on average, and never finer than 2²⁰ cells per axis: a few large boxes (a coarse
//! obstacle's triangles beside a fine sheet) do not put every small one into one cell. Build and
//! queries are linear in the number of primitives for meshes of even size; the queries run in
//! parallel chunks of primitives, each primitive's results sorted, concatenated in primitive order.
//! The candidates do not depend on the cell or the thread count.
//!
//! Units: positions and radius m.

use crate::math::{Real, Vec3};
use rayon::prelude::*;

/// Primitives per parallel task of the grid's build and queries.
const CHUNK: usize = 256;

/// The results of `query(i, out)` for every primitive `i < n`, each primitive's sorted and
/// without repeats, concatenated in primitive order (the same on any thread count). The
/// primitives run in parallel chunks, each filling one list: a list per primitive would cost
/// an allocation each.
fn gather(n: usize, query: impl Fn(usize, &mut Vec<(u32, u32)>) + Sync) -> Vec<(u32, u32)> {
    let per: Vec<Vec<(u32, u32)>> = (0..n.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| {
            let (mut out, mut one) = (Vec::new(), Vec::new());
            for i in c * CHUNK..((c + 1) * CHUNK).min(n) {
                one.clear();
                query(i, &mut one);
                one.sort_unstable();
                one.dedup();
                out.extend_from_slice(&one);
            }
            out
        })
        .collect();
    per.concat()
}

/// Cells per axis at most (the key packs three 21-bit coordinates).
const MAX_CELLS: Real = (1u64 << 20) as Real;

/// An axis-aligned box.
#[derive(Clone, Copy, Debug)]
pub struct Aabb {
    min: Vec3,
    max: Vec3,
}

impl Aabb {
    fn of(points: impl Iterator<Item = Vec3>, inflate: Real) -> Aabb {
        let (mut min, mut max) = (Vec3::repeat(Real::INFINITY), Vec3::repeat(-Real::INFINITY));
        for p in points {
            min = min.inf(&p);
            max = max.sup(&p);
        }
        Aabb {
            min: min.add_scalar(-inflate),
            max: max.add_scalar(inflate),
        }
    }
    /// Whether the two boxes overlap (touching counts).
    #[inline]
    pub fn overlaps(&self, o: &Aabb) -> bool {
        (0..3).all(|k| self.min[k] <= o.max[k] && o.min[k] <= self.max[k])
    }
    #[cfg(test)]
    fn contains(&self, p: &Vec3) -> bool {
        (0..3).all(|k| self.min[k] <= p[k] && p[k] <= self.max[k])
    }
}

/// The grid: origin, cell size, the sorted (cell key, primitive) table, and an open-addressing
/// hash index from each occupied cell's key to its range of the table.
struct Grid {
    origin: Vec3,
    cell: Real,
    table: Vec<(u64, u32)>,
    /// `(key, start, end)` per slot, [`EMPTY`] keys for free slots; a power of two long.
    index: Vec<(u64, u32, u32)>,
}

/// The key of a free slot of [`Grid::index`] (cell keys have 63 bits).
const EMPTY: u64 = u64::MAX;

impl Grid {
    fn coord(&self, p: &Vec3) -> [u64; 3] {
        std::array::from_fn(|k| {
            // Truncation is the floor of a non-negative number (and `floor` is a library call
            // on the baseline x86-64 target).
            (((p[k] - self.origin[k]) / self.cell).max(0.0) as u64).min((1 << 21) - 1)
        })
    }
    fn key(c: [u64; 3]) -> u64 {
        (c[0] << 42) | (c[1] << 21) | c[2]
    }
    /// The grid over `boxes`, each listed under every cell it overlaps.
    fn new(boxes: &[Aabb]) -> Grid {
        let (mut lo, mut hi) = (Vec3::repeat(Real::INFINITY), Vec3::repeat(-Real::INFINITY));
        let mut sides: Vec<Real> = Vec::with_capacity(boxes.len());
        for b in boxes {
            lo = lo.inf(&b.min);
            hi = hi.sup(&b.max);
            sides.push((b.max - b.min).max());
        }
        let extent = (hi - lo).max();
        let largest = sides.iter().copied().fold(0.0, Real::max);
        let mid = sides.len() / 2;
        let median = *sides.select_nth_unstable_by(mid, Real::total_cmp).1;
        let floor = (extent / MAX_CELLS).max(Real::MIN_POSITIVE);
        // Twice the median box, so that a few large boxes (a coarse obstacle's triangles
        // beside a fine sheet) do not put every small one in the same cell; doubled while the
        // boxes would be listed in more than 16 cells each on average.
        let mut cell = largest.min(2.0 * median).max(floor);
        let budget = 16 * boxes.len() + (1 << 20);
        while cell < largest && Self::entries(boxes, lo, cell) > budget {
            cell *= 2.0;
        }
        let cell = cell.min(largest).max(floor);
        let mut g = Grid {
            origin: lo,
            cell,
            table: Vec::new(),
            index: Vec::new(),
        };
        // One list per chunk of boxes (not per box: the allocations cost more than the
        // listing); the sort below fixes the order.
        let per: Vec<Vec<(u64, u32)>> = boxes
            .par_chunks(CHUNK)
            .enumerate()
            .map(|(c, chunk)| {
                let mut out = Vec::with_capacity(4 * chunk.len());
                for (j, b) in chunk.iter().enumerate() {
                    g.cells(b, |k| out.push((k, (c * CHUNK + j) as u32)));
                }
                out
            })
            .collect();
        g.table = per.concat();
        // Rayon's sort pays only on large tables.
        if g.table.len() > 1 << 16 {
            g.table.par_sort_unstable();
        } else {
            g.table.sort_unstable();
        }
        g.index_cells();
        g
    }

    /// The slot of `key` in the index: its own, or the free one where it would go.
    #[inline]
    fn slot(&self, key: u64) -> usize {
        let mask = self.index.len() - 1;
        let mut i = (key.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 32) as usize & mask;
        while self.index[i].0 != key && self.index[i].0 != EMPTY {
            i = (i + 1) & mask;
        }
        i
    }

    /// Fills the index from the sorted table.
    fn index_cells(&mut self) {
        let cells = 1 + self.table.windows(2).filter(|w| w[0].0 != w[1].0).count();
        self.index = vec![(EMPTY, 0, 0); (2 * cells).next_power_of_two()];
        let mut start = 0;
        while start < self.table.len() {
            let key = self.table[start].0;
            let end = start + self.table[start..].partition_point(|e| e.0 == key);
            let i = self.slot(key);
            self.index[i] = (key, start as u32, end as u32);
            start = end;
        }
    }
    /// How many (cell, box) entries a grid of cell size `cell` from `origin` lists.
    fn entries(boxes: &[Aabb], origin: Vec3, cell: Real) -> usize {
        let span = |a: Real, b: Real, o: Real| {
            let at = |v: Real| ((v - o) / cell).max(0.0) as u64;
            (at(b).saturating_sub(at(a)) + 1) as Real
        };
        boxes
            .iter()
            .map(|b| {
                (0..3)
                    .map(|k| span(b.min[k], b.max[k], origin[k]))
                    .product::<Real>()
            })
            .sum::<Real>()
            .min(usize::MAX as Real) as usize
    }

    /// Calls `f` with the key of every cell `b` overlaps.
    fn cells(&self, b: &Aabb, mut f: impl FnMut(u64)) {
        let (a, z) = (self.coord(&b.min), self.coord(&b.max));
        for i in a[0]..=z[0] {
            for j in a[1]..=z[1] {
                for k in a[2]..=z[2] {
                    f(Self::key([i, j, k]));
                }
            }
        }
    }
    /// The primitives listed under cell `key`.
    fn at(&self, key: u64) -> &[(u64, u32)] {
        let (k, lo, hi) = self.index[self.slot(key)];
        if k == EMPTY {
            return &[];
        }
        &self.table[lo as usize..hi as usize]
    }
}

/// The box of the vertices `v` at `x` and, when given, at `to` (the end of a step: the box
/// then holds the straight paths from one to the other), inflated by `inflate`.
#[inline]
fn span(v: &[usize], x: &[Vec3], to: Option<&[Vec3]>, inflate: Real) -> Aabb {
    match to {
        None => Aabb::of(v.iter().map(|&i| x[i]), inflate),
        Some(t) => Aabb::of(
            v.iter().map(|&i| x[i]).chain(v.iter().map(|&i| t[i])),
            inflate,
        ),
    }
}

/// The boxes of the primitives `prims` (vertex lists) at `x` and, when given, `to`, inflated
/// by `radius`, as the queries below compute them: a pair is kept when the box of its face
/// (of its higher-numbered edge), inflated by the query's radius, overlaps that of its vertex
/// (of its lower-numbered edge), not inflated.
pub fn boxes<const N: usize>(
    prims: &[[usize; N]],
    x: &[Vec3],
    to: Option<&[Vec3]>,
    radius: Real,
) -> Vec<Aabb> {
    prims.par_iter().map(|p| span(p, x, to, radius)).collect()
}

/// Vertex `p` and face `f`, `p` not a vertex of `f`, whose boxes overlap, the face's inflated
/// by `radius`. The boxes hold the positions `x` and, when given, `to`: every pair that can
/// come within `radius` on the straight paths from one to the other. Sorted by vertex, then
/// face.
pub fn point_triangle(
    x: &[Vec3],
    to: Option<&[Vec3]>,
    faces: &[[usize; 3]],
    radius: Real,
) -> Vec<(u32, u32)> {
    point_triangle_where(x, to, faces, radius, |_, _| true)
}

/// [`point_triangle`], keeping only the pairs `(p, f)` for which `keep` holds (tested before
/// they are stored: a scene that wants only the pairs between two parts never holds the
/// others).
pub fn point_triangle_where(
    x: &[Vec3],
    to: Option<&[Vec3]>,
    faces: &[[usize; 3]],
    radius: Real,
    keep: impl Fn(u32, u32) -> bool + Sync,
) -> Vec<(u32, u32)> {
    if faces.is_empty() {
        return Vec::new();
    }
    let boxes: Vec<Aabb> = faces.par_iter().map(|f| span(f, x, to, radius)).collect();
    let grid = Grid::new(&boxes);
    gather(x.len(), |p, out| {
        let own = span(&[p], x, to, 0.0);
        grid.cells(&own, |k| {
            for &(_, f) in grid.at(k) {
                if !faces[f as usize].contains(&p)
                    && boxes[f as usize].overlaps(&own)
                    && keep(p as u32, f)
                {
                    out.push((p as u32, f));
                }
            }
        });
    })
}

/// Edge `e` and face `f` sharing no vertex whose boxes at `x` overlap: the candidates for an
/// edge crossing a face. Sorted by edge, then face.
pub fn edge_triangle(x: &[Vec3], edges: &[[usize; 2]], faces: &[[usize; 3]]) -> Vec<(u32, u32)> {
    if faces.is_empty() || edges.is_empty() {
        return Vec::new();
    }
    let boxes: Vec<Aabb> = faces.par_iter().map(|f| span(f, x, None, 0.0)).collect();
    let grid = Grid::new(&boxes);
    gather(edges.len(), |e, out| {
        let own = span(&edges[e], x, None, 0.0);
        grid.cells(&own, |k| {
            for &(_, f) in grid.at(k) {
                let face = &faces[f as usize];
                if !edges[e].iter().any(|v| face.contains(v)) && boxes[f as usize].overlaps(&own) {
                    out.push((e as u32, f));
                }
            }
        });
    })
}

/// Edge pairs `(a, b)`, `a < b`, sharing no vertex, whose boxes (one inflated by `radius`)
/// overlap, the boxes holding `x` and, when given, `to` as in [`point_triangle`]: sorted.
pub fn edge_edge(
    x: &[Vec3],
    to: Option<&[Vec3]>,
    edges: &[[usize; 2]],
    radius: Real,
) -> Vec<(u32, u32)> {
    edge_edge_where(x, to, edges, radius, |_, _| true)
}

/// [`edge_edge`], keeping only the pairs `(a, b)` for which `keep` holds (tested before they
/// are stored).
pub fn edge_edge_where(
    x: &[Vec3],
    to: Option<&[Vec3]>,
    edges: &[[usize; 2]],
    radius: Real,
    keep: impl Fn(u32, u32) -> bool + Sync,
) -> Vec<(u32, u32)> {
    if edges.is_empty() {
        return Vec::new();
    }
    let inflated: Vec<Aabb> = edges.par_iter().map(|e| span(e, x, to, radius)).collect();
    let grid = Grid::new(&inflated);
    gather(edges.len(), |a, out| {
        let own = span(&edges[a], x, to, 0.0);
        grid.cells(&own, |k| {
            for &(_, b) in grid.at(k) {
                let bu = b as usize;
                if bu > a
                    && !edges[bu].iter().any(|v| edges[a].contains(v))
                    && inflated[bu].overlaps(&own)
                    && keep(a as u32, b)
                {
                    out.push((a as u32, b));
                }
            }
        });
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::distance;

    /// A fine sheet of small triangles under two triangles a hundred times larger (a coarse
    /// obstacle): the cell follows the small ones, and the grid finds exactly what brute force
    /// finds.
    #[test]
    fn a_few_large_boxes_keep_the_cell_small_and_the_pairs_exact() {
        let n = 40;
        let mut x: Vec<Vec3> = (0..n * n)
            .map(|k| Vec3::new((k % n) as Real * 0.01, (k / n) as Real * 0.01, 0.0))
            .collect();
        let mut faces: Vec<[usize; 3]> = Vec::new();
        for i in 0..n - 1 {
            for j in 0..n - 1 {
                let a = j * n + i;
                faces.push([a, a + 1, a + n + 1]);
                faces.push([a, a + n + 1, a + n]);
            }
        }
        let base = x.len();
        for p in [[-1.0, -1.0], [2.0, -1.0], [2.0, 2.0], [-1.0, 2.0]] {
            x.push(Vec3::new(p[0], p[1], -0.003));
        }
        faces.push([base, base + 1, base + 2]);
        faces.push([base, base + 2, base + 3]);
        let r = 0.005;
        let boxes: Vec<Aabb> = faces
            .iter()
            .map(|f| Aabb::of(f.iter().map(|&v| x[v]), r))
            .collect();
        let grid = Grid::new(&boxes);
        assert!(grid.cell < 0.05, "cell {}", grid.cell);
        let mut brute = Vec::new();
        for (p, xp) in x.iter().enumerate() {
            for (f, b) in boxes.iter().enumerate() {
                if !faces[f].contains(&p) && b.contains(xp) {
                    brute.push((p as u32, f as u32));
                }
            }
        }
        assert_eq!(point_triangle(&x, None, &faces, r), brute);
        let edges: Vec<[usize; 2]> = faces
            .iter()
            .flat_map(|f| [[f[0], f[1]], [f[1], f[2]], [f[0], f[2]]])
            .collect();
        let mut brute = Vec::new();
        for a in 0..edges.len() {
            let own = Aabb::of(edges[a].iter().map(|&v| x[v]), 0.0);
            for b in a + 1..edges.len() {
                let ib = Aabb::of(edges[b].iter().map(|&v| x[v]), r);
                if !edges[b].iter().any(|v| edges[a].contains(v)) && ib.overlaps(&own) {
                    brute.push((a as u32, b as u32));
                }
            }
        }
        assert_eq!(edge_edge(&x, None, &edges, r), brute);
    }

    /// Two random triangle soups: the grid finds exactly the pairs a brute-force loop over all
    /// pairs finds with the same box test (so every pair within the radius is among them).
    #[test]
    fn the_grid_finds_what_brute_force_finds() {
        let mut seed = 0x853c49e6748fea9bu64;
        let mut rnd = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as Real / (1u64 << 53) as Real
        };
        let n = 300;
        let x: Vec<Vec3> = (0..n)
            .map(|_| Vec3::new(rnd(), rnd(), rnd() * 0.3))
            .collect();
        let faces: Vec<[usize; 3]> = (0..200)
            .map(|i| [i % n, (i * 7 + 3) % n, (i * 13 + 5) % n])
            .filter(|f| f[0] != f[1] && f[1] != f[2] && f[0] != f[2])
            .collect();
        let edges: Vec<[usize; 2]> = faces
            .iter()
            .flat_map(|f| [[f[0], f[1]], [f[1], f[2]]])
            .collect();
        let r = 0.03;
        let boxes: Vec<Aabb> = faces
            .iter()
            .map(|f| Aabb::of(f.iter().map(|&v| x[v]), r))
            .collect();
        let mut brute = Vec::new();
        for (p, xp) in x.iter().enumerate() {
            for (f, b) in boxes.iter().enumerate() {
                if !faces[f].contains(&p) && b.contains(xp) {
                    brute.push((p as u32, f as u32));
                }
            }
        }
        assert_eq!(point_triangle(&x, None, &faces, r), brute);
        // Every vertex–face pair within r is a candidate.
        for p in 0..n {
            for (f, t) in faces.iter().enumerate() {
                if t.contains(&p) {
                    continue;
                }
                let q = [x[p], x[t[0]], x[t[1]], x[t[2]]];
                if distance::point_triangle(&q).d2 < r * r {
                    assert!(brute.contains(&(p as u32, f as u32)));
                }
            }
        }
        let mut brute = Vec::new();
        for a in 0..edges.len() {
            let own = Aabb::of(edges[a].iter().map(|&v| x[v]), 0.0);
            for b in a + 1..edges.len() {
                let ib = Aabb::of(edges[b].iter().map(|&v| x[v]), r);
                if !edges[b].iter().any(|v| edges[a].contains(v)) && ib.overlaps(&own) {
                    brute.push((a as u32, b as u32));
                }
            }
        }
        assert_eq!(edge_edge(&x, None, &edges, r), brute);
        let mut brute = Vec::new();
        for (e, ed) in edges.iter().enumerate() {
            let own = Aabb::of(ed.iter().map(|&v| x[v]), 0.0);
            for (f, t) in faces.iter().enumerate() {
                let fb = Aabb::of(t.iter().map(|&v| x[v]), 0.0);
                if !ed.iter().any(|v| t.contains(v)) && fb.overlaps(&own) {
                    brute.push((e as u32, f as u32));
                }
            }
        }
        assert_eq!(edge_triangle(&x, &edges, &faces), brute);
        // Swept: the boxes hold both ends of a random motion.
        let to: Vec<Vec3> = x
            .iter()
            .map(|p| p + Vec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5) * 0.1)
            .collect();
        let sw = |v: &[usize], inflate: Real| {
            Aabb::of(
                v.iter().map(|&i| x[i]).chain(v.iter().map(|&i| to[i])),
                inflate,
            )
        };
        let mut brute = Vec::new();
        for p in 0..n {
            let own = sw(&[p], 0.0);
            for (f, t) in faces.iter().enumerate() {
                if !t.contains(&p) && sw(t, r).overlaps(&own) {
                    brute.push((p as u32, f as u32));
                }
            }
        }
        assert_eq!(point_triangle(&x, Some(&to), &faces, r), brute);
        let mut brute = Vec::new();
        for a in 0..edges.len() {
            let own = sw(&edges[a], 0.0);
            for b in a + 1..edges.len() {
                if !edges[b].iter().any(|v| edges[a].contains(v)) && sw(&edges[b], r).overlaps(&own)
                {
                    brute.push((a as u32, b as u32));
                }
            }
        }
        assert_eq!(edge_edge(&x, Some(&to), &edges, r), brute);
    }
}
