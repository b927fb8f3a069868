//! Compiles the in-process evaluator's tapes to machine code with cranelift: one function per
//! tape (a sequence of them for a long one, [`Split`]), `fn(inputs: *const f64, outputs: *mut
//! f64, scratch: *mut f64)`, every instruction one IEEE operation in the tape's order (cranelift
//! neither reassociates nor fuses multiply-adds), the elementary functions called as the
//! interpreter calls them. So a compiled kernel gives the interpreter's numbers, which are the
//! compiled module's, without the interpreter's dispatch.
//!
//! ```
//! use tape::{Backend, Instr, Kernel, Tape, Unary};
//! // 2 sin(x) - x^3
//! let tape = Tape::write(|w| {
//!     let x = w.input(0);
//!     let (sin, cube, two) = (w.instr(Instr::Call(Unary::Sin, x)), w.instr(Instr::Powi(x, 3)), w.constant(2.0));
//!     let twice = w.instr(Instr::Mul(two, sin));
//!     vec![w.instr(Instr::Sub(twice, cube))]
//! });
//! let jit = jit::Jit::default();
//! let kernel = jit.kernel(tape);
//! let mut out = [0.0];
//! kernel.run(&[0.5], &mut out);
//! assert_eq!(out[0], 2.0 * f64::sin(0.5) - 0.5f64.powi(3));
//! assert_eq!(jit.interpreted(), 0);
//! ```

use cranelift_codegen::ir::{AbiParam, InstBuilder, MemFlagsData, Signature, types};
use cranelift_codegen::settings::{self, Configurable};
use cranelift_frontend::{FunctionBuilder, FunctionBuilderContext};
use cranelift_jit::{JITBuilder, JITModule};
use cranelift_module::{Linkage, Module};
use tape::{Backend, Instr, Kernel, Tape, Unary};

/// The cranelift backend: each tape compiled to machine code, or left to the interpreter when
/// this machine's code cannot be generated (the kernel then is the tape itself, and
/// [`Jit::interpreted`] counts it, for the caller to say so).
#[derive(Debug, Default)]
pub struct Jit {
    interpreted: std::sync::atomic::AtomicUsize,
}

impl Jit {
    /// How many tapes were left to the interpreter (slower, same numbers).
    pub fn interpreted(&self) -> usize {
        self.interpreted.load(std::sync::atomic::Ordering::Relaxed)
    }
}

impl Backend for Jit {
    fn kernel(&self, tape: Tape) -> Box<dyn Kernel> {
        let tiered = tape.instructions() > TIERED_INSTRUCTIONS;
        let allocator = if tiered { Allocator::SinglePass } else { Allocator::Backtracking };
        match compile_with(&tape, allocator) {
            Ok(k) if tiered => Box::new(Tiered::new(k, tape)),
            Ok(k) => Box::new(k),
            Err(_) => {
                self.interpreted.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                Box::new(tape)
            }
        }
    }
}

/// The most instructions a tape may have to be compiled at once by the best register
/// allocator. A longer one (a robot's right-hand side, a Jacobian of a dozen links) is compiled
/// first by the single-pass allocator, so that the model runs at once, and again by the best
/// one on a background thread once the run proves long ([`TIER_UP_CALLS`]), which its kernel
/// then runs: the same numbers, faster. The best allocator's time per instruction grows with
/// the function's length, the single pass's does not: on the Jacobians of the pendulum on a
/// cart at 1 to 24 links (the matrix's `the_pendulum_on_a_cart_at_every_size_to_24`), about 11
/// microseconds per instruction for tapes of 2,000 to 4,000, 22 for 4,000 to 8,000, 37 for 8,000
/// to 16,000, against 4 by the single pass. So the bound is [`PIECE_INSTRUCTIONS`], where the
/// two are a few times apart, not [`FUNCTION_INSTRUCTIONS`]: `multibody compare` on the 24-link
/// pendulum's file took 0.97 s of CPU with the bound at 16,000 and 0.57 s at 4,000, and 2.4 s
/// against 2.0 s over 20 s of motion, where the best code takes over (`perf stat -r 3`,
/// alternately, on this project's 2-core machine). On the humanoid (talos_reduced on a floating
/// base, `multibody simulate`): ready in 2.1 to 2.3 s of CPU with the single-pass allocator
/// against 3.1 to 3.3 s with the best one, whose calls are then 1.5 to 2 times faster (`cargo
/// bench --bench robot_calls`).
pub const TIERED_INSTRUCTIONS: usize = PIECE_INSTRUCTIONS;

/// How many calls a long tape's kernel runs on its single-pass code before the best allocator
/// compiles it on the background thread. The best code saves a fraction of a call's time, its
/// compile costs as much as hundreds of thousands of calls: a run shorter than this (a check,
/// a short simulation, a trial in a notebook, a Jacobian evaluated a few times) ends before
/// the compile would pay, and leaves the other cores to the caller; a longer one gets it a few
/// tenths of a second into its run. Calls, not seconds, so that when it happens is the same on
/// every machine.
pub const TIER_UP_CALLS: usize = 10_000;

