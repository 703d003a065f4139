//! One explicit step: the gradient, symplectic Euler, and the step fused into the gradient's
//! parallel parts ([`Step`]).

use crate::assembly::Want;
use crate::energy::Potential;
use crate::math::{Real, Vec3};

/// The forces of one explicit step: `g ← ∇Φ(x)` (zeroed first; N), returning Φ (J).
#[inline]
pub fn gradient(pot: &Potential, x: &[Vec3], g: &mut [Real]) -> Real {
    pot.eval(x, &[], Want::Gradient, g, &mut [])
}

/// One symplectic Euler step with drag rate `c` (1/s) and step `dt` (s):
/// `v ← v + dt (−g/m − c v)`, `x ← x + dt v`, with `inv_m` the inverse lumped masses (0 for
/// fixed vertices, which keep v = 0).
#[inline]
pub fn advance(x: &mut [Vec3], v: &mut [Vec3], g: &[Real], inv_m: &[Real], c: Real, dt: Real) {
    for (i, (xi, vi)) in x.iter_mut().zip(v.iter_mut()).enumerate() {
        let f = Vec3::new(g[3 * i], g[3 * i + 1], g[3 * i + 2]);
        advance_node(xi, vi, f, inv_m[i], c, dt);
    }
}

/// [`advance`] for one vertex with gradient `f` (N): the one place its arithmetic is written,
/// so that the fused step ([`Step`]) gives the same bits.
#[inline(always)]
fn advance_node(x: &mut Vec3, v: &mut Vec3, f: Vec3, inv_m: Real, c: Real, dt: Real) {
    if inv_m == 0.0 {
        *v = Vec3::zeros();
        return;
    }
    *v += (-f * inv_m - *v * c) * dt;
    *x += *v * dt;
}

/// A pointer for writes by several threads to entries that each belongs to one of them, with
/// the slice's length (checked in debug builds).
#[derive(Clone, Copy)]
struct Disjoint(*mut Vec3, usize);
// SAFETY: shared only by `Step::take`, whose parts write disjoint entries.
unsafe impl Send for Disjoint {}
unsafe impl Sync for Disjoint {}

impl Disjoint {
    /// Entry `u`.
    ///
    /// # Safety
    /// `u` is in bounds and no other thread touches it meanwhile.
    #[inline(always)]
    unsafe fn at<'a>(self, u: usize) -> &'a mut Vec3 {
        debug_assert!(u < self.1, "Disjoint::at({u}) beyond {}", self.1);
        unsafe { &mut *self.0.add(u) }
    }
}

/// The explicit step, `g ← ∇Φ(x)` then [`advance`], fused when it can be.
///
/// When the scene's only term goes through [`crate::assembly::assemble_elements`] and does
/// not act on the step ([`crate::energy::term::Term::explicit`]), each vertex is
/// advanced inside the gradient's parallel parts, by the part that owns it, right after that
/// part has summed its force ([`crate::assembly::assemble_elements_owned`], through
/// [`crate::energy::Potential::owned`]). The new positions go
/// into a second buffer, since other parts may still be reading the old ones, and the two are
/// swapped when the parts are done. A step is then one parallel region with no serial pass over
/// the nodes, and no core rereads the forces and positions another core has just written. The
/// arithmetic is that of the unfused step, in the same order (the force of a node is
/// `0 + Σ` of its element entries, zero where the term's mask fixes it or a DOF is pinned,
/// then [`advance`]), so both give the same bits, for any number of threads.
pub struct Step {
    /// Whether the scene allows fusing.
    fusable: bool,
    /// The other position buffer.
    next: Vec<Vec3>,
    /// Vertices in no element of the term: no part owns them, the caller advances them with
    /// no force.
    orphans: Vec<usize>,
    /// Per DOF: whether it is pinned (its force is zero).
    pinned: Vec<bool>,
}

