//! A small recursive-descent parser for formulas in one variable z, compiled once into an
//! expression tree (constants folded) that evaluates without allocation.
//!
//! Grammar (lowest to highest precedence):
//!
//! ```text
//! expr    := term (('+' | '-') term)*
//! term    := unary (('*' | '/') unary | power)*      -- a bare `power` is implicit multiplication
//! unary   := ('-' | '+') unary | power
//! power   := primary ('^' unary)?                    -- right-associative: z^2^3 = z^(2^3)
//! primary := number | 'z' | 'pi' | 'π' | 'e' | func '(' expr ')' | '(' expr ')'
//! ```
//!
//! * Numbers: `2`, `0.5`, `.5`, `1e-3`, `2.5E+2`.
//! * Implicit multiplication: `20z`, `2πz`, `2 pi z`, `10(z-0.5)`, `(1+z)(2-z)`; it binds like
//!   `*`, so `1/2z` = (1/2)·z, and `-z^2` = −(z²).
//! * The exponent of `^` is a unary expression, so `e^-20z` = (e^−20)·z: write `exp(-20z)`.
//! * `**` is accepted for `^`; `·` and `×` for `*`; `−` (U+2212) for `-`.
//! * Letters run together split into z, e and pi when that covers them: `piz` = π·z.
//! * Functions: exp, log / ln (natural), log2, log10, sqrt, cbrt, sin, cos, tan, asin, acos,
//!   atan, sinh, cosh, tanh, asinh, abs, sigmoid (1/(1+e^−x)), gauss (e^(−x²)).
//!
//! Errors name the formula and the 1-based character position.

use anyhow::{bail, Result};

/// A unary function callable in formulas.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Func {
    /// `exp(x)`
    Exp,
    /// `ln(x)` (also spelled `log`)
    Ln,
    /// `log2(x)`
    Log2,
    /// `log10(x)`
    Log10,
    /// `sqrt(x)`
    Sqrt,
    /// `cbrt(x)`, the real cube root
    Cbrt,
    /// `sin(x)`
    Sin,
    /// `cos(x)`
    Cos,
    /// `tan(x)`
    Tan,
    /// `asin(x)`
    Asin,
    /// `acos(x)`
    Acos,
    /// `atan(x)`
    Atan,
    /// `sinh(x)`
    Sinh,
    /// `cosh(x)`
    Cosh,
    /// `tanh(x)`
    Tanh,
    /// `asinh(x)`
    Asinh,
    /// `abs(x)`
    Abs,
    /// `sigmoid(x) = 1 / (1 + e^(−x))`
    Sigmoid,
    /// `gauss(x) = e^(−x²)`
    Gauss,
}

impl Func {
    fn from_name(s: &str) -> Option<Func> {
        Some(match s {
            "exp" => Func::Exp,
            "log" | "ln" => Func::Ln,
            "log2" => Func::Log2,
            "log10" => Func::Log10,
            "sqrt" => Func::Sqrt,
            "cbrt" => Func::Cbrt,
            "sin" => Func::Sin,
            "cos" => Func::Cos,
            "tan" => Func::Tan,
            "asin" => Func::Asin,
            "acos" => Func::Acos,
            "atan" => Func::Atan,
            "sinh" => Func::Sinh,
            "cosh" => Func::Cosh,
            "tanh" => Func::Tanh,
            "asinh" => Func::Asinh,
            "abs" => Func::Abs,
            "sigmoid" => Func::Sigmoid,
            "gauss" => Func::Gauss,
            _ => return None,
        })
    }

    /// The function's value at x.
    #[inline]
    pub fn apply(self, x: f64) -> f64 {
        match self {
            Func::Exp => x.exp(),
            Func::Ln => x.ln(),
            Func::Log2 => x.log2(),
            Func::Log10 => x.log10(),
            Func::Sqrt => x.sqrt(),
            Func::Cbrt => x.cbrt(),
            Func::Sin => x.sin(),
            Func::Cos => x.cos(),
            Func::Tan => x.tan(),
            Func::Asin => x.asin(),
            Func::Acos => x.acos(),
            Func::Atan => x.atan(),
            Func::Sinh => x.sinh(),
            Func::Cosh => x.cosh(),
            Func::Tanh => x.tanh(),
            Func::Asinh => x.asinh(),
            Func::Abs => x.abs(),
            Func::Sigmoid => 1.0 / (1.0 + (-x).exp()),
            Func::Gauss => (-x * x).exp(),
        }
    }
}

