//! A distributed moment along a boundary (`[[loads.moment]]`), conservative.
//!
//! The moment `m` (N·m per unit length) acts on the boundary edges whose two vertices are
//! selected, about each edge's *reference* direction `t⁰` (a fixed axis, so the moment is
//! conservative). The boundary face `f` of edge `e` turns about `t⁰` by
//!
//! `θ_e = θ_e⁰ + atan2(−o⁰·A, n⁰·A)`, `A = (x₁ − x₀) × (x₂ − x₀)` (the face's area normal),
//!
//! counted positive when the face's outward direction tilts toward the side its normal points
//! to. `n⁰` (the face normal projected normal to `t⁰`) and `o⁰ = ±t⁰ × n⁰` (outward) are taken
//! at the last accepted state, whose accumulated angle is `θ_e⁰`
//! ([`crate::energy::term::Term::accept`] updates them after every accepted step, and a step
//! that turns an edge by more than π/2 is cut). So the angle is single-valued within a solve
//! and continues through full turns across steps: a strip can be rolled into a full circle.
//! Measuring the turn through the face normal makes it blind, to first order, to twisting about
//! any axis normal to `t⁰` (a vector within the face would pick up twist).
//!
//! **Energy.** Without edge DOFs the boundary's director is the face normal:
//! `E = −s m Σ_e ℓ⁰_e θ_e` (J), `ℓ⁰` the reference edge length, `s` the dial. With edge DOFs
//! the director turns further by the edge DOF's tilt `σ_e φ_e` (outward, see
//! [`crate::energy::midedge_angle`]), which rotates it the opposite way in θ's sense:
//! `E = −s m Σ_e ℓ⁰_e (θ_e − σ_e φ_e)`. The boundary's natural condition is then that the
//! bending moment equals `m`.
//!
//! **Derivatives.** With `p = n⁰·A`, `q = −o⁰·A`, `r² = p² + q²`:
//! `g = ∇_A θ = (−p o⁰ − q n⁰)/r²`,
//! `∇²_A θ = [(q² − p²)(−o⁰n⁰ᵀ − n⁰o⁰ᵀ) + 2pq(n⁰n⁰ᵀ − o⁰o⁰ᵀ)]/r⁴`;
//! `∂A/∂x₀ = [x₂ − x₁]×` (cyclically), and `Σ_c g_c ∂²A_c/∂x_a∂x_b = −[g]×` for
//! `(a, b) = (0, 1), (1, 2), (2, 0)` and its transpose for the reverse pairs.
//!
//! DOF order (10 local): the face's `x[v0], x[v1], x[v2]`, then the edge's DOF `φ_e` (unused
//! without edge DOFs). Units: m in N·m/m, E in J, gradient N and N·m.

use super::select_vertices;
use crate::energy::term::{ElementKernel, Stencil, Term};
use crate::math::{skew, Mat3, Real, SMat, SVec, Vec3};
use crate::mesh::topology::NONE;
use crate::mesh::MeshError;
use crate::scene::Scene;
use crate::solve::Potential;
use std::sync::Mutex;

/// One loaded boundary edge.
#[derive(Clone, Copy, Debug)]
struct Edge {
    /// Nodes: the face's vertices in face order, then the edge node.
    nodes: [usize; 4],
    /// `m ℓ⁰` (N·m).
    weight: Real,
    /// The face's orientation sign on the edge.
    sigma: Real,
}

/// The reference frame of one edge's angle: `o`, `n` span the plane normal to the edge's
/// reference tangent `t⁰`.
#[derive(Clone, Copy, Debug)]
struct Frame {
    o: Vec3,
    n: Vec3,
    t0: Vec3,
    theta: Real,
}

/// The moment kernel with its per-edge frames.
pub struct Moment {
    edges: Vec<Edge>,
    frames: Mutex<Vec<Frame>>,
}

/// The face's area normal `A` at positions `x`.
fn area(x: &[Vec3], e: &Edge) -> Vec3 {
    let [a, b, c, _] = e.nodes;
    (x[b] - x[a]).cross(&(x[c] - x[a]))
}

