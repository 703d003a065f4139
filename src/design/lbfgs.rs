//! Projected L-BFGS with bounds: the optimiser of inverse design.
//!
//! Each iteration takes the variables at a bound whose gradient pushes outward as fixed (their
//! projected gradient is 0), forms the L-BFGS direction on the free ones with the two-loop
//! recursion (Nocedal & Wright, *Numerical Optimization*, 2nd ed., Algorithm 7.4, with the
//! initial inverse Hessian `γ P`, `γ = sᵀy / yᵀPy`, their eq. 7.20 with a preconditioner `P`),
//! projects each trial point onto the box
//! and backtracks (halving) until the Armijo condition `f(p_t) ≤ f(p) + 10⁻⁴ ∇f·(p_t − p)`
//! holds. A trial whose evaluation fails (the equilibrium could not be found there) is cut like
//! one that does not descend: this is the design's continuation, which never jumps further than
//! the equilibrium solver can follow. Pairs with `sᵀy ≤ 10⁻¹⁰ |s||y|` (no positive curvature)
//! are not stored. The first direction is the projected gradient scaled so that its largest
//! entry is `first_step`.
//!
//! The crates compared: argmin's L-BFGS has no bounds; `lbfgsb` binds the Fortran L-BFGS-B,
//! which needs a Fortran compiler this project does not assume. The projected two-loop
//! method is L-BFGS-B's simplest relative (it skips the generalised Cauchy point) and is exact
//! on problems whose bounds are not active, which is where the tests measure it.

use crate::math::Real;
use std::collections::VecDeque;

/// A problem: an objective whose evaluation may fail (no equilibrium at that design).
pub trait Problem {
    /// The objective and its gradient at `p`, remembered as the trial; `Err` says why it
    /// could not be evaluated.
    fn eval(&mut self, p: &[Real]) -> Result<(Real, Vec<Real>), String>;
    /// The last trial is accepted (the problem warm-starts from it from now on).
    fn accept(&mut self);
    /// Applies the preconditioner `P ≈ (∇²f)⁻¹` (symmetric positive definite) to `v` in place:
    /// the initial inverse Hessian of the two-loop recursion is `γ P` (default: `P = I`).
    fn precondition(&self, _v: &mut [Real]) {}
}

/// The optimiser's controls.
#[derive(Clone, Debug)]
pub struct Options {
    /// Pairs kept.
    pub memory: usize,
    /// Iteration limit.
    pub max_iterations: usize,
    /// Relative change of the objective below which it stops.
    pub tolerance: Real,
    /// The largest change of a variable in the first iteration.
    pub first_step: Real,
    /// Lower bound of every variable (−∞: none).
    pub lower: Real,
    /// Upper bound (+∞: none).
    pub upper: Real,
}

/// How the optimisation ended.
#[derive(Clone, Debug, PartialEq)]
pub enum Stop {
    /// It converged; why.
    Converged(String),
    /// It could not improve; why.
    Stalled(String),
    /// The iteration limit.
    Limit,
}

/// What one accepted iteration reports.
pub struct Iterate<'a> {
    /// The iteration (0: the start).
    pub iteration: usize,
    /// The variables.
    pub p: &'a [Real],
    /// The objective.
    pub value: Real,
    /// The projected gradient's largest entry.
    pub gradient: Real,
    /// The step length accepted (1: the full quasi-Newton step).
    pub step: Real,
    /// Trials evaluated in this iteration.
    pub trials: usize,
}

/// How a zero projected gradient at iteration `it` with objective `f` ends the design: at the
/// start with something left to gain it is a critical point the design cannot leave by descent
/// (a flat sheet's curvature does not change to first order), not an optimum.
pub(super) fn zero_gradient(it: usize, f: Real) -> Stop {
    if it == 1 && f > 0.0 {
        Stop::Stalled(
            "the gradient is zero at the starting design, a critical point that is not the \
             target (a flat start changes no curvature to first order: add a distance term or \
             start from a curved design)"
                .into(),
        )
    } else {
        Stop::Converged("the projected gradient is zero".into())
    }
}

/// The gradient with the entries of variables held at a bound (pushed outward) set to zero.
pub(super) fn projected(p: &[Real], g: &[Real], o: &Options) -> Vec<Real> {
    p.iter()
        .zip(g)
        .map(|(&x, &gi)| {
            if (x <= o.lower && gi > 0.0) || (x >= o.upper && gi < 0.0) {
                0.0
            } else {
                gi
            }
        })
        .collect()
}

