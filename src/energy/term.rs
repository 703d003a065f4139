//! The contracts every energy term keeps.
//!
//! A scene's potential Φ is a list of [`Term`]s built once by [`super::registry`] from the
//! validated settings, holding only what the scene enables. Assembly accumulates every term into
//! one gradient and one sparse Hessian; the Hessian's pattern is the union of the terms' stencils.
//!
//! Three kinds of term share the one trait:
//! * an **element term** ([`ElementKernel`] wrapped in [`ElementTerm`]): a pure per-element kernel
//!   over a fixed stencil of DOF nodes, `N` local DOFs, returning the energy and optionally the
//!   gradient (+∂E/∂x, minus the force) and the Hessian; the shell faces, pressure, loads on faces;
//! * a **vertex term** ([`VertexKernel`] wrapped in [`VertexTerm`]): one vertex, 3 DOFs; gravity,
//!   inertia, the ground, point loads;
//! * a **global term**: any term may add a dense low-rank part `Σ_k c_k u_k u_kᵀ` to its Hessian
//!   ([`Term::low_rank`]) that is never densified: Newton solves with the sparse factor plus the
//!   Woodbury identity ([`crate::solve::low_rank`]).
//!
//! Dispatch is once per term: a term's element loop is monomorphic.

use crate::body::Body;
pub use crate::elements::Stencil;
use crate::elements::{
    assemble_elements, assemble_elements_owned, no_contribution, ElementMap, Want,
};
use crate::energy::HessianProjection;
use crate::energy::Potential;
use crate::math::{Mat3, Real, SMat, SVec, Vec3};

/// A dense low-rank Hessian part `c u uᵀ` over all DOFs.
#[derive(Clone, Debug)]
pub struct LowRank {
    /// The coefficient `c` (any sign).
    pub c: Real,
    /// The vector `u` (length = number of DOFs).
    pub u: Vec<Real>,
}

/// A global scalar DOF that a term declares (a force-controlled obstacle's offset along its
/// force): one node of one DOF after the vertex and edge nodes, free, carried in
/// [`crate::solve::State::dofs`] after the edge DOFs, saved with every frame for a restart.
#[derive(Clone, Debug, PartialEq)]
pub struct GlobalDof {
    /// Its name in `log.csv` (the value, in its unit).
    pub name: String,
    /// Newton's residual scale: the length (m) that turns the DOF's gradient into a force
    /// (1 for a translation, whose gradient already is one).
    pub length: Real,
    /// The largest change of the DOF in one Newton iteration (a force-controlled obstacle
    /// moves at most half the sheet's thickness, so that a long first step cannot carry it
    /// through the sheet).
    pub max_step: Real,
    /// Its inertia in dynamics (kg for a translation).
    pub mass: Real,
}

/// A tracked state in a restart frame that cannot be used.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("face {face}: {reason}")]
pub struct StateError {
    /// The face whose value is invalid.
    pub face: usize,
    /// What is wrong with it.
    pub reason: String,
}

/// One energy term of the potential.
pub trait Term: Send + Sync {
    /// The name under which its energy is reported (`log.csv`, `summary.json`).
    fn name(&self) -> &'static str;

    /// The elements and their DOF nodes.
    fn stencil(&self, body: &Body) -> Stencil;

    /// Adds the term's energy (returned), gradient and Hessian (lower triangle, pattern order)
    /// at positions `x` and edge DOFs `phi` into `grad`/`values` as `want` says, skipping fixed
    /// nodes.
    #[allow(clippy::too_many_arguments)]
    fn eval(
        &self,
        pot: &Potential,
        map: &ElementMap,
        x: &[Vec3],
        phi: &[Real],
        want: Want,
        projection: HessianProjection,
        grad: &mut [Real],
        values: &mut [Real],
    ) -> Real;

    /// A term that reports more than its energy under its name (several energies, face
    /// fields, logged quantities, membrane stresses) declares it here (default: none; see
    /// [`energies`]).
    fn reports(&self) -> Option<&dyn Reports> {
        None
    }

    /// A term that tracks a per-face state across steps, carried by the frames, declares it
    /// here (default: none).
    fn tracked(&self) -> Option<&dyn Tracked> {
        None
    }

    /// A term with a state of its own that changes during a run (a multiplier, a moving
    /// slide, a per-face thickness, per-edge frames) declares it here (default: none). The
    /// state itself lives in the driver's [`crate::solve::State`], not in the term.
    fn stateful(&self) -> Option<&dyn Stateful> {
        None
    }

