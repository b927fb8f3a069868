//! Slice-based access to every emitted module, for code that picks a model at runtime.

use std::fmt;

/// Why a call failed: the emitted module's own error, or slices of the wrong length.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Failure {
    /// The equations are singular at `t`: `condition` vanishes.
    Singular { t: f64, condition: &'static str, value: f64 },
    /// Output `index` is not finite at `t`.
    NonFinite { t: f64, index: usize },
    /// A state violates `constraint`.
    ConstraintViolated { constraint: &'static str, residual: f64, tolerance: f64 },
    /// A slice argument has the wrong length.
    Dimension { argument: &'static str, expected: usize, got: usize },
}

impl fmt::Display for Failure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Failure::Singular { t, condition, value } => {
                write!(f, "singular configuration at t = {t}: {condition} (value {value:e})")
            }
            Failure::NonFinite { t, index } => write!(f, "non-finite value in output {index} at t = {t}"),
            Failure::ConstraintViolated { constraint, residual, tolerance } => {
                write!(f, "constraint `{constraint}` is violated: residual {residual:e} exceeds {tolerance:e}")
            }
            Failure::Dimension { argument, expected, got } => {
                write!(f, "`{argument}` has {got} entries, {expected} expected")
            }
        }
    }
}

impl std::error::Error for Failure {}

/// `rhs(t, state, params, g_i, dstate)`.
pub type RhsFn = fn(f64, &[f64], &[f64], &[f64], &mut [f64]) -> Result<(), Failure>;
/// `rhs_baumgarte(t, state, params, g_i, dstate, alpha, beta)`.
pub type StabilizedFn = fn(f64, &[f64], &[f64], &[f64], &mut [f64], f64, f64) -> Result<(), Failure>;
/// `matrix(t, state, params, g_i, out)`: the matrix `rhs` solves, row-major.
pub type MatrixFn = fn(f64, &[f64], &[f64], &[f64], &mut [f64]) -> Result<(), Failure>;
/// `singular_margin(t, state, params, g_i)`.
pub type MarginFn = fn(f64, &[f64], &[f64], &[f64]) -> Result<f64, Failure>;
/// `initial_state(t, q, qdot, params, state, g_i)`.
pub type InitialFn = fn(f64, &[f64], &[f64], &[f64], &mut [f64], &mut [f64]) -> Result<(), Failure>;
/// `velocities(t, state, params, g_i, q, qdot)`.
pub type VelocitiesFn = fn(f64, &[f64], &[f64], &[f64], &mut [f64], &mut [f64]) -> Result<(), Failure>;
/// A function of `(t, q, qdot, params)` writing its outputs.
pub type PointFn = fn(f64, &[f64], &[f64], &[f64], &mut [f64]) -> Result<(), Failure>;

/// One formulation of a model.
#[derive(Clone, Copy, Debug)]
pub struct Formulation {
    /// `lagrange`, `maggi`, `kane` or `reduced_volterra`.
    pub name: &'static str,
    pub states: usize,
    pub equations: usize,
    pub integrates_ignorable: bool,
    /// The last state entry is the work integral `W` (Eq. 80).
    pub has_work_state: bool,
    pub state_names: &'static [&'static str],
    pub rhs: RhsFn,
    /// Lagrange only: the Baumgarte-stabilized right-hand side.
    pub rhs_baumgarte: Option<StabilizedFn>,
    pub initial_state: InitialFn,
    pub velocities: VelocitiesFn,
    /// Size of the matrix `rhs` solves numerically.
    pub matrix_size: usize,
    pub matrix: MatrixFn,
    pub singular_margin: MarginFn,
}

/// One emitted model.
#[derive(Clone, Copy, Debug)]
pub struct Model {
    /// The module name (a model name, or a variant such as `cart_pendulum_baked`).
    pub module: &'static str,
    /// The model's own name.
    pub name: &'static str,
    pub coordinates: &'static [&'static str],
    pub constraints: &'static [&'static str],
    pub ignorable: &'static [usize],
    pub holonomic: usize,
    pub parameter_names: &'static [&'static str],
    /// The model's parameter values (empty when baked).
    pub default_params: fn() -> Vec<f64>,
    /// `(q(0), q'(0))` of the reference run.
    pub initial: (&'static [f64], &'static [f64]),
    /// `(t_start, t_end, dt_out)` of the reference run.
    pub run: (f64, f64, f64),
    /// Outputs: 1 value.
    pub energy: PointFn,
    /// Outputs: 1 value.
    pub work_rate: PointFn,
    /// Outputs: one per ignorable coordinate.
    pub momenta: PointFn,
    /// Outputs: one per constraint.
    pub constraint_residuals: PointFn,
    /// Outputs: one per holonomic constraint (`qdot` is ignored).
    pub position_residuals: PointFn,
    pub formulations: &'static [Formulation],
}