pub(super) fn dot(a: &[Real], b: &[Real]) -> Real {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

pub(super) fn amax(a: &[Real]) -> Real {
    a.iter().fold(0.0, |m: Real, x| m.max(x.abs()))
}

/// Minimises `problem` from `p` (clamped into the bounds), calling `report` after the start
/// and after every accepted iteration; `report` returning `true` stops (converged: a target
/// reached). Returns the stop, the final variables and objective; `Err` when the start
/// cannot be evaluated.
pub fn minimise<P: Problem>(
    problem: &mut P,
    p: Vec<Real>,
    o: &Options,
    report: &mut dyn FnMut(&Iterate, &P) -> Option<String>,
) -> Result<(Stop, Vec<Real>, Real), String> {
    let (mut p, mut f, mut g) = match start(problem, p, o, report)? {
        Ok(s) => s,
        Err(done) => return Ok(done),
    };
    let mut pairs: VecDeque<(Vec<Real>, Vec<Real>, Real)> = VecDeque::new();
    for it in 1..=o.max_iterations {
        let pg = projected(&p, &g, o);
        if amax(&pg) == 0.0 {
            return Ok((zero_gradient(it, f), p, f));
        }
        let free = free(&pg, &g);
        let mut d = two_loop(&pg, &pairs, &free, &|v: &mut [Real]| {
            problem.precondition(v)
        });
        if pairs.is_empty() || dot(&d, &pg) >= 0.0 {
            pairs.clear();
            let mut pd = pg.clone();
            problem.precondition(&mut pd);
            for (x, &f) in pd.iter_mut().zip(&free) {
                if !f {
                    *x = 0.0;
                }
            }
            let s = o.first_step / amax(&pd).max(Real::MIN_POSITIVE);
            d = pd.iter().map(|x| -x * s).collect();
        }
        let (trial, ft, gt, alpha, trials) = match backtrack(problem, &p, &d, f, &g, o, 40) {
            Ok(a) => a,
            Err(why) => return Ok((Stop::Stalled(why), p, f)),
        };
        problem.accept();
        let s: Vec<Real> = trial.iter().zip(&p).map(|(a, b)| a - b).collect();
        let y: Vec<Real> = gt.iter().zip(&g).map(|(a, b)| a - b).collect();
        let sy = dot(&s, &y);
        if sy > 1e-10 * dot(&s, &s).sqrt() * dot(&y, &y).sqrt() {
            pairs.push_back((s, y, 1.0 / sy));
            if pairs.len() > o.memory {
                pairs.pop_front();
            }
        }
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

/// The start of either optimiser: `p` clamped into the bounds, evaluated, accepted and reported
/// as iteration 0. `Ok(Err(…))` when the report stops it there (converged); `Err` when the start
/// cannot be evaluated.
#[allow(clippy::type_complexity)]
pub(super) fn start<P: Problem>(
    problem: &mut P,
    p: Vec<Real>,
    o: &Options,
    report: &mut dyn FnMut(&Iterate, &P) -> Option<String>,
) -> Result<Result<(Vec<Real>, Real, Vec<Real>), (Stop, Vec<Real>, Real)>, String> {
    let p: Vec<Real> = p.iter().map(|x| x.clamp(o.lower, o.upper)).collect();
    let (f, g) = problem.eval(&p)?;
    problem.accept();
    // The relative change of an iteration that has not happened: never below the tolerance.
    Ok(
        match after_step(problem, report, o, (0, &p, f, &g), (0.0, 1), Real::INFINITY) {
            Some(stop) => Err((stop, p, f)),
            None => Ok((p, f, g)),
        },
    )
}

/// The variables free in this iteration: those not held at a bound by a gradient pushing
/// outward (their projected gradient `pg` is zero while the gradient `g` is not).
pub(super) fn free(pg: &[Real], g: &[Real]) -> Vec<bool> {
    pg.iter()
        .zip(g)
        .map(|(a, b)| *a != 0.0 || *b == 0.0)
        .collect()
}

/// The accepted trial of a backtracking line search: the variables, objective, gradient, the
/// step length and the trials evaluated.
pub(super) type Accepted = (Vec<Real>, Real, Vec<Real>, Real, usize);

/// Backtracks along `d` from `p` (objective `f`, gradient `g`), halving from the full step, each
/// trial projected onto the box, until the Armijo condition holds (at most `max_trials`
/// evaluations); a trial whose evaluation fails counts as one that does not descend. `Err` says
/// why no step was accepted.
pub(super) fn backtrack<P: Problem>(
    problem: &mut P,
    p: &[Real],
    d: &[Real],
    f: Real,
    g: &[Real],
    o: &Options,
    max_trials: usize,
) -> Result<Accepted, String> {
    let mut alpha = 1.0;
    let mut trials = 0;
    let mut last_failure = String::new();
    while trials < max_trials {
        let trial: Vec<Real> = p
            .iter()
            .zip(d)
            .map(|(x, di)| (x + alpha * di).clamp(o.lower, o.upper))
            .collect();
        let dp: Vec<Real> = trial.iter().zip(p).map(|(a, b)| a - b).collect();
        if amax(&dp) <= 1e-15 * (1.0 + amax(p)) {
            break;
        }
        trials += 1;
        match problem.eval(&trial) {
            Ok((ft, gt)) if ft.is_finite() && ft <= f + 1e-4 * dot(g, &dp) => {
                return Ok((trial, ft, gt, alpha, trials));
            }
            Ok((ft, _)) => last_failure = format!("the objective went to {ft:e} from {f:e}"),
            Err(e) => last_failure = e,
        }
        alpha *= 0.5;
    }
    Err(if last_failure.is_empty() {
        "the step became too small to change the design".to_string()
    } else {
        format!("no step along the descent direction lowers the objective ({last_failure})")
    })
}

/// Reports accepted iteration `it` (variables `p`, objective `f`, gradient `g`, step length and
/// trials) and decides whether to stop: the report's own reason, or a relative `change` of the
/// objective below the tolerance.
pub(super) fn after_step<P: Problem>(
    problem: &P,
    report: &mut dyn FnMut(&Iterate, &P) -> Option<String>,
    o: &Options,
    (it, p, f, g): (usize, &[Real], Real, &[Real]),
    (step, trials): (Real, usize),
    change: Real,
) -> Option<Stop> {
    let pg = projected(p, g, o);
    if let Some(why) = report(
        &Iterate {
            iteration: it,
            p,
            value: f,
            gradient: amax(&pg),
            step,
            trials,
        },
        problem,
    ) {
        return Some(Stop::Converged(why));
    }
    (change < o.tolerance).then(|| {
        Stop::Converged(format!(
            "the objective changed by {change:.1e} (relative) in the last iteration, below \
             design.tolerance"
        ))
    })
}

/// `−H g` by the two-loop recursion over the stored pairs, on the free variables, with the
/// initial inverse Hessian `γ P`, `γ = sᵀy / yᵀPy` of the newest pair.
fn two_loop(
    g: &[Real],
    pairs: &VecDeque<(Vec<Real>, Vec<Real>, Real)>,
    free: &[bool],
    precondition: &dyn Fn(&mut [Real]),
) -> Vec<Real> {
    let mask = |v: &[Real]| -> Vec<Real> {
        v.iter()
            .zip(free)
            .map(|(x, &f)| if f { *x } else { 0.0 })
            .collect()
    };
    let mut q = mask(g);
    let mut alphas = Vec::with_capacity(pairs.len());
    for (s, y, rho) in pairs.iter().rev() {
        let s = mask(s);
        let a = rho * dot(&s, &q);
        for (qi, yi) in q.iter_mut().zip(mask(y)) {
            *qi -= a * yi;
        }
        alphas.push(a);
    }
    if let Some((s, y, _)) = pairs.back() {
        let mut py = mask(y);
        precondition(&mut py);
        let gamma = dot(s, y) / dot(&mask(y), &py).max(Real::MIN_POSITIVE);
        precondition(&mut q);
        q = mask(&q);
        for qi in &mut q {
            *qi *= gamma;
        }
    }
    for ((s, y, rho), a) in pairs.iter().zip(alphas.iter().rev()) {
        let b = rho * dot(&mask(y), &q);
        for (qi, si) in q.iter_mut().zip(mask(s)) {
            *qi += (a - b) * si;
        }
    }
    mask(&q).iter().map(|x| -x).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Rosenbrock function in 6 variables, once free and once with a bound active at the
    /// solution.
    struct Rosen(Vec<Real>);
    impl Problem for Rosen {
        fn eval(&mut self, p: &[Real]) -> Result<(Real, Vec<Real>), String> {
            self.0 = p.to_vec();
            let n = p.len();
            let mut f = 0.0;
            let mut g = vec![0.0; n];
            for i in 0..n - 1 {
                let (a, b) = (p[i], p[i + 1]);
                f += 100.0 * (b - a * a).powi(2) + (1.0 - a).powi(2);
                g[i] += -400.0 * a * (b - a * a) - 2.0 * (1.0 - a);
                g[i + 1] += 200.0 * (b - a * a);
            }
            Ok((f, g))
        }
        fn accept(&mut self) {}
    }

    #[test]
    fn minimises_rosenbrock_free_and_bounded() {
        let o = Options {
            memory: 8,
            max_iterations: 500,
            tolerance: 1e-16,
            first_step: 0.1,
            lower: Real::NEG_INFINITY,
            upper: Real::INFINITY,
        };
        let mut iterations = 0;
        let (stop, p, f) = minimise(
            &mut Rosen(vec![]),
            vec![-1.2, 1.0, -1.2, 1.0, -1.2, 1.0],
            &o,
            &mut |it, _| {
                iterations = it.iteration;
                None
            },
        )
        .unwrap();
        assert!(
            f < 1e-12 && p.iter().all(|x| (x - 1.0).abs() < 1e-5),
            "{stop:?} {p:?} {f}"
        );
        // Quasi-Newton speed: L-BFGS with a backtracking line search needs a few dozen
        // iterations here, steepest descent thousands.
        assert!(iterations < 150, "{iterations} iterations");
        // With every variable at most 0.5, the first sits on its bound.
        let o = Options { upper: 0.5, ..o };
        let (_, p, _) = minimise(&mut Rosen(vec![]), vec![0.0; 4], &o, &mut |_, _| None).unwrap();
        assert!(p.iter().all(|&x| x <= 0.5));
        assert_eq!(p[0], 0.5, "{p:?}");
    }
}
