//! Values that settings sections share: a number or `"auto"` ([`AutoOr`], [`Softening`]), a
//! number or an expression of the reference coordinates ([`Field`]), with deserialisers whose
//! errors say what they accept.

use crate::math::Real;
use serde::{Deserialize, Serialize};

/// The softening factor of the static solver's membrane continuation.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(untagged)]
pub enum Softening {
    /// A factor ≥ 1 (1 disables the continuation).
    Factor(Real),
    /// `"auto"`: chosen from the mesh size and thickness.
    Auto(Auto),
}

/// The word `"auto"`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Auto {
    /// Automatic.
    Auto,
}

impl Softening {
    /// The factor for a sheet of size `size` (m) and smallest thickness `h` (m).
    pub fn factor(self, size: Real, h: Real) -> Real {
        match self {
            Softening::Factor(c) => c,
            Softening::Auto(_) => ((size / (10.0 * h)).powi(2)).clamp(1.0, 1e8),
        }
    }
}

/// A number, or an expression of the reference coordinates x, y (m) as a string (see
/// `src/expr.rs`), evaluated at each face's reference centroid.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(untagged)]
pub enum Field {
    /// A constant.
    Value(Real),
    /// An expression of x and y.
    Expr(String),
}

impl Field {
    /// The parsed expression (a constant for a number).
    pub fn compile(&self) -> Result<crate::expr::Expr, crate::expr::ExprError> {
        match self {
            Field::Value(v) => Ok(crate::expr::Expr::Num(*v)),
            Field::Expr(s) => crate::expr::Expr::parse(s),
        }
    }

    /// The constant, if this is one.
    pub fn constant(&self) -> Option<Real> {
        match self {
            Field::Value(v) => Some(*v),
            Field::Expr(_) => None,
        }
    }
}

impl From<Real> for Field {
    fn from(v: Real) -> Self {
        Field::Value(v)
    }
}

/// A number or the word `"auto"`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(untagged)]
pub enum AutoOr {
    /// A value.
    Value(Real),
    /// `"auto"`: chosen by the solver (each use documents how).
    Auto(Auto),
}

impl AutoOr {
    /// The value, or `auto` when automatic.
    pub fn or(self, auto: Real) -> Real {
        match self {
            AutoOr::Value(v) => v,
            AutoOr::Auto(_) => auto,
        }
    }
}

/// A settings value that is a number or a string, for the enums that accept either; their
/// errors say what they accept instead of serde's "untagged enum".
pub(crate) enum NumOrStr {
    /// A number.
    Num(Real),
    /// A string.
    Str(String),
}

pub(crate) fn num_or_str<'de, D: serde::Deserializer<'de>>(
    d: D,
    expecting: &'static str,
) -> Result<NumOrStr, D::Error> {
    struct V(&'static str);
    impl serde::de::Visitor<'_> for V {
        type Value = NumOrStr;
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            f.write_str(self.0)
        }
        fn visit_f64<E>(self, v: f64) -> Result<NumOrStr, E> {
            Ok(NumOrStr::Num(v))
        }
        fn visit_i64<E>(self, v: i64) -> Result<NumOrStr, E> {
            Ok(NumOrStr::Num(v as Real))
        }
        fn visit_u64<E>(self, v: u64) -> Result<NumOrStr, E> {
            Ok(NumOrStr::Num(v as Real))
        }
        fn visit_str<E>(self, v: &str) -> Result<NumOrStr, E> {
            Ok(NumOrStr::Str(v.into()))
        }
    }
    d.deserialize_any(V(expecting))
}

/// Number-or-`"auto"` settings.
pub(crate) fn number_or_auto<'de, D: serde::Deserializer<'de>>(
    d: D,
) -> Result<Option<Real>, D::Error> {
    use serde::de::Error;
    match num_or_str(d, "a number or \"auto\"")? {
        NumOrStr::Num(v) => Ok(Some(v)),
        NumOrStr::Str(s) if s == "auto" => Ok(None),
        NumOrStr::Str(s) => Err(D::Error::custom(format!(
            "expected a number or \"auto\", got \"{s}\""
        ))),
    }
}

impl<'de> Deserialize<'de> for AutoOr {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        Ok(number_or_auto(d)?.map_or(AutoOr::Auto(Auto::Auto), AutoOr::Value))
    }
}

