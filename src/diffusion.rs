//! Moisture diffusion through the shell (seed 000 §4): Galerkin finite elements on prisms that
//! extrude each triangle ±h/2 along its normal, backward Euler in time.
//!
//! ## Discretisation
//! The thickness is split into `layers` equal layers (seed 000 uses one; several resolve the
//! through-thickness profile, which Crank's slab solution needs). Node `(v, k)` sits at vertex `v`
//! and height `z_k = −h/2 + k h/layers`, `k = 0` the bottom surface, `k = layers` the top. Each
//! (face, layer) is a 6-node prism with seed 000's shape functions in reference coordinates
//! `(ξ1, ξ2, ζ)`, `ζ ∈ [−1, 1]`:
//! `φ̄_{1,2,3} = λ_{1,2,3}(ξ)(1 − ζ)/2` (bottom), `φ̄_{4,5,6} = λ_{1,2,3}(ξ)(1 + ζ)/2` (top),
//! `λ = (1 − ξ1 − ξ2, ξ1, ξ2)`, and the map `x = v1 + ξ1 e1 + ξ2 e2 + (z_k + (ζ + 1)Δz/2) n̂`.
//! Its Jacobian `J = [e1 e2 n̂Δz/2]` is constant on the element (the face normal is the
//! same at its three vertices), `|det J| = 2A·Δz/2`. Element matrices
//!
//! `M_ij = ∫ φ_i φ_j dV`,  `K_ij = ∫ ∇φ_iᵀ D ∇φ_j dV`,  `∇φ = J⁻ᵀ ∇̄φ̄`,
//!
//! are integrated exactly by the 3-point (degree 2) triangle rule times 2-point Gauss in ζ, and M
//! is then row-sum lumped (each node gets its row's total). The consistent M of seed 000 makes
//! backward Euler non-monotone for small steps: a surface suddenly held at a moisture pushes the
//! nodes below it *negative* (by about 1/4 of the jump when D Δt/Δz² < 1/6), which the step
//! control would then chase. The lumped M keeps the scheme monotone, conserves the same total
//! (row sums are unchanged) and keeps the second order in space (tests).
//! `D = D_along d dᵀ + D_across d⊥ d⊥ᵀ + D_through n̂ n̂ᵀ` (m²/s) with `d` the face's unit machine
//! direction in its plane (fibre direction) and `d⊥ = n̂ × d`.
//!
//! ## Boundary conditions (per face, on its top or bottom surface)
//! * `Sealed`: no flux (the natural condition; also on the sheet's rim).
//! * `Flux(q)`: prescribed inward flux q (moisture·m/s): `∫ q φ_i dA`.
//! * `Robin { k, ambient }`: evaporation/absorption `−D∂u/∂n = k (u − u_amb)` (k in m/s):
//!   adds `k ∫ φ_i φ_j dA` to the matrix and `k u_amb ∫ φ_i dA` to the right-hand side.
//! * `Value(u)`: prescribed moisture on the surface's 3 nodes (water painted on, a damp sponge),
//!   imposed by symmetric elimination.
//!
//! A face side given two different conditions is contradictory input (see
//! [`Diffusion::set_surface`]).
//!
//! ## Time stepping
//! `(M + Δt (K + R)) u^{n+1} = M u^n + Δt (f + r)`, backward Euler: first order in time,
//! unconditionally stable, and with sealed boundaries it conserves `1ᵀ M u` exactly (the
//! columns of K sum to zero), up to round-off. The Cholesky symbolic factorisation is done once
//! per mesh; the numeric one whenever Δt changes.
//!
//! Units: lengths m, time s, moisture u dimensionless (fraction), D m²/s.

use crate::math::{Mat3, Real, Vec3};
use crate::solve::{LinearError, LinearSolver};

/// Diffusivities along the machine direction, across it (in the plane) and through the
/// thickness (m²/s).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Diffusivity {
    /// Along the fibres.
    pub along: Real,
    /// Across the fibres, in the plane.
    pub across: Real,
    /// Through the thickness.
    pub through: Real,
}

/// A condition on one face's top or bottom surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SurfaceBc {
    /// No flux.
    Sealed,
    /// Prescribed inward flux (m/s × moisture).
    Flux(Real),
    /// Exchange with an ambient moisture: outward flux `k (u − ambient)`.
    Robin {
        /// Transfer coefficient (m/s).
        k: Real,
        /// Ambient moisture.
        ambient: Real,
    },
    /// Prescribed moisture.
    Value(Real),
}