impl Model {
    /// The formulation called `name`.
    pub fn formulation(&self, name: &str) -> Option<&'static Formulation> {
        self.formulations.iter().find(|f| f.name == name)
    }
}

fn fixed<'a, const N: usize>(argument: &'static str, s: &'a [f64]) -> Result<&'a [f64; N], Failure> {
    s.try_into().map_err(|_| Failure::Dimension { argument, expected: N, got: s.len() })
}

fn fixed_mut<'a, const N: usize>(argument: &'static str, s: &'a mut [f64]) -> Result<&'a mut [f64; N], Failure> {
    let got = s.len();
    s.try_into().map_err(|_| Failure::Dimension { argument, expected: N, got })
}

macro_rules! failure_from {
    ($m:ident) => {
        impl From<crate::$m::EvalError> for Failure {
            fn from(e: crate::$m::EvalError) -> Failure {
                use crate::$m::EvalError as E;
                match e {
                    E::Singular { t, condition, value } => Failure::Singular { t, condition, value },
                    E::NonFinite { t, index } => Failure::NonFinite { t, index },
                    E::ConstraintViolated { constraint, residual, tolerance } => {
                        Failure::ConstraintViolated { constraint, residual, tolerance }
                    }
                }
            }
        }
    };
}

macro_rules! formulation {
    ($m:ident, lagrange) => {
        Formulation {
            rhs_baumgarte: Some(|t, state, params, g_i, dstate, alpha, beta| {
                let p = crate::$m::Params::from_values(fixed("params", params)?);
                crate::$m::lagrange::rhs_baumgarte(
                    t,
                    fixed("state", state)?,
                    &p,
                    fixed("g_i", g_i)?,
                    fixed_mut("dstate", dstate)?,
                    alpha,
                    beta,
                )?;
                Ok(())
            }),
            ..formulation!(@plain $m, lagrange)
        }
    };
    ($m:ident, $f:ident) => {
        formulation!(@plain $m, $f)
    };
    (@plain $m:ident, $f:ident) => {
        Formulation {
            rhs_baumgarte: None,
            name: stringify!($f),
            states: crate::$m::$f::STATES,
            equations: crate::$m::$f::EQUATIONS,
            integrates_ignorable: crate::$m::$f::INTEGRATES_IGNORABLE,
            has_work_state: crate::$m::$f::HAS_WORK_STATE,
            state_names: &crate::$m::$f::STATE_NAMES,
            rhs: |t, state, params, g_i, dstate| {
                let p = crate::$m::Params::from_values(fixed("params", params)?);
                crate::$m::$f::rhs(t, fixed("state", state)?, &p, fixed("g_i", g_i)?, fixed_mut("dstate", dstate)?)?;
                Ok(())
            },
            initial_state: |t, q, qdot, params, state, g_i| {
                let p = crate::$m::Params::from_values(fixed("params", params)?);
                let (s, g) = crate::$m::$f::initial_state(t, fixed("q", q)?, fixed("qdot", qdot)?, &p)?;
                fixed_mut::<{ crate::$m::$f::STATES }>("state", state)?.copy_from_slice(&s);
                fixed_mut::<{ crate::$m::NUM_IGNORABLE }>("g_i", g_i)?.copy_from_slice(&g);
                Ok(())
            },
            matrix_size: crate::$m::$f::MATRIX_SIZE,
            matrix: |t, state, params, g_i, out| {
                let p = crate::$m::Params::from_values(fixed("params", params)?);
                let a = crate::$m::$f::matrix(t, fixed("state", state)?, &p, fixed("g_i", g_i)?);
                let n = crate::$m::$f::MATRIX_SIZE;
                if out.len() != n * n {
                    return Err(Failure::Dimension { argument: "out", expected: n * n, got: out.len() });
                }
                for (row, chunk) in a.iter().zip(out.chunks_mut(n)) {
                    chunk.copy_from_slice(row);
                }
                Ok(())
            },
            singular_margin: |t, state, params, g_i| {
                let p = crate::$m::Params::from_values(fixed("params", params)?);
                Ok(crate::$m::$f::singular_margin(t, fixed("state", state)?, &p, fixed("g_i", g_i)?))
            },
            velocities: |t, state, params, g_i, q, qdot| {
                let p = crate::$m::Params::from_values(fixed("params", params)?);
                let (a, b) = crate::$m::$f::velocities(t, fixed("state", state)?, &p, fixed("g_i", g_i)?)?;
                fixed_mut::<{ crate::$m::NUM_COORDINATES }>("q", q)?.copy_from_slice(&a);
                fixed_mut::<{ crate::$m::NUM_COORDINATES }>("qdot", qdot)?.copy_from_slice(&b);
                Ok(())
            },
        }
    };
}