/// A long tape's kernel: the single-pass code until the best allocator's is ready, then that.
struct Tiered {
    quick: Compiled,
    slot: std::sync::Arc<upgrades::Slot>,
    calls: std::sync::atomic::AtomicUsize,
}

impl Tiered {
    fn new(quick: Compiled, tape: Tape) -> Tiered {
        Tiered { quick, slot: upgrades::Slot::new(tape), calls: std::sync::atomic::AtomicUsize::new(0) }
    }

    fn current(&self) -> &Compiled {
        self.slot.best.get().unwrap_or(&self.quick)
    }
}

impl Kernel for Tiered {
    fn inputs(&self) -> usize {
        self.quick.inputs
    }
    fn outputs(&self) -> usize {
        self.quick.outputs
    }
    fn run(&self, inputs: &[f64], out: &mut [f64]) {
        use std::sync::atomic::Ordering::Relaxed;
        // Counted until the upgrade is asked for, then only read: threads sharing the kernel
        // (an ensemble) do not contend for the counter for the rest of the run.
        if self.calls.load(Relaxed) < TIER_UP_CALLS && self.calls.fetch_add(1, Relaxed) + 1 == TIER_UP_CALLS {
            upgrades::push(&self.slot);
        }
        self.current().run(inputs, out)
    }
}

/// Compiles every long tape's best code now, even one whose run has not reached
/// [`TIER_UP_CALLS`], and waits until each runs it: for a benchmark that times the calls, or a
/// caller that wants the fastest code before it starts.
///
/// ```
/// jit::settle(); // nothing compiled: returns at once
/// ```
pub fn settle() {
    upgrades::settle()
}

/// The background compiles: one worker thread takes the long tapes in turn, each once its
/// kernel asks (or `settle` does).
mod upgrades {
    use super::{Allocator, Compiled, Tape, compile_with};
    use std::collections::VecDeque;
    use std::sync::{Arc, Condvar, Mutex, MutexGuard, OnceLock, PoisonError, Weak};

    /// A long tape's best code, once compiled, and its tape until its compile is queued.
    pub(super) struct Slot {
        pub(super) best: OnceLock<Compiled>,
        pub(super) tape: Mutex<Option<Tape>>,
    }

    impl Slot {
        /// A slot for `tape`, known to `settle` until its kernel is dropped.
        pub(super) fn new(tape: Tape) -> Arc<Slot> {
            let slot = Arc::new(Slot { best: OnceLock::new(), tape: Mutex::new(Some(tape)) });
            let mut q = lock();
            q.waiting.retain(|s| s.strong_count() > 0);
            q.waiting.push(Arc::downgrade(&slot));
            slot
        }
    }

    struct Queue {
        /// The slots whose compile no one has asked for yet (or has: `tape` is then gone).
        waiting: Vec<Weak<Slot>>,
        jobs: VecDeque<(Tape, Weak<Slot>)>,
        /// Jobs queued or being compiled.
        pending: usize,
        worker: bool,
    }

    static QUEUE: Mutex<Queue> = Mutex::new(Queue { waiting: Vec::new(), jobs: VecDeque::new(), pending: 0, worker: false });
    static DONE: Condvar = Condvar::new();

    fn lock() -> MutexGuard<'static, Queue> {
        QUEUE.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// Queues the compile of `slot`'s best code, unless it is queued already.
    pub(super) fn push(slot: &Arc<Slot>) {
        let Some(tape) = slot.tape.lock().unwrap_or_else(PoisonError::into_inner).take() else {
            return;
        };
        let mut q = lock();
        q.jobs.push_back((tape, Arc::downgrade(slot)));
        q.pending += 1;
        if !q.worker {
            // Without a thread the kernel keeps its single-pass code: slower, same numbers.
            match std::thread::Builder::new().name("jit-upgrades".into()).spawn(work) {
                Ok(_) => q.worker = true,
                Err(_) => {
                    q.jobs.clear();
                    q.pending = 0;
                }
            }
        }
    }

    fn work() {
        loop {
            let job = {
                let mut q = lock();
                match q.jobs.pop_front() {
                    Some(job) => job,
                    // Empty: the last job's end has already woken `settle`.
                    None => {
                        q.worker = false;
                        return;
                    }
                }
            };
            let (tape, slot) = job;
            // A kernel dropped before its turn needs no better code.
            if slot.strong_count() > 0
                && let Ok(best) = compile_with(&tape, Allocator::Backtracking)
                && let Some(slot) = slot.upgrade()
            {
                let _ = slot.best.set(best);
            }
            let mut q = lock();
            q.pending -= 1;
            if q.pending == 0 {
                DONE.notify_all();
            }
        }
    }

    /// Queues every live slot's compile, then waits for the queue.
    pub(super) fn settle() {
        let waiting = std::mem::take(&mut lock().waiting);
        for slot in waiting.iter().filter_map(Weak::upgrade) {
            push(&slot);
        }
        wait();
    }

