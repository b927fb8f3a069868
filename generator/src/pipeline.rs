//! One run of the generator, owned here: a model is derived ([`crate::formulation`]), then
//! emitted as Rust ([`crate::emit`]), evaluated in-process ([`crate::eval`]) or reported
//! ([`inspect`]). The threads and
//! the channels between them are in this file alone; the stages below it are functions of what
//! they are handed and never call back up.
//!
//! Two threads, each in an expression context of its own. The deriving one derives the
//! mechanics, then each formulation as soon as what it needs is there; it hands the mechanics
//! and the formulations of every reuse group but the last ([`emit::reuse_groups`]) to the
//! emitting one, and emits the last group and `model()` itself. The emitting thread decides the
//! ignorable coordinates (handed back for the reduced form), writes the module's head, then each
//! formulation it is handed, while the next is derived. Which formulations share bodies is
//! decided by the groups alone, and each thread's input is fixed (the same parcels in the same
//! order, whatever the timing), so the bytes are too.
//!
//! ```
//! let model = generator::model::load("../models/cart_pendulum.ron").unwrap();
//! let out = generator::generate(&model, &generator::emit::Options::from_model(&model)).unwrap();
//! assert!(out.code.contains("pub mod kane"));
//! let evaluated = generator::evaluate(&model).unwrap();
//! assert_eq!(evaluated.formulations.len(), 4);
//! ```

use crate::emit::{self, Emission, Generated, Options, Parameters, Part, Summary};
use crate::eval::{kernel, model::Evaluated};
use crate::formulation::mechanics::{Mechanics, Quantities};
use crate::formulation::{self, Equations, Request, ignorable};
use crate::model::{ErrorKind, Model, ModelError};
use crate::symbolic::Context;
use crate::symbolic::transfer::{Packer, Parcel, Unpacker};
use std::sync::mpsc::{Receiver, Sender, channel};
use std::time::{Duration, Instant};

/// Derives and emits the module of `model`, in an expression context of its own: everything the
/// derivation builds is freed when it returns, so a process that generates many models holds
/// only the models themselves.
pub fn generate(model: &Model, options: &Options) -> Result<Generated, ModelError> {
    if options.parameters == Parameters::Baked && !model.inputs.is_empty() {
        return Err(model.error(
            ErrorKind::BadValue,
            "emit.parameters",
            "parameters",
            "a model with inputs cannot bake its parameters in: the inputs are read from them at every call".into(),
            "emit with runtime parameters (the default), or remove `inputs`".into(),
        ));
    }
    crate::model::in_own_context(model, |model| {
        crate::symbolic::expr::catch_budget(|| on_two_threads(model, options)).unwrap_or_else(|spent| Err(model.budget_error(spent)))
    })
}

/// `model` as a [`seam::Model`] evaluated in-process, with the options its file asks for (its
/// `emit` section), every formulation it requests: the same optimized functions the emitter
/// writes as Rust, run as register tapes.
pub fn evaluate(model: &Model) -> Result<seam::Model, ModelError> {
    evaluate_with(model, &Options::from_model(model))
}

/// [`evaluate`] with other options (formulations, baked parameters, dropped ignorable
/// coordinates, the exact Jacobians: `jacobian` and `parameter_jacobian` evaluate in-process as
/// the emitted ones do).
pub fn evaluate_with(model: &Model, options: &Options) -> Result<seam::Model, ModelError> {
    Ok(evaluate_reporting(model, options)?.0)
}

/// [`evaluate_with`], and the generation's summary: what the derivation's budgets cut and what it
/// could not decide ([`Summary::warnings`]), for the caller to report.
pub fn evaluate_reporting(model: &Model, options: &Options) -> Result<(seam::Model, Summary), ModelError> {
    evaluate_with_backend(model, options, &kernel::Interpreter)
}

/// [`evaluate_reporting`] with the tapes made kernels by `backend` (the `jit` crate's compiler).
pub fn evaluate_with_backend(model: &Model, options: &Options, backend: &dyn kernel::Backend) -> Result<(seam::Model, Summary), ModelError> {
    let options = Options { tapes: true, source: false, max_lets_per_function: usize::MAX, ..options.clone() };
    let generated = generate(model, &options)?;
    let program = generated.program.ok_or_else(|| model.error(ErrorKind::Emission, "emit", "emit", "internal error: no tapes".into(), String::new()))?;
    Ok((Evaluated::model_with(program, backend), generated.summary))
}