    /// A term that projects the state after each accepted implicit step declares it here
    /// (default: none).
    fn projection(&self) -> Option<&dyn Projection> {
        None
    }

    /// A term whose elements change during a run declares it here (default: fixed elements).
    fn changing(&self) -> Option<&dyn ChangingElements> {
        None
    }

    /// A term that owns global DOFs declares them here (default: none).
    fn global_dofs(&mut self) -> Option<&mut dyn GlobalDofs> {
        None
    }

    /// A term that carries a multiplier updated after each converged solve (a prescribed
    /// volume's pressure) declares it here (default: none).
    fn updates(&self) -> Option<&dyn Multiplier> {
        None
    }

    /// A term that knows how its load moves a static equilibrium declares its predictor here
    /// (default: none).
    fn predictor(&self) -> Option<&dyn Predictor> {
        None
    }

    /// Whether the term is an applied load (gravity, point, traction, pressure, moment): its
    /// forces set the static solver's force scale ([`Potential::load_scale`]) (default: no).
    fn applied_load(&self) -> bool {
        false
    }

    /// A term with a dense low-rank Hessian part declares it here (default: none).
    fn low_rank(&self) -> Option<&dyn LowRankPart> {
        None
    }

    /// A term whose friction takes its normal forces at a lagged iterate (the dynamic
    /// driver's friction lag) declares it here, so that the lag can tell when they settled
    /// (default: none).
    fn lagged(&self) -> Option<&dyn LaggedNormals> {
        None
    }

    /// A term that acts on the explicit driver's steps beyond its energy declares its hooks
    /// here (default: none). The explicit driver fuses the update into the gradient's parallel
    /// parts only when no term declares them.
    fn explicit(&self) -> Option<&dyn ExplicitHooks> {
        None
    }

    /// A term that bounds every Newton step and checks every trial state (contact by
    /// continuous collision detection) declares it here (default: none).
    fn step_limit(&self) -> Option<&dyn StepLimit> {
        None
    }

    /// A term whose energy depends on the faces' rest data (ā, b̄, h̄) declares its rest
    /// sensitivities here, for inverse design (default: none, an energy that does not read
    /// them).
    fn rest_sensitivity(&self) -> Option<&dyn RestSensitivity> {
        None
    }
}

/// The mixed derivatives of a term's gradient with respect to each face's rest data
/// ([`super::sensitivity`]).
pub trait RestSensitivity {
    /// `λᵀ ∂g/∂r_f` for every face `f` at positions `x`, scalar DOFs `phi`, with `λ` in the
    /// global DOF order; an error names what has no sensitivity (a membrane material other
    /// than Koiter's, bend stiffening).
    fn rest_adjoint(
        &self,
        pot: &Potential,
        x: &[Vec3],
        phi: &[Real],
        lambda: &[Real],
    ) -> Result<Vec<super::sensitivity::RestAdjoint>, String>;
}

/// How far a Newton step may go ([`StepLimit::max_fraction`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepBound {
    /// The largest fraction of the step allowed, in `[0, 1]`.
    pub fraction: Real,
    /// Whether the term's elements, gathered again at the step's start, would allow a
    /// markedly longer step: a vertex has used up the room it had from where they were
    /// gathered. Newton then stops, and the driver gathers them again and goes on.
    pub regather: bool,
}

/// The capability of a term that bounds the Newton steps: the line search starts from the
/// largest fraction of the step every such term allows, and accepts no trial state a term
/// does not admit (it halves the step instead).
pub trait StepLimit {
    /// The largest fraction in `[0, 1]` of `step` (DOF order) from the state `(x, phi)` that
    /// the term allows (every state on the segment is admissible), and whether gathering its
    /// elements again at `x` would allow a longer one.
    fn max_fraction(
        &self,
        pot: &Potential,
        map: &ElementMap,
        x: &[Vec3],
        phi: &[Real],
        step: &[Real],
    ) -> StepBound;

    /// Whether the term admits the state `(x, phi)` (the static check of a trial state).
    fn admits(&self, pot: &Potential, map: &ElementMap, x: &[Vec3], phi: &[Real]) -> bool;

