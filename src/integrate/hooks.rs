//! The drivers' calls into the terms' state capabilities ([`crate::energy::term::Stateful`]):
//! each hands a term its own state from the driver's [`State`], so that a step that is cut
//! leaves every term's state as it was before the step.

use crate::energy::Potential;
use crate::math::Real;
use crate::model::Scene;
use crate::solve::State;

/// Tells every tracking term that `state` is accepted (see
/// [`crate::energy::term::Tracked::accept`]).
pub fn accept(scene: &Scene, state: &mut State) {
    for t in scene.terms.iter() {
        if let Some(tr) = t.tracked() {
            tr.accept(&state.x, &state.dofs, state.terms.get_mut(t.name()));
        }
    }
}

/// Whether every tracking term admits `trial` as the next accepted state (see
/// [`crate::energy::term::Tracked::admissible`]).
pub fn admissible(scene: &Scene, trial: &State) -> bool {
    scene.terms.iter().all(|t| {
        t.tracked()
            .is_none_or(|tr| tr.admissible(&trial.x, &trial.dofs, trial.terms.get(t.name())))
    })
}

/// Applies every term's projection to `state` after an accepted implicit step (see
/// [`crate::energy::term::Projection`]). `pot` is evaluated with the states as they were
/// before the projections.
pub fn project(pot: &Potential, state: &mut State) -> Result<(), crate::energy::term::StateError> {
    let before = state.terms.clone();
    let pot = Potential {
        states: &before,
        ..*pot
    };
    for t in pot.terms.iter() {
        if let Some(p) = t.projection() {
            p.project(
                &pot,
                &mut state.x,
                &state.dofs,
                state.terms.get_mut(t.name()),
            )?;
        }
    }
    Ok(())
}

/// Lets every term update its multiplier in `state` after a converged solve with `pot` (whose
/// term states are those the solve used); `true` when one did and the solve must be repeated
/// (see [`crate::energy::term::Multiplier`]).
pub fn update(
    pot: &Potential,
    state: &mut State,
    sensitivity: &mut dyn FnMut(&[Real]) -> Option<Real>,
) -> bool {
    let mut again = false;
    for t in pot.terms.iter() {
        if let Some(m) = t.updates() {
            let own = state.terms.get_mut(t.name());
            again |= m.update(pot, &state.x, &state.dofs, own, sensitivity);
        }
    }
    again
}