    /// Waits until the compiles queued so far are done.
    pub(super) fn wait() {
        let mut q = lock();
        while q.pending > 0 {
            q = DONE.wait(q).unwrap_or_else(PoisonError::into_inner);
        }
    }
}

/// A tape compiled to machine code; the module that owns the code lives as long as it does.
pub struct Compiled {
    module: Option<JITModule>,
    /// The tape's functions, in the order they run.
    code: Vec<Function>,
    /// How many values the functions pass on through the scratch buffer.
    scratch: usize,
    inputs: usize,
    outputs: usize,
}

// SAFETY: the module is only read after `finalize_definitions` (the code is immutable and
// reentrant: it reads its arguments and writes its outputs, nothing else) and only dropped with
// the kernel; no two threads touch its internals.
unsafe impl Send for Compiled {}
unsafe impl Sync for Compiled {}

impl Drop for Compiled {
    fn drop(&mut self) {
        if let Some(module) = self.module.take() {
            // SAFETY: `code` points into the module's memory and dies with `self`.
            unsafe { module.free_memory() };
        }
    }
}

impl Kernel for Compiled {
    fn inputs(&self) -> usize {
        self.inputs
    }
    fn outputs(&self) -> usize {
        self.outputs
    }
    fn run(&self, inputs: &[f64], out: &mut [f64]) {
        assert!(inputs.len() >= self.inputs && out.len() >= self.outputs, "a kernel's buffers are too short");
        let (inputs, out) = (inputs.as_ptr(), out.as_mut_ptr());
        let run = |scratch: *mut f64| {
            for f in &self.code {
                // SAFETY: the code reads `self.inputs` entries, writes `self.outputs` (checked
                // above) and reads and writes `self.scratch` entries of `scratch`.
                unsafe { f(inputs, out, scratch) }
            }
        };
        if self.scratch == 0 {
            run(std::ptr::null_mut());
        } else {
            SCRATCH.with_borrow_mut(|s| {
                if s.len() < self.scratch {
                    s.resize(self.scratch, 0.0);
                }
                run(s.as_mut_ptr())
            });
        }
    }
}

extern "C" fn call_sin(x: f64) -> f64 {
    Unary::Sin.apply(x)
}
extern "C" fn call_cos(x: f64) -> f64 {
    Unary::Cos.apply(x)
}
extern "C" fn call_tan(x: f64) -> f64 {
    Unary::Tan.apply(x)
}
extern "C" fn call_exp(x: f64) -> f64 {
    Unary::Exp.apply(x)
}
extern "C" fn call_ln(x: f64) -> f64 {
    Unary::Ln.apply(x)
}
extern "C" fn call_powi(x: f64, n: i32) -> f64 {
    x.powi(n)
}
extern "C" fn call_powf(x: f64, y: f64) -> f64 {
    x.powf(y)
}

/// Why a tape could not be compiled (this machine's code generator is unavailable).
#[derive(Debug)]
pub struct JitError(pub String);

fn error(e: impl std::fmt::Display) -> JitError {
    JitError(e.to_string())
}

/// The most instructions a tape may have to be compiled as one function, by cranelift's
/// backtracking register allocator, which writes the fastest code but takes superlinear time on
/// one long block: 25 ms for 3854 instructions, 170 ms for 9858, 250 ms for 13736, 2.0 s for
/// 24497, about three minutes for the bicycle's exact Jacobian (194571). A longer tape is cut
/// into functions of at most [`PIECE_INSTRUCTIONS`] ([`function_length`]).
pub const FUNCTION_INSTRUCTIONS: usize = 16_000;

/// The most instructions of each function a tape longer than [`FUNCTION_INSTRUCTIONS`] is cut
/// into; the values one function leaves to a later one pass through a scratch buffer. Measured
/// on this project's machine (`multibody linearize bicycle` and the scaling benchmark's
/// `--one floating 20 compile`, alternately): the bicycle's linearization takes 5.2 s with the
/// single-pass allocator on its one long function (as before the cut), 5.6-5.8 s with pieces of
/// 4000, 5.9 s of 8000, 6.7 s of 16000; the 20-link floating chain's Lagrange and Maggi
/// right-hand sides (38640 instructions of assembly) run at 1.27 and 1.35 times the compiled
/// module's with pieces of 4000, 1.42 and 1.41 with the single-pass allocator, 1.17 and 1.14 as
/// one function (which takes seconds to compile).
pub const PIECE_INSTRUCTIONS: usize = 4_000;

/// The most instructions of each function a tape of `instructions` is compiled into.
///
/// ```
/// assert_eq!(jit::function_length(9858), 9858);
/// assert_eq!(jit::function_length(38640), jit::PIECE_INSTRUCTIONS);
/// ```
pub fn function_length(instructions: usize) -> usize {
    if instructions <= FUNCTION_INSTRUCTIONS { instructions.max(1) } else { PIECE_INSTRUCTIONS }
}