/// A compiled formula.
#[derive(Clone, Debug, PartialEq)]
pub enum Expr {
    /// A numeric literal.
    Const(f64),
    /// The depth variable z.
    Z,
    /// −a
    Neg(Box<Expr>),
    /// a + b
    Add(Box<Expr>, Box<Expr>),
    /// a − b
    Sub(Box<Expr>, Box<Expr>),
    /// a · b
    Mul(Box<Expr>, Box<Expr>),
    /// a / b
    Div(Box<Expr>, Box<Expr>),
    /// a^b (f64::powf)
    Pow(Box<Expr>, Box<Expr>),
    /// Integer power with a constant exponent (f64::powi).
    Powi(Box<Expr>, i32),
    /// A unary function applied to an expression.
    Call(Func, Box<Expr>),
}

impl Expr {
    /// Value at depth z.
    pub fn eval(&self, z: f64) -> f64 {
        match self {
            Expr::Const(c) => *c,
            Expr::Z => z,
            Expr::Neg(a) => -a.eval(z),
            Expr::Add(a, b) => a.eval(z) + b.eval(z),
            Expr::Sub(a, b) => a.eval(z) - b.eval(z),
            Expr::Mul(a, b) => a.eval(z) * b.eval(z),
            Expr::Div(a, b) => a.eval(z) / b.eval(z),
            Expr::Pow(a, b) => a.eval(z).powf(b.eval(z)),
            Expr::Powi(a, k) => a.eval(z).powi(*k),
            Expr::Call(f, a) => f.apply(a.eval(z)),
        }
    }

    fn constant(&self) -> Option<f64> {
        match self {
            Expr::Const(c) => Some(*c),
            _ => None,
        }
    }

    /// Builds a binary node, folding constants.
    fn binary(op: char, a: Expr, b: Expr) -> Expr {
        if let (Some(x), Some(y)) = (a.constant(), b.constant()) {
            return Expr::Const(match op {
                '+' => x + y,
                '-' => x - y,
                '*' => x * y,
                '/' => x / y,
                _ if y.fract() == 0.0 && y.abs() <= 64.0 => x.powi(y as i32),
                _ => x.powf(y),
            });
        }
        let (a, b) = (Box::new(a), Box::new(b));
        match op {
            '+' => Expr::Add(a, b),
            '-' => Expr::Sub(a, b),
            '*' => Expr::Mul(a, b),
            '/' => Expr::Div(a, b),
            _ => match b.constant() {
                Some(k) if k.fract() == 0.0 && k.abs() <= 64.0 => Expr::Powi(a, k as i32),
                _ => Expr::Pow(a, b),
            },
        }
    }

    fn neg(a: Expr) -> Expr {
        match a.constant() {
            Some(x) => Expr::Const(-x),
            None => Expr::Neg(Box::new(a)),
        }
    }

