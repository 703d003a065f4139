//! Arithmetic expressions of the reference coordinates `x`, `y` (m) in settings files, e.g.
//! `rest.abar = ["1 + x^2", "-x*y", "1 + y^2"]` (seed 000 Table 1's hyperboloid) or
//! `growth.s = "log(2 / (1 + (x^2 + y^2)/4))"`.
//!
//! Grammar (usual precedence, `^` binds tightest and associates to the right, unary minus binds
//! looser than `^` so `-x^2 = -(x^2)`):
//!
//! ```text
//! expr   = term (('+' | '-') term)*
//! term   = unary (('*' | '/') unary)*
//! unary  = '-' unary | power
//! power  = atom ('^' unary)?
//! atom   = number | 'x' | 'y' | 'pi' | 'e' | name '(' expr (',' expr)* ')' | '(' expr ')'
//! ```
//!
//! Functions: `sqrt exp log sin cos tan asin acos atan abs sinh cosh tanh` (one argument),
//! `atan2(y, x)`, `min(a, b)`, `max(a, b)`, `pow(a, b)`. Parsing is done once, when the settings
//! are read; evaluation walks the tree (a few ns per node).

use crate::math::Real;

/// A parsed expression.
#[derive(Clone, Debug, PartialEq)]
pub enum Expr {
    /// A constant.
    Num(Real),
    /// The reference x coordinate.
    X,
    /// The reference y coordinate.
    Y,
    /// `-a`.
    Neg(Box<Expr>),
    /// A binary operation.
    Bin(Op, Box<Expr>, Box<Expr>),
    /// A function of one or two arguments.
    Call(Func, Vec<Expr>),
}

/// Binary operators.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Op {
    /// `+`
    Add,
    /// `-`
    Sub,
    /// `*`
    Mul,
    /// `/`
    Div,
    /// `^`
    Pow,
}

/// Functions.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[allow(missing_docs)]
pub enum Func {
    Sqrt,
    Exp,
    Log,
    Sin,
    Cos,
    Tan,
    Asin,
    Acos,
    Atan,
    Abs,
    Sinh,
    Cosh,
    Tanh,
    Atan2,
    Min,
    Max,
    Pow,
}

impl Func {
    fn parse(name: &str) -> Option<(Func, usize)> {
        use Func::*;
        Some(match name {
            "sqrt" => (Sqrt, 1),
            "exp" => (Exp, 1),
            "log" | "ln" => (Log, 1),
            "sin" => (Sin, 1),
            "cos" => (Cos, 1),
            "tan" => (Tan, 1),
            "asin" => (Asin, 1),
            "acos" => (Acos, 1),
            "atan" => (Atan, 1),
            "abs" => (Abs, 1),
            "sinh" => (Sinh, 1),
            "cosh" => (Cosh, 1),
            "tanh" => (Tanh, 1),
            "atan2" => (Atan2, 2),
            "min" => (Min, 2),
            "max" => (Max, 2),
            "pow" => (Pow, 2),
            _ => return None,
        })
    }
}

/// Why an expression does not parse. Positions are 1-based characters.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ExprError {
    /// Something else than what the grammar allows at a position (`found: None` at the end).
    #[error("expected {expected} {}", match found { Some(c) => format!("at character {at}, found '{c}'"), None => "at the end".into() })]
    Expected {
        /// What was expected.
        expected: String,
        /// The character found there.
        found: Option<char>,
        /// Where.
        at: usize,
    },
    /// A malformed number.
    #[error("bad number '{text}' at character {at}")]
    BadNumber {
        /// The number's text.
        text: String,
        /// Where it starts.
        at: usize,
    },
    /// A name that is not a variable, constant or function.
    #[error("unknown name '{name}' at character {at} (variables: x, y; constants: pi, e)")]
    UnknownName {
        /// The name.
        name: String,
        /// Where it starts.
        at: usize,
    },
    /// A function called with the wrong number of arguments.
    #[error("{name} takes {arity} argument(s), got {got} (at character {at})")]
    Arity {
        /// The function.
        name: String,
        /// Arguments it takes.
        arity: usize,
        /// Arguments given.
        got: usize,
        /// Where the call starts.
        at: usize,
    },
}