/// How a tape's instructions are cut into functions ([`function_length`]), and which values
/// cross from one function to a later one (each gets a place in the scratch buffer). Registers
/// are numbered as the tape numbers them: the inputs, then the constants, then one per
/// instruction.
///
/// ```
/// use tape::Instr;
/// // Two inputs, no constants, three instructions cut into functions of two: the third
/// // instruction reads the first one's result (register 2) from the scratch buffer.
/// let split = jit::Split::new(2, 0, &[Instr::Add(0, 1), Instr::Mul(2, 1), Instr::Sub(2, 3)], 2);
/// assert_eq!(split.functions(), vec![0..2, 2..3]);
/// assert_eq!(split.scratch_place(2), Some(0));
/// assert_eq!(split.scratch_place(3), Some(1));
/// assert_eq!(split.scratch_len(), 2);
/// ```
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Split {
    first_instruction_register: usize,
    per_function: usize,
    instructions: usize,
    /// For each instruction's register, its place in the scratch buffer where a later function
    /// reads it.
    place: Vec<Option<u32>>,
    scratch_len: usize,
}

impl Split {
    /// Cuts `instrs` (after `inputs` input and `constants` constant registers) into functions of
    /// at most `most` instructions each, of nearly equal length.
    pub fn new(inputs: usize, constants: usize, instrs: &[Instr], most: usize) -> Split {
        let count = instrs.len().div_ceil(most.max(1)).max(1);
        let per_function = instrs.len().div_ceil(count).max(1);
        let first = inputs + constants;
        let mut place = vec![None; instrs.len()];
        let mut scratch_len = 0;
        for (k, ins) in instrs.iter().enumerate() {
            for x in operands(ins) {
                let x = x as usize;
                if x >= first && (x - first) / per_function != k / per_function && place[x - first].is_none() {
                    place[x - first] = Some(scratch_len as u32);
                    scratch_len += 1;
                }
            }
        }
        Split { first_instruction_register: first, per_function, instructions: instrs.len(), place, scratch_len }
    }

    /// The instructions of each function, in the order they run.
    pub fn functions(&self) -> Vec<std::ops::Range<usize>> {
        (0..self.instructions.div_ceil(self.per_function).max(1)).map(|f| f * self.per_function..((f + 1) * self.per_function).min(self.instructions)).collect()
    }

    /// The function that computes `register` (`None` for an input or a constant).
    fn function_of(&self, register: usize) -> Option<usize> {
        register.checked_sub(self.first_instruction_register).map(|k| k / self.per_function)
    }

    /// Where `register` waits for a later function in the scratch buffer, if one reads it.
    pub fn scratch_place(&self, register: usize) -> Option<usize> {
        register.checked_sub(self.first_instruction_register).and_then(|k| self.place[k]).map(|p| p as usize)
    }

    /// How many values the scratch buffer holds.
    pub fn scratch_len(&self) -> usize {
        self.scratch_len
    }
}

/// The registers an instruction reads.
fn operands(ins: &Instr) -> impl Iterator<Item = u32> {
    let (a, b) = match *ins {
        Instr::Add(x, y) | Instr::Sub(x, y) | Instr::Mul(x, y) | Instr::Div(x, y) | Instr::Powf(x, y) => (x, Some(y)),
        Instr::Neg(x) | Instr::Call(_, x) | Instr::Powi(x, _) => (x, None),
    };
    std::iter::once(a).chain(b)
}

/// One compiled function's signature: `fn(inputs, outputs, scratch)`.
type Function = unsafe extern "C" fn(*const f64, *mut f64, *mut f64);

thread_local! {
    /// The scratch buffer of the tapes cut into several functions, one per thread (a kernel is
    /// shared by the threads of an ensemble).
    static SCRATCH: std::cell::RefCell<Vec<f64>> = const { std::cell::RefCell::new(Vec::new()) };
}

/// Compiles `tape` (see the crate docs) with cranelift's best register allocator.
pub fn compile(tape: &Tape) -> Result<Compiled, JitError> {
    compile_with(tape, Allocator::Backtracking)
}

/// Cranelift's register allocators: the trade between the time to compile and the speed of the
/// code.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Allocator {
    /// The fastest code, in superlinear time on long functions.
    Backtracking,
    /// One pass: compiles in a fraction of the time, the code spills more.
    SinglePass,
}

impl Allocator {
    fn name(self) -> &'static str {
        match self {
            Allocator::Backtracking => "backtracking",
            Allocator::SinglePass => "single_pass",
        }
    }
}