    fn call(f: Func, a: Expr) -> Expr {
        match a.constant() {
            Some(x) => Expr::Const(f.apply(x)),
            None => Expr::Call(f, Box::new(a)),
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
enum Tok {
    Num(f64),
    Z,
    Const(f64),
    Func(Func),
    Op(char),
    LParen,
    RParen,
    End,
}

#[derive(Clone, Debug)]
struct Token {
    tok: Tok,
    /// 1-based character position in the formula.
    pos: usize,
    text: String,
}

fn describe(t: &Token) -> String {
    match t.tok {
        Tok::End => "end of formula".to_string(),
        _ => format!("'{}'", t.text),
    }
}

/// Splits an unknown identifier into z, e and pi (e.g. "piz" → π·z), or None.
fn split_atoms(s: &str) -> Option<Vec<Tok>> {
    let mut out = Vec::new();
    let mut rest = s;
    while !rest.is_empty() {
        if let Some(r) = rest.strip_prefix("pi") {
            out.push(Tok::Const(std::f64::consts::PI));
            rest = r;
        } else if let Some(r) = rest.strip_prefix('z') {
            out.push(Tok::Z);
            rest = r;
        } else if let Some(r) = rest.strip_prefix('e') {
            out.push(Tok::Const(std::f64::consts::E));
            rest = r;
        } else {
            return None;
        }
    }
    Some(out)
}

fn tokenize(src: &str) -> std::result::Result<Vec<Token>, (String, usize)> {
    let chars: Vec<char> = src.chars().collect();
    let mut toks = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        let pos = i + 1;
        if c.is_whitespace() {
            i += 1;
            continue;
        }
        if c.is_ascii_digit() || c == '.' {
            let start = i;
            while i < chars.len() && chars[i].is_ascii_digit() {
                i += 1;
            }
            if i < chars.len() && chars[i] == '.' {
                i += 1;
                while i < chars.len() && chars[i].is_ascii_digit() {
                    i += 1;
                }
            }
            // Exponent only when digits follow ("2e-3"); "2e" and "2ez" are 2·e·…
            if i < chars.len() && (chars[i] == 'e' || chars[i] == 'E') {
                let mut j = i + 1;
                if j < chars.len() && (chars[j] == '+' || chars[j] == '-') {
                    j += 1;
                }
                if j < chars.len() && chars[j].is_ascii_digit() {
                    while j < chars.len() && chars[j].is_ascii_digit() {
                        j += 1;
                    }
                    i = j;
                }
            }
            if i < chars.len() && chars[i] == '.' {
                // "1..2", "1.2.3": swallow the run so the error shows it.
                while i < chars.len() && (chars[i].is_ascii_digit() || chars[i] == '.') {
                    i += 1;
                }
                let text: String = chars[start..i].iter().collect();
                return Err((format!("malformed number '{text}'"), pos));
            }
            let text: String = chars[start..i].iter().collect();
            let v: f64 = text
                .parse()
                .map_err(|_| (format!("malformed number '{text}'"), pos))?;
            toks.push(Token {
                tok: Tok::Num(v),
                pos,
                text,
            });
            continue;
        }
        if c.is_ascii_alphabetic() || c == '_' {
            let start = i;
            while i < chars.len() && (chars[i].is_ascii_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
            let text: String = chars[start..i].iter().collect();
            let tok = match text.as_str() {
                "z" => Some(Tok::Z),
                "pi" => Some(Tok::Const(std::f64::consts::PI)),
                "e" => Some(Tok::Const(std::f64::consts::E)),
                s => Func::from_name(s).map(Tok::Func),
            };
            match tok {
                Some(tok) => toks.push(Token { tok, pos, text }),
                None => match split_atoms(&text) {
                    Some(atoms) => {
                        for tok in atoms {
                            toks.push(Token {
                                tok,
                                pos,
                                text: text.clone(),
                            });
                        }
                    }
                    None => return Err((format!("unknown name '{text}'"), pos)),
                },
            }
            continue;
        }
        let (tok, len) = match c {
            'π' => (Tok::Const(std::f64::consts::PI), 1),
            '+' => (Tok::Op('+'), 1),
            '-' | '−' => (Tok::Op('-'), 1),
            '*' if chars.get(i + 1) == Some(&'*') => (Tok::Op('^'), 2),
            '*' | '·' | '×' => (Tok::Op('*'), 1),
            '/' => (Tok::Op('/'), 1),
            '^' => (Tok::Op('^'), 1),
            '(' => (Tok::LParen, 1),
            ')' => (Tok::RParen, 1),
            _ => return Err((format!("unexpected character '{c}'"), pos)),
        };
        toks.push(Token {
            tok,
            pos,
            text: chars[i..i + len].iter().collect(),
        });
        i += len;
    }
    toks.push(Token {
        tok: Tok::End,
        pos: chars.len() + 1,
        text: String::new(),
    });
    Ok(toks)
}

/// Longest accepted formula (bounds the recursion depth of parsing and evaluation).
pub const MAX_FORMULA_CHARS: usize = 4096;

/// Deepest accepted nesting of parentheses, unary operators and exponents.
pub const MAX_NESTING: usize = 200;

struct Parser {
    toks: Vec<Token>,
    at: usize,
    depth: usize,
}

type PResult<T> = std::result::Result<T, (String, usize)>;

impl Parser {
    fn peek(&self) -> &Token {
        &self.toks[self.at]
    }
    fn next(&mut self) -> Token {
        let t = self.toks[self.at].clone();
        if self.at + 1 < self.toks.len() {
            self.at += 1;
        }
        t
    }
    fn expr(&mut self) -> PResult<Expr> {
        let mut a = self.term()?;
        while let Tok::Op(op @ ('+' | '-')) = self.peek().tok {
            self.next();
            let b = self.term()?;
            a = Expr::binary(op, a, b);
        }
        Ok(a)
    }
    fn term(&mut self) -> PResult<Expr> {
        let mut a = self.unary()?;
        loop {
            match self.peek().tok {
                Tok::Op(op @ ('*' | '/')) => {
                    self.next();
                    let b = self.unary()?;
                    a = Expr::binary(op, a, b);
                }
                Tok::Num(_) | Tok::Z | Tok::Const(_) | Tok::Func(_) | Tok::LParen => {
                    let b = self.power()?;
                    a = Expr::binary('*', a, b);
                }
                _ => return Ok(a),
            }
        }
    }
    fn unary(&mut self) -> PResult<Expr> {
        self.depth += 1;
        if self.depth > MAX_NESTING {
            return Err((
                format!("nested more than {MAX_NESTING} levels deep"),
                self.peek().pos,
            ));
        }
        let r = self.unary_inner();
        self.depth -= 1;
        r
    }
    fn unary_inner(&mut self) -> PResult<Expr> {
        match self.peek().tok {
            Tok::Op('-') => {
                self.next();
                Ok(Expr::neg(self.unary()?))
            }
            Tok::Op('+') => {
                self.next();
                self.unary()
            }
            _ => self.power(),
        }
    }
    fn power(&mut self) -> PResult<Expr> {
        let base = self.primary()?;
        if let Tok::Op('^') = self.peek().tok {
            self.next();
            let e = self.unary()?;
            return Ok(Expr::binary('^', base, e));
        }
        Ok(base)
    }
    fn expect_rparen(&mut self, open: usize) -> PResult<()> {
        let t = self.next();
        if t.tok != Tok::RParen {
            return Err((
                format!(
                    "expected ')' to close '(' at position {open}, found {}",
                    describe(&t)
                ),
                t.pos,
            ));
        }
        Ok(())
    }
    fn primary(&mut self) -> PResult<Expr> {
        let t = self.next();
        match t.tok {
            Tok::Num(v) | Tok::Const(v) => Ok(Expr::Const(v)),
            Tok::Z => Ok(Expr::Z),
            Tok::Func(f) => {
                let p = self.next();
                if p.tok != Tok::LParen {
                    return Err((
                        format!(
                            "expected '(' after function '{}', found {}",
                            t.text,
                            describe(&p)
                        ),
                        p.pos,
                    ));
                }
                let a = self.expr()?;
                self.expect_rparen(p.pos)?;
                Ok(Expr::call(f, a))
            }
            Tok::LParen => {
                let a = self.expr()?;
                self.expect_rparen(t.pos)?;
                Ok(a)
            }
            _ => Err((
                format!(
                    "expected a number, z, a constant, a function or '(', found {}",
                    describe(&t)
                ),
                t.pos,
            )),
        }
    }
}

/// Parses `src` into an expression tree. Errors read
/// "formula 'SRC': WHAT at position P" (1-based character position).
pub fn parse(src: &str) -> Result<Expr> {
    let run = || -> PResult<Expr> {
        let len = src.chars().count();
        if len > MAX_FORMULA_CHARS {
            return Err((
                format!("formula too long ({len} > {MAX_FORMULA_CHARS} characters)"),
                MAX_FORMULA_CHARS + 1,
            ));
        }
        let toks = tokenize(src)?;
        if toks.len() == 1 {
            return Err(("empty formula".to_string(), 1));
        }
        let mut p = Parser {
            toks,
            at: 0,
            depth: 0,
        };
        let e = p.expr()?;
        let t = p.peek().clone();
        if t.tok != Tok::End {
            let msg = if t.tok == Tok::RParen {
                "unmatched ')'".to_string()
            } else {
                format!("unexpected {}", describe(&t))
            };
            return Err((msg, t.pos));
        }
        Ok(e)
    };
    match run() {
        Ok(e) => Ok(e),
        Err((msg, pos)) => bail!("formula '{src}': {msg} at position {pos}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ev(s: &str, z: f64) -> f64 {
        parse(s).unwrap().eval(z)
    }

    #[test]
    fn precedence_and_implicit_multiplication() {
        assert_eq!(ev("1+2*3", 0.0), 7.0);
        assert_eq!(ev("2^3^2", 0.0), 512.0);
        assert_eq!(ev("-z^2", 3.0), -9.0);
        assert_eq!(ev("20z", 0.5), 10.0);
        assert_eq!(ev("1/2z", 4.0), 2.0);
        assert_eq!(ev("(1+z)(2-z)", 1.0), 2.0);
        assert_eq!(ev("2 pi z", 0.5), std::f64::consts::PI);
        assert_eq!(ev("1e-3", 0.0), 0.001);
    }

    #[test]
    fn constant_folding() {
        assert_eq!(
            parse("2*pi*3").unwrap(),
            Expr::Const(6.0 * std::f64::consts::PI)
        );
        assert!(matches!(parse("z^2").unwrap(), Expr::Powi(_, 2)));
        assert!(matches!(parse("z^(1/2)").unwrap(), Expr::Pow(_, _)));
    }
}
