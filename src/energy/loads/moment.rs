//! A distributed moment along a boundary (`[[loads.moment]]`), conservative.
//!
//! The moment `m` (N·m per unit length) acts on the boundary edges whose two vertices are
//! selected, about each edge's *reference* direction `t⁰` (a fixed axis, so the moment is
//! conservative). The turn of the edge's boundary face about `t⁰` is measured through two
//! vectors of the face that are normal to `t⁰` in the reference state: its area normal
//! `A = (x₁ − x₀) × (x₂ − x₀)` and the in-face normal of the edge `B = A × e`,
//! `e = x_j − x_i` the edge. Each vector's angle about `t⁰` is
//!
//! `θ_V = θ_V⁰ + atan2(−o_V·V, n_V·V)`,
//!
//! with `n_V` the vector's direction projected normal to `t⁰` at the last accepted state,
//! `o_V = −k × n_V`, `k = ±t⁰` the sense in which the angle counts positive (the face's outward
//! direction tilting toward the side its normal points to), and `θ_V⁰` the angle accumulated up
//! to that state ([`crate::energy::term::Tracked::accept`] updates them after every accepted step,
//! and a step that turns an edge by more than π/2 is cut). So each angle is single-valued within
//! a solve and continues through full turns across steps: a strip can be rolled into a full
//! circle. The face's turn is the mean `θ = (θ_A + θ_B)/2`.
//!
//! **Why two vectors.** Under a small spatial rotation `ω` of a face whose vector `w` lies
//! normal to `t⁰`, the projected angle changes by `ω_t + ½ ω_p ω_w + O(ω³)`, where `ω_w` is the
//! rotation about `w` and `ω_p` the one about `t⁰ × w`. For `A` the product couples twist and
//! yaw with one sign, for `B` (normal to `A` and to the edge) with the other, and in the mean
//! it cancels: the moment adds no load stiffness to first order. One vector alone gives a
//! stiffness `∓ m ω_twist ω_yaw` that makes the rolled strip buckle sideways beyond three
//! quarters of a turn (measured: the lowest eigenvalue of the Hessian turns negative at 80% of
//! the full-circle moment, while the shell alone stays positive definite there). In plane
//! motion `A` and `B` turn together and `θ_A = θ_B` exactly.
//!
//! **Energy.** Without edge DOFs the boundary's director is the face normal:
//! `E = −s m Σ_e ℓ⁰_e θ_e` (J), `ℓ⁰` the reference edge length, `s` the dial. With edge DOFs
//! the director turns further by the edge DOF's tilt `σ_e φ_e` (outward, see
//! [`crate::energy::midedge_angle`]), which rotates it the opposite way in θ's sense:
//! `E = −s m Σ_e ℓ⁰_e (θ_e − σ_e φ_e)`. The boundary's natural condition is then that the
//! bending moment equals `m`.
//!
//! **Derivatives.** With `p = n_V·V`, `q = −o_V·V`, `r² = p² + q²`:
//! `g_V = ∇_V θ_V = (−p o_V − q n_V)/r²`,
//! `∇²_V θ_V = [(q² − p²)(−o n ᵀ − n oᵀ) + 2pq(n nᵀ − o oᵀ)]/r⁴`.
//! `∂A/∂x_a = M_a = [x_{a+2} − x_{a+1}]×` (cyclically), and `Σ_c g_c ∂²A_c/∂x_a∂x_b = −[g]×`
//! for `(a, b) = (0, 1), (1, 2), (2, 0)` and its transpose for the reverse pairs.
//! `∂B/∂x_a = −[e]× M_a + c_a [A]×` with `c_j = 1`, `c_i = −1` and 0 for the third vertex;
//! `g·B = A·(e × g)`, so `Σ_c g_c ∂²B_c` is the contraction of `A` with `e × g` plus the cross
//! blocks `−c_b M_aᵀ[g]× + c_a [g]× M_b`.
//!
//! DOF order (10 local): the face's `x[v0], x[v1], x[v2]`, then the edge's DOF `φ_e` (unused
//! without edge DOFs). Units: m in N·m/m, E in J, gradient N and N·m.