/// Compiles `tape` with `allocator`: the same instructions in the same order whichever it is,
/// so the same numbers.
pub fn compile_with(tape: &Tape, allocator: Allocator) -> Result<Compiled, JitError> {
    let (inputs, constants, instrs, outputs) = tape.parts();
    let split = Split::new(inputs, constants.len(), instrs, function_length(instrs.len()));
    let mut flags = settings::builder();
    flags.set("opt_level", "speed").map_err(error)?;
    flags.set("regalloc_algorithm", allocator.name()).map_err(error)?;
    // The IR verifier re-checks every function cranelift is given (as wasmtime, we turn it off
    // outside cranelift's own tests): the IR is built by one routine, tested here on every
    // instruction and with both allocators.
    flags.set("enable_verifier", "false").map_err(error)?;
    let isa = cranelift_native::builder().map_err(error)?.finish(settings::Flags::new(flags)).map_err(error)?;
    let mut builder = JITBuilder::with_isa(isa, cranelift_module::default_libcall_names());
    let functions: [(&str, *const u8); 7] = [
        ("mb_sin", call_sin as *const u8),
        ("mb_cos", call_cos as *const u8),
        ("mb_tan", call_tan as *const u8),
        ("mb_exp", call_exp as *const u8),
        ("mb_ln", call_ln as *const u8),
        ("mb_powi", call_powi as *const u8),
        ("mb_powf", call_powf as *const u8),
    ];
    for (name, address) in functions {
        builder.symbol(name, address);
    }
    let mut module = JITModule::new(builder);
    let pointer = module.target_config().pointer_type();
    let mut signature = module.make_signature();
    signature.params.extend([AbiParam::new(pointer), AbiParam::new(pointer), AbiParam::new(pointer)]);
    let import = |module: &mut JITModule, name: &str, params: &[types::Type]| {
        let mut s = Signature::new(module.target_config().default_call_conv);
        s.params.extend(params.iter().map(|t| AbiParam::new(*t)));
        s.returns.push(AbiParam::new(types::F64));
        module.declare_function(name, Linkage::Import, &s).map_err(error)
    };
    let imports = Imports {
        unary: [(Unary::Sin, "mb_sin"), (Unary::Cos, "mb_cos"), (Unary::Tan, "mb_tan"), (Unary::Exp, "mb_exp"), (Unary::Ln, "mb_ln")]
            .into_iter()
            .map(|(u, name)| import(&mut module, name, &[types::F64]).map(|id| (u, id)))
            .collect::<Result<_, _>>()?,
        powi: import(&mut module, "mb_powi", &[types::F64, types::I32])?,
        powf: import(&mut module, "mb_powf", &[types::F64, types::F64])?,
    };
    let mut written: std::collections::HashMap<usize, Vec<usize>> = std::collections::HashMap::new();
    for (k, &r) in outputs.iter().enumerate() {
        written.entry(r as usize).or_default().push(k);
    }
    let mut functions = Vec::new();
    let mut fbc = FunctionBuilderContext::new();
    for (f, range) in split.functions().into_iter().enumerate() {
        let id = module.declare_function(&format!("kernel{f}"), Linkage::Local, &signature).map_err(error)?;
        let mut ctx = module.make_context();
        ctx.func.signature = signature.clone();
        let body = Body { inputs, constants, instrs, outputs, split: &split, written: &written, range };
        body.build(&mut module, &imports, &mut ctx.func, &mut fbc);
        functions.push((id, ctx));
    }
    compile_side_by_side(module.isa(), &mut functions)?;
    // Placed in memory in their order, as `define_function` would place them.
    for (id, ctx) in &functions {
        let code = ctx.compiled_code().expect("every function was compiled");
        let relocs: Vec<cranelift_module::ModuleReloc> =
            code.buffer.relocs().iter().map(|r| cranelift_module::ModuleReloc::from_mach_reloc(r, &ctx.func, *id)).collect();
        module.define_function_bytes(*id, u64::from(code.buffer.alignment), code.code_buffer(), &relocs).map_err(error)?;
    }
    module.finalize_definitions().map_err(error)?;
    let code = functions
        .iter()
        .map(|(id, _)| {
            let address = module.get_finalized_function(*id);
            // SAFETY: the function was built with exactly this signature.
            unsafe { std::mem::transmute::<*const u8, Function>(address) }
        })
        .collect();
    Ok(Compiled { module: Some(module), code, scratch: split.scratch_len(), inputs, outputs: outputs.len() })
}

/// Compiles each function of a tape to machine code, side by side on the machine's threads
/// (a long tape's pieces are independent until they are placed in memory, which stays in their
/// order). Measured on this project's 2-core machine with `perf stat -r 3 multibody linearize
/// bicycle ...` (the command of `docs/bicycle.md`: the exact Jacobian's 194571 instructions in
/// 49 pieces), alternately: 5.94 and 5.98 s of wall time one piece after the other, 5.29 and
/// 5.37 s side by side, the same CPU.
fn compile_side_by_side(
    isa: &dyn cranelift_codegen::isa::TargetIsa,
    functions: &mut [(cranelift_module::FuncId, cranelift_codegen::Context)],
) -> Result<(), JitError> {
    let threads = std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get).clamp(1, functions.len().max(1));
    let per_thread = functions.len().div_ceil(threads).max(1);
    std::thread::scope(|s| {
        let compile = |part: &mut [(cranelift_module::FuncId, cranelift_codegen::Context)]| {
            part.iter_mut().try_for_each(|(_, ctx)| ctx.compile(isa, &mut Default::default()).map(|_| ()).map_err(|e| error(format!("{:?}", e.inner))))
        };
        let mut parts = functions.chunks_mut(per_thread);
        let first = parts.next();
        let handles: Vec<_> = parts.map(|part| s.spawn(move || compile(part))).collect();
        let mut result = first.map_or(Ok(()), compile);
        for h in handles {
            let r = h.join().unwrap_or_else(|panic| std::panic::resume_unwind(panic));
            result = result.and(r);
        }
        result
    })
}