impl Step {
    /// The step for `pot`'s scene; `fuse = false` keeps it unfused (for comparisons).
    pub fn new(pot: &Potential, fuse: bool) -> Step {
        let sc = pot.body;
        let nv = sc.num_vertices();
        let fusable = fuse
            && pot.terms.len() == 1
            && pot.pattern.maps.len() == 1
            && pot.terms[0].explicit().is_none();
        let mut used = vec![!fusable; nv];
        if fusable {
            let map = &pot.pattern.maps[0];
            for e in 0..map.len() {
                for &u in map.element(e) {
                    if u < nv {
                        used[u] = true;
                    }
                }
            }
        }
        let mut pinned = vec![false; pot.pattern.n];
        for &d in &sc.pinned_dofs {
            pinned[d] = true;
        }
        Step {
            fusable,
            next: if fusable {
                vec![Vec3::zeros(); nv]
            } else {
                Vec::new()
            },
            orphans: (0..nv).filter(|&u| !used[u]).collect(),
            pinned,
        }
    }

    /// Whether [`Step::take`] fuses the update into the gradient.
    pub fn fused(&self) -> bool {
        self.fusable
    }

    /// One step from positions `x` (m) with velocities `v` (m/s), drag rate `c` (1/s) and step
    /// `dt` (s), `inv_m` the inverse lumped masses (1/kg, 0 where fixed); returns Φ(x) (J).
    /// `g` is scratch: it holds ∇Φ(x) (N) after an unfused step, zeros after a fused one.
    #[allow(clippy::too_many_arguments)]
    pub fn take(
        &mut self,
        pot: &Potential,
        x: &mut Vec<Vec3>,
        v: &mut [Vec3],
        g: &mut [Real],
        inv_m: &[Real],
        c: Real,
        dt: Real,
    ) -> Real {
        if !self.fusable {
            let energy = gradient(pot, x, g);
            advance(x, v, g, inv_m, c, dt);
            return energy;
        }
        let (n, pinned) = (x.len(), &self.pinned);
        let any_skew = !pot.body.skew.is_empty();
        let skew = |u: usize| {
            if any_skew {
                pot.body.skew_projector(u)
            } else {
                None
            }
        };
        // The writes through `Disjoint` below rely on these.
        assert!(
            v.len() == n && self.next.len() == n && inv_m.len() == n && pinned.len() >= 3 * n,
            "a step built for another scene"
        );
        let (vp, np) = (
            Disjoint(v.as_mut_ptr(), v.len()),
            Disjoint(self.next.as_mut_ptr(), self.next.len()),
        );
        let old: &[Vec3] = x;
        // Whether the term's gradient handed its parts to the hook (a term that does not
        // assemble through the parts writes `g` instead).
        let taken_flag = std::sync::atomic::AtomicBool::new(false);
        let taken = &taken_flag;
        let hook = move |nodes: &[u32], sums: &[Real], fixed: &[bool]| {
            taken.store(true, std::sync::atomic::Ordering::Relaxed);
            let mut at = 0;
            for &u in nodes {
                let u = u as usize;
                if u >= n {
                    // An edge node: no position.
                    at += 1;
                    continue;
                }
                let force = |k: usize| {
                    if fixed[u] || pinned[3 * u + k] {
                        0.0
                    } else {
                        0.0 + sums[at + k]
                    }
                };
                let mut f = Vec3::new(force(0), force(1), force(2));
                if let Some(p) = skew(u) {
                    f = p * f;
                }
                at += 3;
                let mut xu = old[u];
                // SAFETY: each vertex is owned by one part, and only its part's hook writes
                // its velocity and new position (`Disjoint`); `v` and `next` outlive the call.
                unsafe {
                    advance_node(&mut xu, vp.at(u), f, inv_m[u], c, dt);
                    *np.at(u) = xu;
                }
            }
        };
        let fused = Potential {
            owned: Some(&hook),
            ..*pot
        };
        let energy = gradient(&fused, old, g);
        if !taken_flag.load(std::sync::atomic::Ordering::Relaxed) {
            // The term did not assemble through the parts: `g` is its gradient.
            advance(x, v, g, inv_m, c, dt);
            return energy;
        }
        for &u in &self.orphans {
            let mut xu = x[u];
            advance_node(&mut xu, &mut v[u], Vec3::zeros(), inv_m[u], c, dt);
            self.next[u] = xu;
        }
        std::mem::swap(x, &mut self.next);
        energy
    }
}