/// The derivation report of `model` (`inspect`), as text or LaTeX: one derivation of all four
/// formulations, the same one the generator emits from, with each formulation's assembly as
/// the emitter chooses it.
///
/// ```
/// let model = generator::model::load("../models/cart_pendulum.ron").unwrap();
/// let text = generator::inspect(&model, false).unwrap();
/// assert!(text.contains("s = 1"));
/// ```
pub fn inspect(model: &Model, latex: bool) -> Result<String, ModelError> {
    crate::model::in_own_context(model, |model| {
        // A spent node budget is reported as the budget, as `generate` reports it: not as the
        // stage that met its placeholder symbol.
        crate::symbolic::expr::catch_budget(|| {
            let d = formulation::derive(model, &Request::all())?;
            let assemblies = emit::assemblies(model, &d, &Options::from_model(model))?;
            Ok(crate::inspect::report(model, &d, &assemblies, latex))
        })
        .unwrap_or_else(|spent| Err(model.budget_error(spent)))
    })
}

/// Stack of the emitting thread: the recursive passes over the derived expressions (deeper than
/// a model's own, which parsing bounds) need more than a spawned thread's default.
const EMITTER_STACK: usize = 64 << 20;

/// What the deriving thread hands the emitting one, each packed for its context.
enum Job {
    /// The model and the mechanics' quantities (first, once).
    Mechanics(Box<Parcel<(Model, Quantities)>>),
    /// One formulation's equations.
    Form(Box<Parcel<Equations>>),
}

/// The ignorable coordinates as the emitting thread decided them, with the time it took.
type Decided = Result<(Vec<usize>, Duration), ModelError>;

/// See the module docs. Errors are reported in the order the stages run alone: the
/// derivation's, then the emitted functions' in module order.
fn on_two_threads(model: &Model, options: &Options) -> Result<Generated, ModelError> {
    let start = Instant::now();
    let request = Request { formulations: options.formulations.clone(), integrate_ignorable: options.integrate_ignorable };
    // The requested formulations in the order they are derived (the paper's), grouped as they
    // share bodies.
    let kinds: Vec<seam::FormulationKind> = seam::FormulationKind::ALL.into_iter().filter(|k| options.formulations.iter().any(|f| f.kind() == *k)).collect();
    let mut sent = emit::reuse_groups(&kinds);
    let kept = sent.pop().unwrap_or_default();
    let to_send = sent.iter().map(Vec::len).sum();
    std::thread::scope(|scope| {
        let (jobs, inbox) = channel::<Job>();
        let (ignorable_back, ignorable_here) = channel::<Decided>();
        let emitting = std::thread::Builder::new()
            .name("emit".into())
            .stack_size(EMITTER_STACK)
            .spawn_scoped(scope, move || {
                let part = Context::new().enter(|| decide_and_emit(inbox, ignorable_back, options, sent).map(|parts| (parts, Context::current_nodes())));
                // This thread's spent budget is reported as the derivation's would be.
                match crate::symbolic::expr::take_spent() {
                    Some(spent) => Err(model.budget_error(spent)),
                    None => part,
                }
            })
            .map_err(|e| model.error(ErrorKind::Emission, "emit", "emit", format!("cannot start the emitting thread: {e}"), String::new()))?;
        let mut handing = Handing { model, jobs, packer: Packer::default(), ignorable: ignorable_here, to_send };
        let derived = formulation::derive_with(model, &request, &mut handing);
        drop(handing);
        let derive_time = start.elapsed();
        let emit_start = Instant::now();
        // Emission simplifies nothing, and differentiates only for the exact Jacobians: the
        // simplifier's memo of forms and the derivatives' memo (most of the deriving thread's
        // memory past its nodes) are freed before the last group is emitted.
        if let Ok(d) = &derived {
            d.mechanics.tidy.forget();
            Context::forget_derivatives();
        }
        let tail = derived.map(|d| {
            let names = d.equations.iter().map(|e| e.name().to_string()).collect();
            let last = d.equations.iter().filter(|e| kept.contains(&e.kind));
            (emit_last(model, options, &d, kept.clone(), last, names), d)
        });
        let head = emitting.join().unwrap_or_else(|panic| std::panic::resume_unwind(panic));
        let (tail, d) = tail?;
        let (mut parts, emitting_nodes) = head?;
        parts.push(tail?);
        // Both contexts' nodes: the work a derivation did, counted (the same for the same model
        // and options, whatever the timing: each thread's input is fixed).
        let work = emit::Work { derive_time, emit_time: emit_start.elapsed(), nodes: Context::current_nodes() + emitting_nodes };
        Ok(emit::module(model, options, &d, parts, work))
    })
}

/// The deriving thread's part: the formulations `group` (the last reuse group) and `model()`,
/// listing every formulation (`names`).
fn emit_last<'e>(
    model: &Model,
    options: &Options,
    d: &formulation::Derivation,
    group: Vec<seam::FormulationKind>,
    forms: impl Iterator<Item = &'e Equations>,
    names: Vec<String>,
) -> Result<Part, ModelError> {
    let mut emission = Emission::new(model, options, &d.mechanics, &d.ignorable, group)?;
    for eqs in forms {
        emission.form(eqs)?;
    }
    emission.model_fn(names)?;
    Ok(emission.finish())
}