use super::select_vertices;
use crate::body::Body;
use crate::energy::term::{ElementKernel, Reports, StateError, Stateful, Stencil, Term, Tracked};
use crate::energy::Potential;
use crate::math::{skew, Mat3, Real, SMat, SVec, Vec3};
use crate::mesh::topology::NONE;
use crate::mesh::MeshError;

/// One loaded boundary edge.
#[derive(Clone, Copy, Debug)]
struct Edge {
    /// Nodes: the face's vertices in face order, then the edge node.
    nodes: [usize; 4],
    /// The edge's end vertices `(i, j)` as local slots of the face.
    ends: [usize; 2],
    /// The face and the edge's slot in it (the edge is opposite vertex `slot`).
    face: usize,
    slot: usize,
    /// `m ℓ⁰` (N·m).
    weight: Real,
    /// The face's orientation sign on the edge.
    sigma: Real,
}

/// The reference of one vector's angle about `t⁰`: its direction `n` projected normal to `t⁰`
/// at the last accepted state, and the angle accumulated up to there.
#[derive(Clone, Copy, Debug)]
struct Frame {
    n: Vec3,
    theta: Real,
}

/// The frames of one edge: the signed axis `k` (`θ` grows when `n` turns toward `k × n`) and
/// one frame for `A`, one for `B`.
#[derive(Clone, Copy, Debug)]
struct Frames {
    k: Vec3,
    a: Frame,
    b: Frame,
}

/// Reals per edge in the term's state: `k`, then `n` and `θ` of `A`, then of `B`.
const PER_EDGE: usize = 11;

impl Frames {
    /// Edge `e`'s frames in the state `s` (`None` when `s` is too short).
    fn read(s: &[Real], e: usize) -> Option<Frames> {
        let v = s.get(PER_EDGE * e..PER_EDGE * (e + 1))?;
        let vec = |i: usize| Vec3::new(v[i], v[i + 1], v[i + 2]);
        Some(Frames {
            k: vec(0),
            a: Frame {
                n: vec(3),
                theta: v[6],
            },
            b: Frame {
                n: vec(7),
                theta: v[10],
            },
        })
    }

    /// Writes these frames as edge `e`'s in the state `s`.
    fn write(&self, s: &mut [Real], e: usize) {
        let v = &mut s[PER_EDGE * e..PER_EDGE * (e + 1)];
        v[0..3].copy_from_slice(self.k.as_slice());
        v[3..6].copy_from_slice(self.a.n.as_slice());
        v[6] = self.a.theta;
        v[7..10].copy_from_slice(self.b.n.as_slice());
        v[10] = self.b.theta;
    }
}

/// The moment kernel. Its state ([`crate::energy::term::Stateful`], under the name `moment`)
/// is every loaded edge's frames at the last accepted state, 11 reals per edge (`k`, then `n`
/// and `θ` of `A` and of `B`).
pub struct Moment {
    edges: Vec<Edge>,
    num_faces: usize,
    /// The frames at the reference, flattened: the initial state.
    initial: Vec<Real>,
}

/// The face's area normal `A` and in-face edge normal `B = A × e` at positions `x`.
fn vectors(x: &[Vec3], e: &Edge) -> (Vec3, Vec3) {
    let xs = [x[e.nodes[0]], x[e.nodes[1]], x[e.nodes[2]]];
    let a = (xs[1] - xs[0]).cross(&(xs[2] - xs[0]));
    (a, a.cross(&(xs[e.ends[1]] - xs[e.ends[0]])))
}

