//! The expression language of model files: `+ - * / ^`, parentheses, calls, numbers, names,
//! and `q'` for a time derivative. Parsing gives an [`Ast`] with column spans; lowering it to
//! an [`Expr`] asks a resolver what each name means, so unknown names are reported with the
//! column where they stand.

use super::expr::{Expr, Func};
use super::number::{Rat, rat_from_decimal};

/// A parsed expression with the byte range (0-based, end exclusive) it came from.
#[derive(Clone, Debug, PartialEq)]
pub struct Ast {
    pub kind: AstKind,
    pub start: usize,
    pub end: usize,
}

/// The shapes of [`Ast`].
#[derive(Clone, Debug, PartialEq)]
pub enum AstKind {
    Number(Rat),
    /// A name with the number of primes after it (`q'` has one).
    Name(String, usize),
    Neg(Box<Ast>),
    Binary(char, Box<Ast>, Box<Ast>),
    Call(String, Vec<Ast>),
}

/// A syntax error, with a 1-based column.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("column {column}: {message}")]
pub struct ParseError {
    pub column: usize,
    pub message: String,
}

/// An error while lowering a parsed expression (unknown name, wrong call), 1-based column.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("column {column}: {message}")]
pub struct LowerError {
    pub column: usize,
    pub message: String,
}

#[derive(Clone, Debug, PartialEq)]
enum Tok {
    Num(Rat),
    Name(String, usize),
    Op(char),
    End,
}

struct Lexer<'a> {
    src: &'a str,
    pos: usize,
}

impl<'a> Lexer<'a> {
    fn next(&mut self) -> Result<(Tok, usize, usize), ParseError> {
        let bytes = self.src.as_bytes();
        while self.pos < bytes.len() && bytes[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        let start = self.pos;
        if self.pos >= bytes.len() {
            return Ok((Tok::End, start, start));
        }
        let c = bytes[self.pos];
        if c.is_ascii_digit() || (c == b'.' && bytes.get(self.pos + 1).is_some_and(|d| d.is_ascii_digit())) {
            while self.pos < bytes.len() && (bytes[self.pos].is_ascii_digit() || bytes[self.pos] == b'.') {
                self.pos += 1;
            }
            if self.pos < bytes.len() && (bytes[self.pos] == b'e' || bytes[self.pos] == b'E') {
                let save = self.pos;
                self.pos += 1;
                if self.pos < bytes.len() && (bytes[self.pos] == b'+' || bytes[self.pos] == b'-') {
                    self.pos += 1;
                }
                if self.pos < bytes.len() && bytes[self.pos].is_ascii_digit() {
                    while self.pos < bytes.len() && bytes[self.pos].is_ascii_digit() {
                        self.pos += 1;
                    }
                } else {
                    self.pos = save;
                }
            }
            let text = &self.src[start..self.pos];
            let r = rat_from_decimal(text).ok_or_else(|| ParseError { column: start + 1, message: format!("malformed number `{text}`") })?;
            return Ok((Tok::Num(r), start, self.pos));
        }
        if c.is_ascii_alphabetic() || c == b'_' {
            while self.pos < bytes.len() && (bytes[self.pos].is_ascii_alphanumeric() || bytes[self.pos] == b'_') {
                self.pos += 1;
            }
            let name = self.src[start..self.pos].to_string();
            let mut primes = 0;
            while self.pos < bytes.len() && bytes[self.pos] == b'\'' {
                primes += 1;
                self.pos += 1;
            }
            return Ok((Tok::Name(name, primes), start, self.pos));
        }
        if b"+-*/^(),".contains(&c) {
            self.pos += 1;
            return Ok((Tok::Op(c as char), start, self.pos));
        }
        let ch = self.src[start..].chars().next().unwrap_or('?');
        Err(ParseError { column: start + 1, message: format!("unexpected character `{ch}`") })
    }
}

struct Parser<'a> {
    lex: Lexer<'a>,
    tok: Tok,
    start: usize,
    end: usize,
    /// Nesting depth of parentheses, calls, signs and powers so far.
    depth: usize,
}

/// Most levels of nesting (parentheses, calls, signs, powers) an expression may have: deeper
/// input would exhaust the stack of the recursive passes. Models need a handful.
pub const MAX_NESTING: usize = 200;

/// Largest exponent (in magnitude) a power may have: `x^1e18` would only cost time and lose
/// every digit in f64.
pub const MAX_EXPONENT: i64 = 1000;

/// Longest expression (in bytes) a model may give.
pub const MAX_EXPRESSION_LEN: usize = 20_000;

