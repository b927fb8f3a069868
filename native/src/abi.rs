//! The one interface between the tool and a library the compiled route builds: plain C types
//! only, compiled into both (this file is also written beside the library's sources), so the two
//! sides cannot disagree. Nothing here depends on any crate.

/// An input slice.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct Input {
    pub ptr: *const f64,
    pub len: usize,
}

/// An output slice.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct Output {
    pub ptr: *mut f64,
    pub len: usize,
}

/// A `seam::Failure`, flattened: `kind` says which, the other fields carry its values. `text`
/// points to the failure's name (a condition, an argument, a function), valid until the next
/// call on the same thread.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct Fault {
    pub kind: u32,
    pub t: f64,
    pub value: f64,
    pub bound: f64,
    pub index: usize,
    pub expected: usize,
    pub got: usize,
    pub text: *const u8,
    pub text_len: usize,
}

/// `Fault::kind`: which `seam::Failure` it is.
pub mod fault {
    pub const SINGULAR: u32 = 1;
    pub const NON_FINITE: u32 = 2;
    pub const CONSTRAINT_VIOLATED: u32 = 3;
    pub const DIMENSION: u32 = 4;
    pub const MISSING: u32 = 5;
    pub const SINGULAR_MATRIX: u32 = 6;
}

/// The function a call asks for, and the slices it passes: formulation functions read
/// `inputs = [state, params, g_i]` (`initial_state`: `[q, qdot, params]`), model functions
/// `inputs = [q, qdot, params]`; `outputs` are the function's output arguments in order.
pub mod function {
    pub const RHS: u32 = 0;
    pub const RHS_BAUMGARTE: u32 = 1;
    pub const INITIAL_STATE: u32 = 2;
    pub const VELOCITIES: u32 = 3;
    pub const MATRIX: u32 = 4;
    pub const SINGULAR_MARGIN: u32 = 5;
    pub const JACOBIAN: u32 = 6;
    pub const PARAMETER_JACOBIAN: u32 = 7;
    pub const ENERGY: u32 = 8;
    pub const WORK_RATE: u32 = 9;
    pub const MOMENTA: u32 = 10;
    pub const CONSTRAINT_RESIDUALS: u32 = 11;
    pub const POSITION_RESIDUALS: u32 = 12;
    pub const EVENT_VALUES: u32 = 13;
    pub const EVENT_RESETS: u32 = 14;
}

/// `multibody_call(function, formulation, t, inputs[3], outputs[2], alpha, beta, margin, fault)`:
/// 0 on success, otherwise `fault` is filled in.
pub type CallFn = unsafe extern "C" fn(
    function: u32,
    formulation: usize,
    t: f64,
    inputs: *const Input,
    outputs: *const Output,
    alpha: f64,
    beta: f64,
    margin: *mut f64,
    fault: *mut Fault,
) -> i32;

/// `multibody_formulation(k, len)`: the name of formulation `k` (`len` receives its length), or
/// null past the last one.
pub type FormulationFn = unsafe extern "C" fn(k: usize, len: *mut usize) -> *const u8;

/// The exported names.
pub const CALL_SYMBOL: &str = "multibody_call";
pub const FORMULATION_SYMBOL: &str = "multibody_formulation";
pub const KEY_SYMBOL: &str = "MULTIBODY_LIBRARY_KEY";