/// The angle of `v` about `k` in frame `f`: `(θ, g = ∇_v θ, ∇²_v θ)`.
fn angle(k: &Vec3, f: &Frame, v: &Vec3, want_hess: bool) -> (Real, Vec3, Mat3) {
    let o = -k.cross(&f.n);
    let (p, q) = (f.n.dot(v), -o.dot(v));
    let r2 = p * p + q * q;
    let g = (-o * p - f.n * q) / r2;
    let h = if want_hess {
        let on: Mat3 = o * f.n.transpose();
        let nn: Mat3 = f.n * f.n.transpose();
        let oo: Mat3 = o * o.transpose();
        (-(on + on.transpose()) * (q * q - p * p) + (nn - oo) * (2.0 * p * q)) / (r2 * r2)
    } else {
        Mat3::zeros()
    };
    (f.theta + q.atan2(p), g, h)
}

/// The frame of `v` (projected normal to `k`) carrying angle `theta`.
fn frame(k: &Vec3, v: &Vec3, theta: Real) -> Frame {
    Frame {
        n: (v - k * k.dot(v)).normalize(),
        theta,
    }
}

impl Moment {
    /// The face's turn `θ = (θ_A + θ_B)/2` and the two angles, for its vectors `(a, b)`.
    fn turn(f: &Frames, (a, b): (Vec3, Vec3)) -> (Real, Real, Real) {
        let ta = angle(&f.k, &f.a, &a, false).0;
        let tb = angle(&f.k, &f.b, &b, false).0;
        (0.5 * (ta + tb), ta, tb)
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
        let Some(f) = Frames::read(pot.term_state(NAME), e) else {
            return Real::NAN;
        };
        let xs = [x[nodes[0]], x[nodes[1]], x[nodes[2]]];
        let ev = xs[edge.ends[1]] - xs[edge.ends[0]];
        let a = (xs[1] - xs[0]).cross(&(xs[2] - xs[0]));
        let b = a.cross(&ev);
        let want_h = hess.is_some() && !gauss_newton;
        let (ta, ga, ha) = angle(&f.k, &f.a, &a, want_h);
        let (tb, gb, hb) = angle(&f.k, &f.b, &b, want_h);
        // Half of each angle: θ = (θ_A + θ_B)/2.
        let (ga, gb, ha, hb) = (ga * 0.5, gb * 0.5, ha * 0.5, hb * 0.5);
        let w = -pot.dial * edge.weight;
        let nv = pot.body.num_vertices();
        let tilt = if nodes[3] != NONE {
            edge.sigma * phi[nodes[3] - nv]
        } else {
            0.0
        };
        let energy = w * (0.5 * (ta + tb) - tilt);
        // c_a: ∂e/∂x_a = c_a I.
        let c = |v: usize| {
            if v == edge.ends[1] {
                1.0
            } else if v == edge.ends[0] {
                -1.0
            } else {
                0.0
            }
        };
        // ∂A/∂x_a = [x_{a+2} − x_{a+1}]×; ∂B/∂x_a = −[e]× M_a + c_a [A]×.
        let ma: [Mat3; 3] = std::array::from_fn(|v| skew(&(xs[(v + 2) % 3] - xs[(v + 1) % 3])));
        let (se, sa) = (skew(&ev), skew(&a));
        let mb: [Mat3; 3] = std::array::from_fn(|v| -se * ma[v] + sa * c(v));
        if let Some(g) = grad {
            for v in 0..3 {
                g.fixed_rows_mut::<3>(3 * v)
                    .copy_from(&((ma[v].transpose() * ga + mb[v].transpose() * gb) * w));
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
                return energy;
            }
            // Σ_c g_c ∂²A_c for the A angle's g and for B's contraction vector e × g_B.
            let sga = skew(&(ga + ev.cross(&gb)));
            let sgb = skew(&gb);
            for i in 0..3 {
                for j in 0..3 {
                    let mut blk = ma[i].transpose() * ha * ma[j] + mb[i].transpose() * hb * mb[j];
                    if j == (i + 1) % 3 {
                        blk -= sga;
                    } else if i == (j + 1) % 3 {
                        blk += sga;
                    }
                    blk += ma[i].transpose() * sgb * (-c(j)) + sgb * ma[j] * c(i);
                    h.fixed_view_mut::<3, 3>(3 * i, 3 * j).copy_from(&(blk * w));
                }
            }
        }
        energy
    }
}