    /// The largest fraction in `[0, 1]` of the jump from the positions `from` at dial
    /// `from_dial` to `to` at `pot.dial` (a new step's start: vertices on prescribed paths and
    /// the term's own rigid parts moved with the dial, the other vertices where the solve
    /// starts), the scalar DOFs `phi` held, that the term allows, every state on the straight
    /// paths admissible. 1 by default (nothing of the term moves with the dial).
    fn jump_fraction(
        &self,
        _pot: &Potential,
        _from: &[Vec3],
        _to: &[Vec3],
        _phi: &[Real],
        _from_dial: Real,
    ) -> Real {
        1.0
    }

    /// The explicit driver, which has no Newton step to bound: lowers `bounds[v]` to how far
    /// (m) vertex `v` may move from `x`, the positions the term's elements were gathered at,
    /// such that while every vertex stays within its bound every state is admissible and no
    /// element that was not gathered acts (per-vertex displacement bounds, as in offset
    /// geometric contact, Chen et al. 2025).
    fn displacement_bounds(
        &self,
        pot: &Potential,
        map: &ElementMap,
        x: &[Vec3],
        bounds: &mut [Real],
    );

    /// The explicit driver, with [`StepLimit::displacement_bounds`]: how far the dial may
    /// move from `pot.dial` (either way) with the term's own parts that move with it (a mesh
    /// obstacle), such that, while every vertex also stays within its bound from `x`, every
    /// state is admissible and no element that was not gathered acts. `+∞` by default
    /// (nothing of the term moves with the dial).
    fn dial_room(&self, _pot: &Potential, _map: &ElementMap, _x: &[Vec3]) -> Real {
        Real::INFINITY
    }
}

/// The capability of a term that reports more than its energy under its name.
pub trait Reports {
    /// Energies to report, by name; `None` (default) reports the whole term under its name.
    fn energies(
        &self,
        _pot: &Potential,
        _map: &ElementMap,
        _x: &[Vec3],
        _phi: &[Real],
    ) -> Option<Vec<(&'static str, Real)>> {
        None
    }

