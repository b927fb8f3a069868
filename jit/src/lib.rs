//! Compiles the in-process evaluator's tapes to machine code with cranelift: one function per
//! tape, `fn(inputs: *const f64, outputs: *mut f64)`, every instruction one IEEE operation in
//! the tape's order (cranelift neither reassociates nor fuses multiply-adds), the elementary
//! functions called as the interpreter calls them. So a compiled kernel gives the interpreter's
//! numbers, which are the compiled module's, without the interpreter's dispatch.
//!
//! ```
//! use generator::emit::tape::{Slots, Tape};
//! use generator::eval::kernel::{Backend, Kernel};
//! let stmts: Vec<syn::Stmt> = vec![syn::parse_quote!(let x = state[0];), syn::parse_quote!(let x0 = f64::sin(x);)];
//! let tape = Tape::compile(&stmts, &[syn::parse_quote!(2.0 * x0 - f64::powi(x, 3))], &Slots::new(&[("state", 1)])).unwrap();
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
use generator::emit::tape::{Instr, Tape, Unary};
use generator::eval::kernel::{Backend, Kernel};

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
        match compile(&tape) {
            Ok(k) => Box::new(k),
            Err(_) => {
                self.interpreted.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                Box::new(tape)
            }
        }
    }
}

/// A tape compiled to machine code; the module that owns the code lives as long as it does.
pub struct Compiled {
    module: Option<JITModule>,
    code: unsafe extern "C" fn(*const f64, *mut f64),
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
        // SAFETY: the code reads `self.inputs` entries and writes `self.outputs` (checked above).
        unsafe { (self.code)(inputs.as_ptr(), out.as_mut_ptr()) }
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

/// The most instructions a tape may have for cranelift's backtracking register allocator; longer
/// ones get the single-pass allocator. The backtracking one writes the faster code (the 20-link
/// pendulum's and the 8-link floating chain's right-hand sides run 1.1 to 2.7 times faster than
/// with the single-pass one) but takes superlinear time on one long block: 25 ms for 3854
/// instructions, 170 ms for 9858, 250 ms for 13736, 2.0 s for 24497, 2.9 s for 38640, and about
/// three minutes for the bicycle's exact Jacobian (194571), which the single-pass one compiles in
/// 0.5 s (27146 instructions: 45 ms against 1.7 s). Measured on this project's machine with
/// `multibody linearize` and `simulate` on those models.
pub const BACKTRACKING_LIMIT: usize = 16_000;

/// Cranelift's `regalloc_algorithm` for a tape of `instructions` ([`BACKTRACKING_LIMIT`]).
///
/// ```
/// assert_eq!(jit::register_allocator(1000), "backtracking");
/// assert_eq!(jit::register_allocator(200_000), "single_pass");
/// ```
pub fn register_allocator(instructions: usize) -> &'static str {
    if instructions <= BACKTRACKING_LIMIT { "backtracking" } else { "single_pass" }
}