/// The moment term: accumulates each edge's angle after every accepted step.
pub struct MomentTerm(Moment);

/// The name of the moment's term and state.
const NAME: &str = "moment";

impl Term for MomentTerm {
    fn name(&self) -> &'static str {
        NAME
    }
    fn applied_load(&self) -> bool {
        true
    }
    fn stencil(&self, body: &Body) -> Stencil {
        let p = &body.mesh.positions;
        let has_edges = body.has_edge_dofs();
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
        map: &crate::elements::ElementMap,
        x: &[Vec3],
        phi: &[Real],
        want: crate::elements::Want,
        projection: crate::energy::HessianProjection,
        grad: &mut [Real],
        values: &mut [Real],
    ) -> Real {
        crate::elements::assemble_elements::<10, 4, _>(
            map,
            |e, nodes, g, h| {
                let gn = projection == crate::energy::HessianProjection::GaussNewton;
                self.0.eval(pot, e, nodes, x, phi, gn, g, h)
            },
            pot.node_fixed,
            projection,
            want,
            grad,
            values,
            &pot.pattern.col_ptr,
        )
    }

    fn tracked(&self) -> Option<&dyn Tracked> {
        Some(self)
    }

    fn stateful(&self) -> Option<&dyn Stateful> {
        Some(self)
    }

    fn reports(&self) -> Option<&dyn Reports> {
        Some(self)
    }
}

impl Stateful for MomentTerm {
    fn initial_state(&self) -> Vec<Real> {
        self.0.initial.clone()
    }

    /// The initial state's length, finite values and unit vectors.
    fn check_state(&self, state: &[Real]) -> Result<(), String> {
        if state.len() != self.0.initial.len() || !state.iter().all(|v| v.is_finite()) {
            return Err(format!(
                "expected {} finite values ({PER_EDGE} per loaded edge), got {}",
                self.0.initial.len(),
                state.len()
            ));
        }
        for e in 0..self.0.edges.len() {
            let Some(f) = Frames::read(state, e) else {
                continue;
            };
            for v in [f.k, f.a.n, f.b.n] {
                if (v.norm() - 1.0).abs() > 1e-9 {
                    return Err(format!("loaded edge {e}: its frames are not unit vectors"));
                }
            }
        }
        Ok(())
    }
}

impl Reports for MomentTerm {
    fn observables(&self, pot: &Potential, x: &[Vec3], _: &[Real]) -> Vec<(String, Real)> {
        let own = pot.term_state(NAME);
        let mut sum = 0.0;
        for (i, e) in self.0.edges.iter().enumerate() {
            if let Some(f) = Frames::read(own, i) {
                sum += Moment::turn(&f, vectors(x, e)).0;
            }
        }
        vec![("moment_rotation".into(), sum / self.0.edges.len() as Real)]
    }
}

