//! Gauss–Newton with Levenberg–Marquardt damping: the optimiser of inverse design for
//! objectives with a distance term (`design.method = "gauss_newton"`).
//!
//! The distance term is a least-squares sum over the shape's vertices,
//! `J_d = ½ Σ_v c_v |R x_v + t − y_v|²` (`c_v = w_v/L²` for points,
//! [`super::objective::DistanceTerm::model_weights`]). With the equilibrium's response to the
//! design, `S = dx*/dp = −H⁻¹ ∂g/∂p`, and the alignment and closest points held, its
//! Gauss–Newton model is `J_d(p + δ) ≈ J_d + ∇J·δ + ½ δᵀ Sᵀ C S δ`; the smoothness term adds its
//! own Hessian. Each iteration minimises the model plus `½ μ δᵀ M δ` (`M` the step metric: the
//! Sobolev metric of `design.smoothing_length`, else the identity over the number of faces) by
//! preconditioned conjugate gradients, each product `(Sᵀ C S + ∇²J_s + μ M) v` costing one
//! tangent (two gradient evaluations and a solve with the factorisation the gradient already
//! made) and one adjoint (a solve and the pass over the faces). Nocedal & Wright, *Numerical
//! Optimization*, 2nd ed., §10.3 (Levenberg–Marquardt) and Algorithm 7.1 (CG–Newton, stopped at
//! a relative residual of 10⁻²).
//!
//! The step is then shortened, if needed, so that the sheet's predicted displacement `|S δ|`
//! stays within a tenth of the target's size (the re-solve starts from the prediction
//! `x + S δ`, which is exact to first order), and backtracked (halving) until the Armijo
//! condition holds, a trial whose equilibrium is not found counting as a failure. The damping
//! falls by 3 after a full step whose decrease is at least ¾ of the model's (along the step
//! taken: `−gᵀδ (c − c²/2)` for a step shortened by `c`), and doubles on
//! every halving or a decrease under ¼ of the model's. Variables at a bound whose gradient pushes
//! outward are fixed for the iteration, as in [`super::lbfgs`].
//!
//! Compared with L-BFGS, each iteration costs a few dozen solves with an existing factorisation
//! more, and the steps follow the shape's own response: a thin sheet's soft modes, which make
//! the objective's Hessian badly conditioned, are in the model from the first iteration instead
//! of being learnt over many.

use super::lbfgs::{
    after_step, amax, backtrack, dot, free, projected, start, zero_gradient, Iterate, Options,
    Problem, Stop,
};
use crate::math::Real;

/// A problem with the Gauss–Newton model at its last accepted point.
pub trait Model: Problem {
    /// `(Sᵀ C S + ∇²J_s) v` at the last accepted design; `None` when the equilibrium there has
    /// no factorisation (not positive definite).
    fn model_product(&mut self, v: &[Real]) -> Option<Vec<Real>>;
    /// `M v`, the damping metric.
    fn metric_product(&self, v: &[Real]) -> Vec<Real>;
    /// The largest vertex displacement of the response `S v`, over the target's size.
    fn response_size(&mut self, v: &[Real]) -> Option<Real>;
}

/// The largest predicted displacement of one step, over the target's size.
const MAX_RESPONSE: Real = 0.1;

/// The conjugate-gradient iterations per step, at most.
const MAX_CG: usize = 50;

