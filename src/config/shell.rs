//! Configuration values that the shell kernels dispatch on: the edge-DOF bending model's
//! variant, the stretching normalisation and the Hessian projection.

/// The function `g` of the edge-DOF bending model's `q = h g(θ/2 + σφ)`
/// (`material.bending = "midedge_sin"` or `"midedge_tan"`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AngleVariant {
    /// `g = sin`: the mid-edge normal's offset.
    Sin,
    /// `g = tan`.
    Tan,
}

/// Which stretching normalisation to use.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum StretchConvention {
    /// Standard Koiter, strain `(a − ā)/2`: seed 000's `h/4 ‖ā⁻¹a − I‖²_SV`.
    #[default]
    Koiter,
    /// MorphoShell's handbook and code: strain `a − ā` without the ½, a stretching energy 4×
    /// larger. Offered so that MorphoShell users can reproduce earlier results.
    Morphoshell,
}

impl StretchConvention {
    /// Multiplier on the stretching term.
    pub fn factor(self) -> crate::math::Real {
        match self {
            StretchConvention::Koiter => 1.0,
            StretchConvention::Morphoshell => 4.0,
        }
    }
}

/// How to treat negative eigenvalues of an element Hessian.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum HessianProjection {
    /// Use the exact Hessian; indefiniteness is handled by the solver's diagonal shift.
    None,
    /// Exact Hessian when it factorises, the Gauss–Newton Hessian for iterations where it does
    /// not (default: quadratic convergence near a minimum, robust far from one).
    #[default]
    Adaptive,
    /// Always the Gauss–Newton Hessian (positive semi-definite by construction).
    GaussNewton,
    /// Clamp negative eigenvalues to zero.
    ClampZero,
    /// Replace eigenvalues by their absolute values.
    Abs,
}