/// The deriving thread's side of [`on_two_threads`]: the mechanics and the formulations of every
/// group but the last go to the emitting thread, the ignorable coordinates come back from it. A
/// send fails only when the emitting thread stopped at an error, which its result reports.
struct Handing<'a> {
    model: &'a Model,
    jobs: Sender<Job>,
    /// The jobs' expressions, each node packed once on the channel (a formulation refers to the
    /// mechanics' nodes the emitting thread already has).
    packer: Packer,
    ignorable: Receiver<Decided>,
    /// Formulations still to send (the last group's stay here).
    to_send: usize,
}

impl formulation::Stages for Handing<'_> {
    fn mechanics(&mut self, mech: &Mechanics) {
        let _ = self.jobs.send(Job::Mechanics(Box::new(self.packer.pack(&(self.model.clone(), mech.quantities.clone())))));
    }

    fn ignorable(&mut self, model: &Model, _: &Mechanics) -> Result<formulation::Ignorable, ModelError> {
        match self.ignorable.recv() {
            Ok(decided) => decided.map(|(chosen, time)| formulation::Ignorable { reports: Vec::new(), chosen, time }),
            // The emitting thread panicked: joining it reports that.
            Err(_) => Err(model.error(ErrorKind::Emission, "emit", "emit", "internal: the emitting thread stopped".into(), String::new())),
        }
    }

    fn equations(&mut self, eqs: &Equations) {
        if self.to_send > 0 {
            self.to_send -= 1;
            let _ = self.jobs.send(Job::Form(Box::new(self.packer.pack(eqs))));
        }
    }
}

/// The emitting thread (see [`on_two_threads`]): the ignorable coordinates, handed back with the
/// time they took; the module's head; each formulation of the reuse groups `groups` as its
/// [`Job`] arrives.
fn decide_and_emit(
    inbox: Receiver<Job>,
    ignorable_back: Sender<Decided>,
    options: &Options,
    groups: Vec<Vec<seam::FormulationKind>>,
) -> Result<Vec<Part>, ModelError> {
    // No mechanics: the deriving thread stopped first, and reports why.
    crate::symbolic::report::take();
    let Ok(Job::Mechanics(parcel)) = inbox.recv() else { return Ok(Vec::new()) };
    // The jobs' parcels are unpacked in the order they were sent, as one stream.
    let mut unpacker = Unpacker::default();
    let (model, mech) = unpacker.unpack(*parcel);
    let clock = Instant::now();
    let chosen = ignorable::choose(&model, &ignorable::analyze(&model, &mech));
    let _ = ignorable_back.send(chosen.clone().map(|c| (c, clock.elapsed())));
    // An error here is the derivation's, which the deriving thread reports.
    let Ok(chosen) = chosen else { return Ok(Vec::new()) };
    // The head goes with the first group (alone, where every formulation stays on the deriving
    // thread); each group's formulations arrive in order.
    let groups = if groups.is_empty() { vec![Vec::new()] } else { groups };
    let mut parts = Vec::new();
    let mut inbox = inbox.into_iter().filter_map(|job| match job {
        Job::Form(parcel) => Some(parcel),
        Job::Mechanics(_) => None,
    });
    for (k, group) in groups.iter().enumerate() {
        let mut emission = Emission::new(&model, options, &mech, &chosen, group.clone())?;
        if k == 0 {
            emission.head()?;
        }
        // A parcel missing: the deriving thread stopped at an error, which it reports.
        for parcel in inbox.by_ref().take(group.len()) {
            emission.form(&unpacker.unpack(*parcel))?;
        }
        parts.push(emission.finish());
    }
    Ok(parts)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Without the source (in-process evaluation), no text and the very tapes the source's
    /// generation records, instruction for instruction.
    #[test]
    fn the_tapes_are_the_same_without_the_source() {
        let model = crate::model::load("../models/cart_pendulum.ron").unwrap();
        let with = Options { tapes: true, jacobian: true, ..Options::from_model(&model) };
        let written = generate(&model, &with).unwrap();
        let quiet = generate(&model, &Options { source: false, ..with }).unwrap();
        assert!(written.code.contains("pub mod kane") && quiet.code.is_empty());
        let (a, b) = (written.program.unwrap().tapes, quiet.program.unwrap().tapes);
        let mut names: Vec<&String> = a.keys().collect();
        names.sort();
        assert!(names.len() > 10 && names.iter().any(|n| n.ends_with("::jacobian")), "{names:?}");
        assert_eq!(names, {
            let mut n: Vec<&String> = b.keys().collect();
            n.sort();
            n
        });
        for name in names {
            assert_eq!(format!("{:?}", a[name].parts()), format!("{:?}", b[name].parts()), "{name}");
        }
    }
}