/// Top (`z = +h/2`, the normal side) or bottom surface.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    /// `z = +h/2`.
    Top,
    /// `z = −h/2`.
    Bottom,
}

/// The diffusion system of one mesh.
pub struct Diffusion {
    layers: usize,
    nv: usize,
    faces: Vec<[usize; 3]>,
    areas: Vec<Real>,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    mass: Vec<Real>,
    stiffness: Vec<Real>,
    /// Robin matrix contributions (pattern order) and the right-hand side f + r.
    robin: Vec<Real>,
    rhs: Vec<Real>,
    /// Prescribed values per node.
    fixed: Vec<Option<Real>>,
    /// Conditions set per (face, side).
    bcs: Vec<[SurfaceBc; 2]>,
    system: Vec<Real>,
    lin: LinearSolver,
    factored_dt: Option<Real>,
}

/// Triangle quadrature (degree 2): points (ξ1, ξ2) and weights summing to ½.
const TRI3: [(Real, Real, Real); 3] = [
    (1.0 / 6.0, 1.0 / 6.0, 1.0 / 6.0),
    (2.0 / 3.0, 1.0 / 6.0, 1.0 / 6.0),
    (1.0 / 6.0, 2.0 / 3.0, 1.0 / 6.0),
];

/// A surface condition that cannot be set.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SurfaceError {
    /// Two regions give one face side different conditions.
    #[error("face {face} {side:?}: conditions {old:?} and {new:?} contradict each other")]
    Contradict {
        /// The face.
        face: usize,
        /// Its side.
        side: Side,
        /// The condition already set.
        old: SurfaceBc,
        /// The one asked for.
        new: SurfaceBc,
    },
    /// A prescribed moisture cannot be switched to or from another condition.
    #[error("face {face} {side:?}: a prescribed moisture cannot be switched")]
    Prescribed {
        /// The face.
        face: usize,
        /// Its side.
        side: Side,
    },
}