impl Moment {
    /// `(θ, p, q)` for area normal `a`.
    fn angle(&self, f: &Frame, a: &Vec3) -> (Real, Real, Real) {
        let (p, q) = (f.n.dot(a), -f.o.dot(a));
        (f.theta + q.atan2(p), p, q)
    }
}

impl ElementKernel<10, 4> for Moment {
    fn eval(
        &self,
        pot: &Potential,
        e: usize,
        nodes: &[usize],
        x: &[Vec3],
        phi: &[Real],
        gauss_newton: bool,
        grad: Option<&mut SVec<10>>,
        hess: Option<&mut SMat<10, 10>>,
    ) -> Real {
        let edge = &self.edges[e];
        let f = self.frames.lock().map(|fr| fr[e]).unwrap_or(Frame {
            o: Vec3::x(),
            n: Vec3::z(),
            t0: Vec3::y(),
            theta: 0.0,
        });
        let xs = [x[nodes[0]], x[nodes[1]], x[nodes[2]]];
        let a = (xs[1] - xs[0]).cross(&(xs[2] - xs[0]));
        let (theta, p, q) = self.angle(&f, &a);
        let w = -pot.dial * edge.weight;
        let nv = pot.scene.num_vertices();
        let tilt = if nodes[3] != NONE {
            edge.sigma * phi[nodes[3] - nv]
        } else {
            0.0
        };
        let r2 = p * p + q * q;
        let ga = (-f.o * p - f.n * q) / r2;
        // ∂A/∂x_a = [x_{a+2} − x_{a+1}]×.
        let da: [Mat3; 3] = std::array::from_fn(|v| skew(&(xs[(v + 2) % 3] - xs[(v + 1) % 3])));
        if let Some(g) = grad {
            for (v, d) in da.iter().enumerate() {
                g.fixed_rows_mut::<3>(3 * v)
                    .copy_from(&(d.transpose() * ga * w));
            }
            g[9] = if nodes[3] != NONE {
                -w * edge.sigma
            } else {
                0.0
            };
        }
        if let Some(h) = hess {
            h.fill(0.0);
            if gauss_newton {
                // The Gauss–Newton Hessian of a rotation's work is 0 (its curvature is all
                // second-order geometry, like the shell's dropped terms).
                return w * (theta - tilt);
            }
            let on: Mat3 = f.o * f.n.transpose();
            let nn: Mat3 = f.n * f.n.transpose();
            let oo: Mat3 = f.o * f.o.transpose();
            let haa =
                (-(on + on.transpose()) * (q * q - p * p) + (nn - oo) * (2.0 * p * q)) / (r2 * r2);
            let sg = skew(&ga);
            for a in 0..3 {
                for b in 0..3 {
                    let mut blk = da[a].transpose() * haa * da[b];
                    if b == (a + 1) % 3 {
                        blk -= sg;
                    } else if a == (b + 1) % 3 {
                        blk += sg;
                    }
                    h.fixed_view_mut::<3, 3>(3 * a, 3 * b).copy_from(&(blk * w));
                }
            }
        }
        w * (theta - tilt)
    }
}

/// The moment term: accumulates each edge's angle after every accepted step.
pub struct MomentTerm(Moment);