/// Parses one expression.
pub fn parse(src: &str) -> Result<Ast, ParseError> {
    if src.len() > MAX_EXPRESSION_LEN {
        return Err(ParseError {
            column: MAX_EXPRESSION_LEN + 1,
            message: format!("the expression has {} bytes, more than the {MAX_EXPRESSION_LEN} an expression may have", src.len()),
        });
    }
    let mut lex = Lexer { src, pos: 0 };
    let (tok, start, end) = lex.next()?;
    let mut p = Parser { lex, tok, start, end, depth: 0 };
    if p.tok == Tok::End {
        return Err(ParseError { column: 1, message: "empty expression".into() });
    }
    let ast = p.expr()?;
    if p.tok != Tok::End {
        return Err(p.unexpected("an operator or the end of the expression"));
    }
    Ok(ast)
}

impl<'a> Parser<'a> {
    fn bump(&mut self) -> Result<(), ParseError> {
        let (t, s, e) = self.lex.next()?;
        self.tok = t;
        self.start = s;
        self.end = e;
        Ok(())
    }

    /// Enters one level of nesting; fails past [`MAX_NESTING`].
    fn nest(&mut self) -> Result<(), ParseError> {
        self.depth += 1;
        if self.depth > MAX_NESTING {
            return Err(ParseError {
                column: self.start + 1,
                message: format!("the expression is nested more than {MAX_NESTING} levels deep (parentheses, calls, signs and powers)"),
            });
        }
        Ok(())
    }

    fn unexpected(&self, wanted: &str) -> ParseError {
        let found = match &self.tok {
            Tok::End => "the end of the expression".to_string(),
            Tok::Num(_) | Tok::Name(..) | Tok::Op(_) => format!("`{}`", &self.lex.src[self.start..self.end]),
        };
        ParseError { column: self.start + 1, message: format!("expected {wanted}, found {found}") }
    }

    fn expr(&mut self) -> Result<Ast, ParseError> {
        let mut lhs = self.term()?;
        while let Tok::Op(op @ ('+' | '-')) = self.tok {
            self.bump()?;
            let rhs = self.term()?;
            lhs = Ast { start: lhs.start, end: rhs.end, kind: AstKind::Binary(op, Box::new(lhs), Box::new(rhs)) };
        }
        Ok(lhs)
    }

    fn term(&mut self) -> Result<Ast, ParseError> {
        let mut lhs = self.unary()?;
        while let Tok::Op(op @ ('*' | '/')) = self.tok {
            self.bump()?;
            let rhs = self.unary()?;
            lhs = Ast { start: lhs.start, end: rhs.end, kind: AstKind::Binary(op, Box::new(lhs), Box::new(rhs)) };
        }
        Ok(lhs)
    }

    fn unary(&mut self) -> Result<Ast, ParseError> {
        if let Tok::Op(op @ ('-' | '+')) = self.tok {
            let start = self.start;
            self.nest()?;
            self.bump()?;
            let inner = self.unary()?;
            self.depth -= 1;
            if op == '+' {
                return Ok(inner);
            }
            return Ok(Ast { start, end: inner.end, kind: AstKind::Neg(Box::new(inner)) });
        }
        self.power()
    }

    fn power(&mut self) -> Result<Ast, ParseError> {
        let base = self.atom()?;
        if self.tok == Tok::Op('^') {
            self.nest()?;
            self.bump()?;
            let exp = self.unary()?; // right-associative, allows x^-1
            self.depth -= 1;
            return Ok(Ast { start: base.start, end: exp.end, kind: AstKind::Binary('^', Box::new(base), Box::new(exp)) });
        }
        Ok(base)
    }

    fn atom(&mut self) -> Result<Ast, ParseError> {
        let (start, end) = (self.start, self.end);
        match self.tok.clone() {
            Tok::Num(r) => {
                self.bump()?;
                Ok(Ast { kind: AstKind::Number(r), start, end })
            }
            Tok::Name(name, primes) => {
                self.bump()?;
                if self.tok == Tok::Op('(') && primes == 0 {
                    self.nest()?;
                    self.bump()?;
                    let mut args = Vec::new();
                    if self.tok != Tok::Op(')') {
                        loop {
                            args.push(self.expr()?);
                            if self.tok == Tok::Op(',') {
                                self.bump()?;
                                continue;
                            }
                            break;
                        }
                    }
                    if self.tok != Tok::Op(')') {
                        return Err(self.unexpected("`)` closing the call"));
                    }
                    let end = self.end;
                    self.bump()?;
                    self.depth -= 1;
                    return Ok(Ast { kind: AstKind::Call(name, args), start, end });
                }
                Ok(Ast { kind: AstKind::Name(name, primes), start, end })
            }
            Tok::Op('(') => {
                self.nest()?;
                self.bump()?;
                let inner = self.expr()?;
                if self.tok != Tok::Op(')') {
                    return Err(self.unexpected("`)`"));
                }
                self.bump()?;
                self.depth -= 1;
                Ok(inner)
            }
            _ => Err(self.unexpected("a number, a name or `(`")),
        }
    }
}