    /// Everything a frame reports at once: [`Reports::energies`] and [`Reports::face_fields`].
    /// A term whose two share a computation overrides it to do that computation once.
    #[allow(clippy::type_complexity)]
    fn report(
        &self,
        pot: &Potential,
        map: &ElementMap,
        x: &[Vec3],
        phi: &[Real],
    ) -> (Option<Vec<(&'static str, Real)>>, Vec<(String, Vec<Real>)>) {
        (
            self.energies(pot, map, x, phi),
            self.face_fields(pot, x, phi),
        )
    }

    /// Per-face fields this term contributes to the frames (default: none).
    fn face_fields(
        &self,
        _pot: &Potential,
        _x: &[Vec3],
        _phi: &[Real],
    ) -> Vec<(String, Vec<Real>)> {
        Vec::new()
    }

    /// `∂W/∂a` of each face's stretching energy W (J) with respect to its barycentric first
    /// fundamental form, in the stored components `[a11, a12, a22]` (J/m²), for the frames'
    /// Cauchy stress (`fields::cauchy_principal`). Default: `None`, no membrane energy.
    fn membrane_stress(
        &self,
        _pot: &Potential,
        _x: &[Vec3],
        _phi: &[Real],
    ) -> Option<Vec<crate::math::Sym2>> {
        None
    }

    /// Quantities to log per frame, by column name (default: none), e.g. a load's conjugate
    /// displacement for load–displacement curves.
    fn observables(&self, _pot: &Potential, _x: &[Vec3], _phi: &[Real]) -> Vec<(String, Real)> {
        Vec::new()
    }
}

/// The energies `t` reports at `(x, phi)`: its [`Reports::energies`], or its whole energy under
/// its name.
pub fn energies(
    t: &dyn Term,
    pot: &Potential,
    map: &ElementMap,
    x: &[Vec3],
    phi: &[Real],
) -> Vec<(&'static str, Real)> {
    t.reports()
        .and_then(|r| r.energies(pot, map, x, phi))
        .unwrap_or_else(|| whole(t, pot, map, x, phi))
}

/// What a frame reports of `t` at `(x, phi)`: its energies ([`energies`]) and face fields.
#[allow(clippy::type_complexity)]
pub fn report(
    t: &dyn Term,
    pot: &Potential,
    map: &ElementMap,
    x: &[Vec3],
    phi: &[Real],
) -> (Vec<(&'static str, Real)>, Vec<(String, Vec<Real>)>) {
    match t.reports() {
        Some(r) => {
            let (e, f) = r.report(pot, map, x, phi);
            (e.unwrap_or_else(|| whole(t, pot, map, x, phi)), f)
        }
        None => (whole(t, pot, map, x, phi), Vec::new()),
    }
}

/// The quantities `t` logs at `(x, phi)` ([`Reports::observables`]).
pub fn observables(t: &dyn Term, pot: &Potential, x: &[Vec3], phi: &[Real]) -> Vec<(String, Real)> {
    t.reports()
        .map(|r| r.observables(pot, x, phi))
        .unwrap_or_default()
}

/// The whole energy of `t` under its name.
fn whole(
    t: &dyn Term,
    pot: &Potential,
    map: &ElementMap,
    x: &[Vec3],
    phi: &[Real],
) -> Vec<(&'static str, Real)> {
    let e = t.eval(
        pot,
        map,
        x,
        phi,
        Want::Energy,
        HessianProjection::None,
        &mut [],
        &mut [],
    );
    vec![(t.name(), e)]
}

/// The capability of a term with a state of its own.
///
/// The state is a vector of reals that the term reads through [`Potential::term_state`] under
/// its [`Term::name`] (unique among the stateful terms of a scene) and that only the drivers
/// change, through the term's [`Tracked`], [`Projection`], [`Multiplier`], [`Predictor`] and
/// [`ExplicitHooks`] capabilities, which receive it as `own`. It lives in
/// [`crate::solve::State::terms`] beside the positions: a trial step that is cut leaves it as
/// it was, clones of a scene share none of it, and every frame's restart file carries it under
/// the term's name.
pub trait Stateful {
    /// The state at the start of a run.
    fn initial_state(&self) -> Vec<Real>;

    /// Checks a state read from a restart file (default: the initial state's length and finite
    /// values), or says what is wrong with it.
    fn check_state(&self, state: &[Real]) -> Result<(), String> {
        let n = self.initial_state().len();
        if state.len() != n || !state.iter().all(|v| v.is_finite()) {
            return Err(format!("expected {n} finite values, got {state:?}"));
        }
        Ok(())
    }
}

/// Every stateful term's state, under its term's name, in term order (see [`Stateful`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TermStates(Vec<(&'static str, Vec<Real>)>);

impl TermStates {
    /// The initial states of `terms` (those that declare [`Term::stateful`]). Two stateful
    /// terms with one name are an error naming it.
    pub fn initial(terms: &[Box<dyn Term>]) -> Result<TermStates, String> {
        let mut all: Vec<(&'static str, Vec<Real>)> = Vec::new();
        for t in terms {
            if let Some(s) = t.stateful() {
                if all.iter().any(|(n, _)| *n == t.name()) {
                    return Err(format!("two stateful terms are named '{}'", t.name()));
                }
                all.push((t.name(), s.initial_state()));
            }
        }
        Ok(TermStates(all))
    }

    /// The state of the term named `name` (empty when it has none). Kernels ask per element
    /// with their own `&'static str`, so the names are compared by address first.
    #[inline]
    pub fn get(&self, name: &str) -> &[Real] {
        self.0
            .iter()
            .find(|(n, _)| std::ptr::eq(*n, name) || *n == name)
            .map_or(&[], |(_, v)| &v[..])
    }

    /// The state of the term named `name`, to change (empty when it has none).
    pub fn get_mut(&mut self, name: &str) -> &mut [Real] {
        match self.0.iter_mut().find(|(n, _)| *n == name) {
            Some((_, v)) => &mut v[..],
            None => &mut [],
        }
    }

    /// Replaces the state of the term named `name` (nothing when it has none).
    pub fn set(&mut self, name: &str, values: Vec<Real>) {
        if let Some((_, v)) = self.0.iter_mut().find(|(n, _)| *n == name) {
            *v = values;
        }
    }

    /// Every (name, state), in term order.
    pub fn iter(&self) -> impl Iterator<Item = (&'static str, &[Real])> {
        self.0.iter().map(|(n, v)| (*n, &v[..]))
    }

    /// Copies `other` (the same terms) into `self` without allocating.
    pub fn copy_from(&mut self, other: &TermStates) {
        if self.0.len() == other.0.len()
            && self
                .0
                .iter()
                .zip(&other.0)
                .all(|(a, b)| a.1.len() == b.1.len())
        {
            for (a, b) in self.0.iter_mut().zip(&other.0) {
                a.1.copy_from_slice(&b.1);
            }
        } else {
            self.clone_from(other);
        }
    }
}

/// The capability of a term that tracks a per-face state across steps (the moment's angles,
/// the prism's position-based thickness). Its state is the term's [`Stateful`] state `own`.
pub trait Tracked {
    /// The name of the per-face field that shows it. Frames hold it in the face's edge order
    /// (like `edge_angles`) when it has 3 components per face, and a restart from a frame
    /// without its restart file hands it back to [`Tracked::restore`].
    fn state_field(&self) -> &'static str;

    /// Values per face (default: 3).
    fn state_components(&self) -> usize {
        3
    }

    /// The field at `(x, phi)` with the state `own`: [`Tracked::state_components`] values per
    /// face.
    fn field(&self, x: &[Vec3], phi: &[Real], own: &[Real]) -> Vec<Real>;

    /// Rebuilds the state `own` at the restart state `(x, phi)` from a frame's field (`None`
    /// when the frame has none: the term then says in the returned warning what it assumed).
    /// An invalid field is an error naming the face.
    fn restore(
        &self,
        x: &[Vec3],
        phi: &[Real],
        field: Option<&[Real]>,
        own: &mut [Real],
    ) -> Result<Option<String>, StateError>;

    /// Called by the drivers after every accepted step (static continuation step or time
    /// step) at the accepted state (default: nothing).
    fn accept(&self, _x: &[Vec3], _phi: &[Real], _own: &mut [Real]) {}

    /// Whether `(x, phi)` may become the next accepted state from the state `own` (default:
    /// yes); a step too large for the tracked state is refused, and the driver cuts it.
    fn admissible(&self, _x: &[Vec3], _phi: &[Real], _own: &[Real]) -> bool {
        true
    }
}

/// The capability of a term that projects the state after each accepted implicit step.
pub trait Projection {
    /// Applied before the velocities are taken from the positions, such as seed 002's
    /// position-based volume preservation; it may move the positions and the term's own
    /// state. Returns the relative constraint error it corrected (`None` when it had nothing
    /// to correct); an error (an element turned inside out) leaves its state as it was, and
    /// the driver cuts the step.
    /// `own` is the term's state; `pot` holds it as it was before the step's projections.
    fn project(
        &self,
        pot: &Potential,
        x: &mut [Vec3],
        phi: &[Real],
        own: &mut [Real],
    ) -> Result<Option<Real>, StateError>;
}

/// The capability of a term whose elements change during a run (contact pairs).
pub trait ChangingElements {
    /// Its elements at the state `(x, phi)`, in an order that depends on nothing but that
    /// state (so that assembly stays bitwise independent of the threads). The static and
    /// dynamic drivers ask before every step (a continuation step, a time step); the sparsity
    /// pattern is rebuilt when some term's elements changed, and the symbolic factorisation
    /// only when the union of the stencils changed
    /// ([`crate::assembly::Pattern::refreshed`]). The explicit driver does not follow changing
    /// elements: such a scene is refused there. `dial` places what moves with it (a mesh
    /// obstacle).
    fn stencil_at(&self, body: &Body, x: &[Vec3], phi: &[Real], dial: Real) -> Stencil;
}

/// The capability of a term that owns global DOFs (a force-controlled obstacle's offset).
pub trait GlobalDofs {
    /// The DOFs. The scene numbers them after the vertex and edge nodes, in term order, and
    /// tells the term its first node with [`GlobalDofs::bind`] before its stencil is asked for.
    fn dofs(&self) -> Vec<GlobalDof>;
    /// Gives the term the node id of its first global DOF; its DOF in
    /// [`crate::solve::State::dofs`] is `node − vertices`.
    fn bind(&mut self, first_node: usize);
}

/// The capability of a term that carries a multiplier.
pub trait Multiplier {
    /// After a converged solve at `(x, phi)`: updates the multiplier and returns `true` when
    /// the solve must be repeated with it. `sensitivity(u)` is `uᵀ H⁻¹ u` with the solve's last
    /// Hessian (sparse factor and low-rank parts; `None` when there is none), the derivative of
    /// the equilibrium's `u·x` with respect to a load along `u`. `own` is the term's state
    /// (the multiplier); `pot` holds it as it was for the solve.
    fn update(
        &self,
        pot: &Potential,
        x: &[Vec3],
        phi: &[Real],
        own: &mut [Real],
        sensitivity: &mut dyn FnMut(&[Real]) -> Option<Real>,
    ) -> bool;
}

/// The capability of a term that predicts how its load moves a static equilibrium.
pub trait Predictor {
    /// Static continuation, before the solve at the new dial `pot.dial` from the equilibrium
    /// `(x, phi)` at dial `from`: moves `x` (and the term's own multiplier) along the tangent
    /// of the equilibrium path (Euler's predictor), with `solve(r)` applying the last
    /// Hessian's inverse to `r` (`false` when there is none). `own` is the term's state.
    fn predict(
        &self,
        pot: &Potential,
        from: Real,
        x: &mut [Vec3],
        phi: &[Real],
        own: &mut [Real],
        solve: &mut dyn FnMut(&mut [Real]) -> bool,
    );
}

/// The capability of a term with a dense low-rank Hessian part.
pub trait LowRankPart {
    /// The part `Σ c u uᵀ` at `(x, phi)`, appended to `out`. Entries on fixed or pinned DOFs
    /// must be zero.
    fn low_rank(&self, pot: &Potential, x: &[Vec3], phi: &[Real], out: &mut Vec<LowRank>);
}

/// The capability of a term whose friction uses normal forces taken at the friction lag's
/// iterate ([`crate::energy::potential::Friction::x_lag`]).
pub trait LaggedNormals {
    /// The largest normal force (N) at the iterate `trial` at dial `dial`, and the largest
    /// change of a normal force from the lagged iterate `lag` at dial `dial_lag` to it.
    fn lag_change(&self, trial: &[Vec3], dial: Real, lag: &[Vec3], dial_lag: Real) -> (Real, Real);
}

/// The capability of a term that acts on the explicit driver's steps.
pub trait ExplicitHooks {
    /// Before the gradient at positions `x` of a step `dt` (s) at dial `dial`: a term with a
    /// state of its own that follows the sheet (a moving slide) advances its state `own` to
    /// these positions, so that the gradient sees the two consistent. Default: nothing.
    fn explicit_begin(&self, _body: &Body, _dial: Real, _x: &[Vec3], _dt: Real, _own: &mut [Real]) {
    }

    /// After the gradient `g` at positions `x` with velocities `v` and before the step `dt`
    /// (s): adjusts `g` and `v` beyond the term's energy (stick/slip friction).
    fn explicit_step(&self, pot: &Potential, x: &[Vec3], v: &mut [Vec3], g: &mut [Real], dt: Real);

    /// The force (N) left unbalanced at positions `x` on a degree of freedom the term moves
    /// itself (a force-controlled slide: the prescribed force minus the sheet's push on it),
    /// which the equilibrium test requires to vanish like the sheet's own forces; or why it
    /// never can (the slide has passed the sheet). Default: 0.
    fn explicit_unbalanced(&self, _pot: &Potential, _x: &[Vec3]) -> Result<Real, String> {
        Ok(0.0)
    }
}

/// A pure per-element kernel with `N` local DOFs over `S` stencil slots (compile-time sizes for
/// the assembly loops).
pub trait ElementKernel<const N: usize, const S: usize>: Send + Sync {
    /// Whether the per-element projections (`"abs"`, `"clamp_zero"`) may be applied to its
    /// element Hessians (not for a split that is not itself meaningful, such as the cones of an
    /// enclosed volume, whose per-face Hessians depend on the origin).
    const PROJECTABLE: bool = true;
    /// Whether the kernel is an applied load ([`Term::applied_load`]).
    const LOAD: bool = false;

    /// Energy of element `e` with stencil `nodes`, optional gradient and Hessian in the local
    /// DOF order of the stencil's slots. `gauss_newton` asks for a positive semi-definite
    /// Hessian where the kernel has one.
    #[allow(clippy::too_many_arguments)]
    fn eval(
        &self,
        pot: &Potential,
        e: usize,
        nodes: &[usize],
        x: &[Vec3],
        phi: &[Real],
        gauss_newton: bool,
        grad: Option<&mut SVec<N>>,
        hess: Option<&mut SMat<N, N>>,
    ) -> Real;
}

/// An [`ElementKernel`] as a [`Term`]: stencil from a function, the coloured assembly loop.
pub struct ElementTerm<K, const N: usize, const S: usize> {
    /// Reported name.
    pub name: &'static str,
    /// The kernel.
    pub kernel: K,
    /// The stencil builder.
    pub stencil: fn(&Body, &K) -> Stencil,
}

impl<K: ElementKernel<N, S>, const N: usize, const S: usize> Term for ElementTerm<K, N, S> {
    fn name(&self) -> &'static str {
        self.name
    }
    fn applied_load(&self) -> bool {
        K::LOAD
    }
    fn stencil(&self, body: &Body) -> Stencil {
        (self.stencil)(body, &self.kernel)
    }
    fn eval(
        &self,
        pot: &Potential,
        map: &ElementMap,
        x: &[Vec3],
        phi: &[Real],
        want: Want,
        projection: HessianProjection,
        grad: &mut [Real],
        values: &mut [Real],
    ) -> Real {
        let gn = projection == HessianProjection::GaussNewton;
        assemble_elements_owned::<N, S, _>(
            map,
            |e, nodes, g, h| self.kernel.eval(pot, e, nodes, x, phi, gn, g, h),
            pot.node_fixed,
            if K::PROJECTABLE {
                projection
            } else {
                HessianProjection::None
            },
            want,
            grad,
            values,
            &pot.pattern.col_ptr,
            pot.owned,
        )
    }
}

/// A per-vertex kernel: energy, gradient (N) and Hessian (N/m) of one vertex at `x`.
pub trait VertexKernel: Send + Sync {
    /// Whether the kernel is an applied load ([`Term::applied_load`]).
    const LOAD: bool = false;
    /// `None` when the vertex does not contribute. `own` is the kernel's own state
    /// ([`VertexKernel::initial_state`], fetched once per evaluation; empty without one).
    fn eval(&self, pot: &Potential, own: &[Real], v: usize, x: &Vec3)
        -> Option<(Real, Vec3, Mat3)>;
    /// Quantities to log (see [`Reports::observables`]; default: none).
    fn observables(&self, _pot: &Potential, _x: &[Vec3]) -> Vec<(String, Real)> {
        Vec::new()
    }
    /// Whether the kernel acts on the explicit driver's steps: its term then declares
    /// [`ExplicitHooks`] with the three methods below (default: no).
    fn explicit_hooks(&self) -> bool {
        false
    }
    /// See [`ExplicitHooks::explicit_begin`] (default: nothing).
    fn explicit_begin(&self, _body: &Body, _dial: Real, _x: &[Vec3], _dt: Real, _own: &mut [Real]) {
    }
    /// See [`ExplicitHooks::explicit_step`] (default: nothing).
    fn explicit_step(
        &self,
        _pot: &Potential,
        _x: &[Vec3],
        _v: &mut [Vec3],
        _g: &mut [Real],
        _dt: Real,
    ) {
    }
    /// The kernel's own state at the start of a run, if it has one: its term then declares
    /// [`Stateful`] (default: none).
    fn initial_state(&self) -> Option<Vec<Real>> {
        None
    }
    /// Whether the kernel's friction uses lagged normal forces: its term then declares
    /// [`LaggedNormals`] with [`VertexKernel::lag_change`] (default: no).
    fn lags_normals(&self) -> bool {
        false
    }
    /// See [`LaggedNormals::lag_change`] (default: no force, no change).
    fn lag_change(
        &self,
        _trial: &[Vec3],
        _dial: Real,
        _lag: &[Vec3],
        _dial_lag: Real,
    ) -> (Real, Real) {
        (0.0, 0.0)
    }
    /// See [`ExplicitHooks::explicit_unbalanced`] (default: 0).
    fn explicit_unbalanced(&self, _pot: &Potential, _x: &[Vec3]) -> Result<Real, String> {
        Ok(0.0)
    }
}

/// A [`VertexKernel`] as a [`Term`]. Fixed vertices contribute nothing to Φ (a constant);
/// the reported energy includes them.
pub struct VertexTerm<K> {
    /// Reported name.
    pub name: &'static str,
    /// The kernel.
    pub kernel: K,
    /// Whether its energy is reported (inertia and friction are parts of one step's
    /// incremental potential, not stored energies: the kinetic energy is reported instead).
    pub report: bool,
}

impl<K: VertexKernel> Term for VertexTerm<K> {
    fn name(&self) -> &'static str {
        self.name
    }
    fn applied_load(&self) -> bool {
        K::LOAD
    }
    fn explicit(&self) -> Option<&dyn ExplicitHooks> {
        self.kernel.explicit_hooks().then_some(self)
    }
    fn stateful(&self) -> Option<&dyn Stateful> {
        self.kernel.initial_state().is_some().then_some(self)
    }
    fn lagged(&self) -> Option<&dyn LaggedNormals> {
        self.kernel.lags_normals().then_some(self)
    }
    fn reports(&self) -> Option<&dyn Reports> {
        Some(self)
    }
    fn stencil(&self, body: &Body) -> Stencil {
        Stencil::vertices(&body.mesh.positions)
    }
    fn eval(
        &self,
        pot: &Potential,
        map: &ElementMap,
        x: &[Vec3],
        _phi: &[Real],
        want: Want,
        projection: HessianProjection,
        grad: &mut [Real],
        values: &mut [Real],
    ) -> Real {
        let fixed = pot.node_fixed;
        let own = pot.term_state(self.name);
        assemble_elements::<3, 1, _>(
            map,
            |v, _, g, h| {
                if fixed[v] {
                    return no_contribution(g, h);
                }
                let (e, gv, hv) = self.kernel.eval(pot, own, v, &x[v]).unwrap_or((
                    0.0,
                    Vec3::zeros(),
                    Mat3::zeros(),
                ));
                if let Some(g) = g {
                    g.copy_from(&gv);
                }
                if let Some(h) = h {
                    h.copy_from(&hv);
                }
                e
            },
            pot.node_fixed,
            projection,
            want,
            grad,
            values,
            &pot.pattern.col_ptr,
        )
    }
}

impl<K: VertexKernel> Reports for VertexTerm<K> {
    fn observables(&self, pot: &Potential, x: &[Vec3], _: &[Real]) -> Vec<(String, Real)> {
        self.kernel.observables(pot, x)
    }
    fn energies(
        &self,
        pot: &Potential,
        _: &ElementMap,
        x: &[Vec3],
        _: &[Real],
    ) -> Option<Vec<(&'static str, Real)>> {
        if !self.report {
            return Some(Vec::new());
        }
        let own = pot.term_state(self.name);
        let e = x
            .iter()
            .enumerate()
            .filter_map(|(v, xv)| self.kernel.eval(pot, own, v, xv).map(|r| r.0))
            .sum();
        Some(vec![(self.name, e)])
    }
}

impl<K: VertexKernel> LaggedNormals for VertexTerm<K> {
    fn lag_change(&self, trial: &[Vec3], dial: Real, lag: &[Vec3], dial_lag: Real) -> (Real, Real) {
        self.kernel.lag_change(trial, dial, lag, dial_lag)
    }
}

impl<K: VertexKernel> Stateful for VertexTerm<K> {
    fn initial_state(&self) -> Vec<Real> {
        self.kernel.initial_state().unwrap_or_default()
    }
}

impl<K: VertexKernel> ExplicitHooks for VertexTerm<K> {
    fn explicit_begin(&self, body: &Body, dial: Real, x: &[Vec3], dt: Real, own: &mut [Real]) {
        self.kernel.explicit_begin(body, dial, x, dt, own);
    }
    fn explicit_step(&self, pot: &Potential, x: &[Vec3], v: &mut [Vec3], g: &mut [Real], dt: Real) {
        self.kernel.explicit_step(pot, x, v, g, dt);
    }
    fn explicit_unbalanced(&self, pot: &Potential, x: &[Vec3]) -> Result<Real, String> {
        self.kernel.explicit_unbalanced(pot, x)
    }
}

/// A scene's terms, shared (cheap to clone with the scene).
#[derive(Clone, Default)]
pub struct Terms(pub std::sync::Arc<Vec<Box<dyn Term>>>);

impl std::ops::Deref for Terms {
    type Target = [Box<dyn Term>];
    fn deref(&self) -> &Self::Target {
        &self.0
    }
}

impl std::fmt::Debug for Terms {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_list()
            .entries(self.0.iter().map(|t| t.name()))
            .finish()
    }
}

impl Terms {
    /// Adds a term after the registry's (for library users' own terms; build the pattern
    /// after this). Returns the term back if the list is shared with another scene.
    pub fn push(&mut self, t: Box<dyn Term>) -> Result<(), Box<dyn Term>> {
        match std::sync::Arc::get_mut(&mut self.0) {
            Some(list) => {
                list.push(t);
                Ok(())
            }
            None => Err(t),
        }
    }
}

/// The per-face fields with one value per corner slot (the edge opposite each corner):
/// `edge_angles` and the terms' 3-component state fields. Frames write them in the input's
/// corner order.
pub fn slot_fields(terms: &[Box<dyn Term>]) -> Vec<&'static str> {
    let mut names = vec!["edge_angles"];
    names.extend(
        terms
            .iter()
            .filter_map(|t| t.tracked())
            .filter(|t| t.state_components() == 3)
            .map(|t| t.state_field()),
    );
    names
}