/// The elementary functions the compiled code calls.
struct Imports {
    unary: Vec<(Unary, cranelift_module::FuncId)>,
    powi: cranelift_module::FuncId,
    powf: cranelift_module::FuncId,
}

/// One function of a tape: its instructions, in the tape's order, and the outputs it computes.
struct Body<'a> {
    inputs: usize,
    constants: &'a [f64],
    instrs: &'a [Instr],
    outputs: &'a [u32],
    split: &'a Split,
    /// For each register an output is, the outputs' indices.
    written: &'a std::collections::HashMap<usize, Vec<usize>>,
    /// This function's instructions (the first function's starts at 0).
    range: std::ops::Range<usize>,
}

impl Body<'_> {
    fn build(&self, module: &mut JITModule, imports: &Imports, func: &mut cranelift_codegen::ir::Function, fbc: &mut FunctionBuilderContext) {
        let frontend = module.target_config();
        let mut b = FunctionBuilder::new(func, fbc);
        let block = b.create_block();
        b.append_block_params_for_function_params(block);
        b.switch_to_block(block);
        b.seal_block(block);
        let (input, output, scratch) = (b.block_params(block)[0], b.block_params(block)[1], b.block_params(block)[2]);
        let flags = MemFlagsData::trusted();
        let unary: Vec<(Unary, cranelift_codegen::ir::FuncRef)> = imports.unary.iter().map(|(u, id)| (*u, module.declare_func_in_func(*id, b.func))).collect();
        let powi = module.declare_func_in_func(imports.powi, b.func);
        let powf = module.declare_func_in_func(imports.powf, b.func);
        let first = self.inputs + self.constants.len();
        // The values this function computes, and those it reads from elsewhere (loaded or
        // materialized once, at the first use).
        let mut own = Vec::with_capacity(self.range.len());
        let mut outside = std::collections::HashMap::new();
        let mut value = |b: &mut FunctionBuilder, own: &[cranelift_codegen::ir::Value], r: u32| {
            let r = r as usize;
            if r >= first + self.range.start {
                return own[r - first - self.range.start];
            }
            *outside.entry(r).or_insert_with(|| {
                if r < self.inputs {
                    b.ins().load(types::F64, flags, input, (8 * r) as i32)
                } else if r < first {
                    b.ins().f64const(self.constants[r - self.inputs])
                } else {
                    let place = self.split.scratch_place(r).expect("a value read by a later function has a place");
                    b.ins().load(types::F64, flags, scratch, (8 * place) as i32)
                }
            })
        };
        for ins in &self.instrs[self.range.clone()] {
            // The operands, in the order the instruction names them (a unary one's `y` is its `x`).
            let mut operands = operands(ins).map(|r| value(&mut b, &own, r));
            let x = operands.next().expect("every instruction reads a register");
            let y = operands.next().unwrap_or(x);
            let v = match *ins {
                Instr::Add(..) => b.ins().fadd(x, y),
                Instr::Sub(..) => b.ins().fsub(x, y),
                Instr::Mul(..) => b.ins().fmul(x, y),
                Instr::Div(..) => b.ins().fdiv(x, y),
                Instr::Neg(..) => b.ins().fneg(x),
                Instr::Call(Unary::Sqrt, _) => b.ins().sqrt(x),
                Instr::Call(Unary::Abs, _) => b.ins().fabs(x),
                Instr::Call(u, _) => {
                    let f = unary.iter().find(|(k, _)| *k == u).expect("every other unary is imported").1;
                    let call = b.ins().call(f, &[x]);
                    b.inst_results(call)[0]
                }
                Instr::Powi(_, n) => {
                    let n = b.ins().iconst(types::I32, i64::from(n));
                    let call = b.ins().call(powi, &[x, n]);
                    b.inst_results(call)[0]
                }
                Instr::Powf(..) => {
                    let call = b.ins().call(powf, &[x, y]);
                    b.inst_results(call)[0]
                }
            };
            // Stored as soon as computed, so that it need not stay in a register.
            let r = first + self.range.start + own.len();
            if let Some(place) = self.split.scratch_place(r) {
                b.ins().store(flags, v, scratch, (8 * place) as i32);
            }
            for &k in self.written.get(&r).map(Vec::as_slice).unwrap_or_default() {
                b.ins().store(flags, v, output, (8 * k) as i32);
            }
            own.push(v);
        }
        // The outputs that are inputs or constants, written by the first function.
        if self.range.start == 0 {
            for (k, &r) in self.outputs.iter().enumerate() {
                if self.split.function_of(r as usize).is_none() {
                    let v = value(&mut b, &own, r);
                    b.ins().store(flags, v, output, (8 * k) as i32);
                }
            }
        }
        b.ins().return_(&[]);
        b.finalize(frontend);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use generator::emit::tape::Slots;

    /// Every instruction the tapes have, compiled (no fallback to the interpreter), gives the
    /// interpreter's numbers to the bit, including where one is not finite.
    #[test]
    fn every_instruction_compiles_to_the_interpreter_s_numbers() {
        let stmts: Vec<syn::Stmt> = vec![
            syn::parse_quote!(let x = state[0];),
            syn::parse_quote!(let y = state[1];),
            syn::parse_quote!(let a = f64::sin(x) * f64::cos(y) - f64::tan(x / y);),
            syn::parse_quote!(let b = f64::exp(-x) + f64::ln(y) + f64::abs(x - y) + f64::sqrt(y);),
            syn::parse_quote!(let c = f64::powi(x, 7) - f64::powi(y, -3) + f64::powf(x, y);),
        ];
        let outputs: Vec<syn::Expr> = vec![syn::parse_quote!(a * b + c), syn::parse_quote!(-a / c), syn::parse_quote!(t + 2.5)];
        let tape = generator::emit::tape::compile(&stmts, &outputs, &Slots::new(&[("t", 1), ("state", 2)])).unwrap();
        for allocator in [Allocator::Backtracking, Allocator::SinglePass] {
            let compiled = compile_with(&tape, allocator).expect("this machine's code generator is available");
            for inputs in [[0.3, 0.7, 1.9], [1.0, -2.5, 0.25], [0.0, 0.0, -1.0]] {
                let (mut a, mut b) = ([0.0; 3], [0.0; 3]);
                tape.eval(&inputs, &mut a);
                compiled.run(&inputs, &mut b);
                for (x, y) in a.iter().zip(&b) {
                    assert!(x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan()), "{allocator:?}: {a:?} against {b:?} at {inputs:?}");
                }
            }
            assert_eq!((compiled.inputs(), compiled.outputs()), (3, 3));
        }
    }

    /// The tests that look at the background compiles, one at a time (`settle` asks for every
    /// live kernel's).
    static UPGRADES: std::sync::Mutex<()> = std::sync::Mutex::new(());

    /// A tape longer than [`TIERED_INSTRUCTIONS`]: two inputs, a few outputs.
    fn long_tape() -> Tape {
        Tape::write(|w| {
            let (mut a, mut b) = (w.input(0), w.input(1));
            let (c, d) = (w.constant(0.999), w.constant(0.001));
            let mut outs = Vec::new();
            for k in 0..TIERED_INSTRUCTIONS / 3 + 10 {
                let x = w.instr(Instr::Mul(a, c));
                let y = w.instr(Instr::Mul(b, d));
                let s = w.instr(if k % 5 == 0 { Instr::Sub(x, y) } else { Instr::Add(x, y) });
                (a, b) = (s, a);
                if k % 1000 == 0 {
                    outs.push(s);
                }
            }
            outs
        })
    }

    /// A long tape's kernel runs the single-pass code at once and the best allocator's once the
    /// background compile is done: the interpreter's numbers before and after; a short tape is
    /// compiled once, by the best allocator.
    #[test]
    fn a_long_tape_runs_at_once_and_its_best_code_later_with_the_same_numbers() {
        let _one = UPGRADES.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        let long = long_tape();
        assert!(long.instructions() > TIERED_INSTRUCTIONS);
        let quick = compile_with(&long, Allocator::SinglePass).unwrap();
        let tiered = Tiered::new(quick, long.clone());
        let state = [0.3, -0.7];
        let mut want = vec![0.0; long.outputs()];
        long.eval(&state, &mut want);
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        let mut got = vec![f64::NAN; long.outputs()];
        tiered.run(&state, &mut got);
        assert_eq!(bits(&got), bits(&want), "before the upgrade");
        settle();
        assert!(tiered.slot.best.get().is_some(), "settled: the best code is in place");
        got.fill(f64::NAN);
        tiered.run(&state, &mut got);
        assert_eq!(bits(&got), bits(&want), "after the upgrade");
        // Through the backend: the long tape is tiered, a short one is not.
        let jit = Jit::default();
        let kernel = jit.kernel(long.clone());
        settle();
        got.fill(f64::NAN);
        kernel.run(&state, &mut got);
        assert_eq!(bits(&got), bits(&want));
        let short = Tape::write(|w| vec![w.instr(Instr::Add(w.input(0), w.input(1)))]);
        assert_eq!(jit.kernel(short).outputs(), 1);
        assert_eq!(jit.interpreted(), 0);
    }

    /// A long tape's best code is compiled once its kernel has run [`TIER_UP_CALLS`] times, not
    /// before (a short run pays for one compile), and asked for once; `settle` asks for it at
    /// once.
    #[test]
    fn the_best_code_is_compiled_once_the_run_proves_long() {
        let _one = UPGRADES.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        let long = long_tape();
        let tiered = Tiered::new(compile_with(&long, Allocator::SinglePass).unwrap(), long.clone());
        let (state, mut out) = ([0.3, -0.7], vec![0.0; long.outputs()]);
        for _ in 0..TIER_UP_CALLS - 1 {
            tiered.run(&state, &mut out);
        }
        upgrades::wait();
        assert!(tiered.slot.best.get().is_none(), "not asked for before the call that proves the run long");
        tiered.run(&state, &mut out);
        upgrades::wait();
        assert!(tiered.slot.best.get().is_some(), "asked for at call {TIER_UP_CALLS}");
        assert!(tiered.slot.tape.lock().unwrap().is_none(), "asked for once: the tape left the slot");
        // `settle` compiles a live kernel's best code unasked (a benchmark times the best code).
        let live = Tiered::new(compile_with(&long, Allocator::SinglePass).unwrap(), long);
        settle();
        assert!(live.slot.best.get().is_some());
    }

    /// A tape of many functions gives the interpreter's numbers to the bit too: a long chain of
    /// dependent operations that keeps many values alive across the cuts (so that registers
    /// spill and the scratch buffer carries values to functions far ahead), with outputs from
    /// the first function, the last, an input and a constant.
    #[test]
    fn a_tape_cut_into_functions_gives_the_interpreter_s_numbers() {
        let mut stmts: Vec<syn::Stmt> = vec![syn::parse_quote!(let v0 = state[0];), syn::parse_quote!(let v1 = state[1];)];
        let count = FUNCTION_INSTRUCTIONS + 100;
        for k in 2..count {
            let (a, b) = (k - 1, k / 2);
            let text = if k % 7 == 0 { format!("let v{k} = f64::sin(v{a}) - v{b};") } else { format!("let v{k} = v{a} * 0.999 + v{b} * 0.001;") };
            stmts.push(syn::parse_str(&text).unwrap());
        }
        let mut outputs: Vec<syn::Expr> = (count - 40..count).map(|k| syn::parse_str(&format!("v{k} + v{}", k / 3)).unwrap()).collect();
        outputs.extend([syn::parse_quote!(v5 * v3), syn::parse_quote!(v1), syn::parse_quote!(2.5), syn::parse_quote!(v5 * v3)]);
        let tape = generator::emit::tape::compile(&stmts, &outputs, &Slots::new(&[("state", 2)])).unwrap();
        let (inputs, constants, instrs, _) = tape.parts();
        let split = Split::new(inputs, constants.len(), instrs, function_length(instrs.len()));
        assert!(split.functions().len() >= 3, "{} instructions in {} functions", instrs.len(), split.functions().len());
        let compiled = compile(&tape).expect("this machine's code generator is available");
        let state = [0.3, -0.7];
        let (mut a, mut b) = (vec![0.0; outputs.len()], vec![f64::NAN; outputs.len()]);
        tape.eval(&state, &mut a);
        compiled.run(&state, &mut b);
        assert!(a.iter().all(|x| x.is_finite()));
        assert_eq!(a.iter().map(|x| x.to_bits()).collect::<Vec<_>>(), b.iter().map(|x| x.to_bits()).collect::<Vec<_>>());
        assert_eq!(&b[outputs.len() - 3..outputs.len() - 1], &[-0.7, 2.5]);
        // Run again from other threads, each with its own scratch buffer.
        std::thread::scope(|s| {
            for t in 0..4 {
                let (compiled, tape) = (&compiled, &tape);
                s.spawn(move || {
                    let state = [0.1 * f64::from(t), 0.2];
                    let (mut a, mut b) = (vec![0.0; 44], vec![0.0; 44]);
                    tape.eval(&state, &mut a);
                    compiled.run(&state, &mut b);
                    assert_eq!(a.iter().map(|x| x.to_bits()).collect::<Vec<_>>(), b.iter().map(|x| x.to_bits()).collect::<Vec<_>>());
                });
            }
        });
    }

    /// Every register read outside the function that computes it has its own place in the
    /// scratch buffer, and no other register has one; the functions cover the tape in order.
    #[test]
    fn a_split_gives_a_place_to_exactly_the_values_that_cross() {
        let instrs: Vec<Instr> = (0..23u32).map(|k| if k % 3 == 0 { Instr::Add(k + 2, k / 2) } else { Instr::Mul(k + 2, 1) }).collect();
        let split = Split::new(2, 1, &instrs, 5);
        let functions = split.functions();
        assert_eq!(functions.len(), 5);
        assert_eq!(functions.iter().map(|r| r.len()).sum::<usize>(), 23);
        assert!(functions.windows(2).all(|w| w[0].end == w[1].start) && functions[0].start == 0);
        let function_of = |k: usize| functions.iter().position(|r| r.contains(&k)).unwrap();
        let mut crossing = std::collections::BTreeSet::new();
        for (k, ins) in instrs.iter().enumerate() {
            for x in operands(ins) {
                if x >= 3 && function_of(x as usize - 3) != function_of(k) {
                    crossing.insert(x as usize);
                }
            }
        }
        assert!(!crossing.is_empty());
        let mut places = std::collections::BTreeSet::new();
        for r in 0..26 {
            match split.scratch_place(r) {
                Some(p) => assert!(crossing.contains(&r) && places.insert(p), "register {r}"),
                None => assert!(!crossing.contains(&r), "register {r}"),
            }
        }
        assert_eq!(places.len(), split.scratch_len());
    }
}
