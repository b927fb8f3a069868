//! The bodies a module has built, so that a function whose outputs are another's (in any order,
//! beside constants) takes that body instead of building it again: on a model without
//! constraints, Maggi's `rhs` is Lagrange's with the speeds reordered and `W`, `c` constant, and
//! their `initial_state` and `velocities` coincide too. Building a body (pair sharing, sum
//! factoring, Horner forms, lowering) is the emission's main cost; on the planar chain of 20
//! rods in absolute angles, Maggi's `rhs` is a quarter of it.
//!
//! Only formulations whose states hold the same kind of speeds can share a body (the inputs
//! differ otherwise), so a formulation's bodies are kept only when one of the same kind is still
//! to be emitted by the same emitter (Lagrange's for Maggi, Kane's for the reduced form, which
//! is Kane's without ignorable coordinates), and let go when the kind changes. Measured on the
//! 50-link pendulum on a cart, whose Maggi `rhs` is Lagrange's (command line, peak memory):
//! about 560 MB without reuse, about 570 MB with it, 790 MB when every body was kept to the end
//! (Kane's too, for a reduced form emitted on the other thread); the CPU about a quarter less.

use super::function::{Arg, Body, Input};
use super::lower::{LowerError, lower};
use crate::symbolic::{Expr, Symbol};
use rustc_hash::FxHashMap as HashMap;
use seam::{FormulationKind, Speeds};

/// What a body is built from besides its outputs: two requests with the same signature and the
/// same non-constant outputs get the same statements.
#[derive(PartialEq, Eq, Debug)]
pub struct Signature {
    name: String,
    definitions: Vec<(Symbol, Expr)>,
    inputs: Vec<(Symbol, String, usize, String)>,
    args: Vec<(String, String)>,
    max_lets: usize,
}

impl Signature {
    /// The signature of a body named `name` (helpers of a split body are named after it).
    pub fn new(name: &str, definitions: &[(Symbol, Expr)], inputs: &[Input], args: &[Arg], max_lets: usize) -> Signature {
        Signature {
            name: name.to_string(),
            definitions: definitions.to_vec(),
            inputs: inputs.iter().map(|i| (i.symbol, i.ident.clone(), i.arg, i.source.to_string())).collect(),
            args: args.iter().map(|a| (a.name.clone(), a.ty.to_string())).collect(),
            max_lets,
        }
    }
}

/// Bodies built so far, with the outputs they were built for.
#[derive(Default)]
pub struct Bodies {
    built: Vec<Built>,
    /// The formulations the emitter emits, in order.
    emits: Vec<FormulationKind>,
    /// The kind of speeds of the formulation being emitted (None before the first).
    speeds: Option<Speeds>,
    /// Whether the bodies built now are kept: a formulation of the same kind follows.
    keep: bool,
}

struct Built {
    signature: Signature,
    /// Each non-constant output: where it first appears, and how often.
    outputs: HashMap<Expr, (usize, usize)>,
    body: Body,
}

/// Each non-constant output of `outputs`: its first position and its number of occurrences.
fn occurrences(outputs: &[Expr]) -> HashMap<Expr, (usize, usize)> {
    let mut seen: HashMap<Expr, (usize, usize)> = HashMap::default();
    for (k, e) in outputs.iter().enumerate().filter(|(_, e)| e.as_num().is_none()) {
        seen.entry(*e).or_insert((k, 0)).1 += 1;
    }
    seen
}

impl Bodies {
    /// For an emitter that emits the formulations `emits`, in that order.
    pub fn new(emits: Vec<FormulationKind>) -> Bodies {
        Bodies { emits, ..Bodies::default() }
    }

    /// The formulation `kind` starts: the bodies kept for formulations of another kind of speeds
    /// are let go, and its own are kept when one of its kind follows it in this emitter.
    pub fn start(&mut self, kind: FormulationKind) {
        let speeds = kind.speeds();
        if self.speeds != Some(speeds) {
            self.built.clear();
            self.speeds = Some(speeds);
        }
        self.keep = self.emits.iter().skip_while(|k| **k != kind).skip(1).any(|k| k.speeds() == speeds);
    }

    /// A body built before with this signature and the same non-constant outputs, each as
    /// often: its statements, with the outputs in `outputs`' order and the constants lowered
    /// here (they cost no operation, so the counts carry over).
    pub fn find(&self, signature: &Signature, outputs: &[Expr]) -> Option<Result<Body, LowerError>> {
        let wanted = occurrences(outputs);
        let built = self.built.iter().find(|b| {
            b.signature == *signature && b.outputs.len() == wanted.len() && wanted.iter().all(|(e, (_, n))| b.outputs.get(e).is_some_and(|(_, m)| m == n))
        })?;
        let lowered = outputs
            .iter()
            .map(|e| match built.outputs.get(e) {
                Some(&(k, _)) => Ok(built.body.outputs[k].clone()),
                None => lower(*e, &|_| None, &|_| None).map(|(t, _)| t),
            })
            .collect::<Result<Vec<_>, _>>();
        Some(lowered.map(|outputs| Body { outputs, ..built.body.clone() }))
    }