impl Tracked for MomentTerm {
    fn accept(&self, x: &[Vec3], _: &[Real], own: &mut [Real]) {
        for (i, e) in self.0.edges.iter().enumerate() {
            let Some(mut f) = Frames::read(own, i) else {
                continue;
            };
            let (a, b) = vectors(x, e);
            let (_, ta, tb) = Moment::turn(&f, (a, b));
            f.a = frame(&f.k, &a, ta);
            f.b = frame(&f.k, &b, tb);
            f.write(own, i);
        }
    }
    /// Each edge's angles may change by at most π/2 per step, well inside the atan2 branch.
    fn admissible(&self, x: &[Vec3], _: &[Real], own: &[Real]) -> bool {
        self.0.edges.iter().enumerate().all(|(i, e)| {
            let Some(f) = Frames::read(own, i) else {
                return false;
            };
            let (_, ta, tb) = Moment::turn(&f, vectors(x, e));
            let lim = std::f64::consts::FRAC_PI_2;
            (ta - f.a.theta).abs() <= lim && (tb - f.b.theta).abs() <= lim
        })
    }
    fn state_field(&self) -> &'static str {
        "moment_turn"
    }
    /// Each loaded edge's turn θ (rad) at its boundary face and edge slot; 0 elsewhere.
    fn field(&self, x: &[Vec3], _: &[Real], own: &[Real]) -> Vec<Real> {
        let mut out = vec![0.0; 3 * self.0.num_faces];
        for (i, e) in self.0.edges.iter().enumerate() {
            if let Some(f) = Frames::read(own, i) {
                out[3 * e.face + e.slot] = Moment::turn(&f, vectors(x, e)).0;
            }
        }
        out
    }
    /// Both angles of each edge restart from the frame's turn, re-centred at `x`. Without the
    /// field the turns are counted from the reference within ±π.
    fn restore(
        &self,
        x: &[Vec3],
        phi: &[Real],
        field: Option<&[Real]>,
        own: &mut [Real],
    ) -> Result<Option<String>, StateError> {
        let Some(field) = field else {
            self.accept(x, phi, own);
            return Ok(Some(
                "no 'moment_turn' field: the end moment's turns are counted from the reference \
                 mesh within ±π"
                    .into(),
            ));
        };
        for (i, e) in self.0.edges.iter().enumerate() {
            let theta = field.get(3 * e.face + e.slot).copied().unwrap_or(Real::NAN);
            if !theta.is_finite() {
                return Err(StateError {
                    face: e.face,
                    reason: format!("field 'moment_turn' is not finite at edge {}", e.slot),
                });
            }
            let Some(mut f) = Frames::read(own, i) else {
                continue;
            };
            let (a, b) = vectors(x, e);
            f.a = frame(&f.k, &a, theta);
            f.b = frame(&f.k, &b, theta);
            f.write(own, i);
        }
        Ok(None)
    }
}

/// The moment term of a scene (`None` without moments).
pub fn term(
    body: &Body,
    loads: &[crate::config::loads::MomentLoad],
) -> Result<Option<Box<dyn Term>>, MeshError> {
    if loads.is_empty() {
        return Ok(None);
    }
    let mesh = &body.mesh;
    let topo = &body.topo;
    let nv = body.num_vertices();
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
            let sigma = body.edge_sign.get(f).map_or(1.0, |s| s[slot]);
            let local = |v: usize| (0..3).find(|&s| face[s] == v).unwrap_or(0);
            let edge = Edge {
                nodes: [face[0], face[1], face[2], nv + e],
                ends: [local(i), local(j)],
                face: f,
                slot,
                weight: l.moment * len,
                sigma,
            };
            let t0 = (pos[j] - pos[i]).normalize();
            let (a, b) = vectors(pos, &edge);
            let n = (a - t0 * t0.dot(&a)).normalize();
            // Outward: from the opposite vertex toward the edge, within the face.
            let u = (pos[i] + pos[j]) * 0.5 - pos[k];
            let o = t0.cross(&n);
            let o = if o.dot(&u) < 0.0 { -o } else { o };
            // θ grows as n turns toward −o: k × n = −o.
            let axis = o.cross(&n);
            frames.push(Frames {
                k: axis,
                a: frame(&axis, &a, 0.0),
                b: frame(&axis, &b, 0.0),
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
    let mut initial = vec![0.0; PER_EDGE * frames.len()];
    for (e, f) in frames.iter().enumerate() {
        f.write(&mut initial, e);
    }
    Ok(Some(Box::new(MomentTerm(Moment {
        edges,
        num_faces: mesh.faces.len(),
        initial,
    }))))
}