/// Compiles `tape` (see the crate docs).
pub fn compile(tape: &Tape) -> Result<Compiled, JitError> {
    let (inputs, constants, instrs, outputs) = tape.parts();
    let mut flags = settings::builder();
    flags.set("opt_level", "speed").map_err(error)?;
    flags.set("regalloc_algorithm", register_allocator(instrs.len())).map_err(error)?;
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
    signature.params.push(AbiParam::new(pointer));
    signature.params.push(AbiParam::new(pointer));
    let import = |module: &mut JITModule, name: &str, params: &[types::Type]| {
        let mut s = Signature::new(module.target_config().default_call_conv);
        s.params.extend(params.iter().map(|t| AbiParam::new(*t)));
        s.returns.push(AbiParam::new(types::F64));
        module.declare_function(name, Linkage::Import, &s).map_err(error)
    };
    let unary: Vec<(Unary, cranelift_module::FuncId)> =
        [(Unary::Sin, "mb_sin"), (Unary::Cos, "mb_cos"), (Unary::Tan, "mb_tan"), (Unary::Exp, "mb_exp"), (Unary::Ln, "mb_ln")]
            .into_iter()
            .map(|(u, name)| import(&mut module, name, &[types::F64]).map(|id| (u, id)))
            .collect::<Result<_, _>>()?;
    let powi = import(&mut module, "mb_powi", &[types::F64, types::I32])?;
    let powf = import(&mut module, "mb_powf", &[types::F64, types::F64])?;
    let id = module.declare_function("kernel", Linkage::Local, &signature).map_err(error)?;
    let mut ctx = module.make_context();
    ctx.func.signature = signature;
    let mut fbc = FunctionBuilderContext::new();
    let frontend = module.target_config();
    {
        let mut b = FunctionBuilder::new(&mut ctx.func, &mut fbc);
        let block = b.create_block();
        b.append_block_params_for_function_params(block);
        b.switch_to_block(block);
        b.seal_block(block);
        let (input, output) = (b.block_params(block)[0], b.block_params(block)[1]);
        let flags = MemFlagsData::trusted();
        let unary_refs: Vec<(Unary, cranelift_codegen::ir::FuncRef)> = unary.iter().map(|(u, id)| (*u, module.declare_func_in_func(*id, b.func))).collect();
        let powi_ref = module.declare_func_in_func(powi, b.func);
        let powf_ref = module.declare_func_in_func(powf, b.func);
        let mut regs = Vec::with_capacity(inputs + constants.len() + instrs.len());
        for k in 0..inputs {
            regs.push(b.ins().load(types::F64, flags, input, (8 * k) as i32));
        }
        for c in constants {
            regs.push(b.ins().f64const(*c));
        }
        for ins in instrs {
            let r = |i: u32| regs[i as usize];
            let v = match *ins {
                Instr::Add(x, y) => b.ins().fadd(r(x), r(y)),
                Instr::Sub(x, y) => b.ins().fsub(r(x), r(y)),
                Instr::Mul(x, y) => b.ins().fmul(r(x), r(y)),
                Instr::Div(x, y) => b.ins().fdiv(r(x), r(y)),
                Instr::Neg(x) => b.ins().fneg(r(x)),
                Instr::Call(Unary::Sqrt, x) => b.ins().sqrt(r(x)),
                Instr::Call(Unary::Abs, x) => b.ins().fabs(r(x)),
                Instr::Call(u, x) => {
                    let f = unary_refs.iter().find(|(k, _)| *k == u).expect("every other unary is imported").1;
                    let call = b.ins().call(f, &[r(x)]);
                    b.inst_results(call)[0]
                }
                Instr::Powi(x, n) => {
                    let n = b.ins().iconst(types::I32, i64::from(n));
                    let call = b.ins().call(powi_ref, &[r(x), n]);
                    b.inst_results(call)[0]
                }
                Instr::Powf(x, y) => {
                    let call = b.ins().call(powf_ref, &[r(x), r(y)]);
                    b.inst_results(call)[0]
                }
            };
            regs.push(v);
        }
        for (k, &reg) in outputs.iter().enumerate() {
            b.ins().store(flags, regs[reg as usize], output, (8 * k) as i32);
        }
        b.ins().return_(&[]);
        b.finalize(frontend);
    }
    module.define_function(id, &mut ctx).map_err(error)?;
    module.clear_context(&mut ctx);
    module.finalize_definitions().map_err(error)?;
    let address = module.get_finalized_function(id);
    // SAFETY: the function was built with exactly this signature.
    let code = unsafe { std::mem::transmute::<*const u8, unsafe extern "C" fn(*const f64, *mut f64)>(address) };
    Ok(Compiled { module: Some(module), code, inputs, outputs: outputs.len() })
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
        let tape = Tape::compile(&stmts, &outputs, &Slots::new(&[("t", 1), ("state", 2)])).unwrap();
        let compiled = compile(&tape).expect("this machine's code generator is available");
        for inputs in [[0.3, 0.7, 1.9], [1.0, -2.5, 0.25], [0.0, 0.0, -1.0]] {
            let (mut a, mut b) = ([0.0; 3], [0.0; 3]);
            tape.eval(&inputs, &mut a);
            compiled.run(&inputs, &mut b);
            for (x, y) in a.iter().zip(&b) {
                assert!(x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan()), "{a:?} against {b:?} at {inputs:?}");
            }
        }
        assert_eq!((compiled.inputs(), compiled.outputs()), (3, 3));
    }

    /// A tape longer than `BACKTRACKING_LIMIT` (compiled with the single-pass allocator) gives
    /// the interpreter's numbers to the bit too: a long chain of dependent operations that keeps
    /// many values alive, so that registers spill.
    #[test]
    fn a_tape_past_the_backtracking_limit_gives_the_interpreter_s_numbers() {
        let mut stmts: Vec<syn::Stmt> = vec![syn::parse_quote!(let v0 = state[0];), syn::parse_quote!(let v1 = state[1];)];
        let count = BACKTRACKING_LIMIT / 2 + 100;
        for k in 2..count {
            let (a, b) = (k - 1, k / 2);
            let text = if k % 7 == 0 { format!("let v{k} = f64::sin(v{a}) - v{b};") } else { format!("let v{k} = v{a} * 0.999 + v{b} * 0.001;") };
            stmts.push(syn::parse_str(&text).unwrap());
        }
        let outputs: Vec<syn::Expr> = (count - 40..count).map(|k| syn::parse_str(&format!("v{k} + v{}", k / 3)).unwrap()).collect();
        let tape = Tape::compile(&stmts, &outputs, &Slots::new(&[("state", 2)])).unwrap();
        let (_, _, instrs, _) = tape.parts();
        assert!(instrs.len() > BACKTRACKING_LIMIT, "{} instructions", instrs.len());
        assert_eq!(register_allocator(instrs.len()), "single_pass");
        let compiled = compile(&tape).expect("this machine's code generator is available");
        let inputs = [0.3, -0.7];
        let (mut a, mut b) = (vec![0.0; 40], vec![0.0; 40]);
        tape.eval(&inputs, &mut a);
        compiled.run(&inputs, &mut b);
        assert!(a.iter().all(|x| x.is_finite()));
        assert_eq!(a.iter().map(|x| x.to_bits()).collect::<Vec<_>>(), b.iter().map(|x| x.to_bits()).collect::<Vec<_>>());
    }
}