impl Diffusion {
    /// Builds M and K on the reference mesh. `thickness` and `directions` (unit machine
    /// directions, any vector in or near the face plane; projected) are per face.
    pub fn new(
        positions: &[Vec3],
        faces: &[[usize; 3]],
        thickness: &[Real],
        directions: &[Vec3],
        diffusivity: Diffusivity,
        layers: usize,
    ) -> Result<Self, LinearError> {
        let layers = layers.max(1);
        let nv = positions.len();
        let nn = nv * (layers + 1);
        let node = |v: usize, k: usize| v * (layers + 1) + k;
        // Pattern: nodes of one prism are coupled.
        let mut cols: Vec<Vec<usize>> = vec![Vec::new(); nn];
        for f in faces {
            for k in 0..layers {
                let ns: Vec<usize> = (0..6).map(|a| node(f[a % 3], k + a / 3)).collect();
                for &i in &ns {
                    for &j in &ns {
                        if i >= j {
                            cols[j].push(i);
                        }
                    }
                }
            }
        }
        let mut col_ptr = vec![0];
        let mut row_idx = Vec::new();
        for (j, c) in cols.iter_mut().enumerate() {
            c.push(j);
            c.sort_unstable();
            c.dedup();
            row_idx.extend_from_slice(c);
            col_ptr.push(row_idx.len());
        }
        let nnz = row_idx.len();
        let at = |i: usize, j: usize| -> usize {
            let (i, j) = if i >= j { (i, j) } else { (j, i) };
            col_ptr[j]
                + row_idx[col_ptr[j]..col_ptr[j + 1]]
                    .binary_search(&i)
                    .unwrap_or(0)
        };
        let mut mass = vec![0.0; nnz];
        let mut stiffness = vec![0.0; nnz];
        let mut areas = Vec::with_capacity(faces.len());
        for (fi, f) in faces.iter().enumerate() {
            let (e1, e2) = (
                positions[f[1]] - positions[f[0]],
                positions[f[2]] - positions[f[0]],
            );
            let c = e1.cross(&e2);
            let area = 0.5 * c.norm();
            areas.push(area);
            let n = c / c.norm();
            let d = {
                let p = directions[fi] - n * n.dot(&directions[fi]);
                if p.norm() > 0.0 {
                    p.normalize()
                } else {
                    e1.normalize()
                }
            };
            let dp = n.cross(&d);
            let dm = d * d.transpose() * diffusivity.along
                + dp * dp.transpose() * diffusivity.across
                + n * n.transpose() * diffusivity.through;
            let dz = thickness[fi] / layers as Real;
            let jac = Mat3::from_columns(&[e1, e2, n * (0.5 * dz)]);
            let jit = jac.try_inverse().unwrap_or_else(Mat3::zeros).transpose();
            let detj = jac.determinant().abs();
            let mut me = [[0.0; 6]; 6];
            let mut ke = [[0.0; 6]; 6];
            for &(x1, x2, wt) in &TRI3 {
                for zeta in [-1.0 / 3f64.sqrt(), 1.0 / 3f64.sqrt()] {
                    let lam = [1.0 - x1 - x2, x1, x2];
                    let dlam = [(-1.0, -1.0), (1.0, 0.0), (0.0, 1.0)];
                    let mut phi = [0.0; 6];
                    let mut grad = [Vec3::zeros(); 6];
                    for a in 0..6 {
                        let (l, (g1, g2)) = (lam[a % 3], dlam[a % 3]);
                        let s = if a < 3 { -1.0 } else { 1.0 };
                        let w = 0.5 * (1.0 + s * zeta);
                        phi[a] = l * w;
                        grad[a] = jit * Vec3::new(g1 * w, g2 * w, 0.5 * s * l);
                    }
                    let wq = wt * detj; // ζ weight 1
                    for a in 0..6 {
                        for b in 0..6 {
                            // Row-sum lumped mass: the diagonal gets the whole row.
                            me[a][a] += wq * phi[a] * phi[b];
                            ke[a][b] += wq * grad[a].dot(&(dm * grad[b]));
                        }
                    }
                }
            }
            for k in 0..layers {
                let ns: [usize; 6] = std::array::from_fn(|a| node(f[a % 3], k + a / 3));
                for a in 0..6 {
                    for b in 0..6 {
                        if ns[a] >= ns[b] {
                            let p = at(ns[a], ns[b]);
                            mass[p] += me[a][b];
                            stiffness[p] += ke[a][b];
                        }
                    }
                }
            }
        }
        let lin = LinearSolver::from_csc(nn, col_ptr.clone(), row_idx.clone())?;
        Ok(Diffusion {
            layers,
            nv,
            faces: faces.to_vec(),
            areas,
            mass,
            stiffness,
            robin: vec![0.0; nnz],
            rhs: vec![0.0; nn],
            fixed: vec![None; nn],
            bcs: vec![[SurfaceBc::Sealed; 2]; faces.len()],
            system: vec![0.0; nnz],
            col_ptr,
            row_idx,
            lin,
            factored_dt: None,
        })
    }

    /// Number of nodes (vertices × (layers + 1)).
    pub fn num_nodes(&self) -> usize {
        self.nv * (self.layers + 1)
    }

    /// Node index of vertex `v` at layer boundary `k` (0 = bottom, `layers` = top).
    pub fn node(&self, v: usize, k: usize) -> usize {
        v * (self.layers + 1) + k
    }

    fn pos(&self, i: usize, j: usize) -> usize {
        let (i, j) = if i >= j { (i, j) } else { (j, i) };
        let c = &self.row_idx[self.col_ptr[j]..self.col_ptr[j + 1]];
        self.col_ptr[j] + c.binary_search(&i).unwrap_or(0)
    }

    /// Sets the condition on face `f`'s `side`. An error if that surface already has a
    /// different non-sealed condition (contradictory regions).
    pub fn set_surface(&mut self, f: usize, side: Side, bc: SurfaceBc) -> Result<(), SurfaceError> {
        let s = side as usize;
        let old = self.bcs[f][s];
        if old != SurfaceBc::Sealed && old != bc {
            return Err(SurfaceError::Contradict {
                face: f,
                side,
                old,
                new: bc,
            });
        }
        if old != bc {
            self.bcs[f][s] = bc;
            self.apply(f, side, bc, 1.0);
        }
        Ok(())
    }

    /// The condition on one face side.
    pub fn surface(&self, f: usize, side: Side) -> SurfaceBc {
        self.bcs[f][side as usize]
    }

    /// Replaces the flux or Robin condition of one face side by another (or by sealed), e.g. a
    /// surface that touches or leaves a moist ground. Prescribed values cannot be replaced.
    pub fn replace_surface(
        &mut self,
        f: usize,
        side: Side,
        bc: SurfaceBc,
    ) -> Result<(), SurfaceError> {
        let s = side as usize;
        let old = self.bcs[f][s];
        if matches!(old, SurfaceBc::Value(_)) || matches!(bc, SurfaceBc::Value(_)) {
            return Err(SurfaceError::Prescribed { face: f, side });
        }
        if old != bc {
            self.apply(f, side, old, -1.0);
            self.bcs[f][s] = bc;
            self.apply(f, side, bc, 1.0);
        }
        Ok(())
    }

