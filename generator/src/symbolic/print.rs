//! Printing as readable text (`Display`) and as LaTeX.
//!
//! Terms and factors are printed in a readable order (by their text), independent of the
//! internal order, so the same expression always prints the same.
//!
//! ```
//! use generator::symbolic::Expr;
//! let (m, l, th) = (Expr::sym("m2"), Expr::sym("l"), Expr::sym("theta2"));
//! let e = m * l.powi(2) * th.cos() / 2;
//! assert_eq!(e.to_string(), "l^2*m2*cos(theta2)/2");
//! assert_eq!(e.to_latex(), "\\frac{l^{2} m_{2} \\cos\\left(\\theta_{2}\\right)}{2}");
//! ```

use super::expr::{Expr, Node};
use super::number::Rat;
use num_traits::{One, Signed};
use std::collections::HashMap;
use std::fmt;

#[derive(Clone, Copy, PartialEq, Eq, Hash)]
enum Style {
    Text,
    Latex,
}

/// Precedence levels: sums bind loosest.
const SUM: u8 = 1;
const PRODUCT: u8 = 2;
const POWER: u8 = 3;

/// Largest tree (nodes counted with repetition) printed in full: an expression DAG of a long
/// chain can stand for a tree with more nodes than memory holds, and is not read as text.
pub const MAX_PRINTED_TREE: u32 = 20_000;

impl fmt::Display for Expr {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.tree_size() > MAX_PRINTED_TREE {
            return write!(f, "<expression of {} distinct nodes, too large to print>", self.dag_size());
        }
        f.write_str(&Renderer::default().render(*self, Style::Text).0)
    }
}

impl Expr {
    /// LaTeX source for the expression.
    pub fn to_latex(self) -> String {
        if self.tree_size() > MAX_PRINTED_TREE {
            return format!("\\text{{(expression of {} distinct nodes)}}", self.dag_size());
        }
        Renderer::default().render(self, Style::Latex).0
    }
}

/// Expressions printed with their shared subexpressions named once: `(one string per item,
/// definitions "name = expression" in an order where each uses only names before it)`.
/// Subexpressions larger than `inline` tree nodes that occur more than once get a name
/// (`#1`, `#2`, ... in text, `x_{1}`, ... in LaTeX), so the output grows with the number of
/// distinct nodes, not with the tree a DAG stands for.
pub fn render_shared(items: &[Expr], latex: bool, inline: u32) -> (Vec<String>, Vec<(String, String)>) {
    let st = if latex { Style::Latex } else { Style::Text };
    let order = super::expr::post_order(items);
    let mut uses: HashMap<Expr, usize> = HashMap::new();
    for e in &order {
        for c in e.children() {
            *uses.entry(c).or_default() += 1;
        }
    }
    let mut r = Renderer::default();
    let mut defs = Vec::new();
    for e in order {
        let shared = uses.get(&e).copied().unwrap_or(0) >= 2 && e.tree_size() > inline;
        let huge = e.tree_size() > MAX_PRINTED_TREE / 4 && !items.contains(&e);
        if shared || huge {
            let text = r.render(e, st).0;
            let k = defs.len() + 1;
            let name = if latex { format!("x_{{{k}}}") } else { format!("#{k}") };
            defs.push((name.clone(), text));
            r.names.insert(e, name);
            // Everything rendered so far may have inlined it: renders from here on use the name.
            r.memo.clear();
        }
    }
    let out = items.iter().map(|e| r.render_inner(*e, st).0).collect();
    (out, defs)
}

/// Renders expressions, memoized per node and style, with names for some subexpressions.
#[derive(Default)]
struct Renderer {
    memo: HashMap<(Expr, Style), (String, u8)>,
    names: HashMap<Expr, String>,
}

impl Renderer {
    /// Renders with its precedence (a named subexpression as its name).
    fn render(&mut self, e: Expr, st: Style) -> (String, u8) {
        if let Some(n) = self.names.get(&e) {
            return (n.clone(), 10);
        }
        self.render_inner(e, st)
    }

    /// Renders the node itself even when it has a name.
    fn render_inner(&mut self, e: Expr, st: Style) -> (String, u8) {
        if let Some(r) = self.memo.get(&(e, st)) {
            return r.clone();
        }
        let r = self.node(e, st);
        self.memo.insert((e, st), r.clone());
        r
    }