/// What a resolver says a name or call means.
pub trait Resolver {
    /// The expression for a name with `primes` time derivatives, or an error message.
    fn name(&self, name: &str, primes: usize) -> Result<Expr, String>;
    /// A call that is not an elementary function (`F(t)`, `omega_x(body)`): its expression.
    fn call(&self, name: &str, args: &[Ast], lower: &dyn Fn(&Ast) -> Result<Expr, LowerError>) -> Result<Expr, String> {
        let _ = (args, lower);
        Err(format!("unknown function `{name}`"))
    }
}

/// Lowers an [`Ast`] with a resolver.
pub fn lower(ast: &Ast, r: &dyn Resolver) -> Result<Expr, LowerError> {
    let err = |message: String| LowerError { column: ast.start + 1, message };
    Ok(match &ast.kind {
        AstKind::Number(x) => Expr::num(x.clone()),
        AstKind::Name(n, p) => r.name(n, *p).map_err(err)?,
        AstKind::Neg(a) => -lower(a, r)?,
        AstKind::Binary(op, a, b) => {
            let (x, y) = (lower(a, r)?, lower(b, r)?);
            match op {
                '+' => x + y,
                '-' => x - y,
                '*' => x * y,
                '/' => {
                    if y.is_zero() {
                        return Err(LowerError { column: b.start + 1, message: "division by zero".into() });
                    }
                    x / y
                }
                _ => {
                    if let Some(e) = y.as_num()
                        && e.abs() > crate::symbolic::number::Rat::int(MAX_EXPONENT)
                    {
                        return Err(LowerError { column: b.start + 1, message: format!("exponent `{y}` is larger than {MAX_EXPONENT} in magnitude") });
                    }
                    let Some(e) = y.as_num() else {
                        return Err(LowerError {
                            column: b.start + 1,
                            message: format!("exponent `{y}` must be a rational number (write exp(y*ln(x)) for x^y)"),
                        });
                    };
                    x.pow_rat(&e)
                }
            }
        }
        AstKind::Call(name, args) => {
            if let Some(f) = Func::from_name(name) {
                if args.len() != 1 {
                    return Err(err(format!("`{name}` takes 1 argument, found {}", args.len())));
                }
                Expr::apply(f, lower(&args[0], r)?)
            } else if name == "sqrt" {
                if args.len() != 1 {
                    return Err(err(format!("`sqrt` takes 1 argument, found {}", args.len())));
                }
                lower(&args[0], r)?.sqrt()
            } else {
                r.call(name, args, &|a| lower(a, r)).map_err(err)?
            }
        }
    })
}

/// A resolver that accepts every name as a symbol (primes kept in the name) and `pi`.
#[cfg(test)]
pub struct AnyName;

#[cfg(test)]
impl Resolver for AnyName {
    fn name(&self, name: &str, primes: usize) -> Result<Expr, String> {
        Ok(super::expr::Symbol::new(&format!("{name}{}", "'".repeat(primes))).expr())
    }
}

/// Lowers with [`AnyName`]: for tests.
#[cfg(test)]
pub fn lower_default(ast: &Ast) -> Result<Expr, LowerError> {
    lower(ast, &AnyName)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(s: &str) -> Expr {
        lower_default(&parse(s).unwrap()).unwrap()
    }

    #[test]
    fn precedence_and_associativity() {
        let x = Expr::sym("x");
        assert_eq!(p("1 + 2*3"), Expr::int(7));
        assert_eq!(p("2^3^2"), Expr::int(512));
        assert_eq!(p("-x^2"), -(x.powi(2)));
        assert_eq!(p("x^-1"), x.recip());
        assert_eq!(p("8/4/2"), Expr::int(1));
        assert_eq!(p("1.5e1"), Expr::int(15));
        assert_eq!(p("sqrt(x)^2"), x);
    }

    #[test]
    fn errors_point_at_columns() {
        assert_eq!(parse("x + ").unwrap_err().column, 5);
        assert_eq!(parse("(x + 1").unwrap_err().column, 7);
        assert_eq!(parse("x $ 1").unwrap_err().column, 3);
        assert_eq!(parse("").unwrap_err().message, "empty expression");
        let e = lower_default(&parse("x^y").unwrap()).unwrap_err();
        assert_eq!(e.column, 3);
        let e = lower_default(&parse("sin(x, y)").unwrap()).unwrap_err();
        assert_eq!(e.column, 1);
    }
}

/// The examples that were this module's documentation when it was public.
#[cfg(test)]
mod examples {
    #[test]
    fn module_example() {
        use crate::symbolic::parse::{lower_default, parse};
        let ast = parse("l*cos(theta1 - theta2)*theta1' + l*theta2'").unwrap();
        let e = lower_default(&ast).unwrap();
        assert_eq!(e.to_string(), "l*theta1'*cos(theta1 - theta2) + l*theta2'");
        assert_eq!(parse("1 + * 2").unwrap_err().column, 5);
    }
}