    /// Adds (`sign = 1`) or removes (`−1`) the contributions of a condition.
    fn apply(&mut self, f: usize, side: Side, bc: SurfaceBc, sign: Real) {
        let k = match side {
            Side::Top => self.layers,
            Side::Bottom => 0,
        };
        let ns = self.faces[f].map(|v| self.node(v, k));
        let area = self.areas[f] * sign;
        match bc {
            SurfaceBc::Sealed => {}
            SurfaceBc::Flux(q) => {
                for &i in &ns {
                    self.rhs[i] += q * area / 3.0;
                }
            }
            SurfaceBc::Robin { k, ambient } => {
                for a in 0..3 {
                    self.rhs[ns[a]] += k * ambient * area / 3.0;
                    for b in 0..3 {
                        if ns[a] >= ns[b] {
                            let m = if a == b { area / 6.0 } else { area / 12.0 };
                            let p = self.pos(ns[a], ns[b]);
                            self.robin[p] += k * m;
                        }
                    }
                }
                self.factored_dt = None;
            }
            SurfaceBc::Value(u) => {
                for &i in &ns {
                    self.fixed[i] = Some(u);
                }
                self.factored_dt = None;
            }
        }
    }

    /// Prescribes the moisture at one node (e.g. on the sheet's rim).
    pub fn set_node_value(&mut self, node: usize, u: Real) {
        self.fixed[node] = Some(u);
        self.factored_dt = None;
    }

    /// Whether node `i` has a prescribed value.
    pub fn is_prescribed(&self, i: usize) -> bool {
        self.fixed[i].is_some()
    }

    /// Total moisture `1ᵀ M u` (m³ × moisture).
    pub fn total(&self, u: &[Real]) -> Real {
        self.mass_times(u).iter().sum()
    }

    fn mass_times(&self, u: &[Real]) -> Vec<Real> {
        let mut out = vec![0.0; u.len()];
        for j in 0..u.len() {
            for p in self.col_ptr[j]..self.col_ptr[j + 1] {
                let i = self.row_idx[p];
                out[i] += self.mass[p] * u[j];
                if i != j {
                    out[j] += self.mass[p] * u[i];
                }
            }
        }
        out
    }

    /// One backward-Euler step of length `dt` (s), in place.
    pub fn step(&mut self, u: &mut [Real], dt: Real) -> Result<(), LinearError> {
        let n = u.len();
        let mut r = self.mass_times(u);
        for (ri, fi) in r.iter_mut().zip(&self.rhs) {
            *ri += dt * fi;
        }
        let refactor = self.factored_dt != Some(dt);
        for j in 0..n {
            for p in self.col_ptr[j]..self.col_ptr[j + 1] {
                let i = self.row_idx[p];
                let a = self.mass[p] + dt * (self.stiffness[p] + self.robin[p]);
                match (self.fixed[i], self.fixed[j]) {
                    (None, None) => {
                        if refactor {
                            self.system[p] = a;
                        }
                    }
                    (None, Some(g)) => {
                        r[i] -= a * g;
                        self.system[p] = 0.0;
                    }
                    (Some(g), None) => {
                        r[j] -= a * g;
                        self.system[p] = 0.0;
                    }
                    (Some(_), Some(_)) => {
                        self.system[p] = if i == j { 1.0 } else { 0.0 };
                    }
                }
            }
        }
        for (i, f) in self.fixed.iter().enumerate() {
            if let Some(g) = f {
                r[i] = *g;
            }
        }
        if refactor {
            self.lin.factor(&self.system)?;
            self.factored_dt = Some(dt);
        }
        self.lin.solve_in_place(&mut r);
        u.copy_from_slice(&r);
        Ok(())
    }

    /// Mean moisture over face `f`'s top and bottom surfaces `(m⁺, m⁻)`.
    pub fn surface_moisture(&self, u: &[Real], f: usize) -> (Real, Real) {
        let face = self.faces[f];
        let mean = |k: usize| face.iter().map(|&v| u[self.node(v, k)]).sum::<Real>() / 3.0;
        (mean(self.layers), mean(0))
    }
}
