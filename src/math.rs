//! Scalar, vector and matrix aliases. Nothing else in shellsim names nalgebra types directly,
//! so that the numeric backend can change in one place.

/// The floating-point type used everywhere (SI units).
pub type Real = f64;
/// A point or vector in 3D.
pub type Vec3 = nalgebra::Vector3<Real>;
/// A 2-vector (barycentric or reference Cartesian coordinates).
pub type Vec2 = nalgebra::Vector2<Real>;
/// A 2×2 matrix.
pub type Mat2 = nalgebra::Matrix2<Real>;
/// A 3×3 matrix.
pub type Mat3 = nalgebra::Matrix3<Real>;
/// A fixed-size column vector.
pub type SVec<const N: usize> = nalgebra::SVector<Real, N>;
/// A fixed-size matrix.
pub type SMat<const R: usize, const C: usize> = nalgebra::SMatrix<Real, R, C>;

/// A symmetric 2×2 tensor stored as `[xx, xy, yy]` (the order of the `abar_info` fields).
pub type Sym2 = SVec<3>;

/// Expands a `[xx, xy, yy]` triple to a full symmetric matrix.
#[inline]
pub fn sym_to_mat(s: &Sym2) -> Mat2 {
    Mat2::new(s[0], s[1], s[1], s[2])
}

/// Packs the symmetric part of a 2×2 matrix as `[xx, xy, yy]`.
#[inline]
pub fn mat_to_sym(m: &Mat2) -> Sym2 {
    Sym2::new(m[(0, 0)], 0.5 * (m[(0, 1)] + m[(1, 0)]), m[(1, 1)])
}

/// Determinant of a symmetric 2×2 tensor.
#[inline]
pub fn sym_det(s: &Sym2) -> Real {
    s[0] * s[2] - s[1] * s[1]
}

/// The cross-product matrix `[v]×` with `[v]× w = v × w`.
#[inline]
pub fn skew(v: &Vec3) -> Mat3 {
    Mat3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0)
}

/// Eigenvalues (ascending) of a general real 2×2 matrix with real spectrum; complex pairs
/// return their real part twice.
pub fn eig2(m: &Mat2) -> (Real, Real) {
    let tr = m.trace();
    let det = m.determinant();
    let disc = (0.25 * tr * tr - det).max(0.0).sqrt();
    (0.5 * tr - disc, 0.5 * tr + disc)
}

/// A number for people (messages, labels, the terminal): four significant digits, plain
/// between 1e-3 and 1e5 (`0.7`, `0.7284`, `12.5`, `31416`), otherwise scientific with the
/// mantissa's trailing zeros dropped (`1.5e-7`, `2.346e12`); `"not finite"` for NaN and
/// infinities (messages, logs and summaries never carry `NaN` or `inf`).
pub fn human(x: impl std::borrow::Borrow<Real>) -> String {
    let x = *x.borrow();
    if !x.is_finite() {
        return "not finite".into();
    }
    if x == 0.0 {
        return "0".into();
    }
    let trim = |s: String| -> String {
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    };
    let a = x.abs();
    if (1e-3..1e5).contains(&a) {
        let decimals = (3 - a.log10().floor() as i32).max(0) as usize;
        let s = trim(format!("{x:.decimals$}"));
        // Rounding can carry past the plain range (99999.5 → "100000"): that stays plain.
        if s != "-0" {
            return s;
        }
    }
    let s = format!("{x:.3e}");
    let (m, e) = s.split_once('e').unwrap_or((&s, "0"));
    format!("{}e{e}", trim(m.to_string()))
}