impl Expr {
    /// Parses `text`; the error names the character position (1-based) and what was expected.
    pub fn parse(text: &str) -> Result<Expr, ExprError> {
        let mut p = Parser {
            s: text.as_bytes(),
            i: 0,
        };
        let e = p.expr()?;
        p.skip();
        if p.i < p.s.len() {
            return Err(p.error("an operator or the end"));
        }
        Ok(e)
    }

    /// Value at `(x, y)`.
    pub fn eval(&self, x: Real, y: Real) -> Real {
        match self {
            Expr::Num(v) => *v,
            Expr::X => x,
            Expr::Y => y,
            Expr::Neg(a) => -a.eval(x, y),
            Expr::Bin(op, a, b) => {
                let (a, b) = (a.eval(x, y), b.eval(x, y));
                match op {
                    Op::Add => a + b,
                    Op::Sub => a - b,
                    Op::Mul => a * b,
                    Op::Div => a / b,
                    Op::Pow => a.powf(b),
                }
            }
            Expr::Call(f, args) => {
                let a = args[0].eval(x, y);
                let b = || args[1].eval(x, y);
                use Func::*;
                match f {
                    Sqrt => a.sqrt(),
                    Exp => a.exp(),
                    Log => a.ln(),
                    Sin => a.sin(),
                    Cos => a.cos(),
                    Tan => a.tan(),
                    Asin => a.asin(),
                    Acos => a.acos(),
                    Atan => a.atan(),
                    Abs => a.abs(),
                    Sinh => a.sinh(),
                    Cosh => a.cosh(),
                    Tanh => a.tanh(),
                    Atan2 => a.atan2(b()),
                    Min => a.min(b()),
                    Max => a.max(b()),
                    Pow => a.powf(b()),
                }
            }
        }
    }
}

struct Parser<'a> {
    s: &'a [u8],
    i: usize,
}