impl<'de> Deserialize<'de> for Softening {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        Ok(number_or_auto(d)?.map_or(Softening::Auto(Auto::Auto), Softening::Factor))
    }
}

impl<'de> Deserialize<'de> for Field {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        Ok(
            match num_or_str(d, "a number or an expression of x and y in quotes")? {
                NumOrStr::Num(v) => Field::Value(v),
                NumOrStr::Str(s) => Field::Expr(s),
            },
        )
    }
}

/// `[a, b, c]` with every number as [`crate::math::human`] writes it, for messages.
pub(crate) fn vec_e(v: &[Real]) -> String {
    let parts: Vec<String> = v.iter().map(crate::math::human).collect();
    format!("[{}]", parts.join(", "))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, Deserialize)]
    struct T {
        a: AutoOr,
        s: Softening,
        f: Field,
    }

    /// A number or `"auto"`, and a number or an expression; other words are errors that say
    /// what is accepted.
    #[test]
    fn numbers_words_and_expressions() {
        let t: T = toml::from_str("a = 2\ns = \"auto\"\nf = \"x + y\"").unwrap();
        assert_eq!(t.a.or(1.0), 2.0);
        assert_eq!(t.s.factor(10.0, 1.0), 1.0);
        assert_eq!(t.s.factor(1000.0, 1.0), 1e4); // (L / 10 h)²
        assert_eq!(t.f, Field::Expr("x + y".into()));
        let t: T = toml::from_str("a = \"auto\"\ns = 4\nf = 3").unwrap();
        assert_eq!(t.a.or(1.5), 1.5);
        assert_eq!(t.s.factor(1000.0, 1.0), 4.0);
        assert_eq!(t.f.constant(), Some(3.0));
        let e = toml::from_str::<T>("a = \"often\"\ns = 1\nf = 1").unwrap_err();
        assert!(e.to_string().contains("a number or \"auto\""), "{e}");
    }
}

/// A table `y(x)` of rows `[x, y]`, x strictly increasing: linear between rows, constant beyond
/// the first and the last (a modulus factor against temperature or moisture).
#[derive(Clone, Debug, PartialEq)]
pub struct Curve {
    /// The abscissae, strictly increasing.
    pub x: Vec<Real>,
    /// The values.
    pub y: Vec<Real>,
}

impl Curve {
    /// From validated rows (`check_curve`).
    pub fn from_rows(rows: &[[Real; 2]]) -> Self {
        Curve {
            x: rows.iter().map(|r| r[0]).collect(),
            y: rows.iter().map(|r| r[1]).collect(),
        }
    }

    /// `y(x)`.
    pub fn at(&self, x: Real) -> Real {
        let n = self.x.len();
        if n == 0 {
            return 1.0;
        }
        if x.is_nan() || x <= self.x[0] {
            return self.y[0];
        }
        if x >= self.x[n - 1] {
            return self.y[n - 1];
        }
        let k = self.x.partition_point(|&v| v <= x);
        let s = (x - self.x[k - 1]) / (self.x[k] - self.x[k - 1]);
        self.y[k - 1] + s * (self.y[k] - self.y[k - 1])
    }
}

/// Checks a softening table at `key`: at least one row, finite, the first column strictly
/// increasing (`what` names it, with its unit), each factor in (0, 1000].
pub(crate) fn check_curve(key: &str, rows: &[[Real; 2]], what: &str) -> Result<(), super::Invalid> {
    let ck = super::Check;
    if rows.is_empty() {
        return ck.inv(key, format!("needs rows [{what}, factor]"));
    }
    for (i, r) in rows.iter().enumerate() {
        let k = format!("{key}[{i}]");
        if !r[0].is_finite() {
            return ck.inv(&k, format!("the {what} must be finite"));
        }
        if i > 0 && r[0] <= rows[i - 1][0] {
            return ck.inv(
                &k,
                format!(
                    "the table is not monotone in its {what}: {} after {} (it must increase \
                     strictly)",
                    crate::math::human(r[0]),
                    crate::math::human(rows[i - 1][0])
                ),
            );
        }
        if !(r[1].is_finite() && r[1] > 0.0 && r[1] <= 1e3) {
            return ck.inv(
                &k,
                format!(
                    "the factor on the moduli must lie in (0, 1000], got {}",
                    crate::math::human(r[1])
                ),
            );
        }
    }
    Ok(())
}
