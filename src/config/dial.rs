//! `[dial]`: how the rest forms are dialled in (their order, the starting forms) and the holds
//! on the way.

use super::limits::MAX_HOLDS;
use super::{Check, Invalid};
use crate::math::Real;
use serde::{Deserialize, Serialize};

/// The order in which ā and b̄ are dialled.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DialOrder {
    /// Both together: dial s takes both from their initial to their target values.
    #[default]
    Together,
    /// b̄ over the first half of the dial (ā at its initial value), then ā over the second half.
    BbarFirst,
}

/// How the rest forms are dialled.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Dial {
    /// `"together"` (default) or `"bbar_first"`.
    pub order: DialOrder,
    /// Dial factors in (0, 1) at which the dial stops until the sheet is at equilibrium, then
    /// goes on (ascending; default: none).
    pub holds: Vec<Real>,
    /// Where the dial starts: `"reference"` (default) or `"start"`.
    pub from: DialFrom,
}

/// The forms at dial 0.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DialFrom {
    /// The reference mesh's own forms.
    #[default]
    Reference,
    /// The forms of the state the run starts from (a `--restart` frame or MorphoShell ansatz,
    /// as MorphoShell's `dialling_from_ansatz_rather_than_ref_state`); the dial starts at 0.
    /// Without a restart this is the reference mesh.
    Start,
}

impl Dial {
    /// Validates `[dial]`: holds ascending strictly inside (0, 1), and `from = "start"` only
    /// when the rest forms are not computed by a growth law or moisture (`computed_rest`).
    pub fn validate(&self, computed_rest: bool) -> Result<(), Invalid> {
        let ck = Check;
        if self.holds.len() > MAX_HOLDS {
            return ck.inv(
                "dial.holds",
                format!(
                    "{} holds is more than {MAX_HOLDS}: each hold is a solve to equilibrium \
                     and a frame",
                    self.holds.len()
                ),
            );
        }
        let mut last = 0.0;
        for (i, &h) in self.holds.iter().enumerate() {
            if !(h.is_finite() && h > last && h < 1.0) {
                return ck.inv(
                    &format!("dial.holds[{i}]"),
                    format!("holds must ascend strictly inside (0, 1), got {h}"),
                );
            }
            last = h;
        }
        if self.from == DialFrom::Start && computed_rest {
            return ck.inv(
                "dial.from",
                "\"start\" dials rest.target's forms from the starting state; growth laws and \
                 moisture set the rest forms from the reference mesh, so the two do not combine"
                    .into(),
            );
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Holds ascend strictly inside (0, 1); `from = "start"` refuses computed rest forms.
    #[test]
    fn holds_ascend_inside_the_dial() {
        assert_eq!(Dial::default().validate(true), Ok(()));
        let holds = |h: Vec<Real>| Dial {
            holds: h,
            ..Dial::default()
        };
        assert_eq!(holds(vec![0.25, 0.5]).validate(false), Ok(()));
        assert_eq!(
            holds(vec![0.5, 0.25]).validate(false).unwrap_err().key,
            "dial.holds[1]"
        );
        assert_eq!(
            holds(vec![1.0]).validate(false).unwrap_err().key,
            "dial.holds[0]"
        );
        let start = Dial {
            from: DialFrom::Start,
            ..Dial::default()
        };
        assert_eq!(start.validate(false), Ok(()));
        assert_eq!(start.validate(true).unwrap_err().key, "dial.from");
    }
}