macro_rules! point {
    // A scalar function, written as one output.
    ($m:ident, $fun:ident) => {
        |t, q, qdot, params, out| {
            let p = crate::$m::Params::from_values(fixed("params", params)?);
            fixed_mut::<1>("out", out)?[0] = crate::$m::$fun(t, fixed("q", q)?, fixed("qdot", qdot)?, &p);
            Ok(())
        }
    };
    ($m:ident, $fun:ident, $n:expr) => {
        |t, q, qdot, params, out| {
            let p = crate::$m::Params::from_values(fixed("params", params)?);
            let v = crate::$m::$fun(t, fixed("q", q)?, fixed("qdot", qdot)?, &p);
            fixed_mut::<{ $n }>("out", out)?.copy_from_slice(&v);
            Ok(())
        }
    };
}

macro_rules! model {
    ($m:ident, [$($f:ident),*]) => {{
        Model {
            module: stringify!($m),
            name: crate::$m::MODEL,
            coordinates: &crate::$m::COORDINATES,
            constraints: &crate::$m::CONSTRAINTS,
            ignorable: &crate::$m::IGNORABLE,
            holonomic: crate::$m::NUM_HOLONOMIC,
            parameter_names: &crate::$m::Params::NAMES,
            default_params: || crate::$m::Params::default().values().to_vec(),
            initial: (&crate::$m::INITIAL_Q[..], &crate::$m::INITIAL_QDOT[..]),
            run: (crate::$m::T_START, crate::$m::T_END, crate::$m::DT_OUT),
            energy: point!($m, energy),
            work_rate: point!($m, work_rate),
            momenta: point!($m, momenta, crate::$m::NUM_IGNORABLE),
            constraint_residuals: point!($m, constraint_residuals, crate::$m::NUM_CONSTRAINTS),
            position_residuals: |t, q, _qdot, params, out| {
                let p = crate::$m::Params::from_values(fixed("params", params)?);
                let v = crate::$m::position_residuals(t, fixed("q", q)?, &p);
                fixed_mut::<{ crate::$m::NUM_HOLONOMIC }>("out", out)?.copy_from_slice(&v);
                Ok(())
            },
            formulations: &[$(formulation!($m, $f)),*],
        }
    }};
}

failure_from!(cart_pendulum);
failure_from!(three_body);
failure_from!(satellite_boom);
failure_from!(cartesian_pendulum);
failure_from!(rolling_disk);
failure_from!(spring_cart);
failure_from!(pendulum_on_cart_5);
failure_from!(cart_pendulum_baked);
failure_from!(three_body_split);
failure_from!(three_body_drop);

/// Every emitted module.
pub fn models() -> Vec<Model> {
    vec![
        model!(cart_pendulum, [lagrange, maggi, kane, reduced_volterra]),
        model!(three_body, [lagrange, maggi, kane, reduced_volterra]),
        model!(satellite_boom, [lagrange, maggi, kane, reduced_volterra]),
        model!(cartesian_pendulum, [lagrange, maggi, kane, reduced_volterra]),
        model!(rolling_disk, [lagrange, maggi, kane, reduced_volterra]),
        model!(spring_cart, [lagrange, maggi, kane, reduced_volterra]),
        model!(pendulum_on_cart_5, [lagrange, maggi, kane, reduced_volterra]),
        model!(cart_pendulum_baked, [lagrange, maggi, kane, reduced_volterra]),
        model!(three_body_split, [lagrange, maggi, kane, reduced_volterra]),
        model!(three_body_drop, [reduced_volterra]),
    ]
}

/// The module called `module`.
pub fn find(module: &str) -> Option<Model> {
    models().into_iter().find(|m| m.module == module)
}