    /// Keeps `body`, built under `signature` for `outputs`, if a later formulation may reuse it.
    pub fn remember(&mut self, signature: Signature, outputs: &[Expr], body: &Body) {
        if !self.keep {
            return;
        }
        self.built.push(Built { signature, outputs: occurrences(outputs), body: body.clone() });
    }
}

#[cfg(test)]
mod tests {
    use super::super::function::body_with_definitions;
    use super::*;
    use quote::{ToTokens, quote};

    fn args() -> Vec<Arg> {
        vec![Arg::new("x", quote!(&[f64; 3]))]
    }

    fn inputs() -> Vec<Input> {
        ["a", "b", "c"].iter().enumerate().map(|(k, s)| Input::new(Symbol::new(s), s, 0, quote!(x[#k]))).collect()
    }

    fn built(outputs: &[Expr]) -> (Bodies, Body) {
        let body = body_with_definitions("f", &[], outputs, &inputs(), &args(), 100, &mut Default::default()).unwrap();
        let mut bodies = Bodies::new(vec![FormulationKind::Lagrange, FormulationKind::Maggi]);
        bodies.start(FormulationKind::Lagrange);
        bodies.remember(Signature::new("f", &[], &inputs(), &args(), 100), outputs, &body);
        (bodies, body)
    }

    fn text(e: &syn::Expr) -> String {
        e.to_token_stream().to_string()
    }

    #[test]
    fn the_same_outputs_reordered_beside_constants_take_the_built_body() {
        let (a, b, c) = (Symbol::new("a").expr(), Symbol::new("b").expr(), Symbol::new("c").expr());
        let (first, second) = (a.sin() * b + c, a.sin() * b * c);
        let (bodies, body) = built(&[first, second, Expr::int(2)]);
        let wanted = [Expr::zero(), second, Expr::int(-3), first];
        let reused = bodies.find(&Signature::new("f", &[], &inputs(), &args(), 100), &wanted).expect("the same outputs").unwrap();
        let texts: Vec<String> = reused.outputs.iter().map(text).collect();
        assert_eq!(texts, ["0.0", text(&body.outputs[1]).as_str(), "- 3.0", text(&body.outputs[0]).as_str()]);
        assert_eq!(reused.stmts.len(), body.stmts.len());
        assert_eq!((reused.ops, reused.lets, reused.used_args), (body.ops, body.lets, body.used_args));
    }

    #[test]
    fn other_outputs_or_another_signature_build_anew() {
        let (a, b, c) = (Symbol::new("a").expr(), Symbol::new("b").expr(), Symbol::new("c").expr());
        let (first, second) = (a.sin() * b + c, a.sin() * b * c);
        let (bodies, _) = built(&[first, second]);
        let signature = Signature::new("f", &[], &inputs(), &args(), 100);
        assert!(bodies.find(&signature, &[first]).is_none(), "an output left out");
        assert!(bodies.find(&signature, &[first, second, a]).is_none(), "an output added");
        assert!(bodies.find(&signature, &[first, second, second]).is_none(), "an output twice");
        assert!(bodies.find(&Signature::new("g", &[], &inputs(), &args(), 100), &[first, second]).is_none(), "another name");
        assert!(bodies.find(&Signature::new("f", &[], &inputs(), &args(), 1), &[first, second]).is_none(), "another split");
        assert!(bodies.find(&signature, &[second, first]).is_some());
    }

    #[test]
    fn bodies_are_kept_for_a_later_formulation_of_the_same_kind_only() {
        use FormulationKind::{Kane, Lagrange, Maggi, ReducedVolterra};
        let (a, b) = (Symbol::new("a").expr(), Symbol::new("b").expr());
        let outputs = [a.sin() * b];
        let signature = || Signature::new("f", &[], &inputs(), &args(), 100);
        let body = body_with_definitions("f", &[], &outputs, &inputs(), &args(), 100, &mut Default::default()).unwrap();
        let mut bodies = Bodies::new(vec![Lagrange, Maggi, Kane]);
        bodies.remember(signature(), &outputs, &body);
        assert!(bodies.find(&signature(), &outputs).is_none(), "before the first formulation: nothing follows");
        bodies.start(Lagrange);
        bodies.remember(signature(), &outputs, &body);
        bodies.start(Maggi);
        assert!(bodies.find(&signature(), &outputs).is_some(), "kept for Maggi after Lagrange");
        bodies.remember(signature(), &outputs, &body);
        bodies.start(Kane);
        assert!(bodies.find(&signature(), &outputs).is_none(), "let go for Kane");
        bodies.remember(signature(), &outputs, &body);
        bodies.start(Kane);
        assert!(bodies.find(&signature(), &outputs).is_none(), "the reduced form is emitted elsewhere: Kane's are not kept");
        let mut alone = Bodies::new(vec![Kane, ReducedVolterra]);
        alone.start(Kane);
        alone.remember(signature(), &outputs, &body);
        alone.start(ReducedVolterra);
        assert!(alone.find(&signature(), &outputs).is_some(), "kept for the reduced form after Kane");
    }
}
