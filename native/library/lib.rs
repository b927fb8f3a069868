//! A model's emitted module as a shared library, written by multibody's compiled route: the
//! module (`module.rs`, exactly as `multibody generate` writes it) behind one C function,
//! `multibody_call`, whose types are `abi.rs`. This file is fixed text, the same for every model.

#![allow(warnings)]

#[path = "module.rs"]
mod module;
mod abi;

use abi::{fault, function, Fault, Input, Output};
use std::cell::RefCell;
use std::sync::OnceLock;

/// The key the library was built under (64 hex digits), checked by the tool when it loads it.
#[unsafe(no_mangle)]
pub static MULTIBODY_LIBRARY_KEY: [u8; 64] = *include_bytes!("key.txt");

fn model() -> &'static seam::Model {
    static MODEL: OnceLock<seam::Model> = OnceLock::new();
    MODEL.get_or_init(module::model)
}

thread_local! {
    /// The text of the last fault on this thread.
    static TEXT: RefCell<String> = const { RefCell::new(String::new()) };
}

unsafe fn input<'a>(inputs: *const Input, k: usize) -> &'a [f64] {
    let i = *inputs.add(k);
    std::slice::from_raw_parts(i.ptr, i.len)
}

unsafe fn output<'a>(outputs: *const Output, k: usize) -> &'a mut [f64] {
    let o = *outputs.add(k);
    std::slice::from_raw_parts_mut(o.ptr, o.len)
}

/// # Safety
/// `inputs` holds 3 and `outputs` 2 valid, non-overlapping slices; `margin` and `fault` are valid.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn multibody_call(
    which: u32,
    formulation: usize,
    t: f64,
    inputs: *const Input,
    outputs: *const Output,
    alpha: f64,
    beta: f64,
    margin: *mut f64,
    out: *mut Fault,
) -> i32 {
    let m = model();
    let (a, b, c) = (input(inputs, 0), input(inputs, 1), input(inputs, 2));
    let result = if which >= function::ENERGY {
        let f = &m.functions;
        let o = output(outputs, 0);
        match which {
            function::ENERGY => f.energy(t, a, b, c, o),
            function::WORK_RATE => f.work_rate(t, a, b, c, o),
            function::MOMENTA => f.momenta(t, a, b, c, o),
            function::CONSTRAINT_RESIDUALS => f.constraint_residuals(t, a, b, c, o),
            function::POSITION_RESIDUALS => f.position_residuals(t, a, b, c, o),
            function::EVENT_VALUES => f.event_values(t, a, b, c, o),
            _ => f.event_resets(t, a, b, c, o),
        }
    } else {
        match m.formulations.get(formulation) {
            None => Err(seam::Failure::Missing { function: "formulation" }),
            Some(form) => {
                let f = &form.functions;
                match which {
                    function::RHS => f.rhs(t, a, b, c, output(outputs, 0)),
                    function::RHS_BAUMGARTE => f.rhs_baumgarte(t, a, b, c, output(outputs, 0), alpha, beta),
                    function::INITIAL_STATE => f.initial_state(t, a, b, c, output(outputs, 0), output(outputs, 1)),
                    function::VELOCITIES => f.velocities(t, a, b, c, output(outputs, 0), output(outputs, 1)),
                    function::MATRIX => f.matrix(t, a, b, c, output(outputs, 0)),
                    function::SINGULAR_MARGIN => f.singular_margin(t, a, b, c).map(|v| *margin = v),
                    function::JACOBIAN => f.jacobian(t, a, b, c, output(outputs, 0), output(outputs, 1)),
                    _ => f.parameter_jacobian(t, a, b, c, output(outputs, 0), output(outputs, 1)),
                }
            }
        }
    };
    let failure = match result {
        Ok(()) => return 0,
        Err(e) => e,
    };
    let mut f = Fault { kind: 0, t: 0.0, value: 0.0, bound: 0.0, index: 0, expected: 0, got: 0, text: std::ptr::null(), text_len: 0 };
    let text: &str = match &failure {
        seam::Failure::Singular { t, condition, value } => {
            (f.kind, f.t, f.value) = (fault::SINGULAR, *t, *value);
            condition
        }
        seam::Failure::SingularMatrix { t, matrix, column } => {
            (f.kind, f.t, f.index) = (fault::SINGULAR_MATRIX, *t, *column);
            matrix
        }
        seam::Failure::NonFinite { t, index } => {
            (f.kind, f.t, f.index) = (fault::NON_FINITE, *t, *index);
            ""
        }
        seam::Failure::ConstraintViolated { constraint, residual, tolerance } => {
            (f.kind, f.value, f.bound) = (fault::CONSTRAINT_VIOLATED, *residual, *tolerance);
            constraint
        }
        seam::Failure::Dimension { argument, expected, got } => {
            (f.kind, f.expected, f.got) = (fault::DIMENSION, *expected, *got);
            argument
        }
        seam::Failure::Missing { function } => {
            f.kind = fault::MISSING;
            function
        }
    };
    TEXT.with(|cell| {
        let mut s = cell.borrow_mut();
        s.clear();
        s.push_str(text);
        (f.text, f.text_len) = (s.as_ptr(), s.len());
    });
    *out = f;
    1
}

/// # Safety
/// `len` is valid.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn multibody_formulation(k: usize, len: *mut usize) -> *const u8 {
    match model().formulations.get(k) {
        Some(f) => {
            let name = f.kind.name();
            *len = name.len();
            name.as_ptr()
        }
        None => std::ptr::null(),
    }
}