    fn node(&mut self, e: Expr, st: Style) -> (String, u8) {
        match &*e.node() {
            Node::Num(r) => render_rat(r, st),
            Node::Sym(s) => (symbol_name(&s.name(), st), 10),
            Node::Fun(f, a) => {
                let arg = self.render(*a, st).0;
                match st {
                    Style::Text => (format!("{}({arg})", f.name()), 10),
                    Style::Latex => {
                        let name = match f.name() {
                            "abs" => return (format!("\\left|{arg}\\right|"), 10),
                            "ln" => "\\ln".to_string(),
                            n => format!("\\{n}"),
                        };
                        (format!("{name}\\left({arg}\\right)"), 10)
                    }
                }
            }
            Node::Apply(n, a) => {
                let arg = self.render(*a, st).0;
                match st {
                    Style::Text => (format!("{}({arg})", n.name()), 10),
                    Style::Latex => (format!("{}\\left({arg}\\right)", symbol_name(&n.name(), st)), 10),
                }
            }
            Node::Add { constant, terms } => {
                let mut parts: Vec<(String, bool, String)> = terms
                    .iter()
                    .map(|(t, c)| {
                        let neg = c.is_negative();
                        let body = self.render(t.scale(&c.abs()), st);
                        (self.render(*t, Style::Text).0, neg, body.0)
                    })
                    .collect();
                parts.sort();
                let mut parts: Vec<(bool, String)> = parts.into_iter().map(|(_, n, b)| (n, b)).collect();
                if !constant.is_zero() {
                    parts.push((constant.is_negative(), render_rat(&constant.abs(), st).0));
                }
                let mut out = String::new();
                for (i, (neg, body)) in parts.iter().enumerate() {
                    match (i, neg) {
                        (0, true) => out.push('-'),
                        (0, false) => {}
                        (_, true) => out.push_str(" - "),
                        (_, false) => out.push_str(" + "),
                    }
                    out.push_str(body);
                }
                (out, SUM)
            }
            Node::Mul { coefficient, factors } => self.product(coefficient, factors, st),
        }
    }

    fn product(&mut self, coefficient: &Rat, factors: &[(Expr, Rat)], st: Style) -> (String, u8) {
        // Symbols first (by name), then the rest, each group in text order.
        let mut num: Vec<(bool, String, String)> = Vec::new();
        let mut den: Vec<(bool, String, String)> = Vec::new();
        for (b, x) in factors {
            let key = (b.as_sym().is_none(), self.render(*b, Style::Text).0);
            let power = self.power(*b, &x.abs(), st);
            let target = if x.is_negative() { &mut den } else { &mut num };
            target.push((key.0, key.1, power));
        }
        num.sort();
        den.sort();
        let mut num: Vec<String> = num.into_iter().map(|t| t.2).collect();
        let mut den: Vec<String> = den.into_iter().map(|t| t.2).collect();
        let neg = coefficient.is_negative();
        if coefficient.is_exact() {
            let (cn, cd) = (coefficient.numer().abs(), coefficient.denom().clone());
            if !cn.is_one() {
                num.insert(0, cn.to_string());
            }
            if !cd.is_one() {
                den.insert(0, cd.to_string());
            }
        } else {
            // A rounded number ([`Rat::inexact`]) as the float it is.
            num.insert(0, coefficient.abs().to_string());
        }
        let sep = if st == Style::Text { "*" } else { " " };
        let numerator = if num.is_empty() { "1".to_string() } else { num.join(sep) };
        let body = if den.is_empty() {
            numerator
        } else {
            match st {
                Style::Text => {
                    let d = if den.len() == 1 { den[0].clone() } else { format!("({})", den.join("*")) };
                    format!("{numerator}/{d}")
                }
                Style::Latex => format!("\\frac{{{numerator}}}{{{}}}", den.join(" ")),
            }
        };
        if neg { (format!("-{body}"), SUM) } else { (body, PRODUCT) }
    }

