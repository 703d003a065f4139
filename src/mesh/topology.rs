//! Mesh connectivity, built once per mesh: edges, edge–face adjacency, each face's three
//! neighbours across its edges and the vertices opposite those edges, and boundary flags.
//!
//! Convention (seed 000 §3): edge `i` of face `[v0, v1, v2]` is the edge *opposite* vertex `i`,
//! i.e. it joins `v[(i+1)%3]` and `v[(i+2)%3]`.

use super::{Mesh, MeshError};
use std::collections::HashMap;

/// Sentinel for "no face / no vertex" across a boundary edge.
pub const NONE: usize = usize::MAX;

/// Connectivity of a valid, manifold, consistently oriented triangle mesh.
#[derive(Clone, Debug)]
pub struct Topology {
    /// Unique edges as sorted vertex pairs.
    pub edges: Vec<[usize; 2]>,
    /// The one or two faces incident on each edge (`NONE` for the missing second face).
    pub edge_faces: Vec<[usize; 2]>,
    /// For each face, the edge index opposite each of its vertices.
    pub face_edges: Vec<[usize; 3]>,
    /// For each face, the neighbouring face across the edge opposite vertex `i` (or `NONE`).
    pub face_neighbors: Vec<[usize; 3]>,
    /// For each face, the vertex of that neighbour that is not on the shared edge (or `NONE`).
    pub opposite_vertex: Vec<[usize; 3]>,
    /// True for vertices on the boundary.
    pub boundary_vertex: Vec<bool>,
}

impl Topology {
    /// Builds the connectivity and rejects non-manifold edges and vertices, duplicate faces and
    /// inconsistent orientation, naming the offending faces or vertex.
    pub fn build(mesh: &Mesh) -> Result<Self, MeshError> {
        let nv = mesh.positions.len();
        let nf = mesh.faces.len();
        let mut face_keys: HashMap<[usize; 3], usize> = HashMap::with_capacity(nf);
        for (fi, f) in mesh.faces.iter().enumerate() {
            let mut key = *f;
            key.sort_unstable();
            if let Some(&other) = face_keys.get(&key) {
                return Err(mesh.invalid(format!(
                    "faces {other} and {fi} are duplicates (vertices {key:?})"
                )));
            }
            face_keys.insert(key, fi);
        }
        let mut edge_index: HashMap<[usize; 2], usize> = HashMap::with_capacity(3 * nf / 2 + 8);
        let mut edges = Vec::with_capacity(3 * nf / 2 + 8);
        let mut edge_faces: Vec<[usize; 2]> = Vec::with_capacity(3 * nf / 2 + 8);
        // Direction in which the first face traverses the edge, to check orientation.
        let mut edge_dir: Vec<[usize; 2]> = Vec::with_capacity(3 * nf / 2 + 8);
        let mut face_edges = vec![[NONE; 3]; nf];
        for (fi, f) in mesh.faces.iter().enumerate() {
            for i in 0..3 {
                let a = f[(i + 1) % 3];
                let b = f[(i + 2) % 3];
                let key = if a < b { [a, b] } else { [b, a] };
                let e = *edge_index.entry(key).or_insert_with(|| {
                    edges.push(key);
                    edge_faces.push([NONE, NONE]);
                    edge_dir.push([a, b]);
                    edges.len() - 1
                });
                let ef = &mut edge_faces[e];
                if ef[0] == NONE {
                    ef[0] = fi;
                } else if ef[1] == NONE {
                    if edge_dir[e] == [a, b] {
                        return Err(mesh.invalid(format!(
                            "faces {} and {fi} traverse their shared edge ({a}, {b}) in the same \
                             direction: the mesh is not consistently oriented (reorient the faces \
                             so that neighbours agree)",
                            ef[0]
                        )));
                    }
                    ef[1] = fi;
                } else {
                    return Err(mesh.invalid(format!(
                        "edge ({}, {}) is non-manifold: shared by faces {}, {} and {fi}",
                        key[0], key[1], ef[0], ef[1]
                    )));
                }
                face_edges[fi][i] = e;
            }
        }
        let mut face_neighbors = vec![[NONE; 3]; nf];
        let mut opposite_vertex = vec![[NONE; 3]; nf];
        let mut boundary_vertex = vec![false; nv];
        for fi in 0..nf {
            for i in 0..3 {
                let e = face_edges[fi][i];
                let [f0, f1] = edge_faces[e];
                let g = if f0 == fi { f1 } else { f0 };
                if g == NONE {
                    boundary_vertex[edges[e][0]] = true;
                    boundary_vertex[edges[e][1]] = true;
                    continue;
                }
                face_neighbors[fi][i] = g;
                let [p, q] = edges[e];
                opposite_vertex[fi][i] = mesh.faces[g]
                    .iter()
                    .copied()
                    .find(|&v| v != p && v != q)
                    .unwrap_or(NONE);
            }
        }
        let topo = Topology {
            edges,
            edge_faces,
            face_edges,
            face_neighbors,
            opposite_vertex,
            boundary_vertex,
        };
        topo.check_vertex_manifold(mesh)?;
        Ok(topo)
    }

    /// Each vertex's faces must form a single fan (a disk or half-disk). Counts the fan's
    /// connected components through shared interior edges.
    fn check_vertex_manifold(&self, mesh: &Mesh) -> Result<(), MeshError> {
        let nv = mesh.positions.len();
        let mut vf: Vec<Vec<usize>> = vec![Vec::new(); nv];
        for (fi, f) in mesh.faces.iter().enumerate() {
            for &v in f {
                vf[v].push(fi);
            }
        }
        let mut stack = Vec::new();
        let mut seen: HashMap<usize, bool> = HashMap::new();
        for (v, faces) in vf.iter().enumerate() {
            if faces.len() < 2 {
                continue;
            }
            seen.clear();
            for &f in faces {
                seen.insert(f, false);
            }
            stack.clear();
            stack.push(faces[0]);
            seen.insert(faces[0], true);
            let mut reached = 1;
            while let Some(f) = stack.pop() {
                for i in 0..3 {
                    let g = self.face_neighbors[f][i];
                    // Only edges through v connect the fan: edge i contains v iff vertex i != v.
                    if g == NONE || mesh.faces[f][i] == v {
                        continue;
                    }
                    if let Some(s) = seen.get_mut(&g) {
                        if !*s {
                            *s = true;
                            reached += 1;
                            stack.push(g);
                        }
                    }
                }
            }
            if reached != faces.len() {
                return Err(mesh.invalid(format!(
                    "vertex {v} is non-manifold: its {} faces form more than one fan",
                    faces.len()
                )));
            }
        }
        Ok(())
    }

    /// Number of edges.
    pub fn num_edges(&self) -> usize {
        self.edges.len()
    }

    /// The connected piece of each face (faces sharing an edge are connected; the pieces
    /// numbered in the order of their first face), and the number of pieces.
    pub fn face_pieces(&self) -> (Vec<usize>, usize) {
        let nf = self.face_neighbors.len();
        let mut piece = vec![usize::MAX; nf];
        let mut count = 0;
        let mut stack = Vec::new();
        for start in 0..nf {
            if piece[start] != usize::MAX {
                continue;
            }
            piece[start] = count;
            stack.push(start);
            while let Some(f) = stack.pop() {
                for &g in &self.face_neighbors[f] {
                    if g != NONE && piece[g] == usize::MAX {
                        piece[g] = count;
                        stack.push(g);
                    }
                }
            }
            count += 1;
        }
        (piece, count)
    }
}