/// Solves `(B + μ M) δ = −g` on the free variables by preconditioned CG, from `δ = 0`, to a
/// relative residual of 10⁻² or [`MAX_CG`] iterations; `None` when a product fails.
fn solve_step<P: Model>(problem: &mut P, g: &[Real], free: &[bool], mu: Real) -> Option<Vec<Real>> {
    let mask = |v: &mut Vec<Real>| {
        for (x, &f) in v.iter_mut().zip(free) {
            if !f {
                *x = 0.0;
            }
        }
    };
    let apply = |problem: &mut P, v: &[Real]| -> Option<Vec<Real>> {
        let mut out = problem.model_product(v)?;
        let m = problem.metric_product(v);
        for (o, mi) in out.iter_mut().zip(&m) {
            *o += mu * mi;
        }
        mask(&mut out);
        Some(out)
    };
    let n = g.len();
    let mut x = vec![0.0; n];
    let mut r: Vec<Real> = g.iter().map(|v| -v).collect();
    mask(&mut r);
    let r0 = dot(&r, &r).sqrt();
    if r0 == 0.0 {
        return Some(x);
    }
    let mut z = r.clone();
    problem.precondition(&mut z);
    mask(&mut z);
    let mut d = z.clone();
    let mut rz = dot(&r, &z);
    for _ in 0..MAX_CG {
        let bd = apply(problem, &d)?;
        let curv = dot(&d, &bd);
        if curv.is_nan() || curv <= 0.0 {
            break;
        }
        let a = rz / curv;
        for i in 0..n {
            x[i] += a * d[i];
            r[i] -= a * bd[i];
        }
        if dot(&r, &r).sqrt() <= 1e-2 * r0 {
            break;
        }
        z.clone_from(&r);
        problem.precondition(&mut z);
        mask(&mut z);
        let rz1 = dot(&r, &z);
        let beta = rz1 / rz;
        rz = rz1;
        for i in 0..n {
            d[i] = z[i] + beta * d[i];
        }
    }
    if dot(&x, g) >= 0.0 {
        // Not a descent direction (round-off in the products): the preconditioned gradient.
        x.iter_mut().zip(g).for_each(|(xi, gi)| *xi = -gi);
        problem.precondition(&mut x);
        mask(&mut x);
    }
    Some(x)
}

/// Minimises `problem` from `p` (clamped into the bounds) by damped Gauss–Newton, calling
/// `report` after the start and after every accepted iteration, as
/// [`super::lbfgs::minimise`] does (`Options::memory` and `first_step` are not used).
pub fn minimise<P: Model>(
    problem: &mut P,
    p: Vec<Real>,
    o: &Options,
    report: &mut dyn FnMut(&Iterate, &P) -> Option<String>,
) -> Result<(Stop, Vec<Real>, Real), String> {
    let (mut p, mut f, mut g) = match start(problem, p, o, report)? {
        Ok(s) => s,
        Err(done) => return Ok(done),
    };
    let mut mu: Option<Real> = None;
    for it in 1..=o.max_iterations {
        let pg = projected(&p, &g, o);
        if amax(&pg) == 0.0 {
            return Ok((zero_gradient(it, f), p, f));
        }
        let free = free(&pg, &g);
        // The first damping: a thousandth of the model's curvature along the gradient, relative
        // to the metric's.
        let damping = match mu {
            Some(m) => m,
            None => {
                let bg = problem
                    .model_product(&pg)
                    .ok_or("the starting equilibrium has no positive definite Hessian")?;
                let mg = problem.metric_product(&pg);
                let m = 1e-3 * dot(&pg, &bg).max(0.0) / dot(&pg, &mg).max(Real::MIN_POSITIVE);
                m.max(Real::MIN_POSITIVE)
            }
        };
        let Some(mut d) = solve_step(problem, &pg, &free, damping) else {
            return Ok((
                Stop::Stalled("the equilibrium's Hessian is no longer positive definite".into()),
                p,
                f,
            ));
        };
        // The model's decrease along c·δ, with δᵀBδ ≈ −gᵀδ at the model's minimiser:
        // −gᵀδ (c − c²/2); c < 1 when the step is shortened to the displacement bound.
        let mut c = 1.0;
        if let Some(size) = problem.response_size(&d) {
            if size > MAX_RESPONSE {
                c = MAX_RESPONSE / size;
                d.iter_mut().for_each(|x| *x *= c);
            }
        }
        let predicted = -dot(&pg, &d) * (1.0 - 0.5 * c);
        let (trial, ft, gt, alpha, trials) = match backtrack(problem, &p, &d, f, &g, o, 30) {
            Ok(a) => a,
            Err(why) => return Ok((Stop::Stalled(why), p, f)),
        };
        problem.accept();
        let ratio = (f - ft) / predicted.max(Real::MIN_POSITIVE);
        mu = Some(if alpha < 1.0 {
            damping / alpha
        } else if ratio > 0.75 {
            damping / 3.0
        } else if ratio < 0.25 {
            damping * 2.0
        } else {
            damping
        });
        let change = (f - ft).abs() / f.abs().max(Real::MIN_POSITIVE);
        p = trial;
        f = ft;
        g = gt;
        if let Some(stop) = after_step(problem, report, o, (it, &p, f, &g), (alpha, trials), change)
        {
            return Ok((stop, p, f));
        }
    }
    Ok((Stop::Limit, p, f))
}