impl Parser<'_> {
    fn skip(&mut self) {
        while self.i < self.s.len() && self.s[self.i].is_ascii_whitespace() {
            self.i += 1;
        }
    }

    fn peek(&mut self) -> Option<u8> {
        self.skip();
        self.s.get(self.i).copied()
    }

    fn error(&self, expected: &str) -> ExprError {
        ExprError::Expected {
            expected: expected.into(),
            found: self.s.get(self.i).map(|&c| c as char),
            at: self.i + 1,
        }
    }

    fn expr(&mut self) -> Result<Expr, ExprError> {
        let mut e = self.term()?;
        while let Some(c @ (b'+' | b'-')) = self.peek() {
            self.i += 1;
            let r = self.term()?;
            let op = if c == b'+' { Op::Add } else { Op::Sub };
            e = Expr::Bin(op, Box::new(e), Box::new(r));
        }
        Ok(e)
    }

    fn term(&mut self) -> Result<Expr, ExprError> {
        let mut e = self.unary()?;
        while let Some(c @ (b'*' | b'/')) = self.peek() {
            self.i += 1;
            let r = self.unary()?;
            let op = if c == b'*' { Op::Mul } else { Op::Div };
            e = Expr::Bin(op, Box::new(e), Box::new(r));
        }
        Ok(e)
    }

    fn unary(&mut self) -> Result<Expr, ExprError> {
        match self.peek() {
            Some(b'-') => {
                self.i += 1;
                Ok(Expr::Neg(Box::new(self.unary()?)))
            }
            Some(b'+') => {
                self.i += 1;
                self.unary()
            }
            _ => self.power(),
        }
    }

    fn power(&mut self) -> Result<Expr, ExprError> {
        let base = self.atom()?;
        if self.peek() == Some(b'^') {
            self.i += 1;
            let exp = self.unary()?;
            return Ok(Expr::Bin(Op::Pow, Box::new(base), Box::new(exp)));
        }
        Ok(base)
    }

    fn atom(&mut self) -> Result<Expr, ExprError> {
        match self.peek() {
            Some(b'(') => {
                self.i += 1;
                let e = self.expr()?;
                if self.peek() != Some(b')') {
                    return Err(self.error("')'"));
                }
                self.i += 1;
                Ok(e)
            }
            Some(c) if c.is_ascii_digit() || c == b'.' => {
                let start = self.i;
                while self.i < self.s.len()
                    && (self.s[self.i].is_ascii_digit() || self.s[self.i] == b'.')
                {
                    self.i += 1;
                }
                // Exponent: 1e-3, 2.5E+4.
                if self.i < self.s.len() && matches!(self.s[self.i], b'e' | b'E') {
                    let save = self.i;
                    self.i += 1;
                    if self.i < self.s.len() && matches!(self.s[self.i], b'+' | b'-') {
                        self.i += 1;
                    }
                    if self.i < self.s.len() && self.s[self.i].is_ascii_digit() {
                        while self.i < self.s.len() && self.s[self.i].is_ascii_digit() {
                            self.i += 1;
                        }
                    } else {
                        self.i = save;
                    }
                }
                let text = std::str::from_utf8(&self.s[start..self.i]).unwrap_or("");
                text.parse::<Real>()
                    .map(Expr::Num)
                    .map_err(|_| ExprError::BadNumber {
                        text: text.into(),
                        at: start + 1,
                    })
            }
            Some(c) if c.is_ascii_alphabetic() => {
                let start = self.i;
                while self.i < self.s.len()
                    && (self.s[self.i].is_ascii_alphanumeric() || self.s[self.i] == b'_')
                {
                    self.i += 1;
                }
                let name = std::str::from_utf8(&self.s[start..self.i]).unwrap_or("");
                match name {
                    "x" => return Ok(Expr::X),
                    "y" => return Ok(Expr::Y),
                    "pi" => return Ok(Expr::Num(std::f64::consts::PI)),
                    "e" => return Ok(Expr::Num(std::f64::consts::E)),
                    _ => {}
                }
                let Some((f, arity)) = Func::parse(name) else {
                    return Err(ExprError::UnknownName {
                        name: name.into(),
                        at: start + 1,
                    });
                };
                if self.peek() != Some(b'(') {
                    return Err(self.error(&format!("'(' after {name}")));
                }
                self.i += 1;
                let mut args = vec![self.expr()?];
                while self.peek() == Some(b',') {
                    self.i += 1;
                    args.push(self.expr()?);
                }
                if self.peek() != Some(b')') {
                    return Err(self.error("')'"));
                }
                self.i += 1;
                if args.len() != arity {
                    return Err(ExprError::Arity {
                        name: name.into(),
                        arity,
                        got: args.len(),
                        at: start + 1,
                    });
                }
                Ok(Expr::Call(f, args))
            }
            _ => Err(self.error("a number, x, y, a function or '('")),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn precedence_and_functions() {
        let v = |s: &str| Expr::parse(s).unwrap().eval(0.5, -2.0);
        assert_eq!(v("1 + 2 * 3"), 7.0);
        assert_eq!(v("2^3^2"), 512.0);
        assert_eq!(v("-x^2"), -0.25);
        assert_eq!(v("(1 + x) * y"), -3.0);
        assert_eq!(v("8 / 2 / 2"), 2.0);
        assert_eq!(v("1 - 2 - 3"), -4.0);
        assert_eq!(v("2e-3 * 1E3"), 2.0);
        assert_eq!(v("atan2(y, x)"), (-2.0f64).atan2(0.5));
        assert_eq!(v("max(x, y) + min(x, y)"), -1.5);
        assert_eq!(v("sqrt(x*x + y*y)"), (4.25f64).sqrt());
        assert_eq!(v("exp(log(3))"), 3.0f64.ln().exp());
        assert_eq!(v("pi"), std::f64::consts::PI);
        assert_eq!(v("2 * -x"), -1.0);
    }

    #[test]
    fn errors_name_the_position() {
        for (s, needle) in [
            ("1 +", "at the end"),
            ("1 + * 2", "character 5"),
            ("foo(x)", "unknown name 'foo'"),
            ("sqrt(x, y)", "takes 1 argument"),
            ("(x + 1", "')'"),
            ("x y", "character 3"),
            ("z", "unknown name 'z'"),
        ] {
            let e = Expr::parse(s).unwrap_err().to_string();
            assert!(e.contains(needle), "{s}: {e}");
        }
    }
}