    fn power(&mut self, b: Expr, x: &Rat, st: Style) -> String {
        let (base, prec) = self.render(b, st);
        let half = Rat::frac(1, 2);
        if *x == half {
            return match st {
                Style::Text => format!("sqrt({base})"),
                Style::Latex => format!("\\sqrt{{{base}}}"),
            };
        }
        let base = if x.is_one() {
            if prec < PRODUCT || (prec == PRODUCT && st == Style::Text && base.contains('/')) { paren(&base, st) } else { base }
        } else if prec <= POWER {
            paren(&base, st)
        } else {
            base
        };
        if x.is_one() {
            return base;
        }
        match st {
            Style::Text => {
                if x.denom().is_one() {
                    format!("{base}^{}", x.numer())
                } else {
                    format!("{base}^({}/{})", x.numer(), x.denom())
                }
            }
            Style::Latex => {
                let e = if x.denom().is_one() { x.numer().to_string() } else { format!("{}/{}", x.numer(), x.denom()) };
                format!("{base}^{{{e}}}")
            }
        }
    }
}

fn render_rat(r: &Rat, st: Style) -> (String, u8) {
    if !r.is_exact() {
        return (r.to_string(), if r.is_negative() { SUM } else { 10 });
    }
    if r.denom().is_one() {
        let s = r.numer().to_string();
        let p = if r.is_negative() { SUM } else { 10 };
        return (s, p);
    }
    match st {
        Style::Text => (format!("{}/{}", r.numer(), r.denom()), PRODUCT),
        Style::Latex => {
            let sign = if r.is_negative() { "-" } else { "" };
            (format!("{sign}\\frac{{{}}}{{{}}}", r.numer().abs(), r.denom()), PRODUCT)
        }
    }
}

fn paren(s: &str, st: Style) -> String {
    match st {
        Style::Text => format!("({s})"),
        Style::Latex => format!("\\left({s}\\right)"),
    }
}

const GREEK: &[&str] = &[
    "alpha", "beta", "gamma", "delta", "epsilon", "zeta", "eta", "theta", "iota", "kappa", "lambda", "mu", "nu", "xi", "pi", "rho", "sigma", "tau", "upsilon",
    "phi", "chi", "psi", "omega", "Gamma", "Delta", "Theta", "Lambda", "Xi", "Pi", "Sigma", "Phi", "Psi", "Omega",
];

/// A symbol name in the given style: LaTeX gets Greek letters, subscripts and dots.
fn symbol_name(name: &str, st: Style) -> String {
    if st == Style::Text {
        return name.to_string();
    }
    let primes = name.chars().rev().take_while(|c| *c == '\'').count();
    let core = &name[..name.len() - primes];
    let (stem, sub) = match core.find('_') {
        Some(i) => (&core[..i], core[i + 1..].to_string()),
        None => {
            let digits = core.chars().rev().take_while(|c| c.is_ascii_digit()).count();
            (&core[..core.len() - digits], core[core.len() - digits..].to_string())
        }
    };
    let stem_tex = if GREEK.contains(&stem) {
        format!("\\{stem}")
    } else if stem.chars().count() > 1 {
        format!("\\mathrm{{{stem}}}")
    } else {
        stem.to_string()
    };
    let mut s = match primes {
        0 => stem_tex,
        1 => format!("\\dot{{{stem_tex}}}"),
        _ => format!("\\ddot{{{stem_tex}}}"),
    };
    if !sub.is_empty() {
        s = format!("{s}_{{{}}}", sub.replace('_', ","));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_is_readable() {
        let (x, y) = (Expr::sym("x"), Expr::sym("y"));
        assert_eq!((x - y * 2).to_string(), "x - 2*y");
        assert_eq!((x + 1).powi(2).to_string(), "(x + 1)^2");
        assert_eq!((x / (y * 3)).to_string(), "x/(3*y)");
        assert_eq!((-x).to_string(), "-x");
        assert_eq!((x + y).sqrt().to_string(), "sqrt(x + y)");
    }

    #[test]
    fn latex_names() {
        assert_eq!(Expr::sym("theta1'").to_latex(), "\\dot{\\theta}_{1}");
        assert_eq!(Expr::sym("G_x").to_latex(), "G_{x}");
        assert_eq!(Expr::sym("mg").to_latex(), "\\mathrm{mg}");
    }
}

/// The examples that were this module's documentation when it was public.
#[cfg(test)]
mod examples {
    #[test]
    fn render_shared_example() {
        use crate::symbolic::{Expr, print::render_shared};
        let (x, y) = (Expr::sym("x"), Expr::sym("y"));
        let shared = (x + y * y).sin();
        let (items, defs) = render_shared(&[shared + x, shared * y], false, 4);
        assert_eq!(defs, vec![("#1".to_string(), "sin(x + y^2)".to_string())]);
        assert_eq!(items, vec!["#1 + x".to_string(), "y*#1".to_string()]);
    }
}