impl Term for MomentTerm {
    fn name(&self) -> &'static str {
        "moment"
    }
    fn stencil(&self, scene: &Scene) -> Stencil {
        let p = &scene.mesh.positions;
        let has_edges = scene.has_edge_dofs();
        Stencil {
            slot_dofs: vec![3, 3, 3, 1],
            nodes: self
                .0
                .edges
                .iter()
                .flat_map(|e| {
                    let mut n = e.nodes;
                    if !has_edges {
                        n[3] = NONE;
                    }
                    n
                })
                .collect(),
            anchors: self
                .0
                .edges
                .iter()
                .map(|e| (p[e.nodes[0]] + p[e.nodes[1]] + p[e.nodes[2]]) / 3.0)
                .collect(),
        }
    }
    fn eval(
        &self,
        pot: &Potential,
        map: &crate::assembly::ElementMap,
        x: &[Vec3],
        phi: &[Real],
        want: crate::assembly::Want,
        projection: crate::energy::HessianProjection,
        grad: &mut [Real],
        values: &mut [Real],
    ) -> Real {
        crate::assembly::assemble_elements::<10, 4, _>(
            map,
            |e, nodes, g, h| {
                let gn = projection == crate::energy::HessianProjection::GaussNewton;
                self.0.eval(pot, e, nodes, x, phi, gn, g, h)
            },
            &pot.scene.node_fixed,
            projection,
            want,
            grad,
            values,
            &pot.pattern.col_ptr,
        )
    }
    fn accept(&self, x: &[Vec3], _: &[Real]) {
        if let Ok(mut frames) = self.0.frames.lock() {
            for (e, f) in self.0.edges.iter().zip(frames.iter_mut()) {
                let a = area(x, e);
                let (theta, _, _) = self.0.angle(f, &a);
                let n = (a - f.t0 * f.t0.dot(&a)).normalize();
                let o = f.t0.cross(&n);
                let o = if o.dot(&f.o) < 0.0 { -o } else { o };
                *f = Frame {
                    o,
                    n,
                    t0: f.t0,
                    theta,
                };
            }
        }
    }
    /// Each edge's angle may change by at most π/2 per step, well inside the atan2 branch.
    fn admissible(&self, x: &[Vec3], _: &[Real]) -> bool {
        let Ok(frames) = self.0.frames.lock() else {
            return false;
        };
        self.0.edges.iter().zip(frames.iter()).all(|(e, f)| {
            (self.0.angle(f, &area(x, e)).0 - f.theta).abs() <= std::f64::consts::FRAC_PI_2
        })
    }
    fn observables(&self, _: &Potential, x: &[Vec3], _: &[Real]) -> Vec<(String, Real)> {
        let Ok(frames) = self.0.frames.lock() else {
            return Vec::new();
        };
        let mut sum = 0.0;
        for (e, f) in self.0.edges.iter().zip(frames.iter()) {
            sum += self.0.angle(f, &area(x, e)).0;
        }
        vec![("moment_rotation".into(), sum / self.0.edges.len() as Real)]
    }
}

/// The moment term of a scene (`None` without moments).
pub fn term(scene: &Scene) -> Result<Option<Box<dyn Term>>, MeshError> {
    let loads = &scene.settings.loads.moment;
    if loads.is_empty() {
        return Ok(None);
    }
    let mesh = &scene.mesh;
    let topo = &scene.topo;
    let nv = scene.num_vertices();
    let mut edges = Vec::new();
    let mut frames = Vec::new();
    for (li, l) in loads.iter().enumerate() {
        let what = format!("loads.moment[{li}]");
        let mut on = vec![false; nv];
        for v in select_vertices(mesh, &l.on, &what)? {
            on[v] = true;
        }
        let before = edges.len();
        for (e, ends) in topo.edges.iter().enumerate() {
            let [f, g] = topo.edge_faces[e];
            if g != NONE || !(on[ends[0]] && on[ends[1]]) {
                continue;
            }
            let face = mesh.faces[f];
            // The vertex opposite the edge.
            let slot = (0..3)
                .find(|&s| face[s] != ends[0] && face[s] != ends[1])
                .unwrap_or(0);
            let (i, j, k) = (face[(slot + 1) % 3], face[(slot + 2) % 3], face[slot]);
            let pos = &mesh.positions;
            let len = (pos[j] - pos[i]).norm();
            let sigma = scene.edge_sign.get(f).map_or(1.0, |s| s[slot]);
            let edge = Edge {
                nodes: [face[0], face[1], face[2], nv + e],
                weight: l.moment * len,
                sigma,
            };
            let t0 = (pos[j] - pos[i]).normalize();
            let a = area(pos, &edge);
            let n = (a - t0 * t0.dot(&a)).normalize();
            let u = (pos[i] + pos[j]) * 0.5 - pos[k];
            let o = t0.cross(&n);
            let o = if o.dot(&u) < 0.0 { -o } else { o };
            frames.push(Frame {
                o,
                n,
                t0,
                theta: 0.0,
            });
            edges.push(edge);
        }
        if edges.len() == before {
            return Err(mesh.invalid(format!(
                "{what} selects no boundary edge: a moment acts along a boundary, and both ends \
                 of a boundary edge must be selected"
            )));
        }
    }
    Ok(Some(Box::new(MomentTerm(Moment {
        edges,
        frames: Mutex::new(frames),
    }))))
}
