//! The module behind the seam: the items that describe an emitted module as a
//! `seam::Model`, so that code which picks a model at run time (the runtime, a user's own
//! crate) calls it through slices without knowing it at compile time.
//!
//! Each formulation submodule gets `pub const FORMULATION: seam::Formulation`, the module gets
//! `pub fn model() -> seam::Model`; both adapt slices to the module's fixed-size functions and
//! report a wrong length as `seam::Failure::Dimension`. The seam crate is named by
//! [`super::Options::seam_path`] (`::seam` by default, or a re-export such as `runtime::seam`).

use super::Function;
use super::function::ident;
use proc_macro2::TokenStream;
use quote::quote;

/// `pub use <seam>::Failure;`: the one error type of every emitted function.
pub(super) fn failure_import(seam: &syn::Path) -> TokenStream {
    quote! {
        #[doc = "Why an emitted function could not produce a value (the seam's error type, shared by every module)."]
        pub use #seam::Failure;
    }
}

/// `FORMULATION` of the formulation submodule `name`; `stabilized` when it has
/// `rhs_baumgarte`.
pub(super) fn formulation_const(seam: &syn::Path, kind: seam::FormulationKind, stabilized: bool, jacobian: bool, parameter_jacobian: bool) -> TokenStream {
    let variant = ident(&format!("{kind:?}"));
    let parameter_jacobian = if parameter_jacobian {
        quote! {
            Some(|t, state, params, g_i, dstate, jac| {
                let p = Params::from_values(#seam::array("params", params)?);
                let mut j = [[0.0f64; Params::NAMES.len()]; STATES];
                parameter_jacobian(t, #seam::array("state", state)?, &p, #seam::array("g_i", g_i)?, #seam::array_mut("dstate", dstate)?, &mut j)?;
                #seam::copy_rows(&j, jac)
            })
        }
    } else {
        quote!(None)
    };
    let jacobian = if jacobian {
        quote! {
            Some(|t, state, params, g_i, dstate, jac| {
                let p = Params::from_values(#seam::array("params", params)?);
                let mut j = [[0.0f64; STATES]; STATES];
                jacobian(t, #seam::array("state", state)?, &p, #seam::array("g_i", g_i)?, #seam::array_mut("dstate", dstate)?, &mut j)?;
                #seam::copy_matrix(&j, jac)
            })
        }
    } else {
        quote!(None)
    };
    let baumgarte = if stabilized {
        quote! {
            Some(|t, state, params, g_i, dstate, alpha, beta| {
                let p = Params::from_values(#seam::array("params", params)?);
                rhs_baumgarte(t, #seam::array("state", state)?, &p, #seam::array("g_i", g_i)?, #seam::array_mut("dstate", dstate)?, alpha, beta)
            })
        }
    } else {
        quote!(None)
    };
    quote! {
        #[doc = "This formulation through slices, for code that picks a model at run time."]
        pub const FORMULATION: #seam::StaticFormulation = #seam::StaticFormulation {
            kind: #seam::FormulationKind::#variant,
            coordinates: &STATE_COORDINATES,
            speeds: SPEEDS,
            work: HAS_WORK_STATE,
            equations: EQUATIONS,
            depends_on_time: DEPENDS_ON_TIME,
            state_names: &STATE_NAMES,
            rhs: |t, state, params, g_i, dstate| {
                let p = Params::from_values(#seam::array("params", params)?);
                rhs(t, #seam::array("state", state)?, &p, #seam::array("g_i", g_i)?, #seam::array_mut("dstate", dstate)?)
            },
            rhs_baumgarte: #baumgarte,
            initial_state: |t, q, qdot, params, state, g_i| {
                let p = Params::from_values(#seam::array("params", params)?);
                let (s, g) = initial_state(t, #seam::array("q", q)?, #seam::array("qdot", qdot)?, &p)?;
                *#seam::array_mut::<STATES>("state", state)? = s;
                *#seam::array_mut::<NUM_IGNORABLE>("g_i", g_i)? = g;
                Ok(())
            },
            velocities: |t, state, params, g_i, q, qdot| {
                let p = Params::from_values(#seam::array("params", params)?);
                let (a, b) = velocities(t, #seam::array("state", state)?, &p, #seam::array("g_i", g_i)?)?;
                *#seam::array_mut::<NUM_COORDINATES>("q", q)? = a;
                *#seam::array_mut::<NUM_COORDINATES>("qdot", qdot)? = b;
                Ok(())
            },
            matrix_size: MATRIX_SIZE,
            matrix: |t, state, params, g_i, out| {
                let p = Params::from_values(#seam::array("params", params)?);
                #seam::copy_matrix(&matrix(t, #seam::array("state", state)?, &p, #seam::array("g_i", g_i)?), out)
            },
            singular_margin: |t, state, params, g_i| {
                let p = Params::from_values(#seam::array("params", params)?);
                Ok(singular_margin(t, #seam::array("state", state)?, &p, #seam::array("g_i", g_i)?))
            },
            jacobian: #jacobian,
            parameter_jacobian: #parameter_jacobian,
        };
    }
}

/// What the module was emitted with, as [`model_fn`] needs it.
pub(super) struct SeamParts<'a> {
    pub seam: &'a syn::Path,
    /// The name the module is emitted under.
    pub module: &'a str,
    pub formulations: Vec<String>,
    pub functions: &'a [Function],
    pub has_initial: bool,
    pub has_run: bool,
    pub has_events: bool,
    pub has_gimbals: bool,
    pub has_inputs: bool,
}

/// `FORMULATIONS` and `pub fn model() -> seam::Model`.
pub(super) fn model_fn(parts: &SeamParts) -> TokenStream {
    let seam = parts.seam;
    let module = parts.module;
    let forms: Vec<proc_macro2::Ident> = parts.formulations.iter().map(|f| ident(f)).collect();
    let nf = super::syntax::usize_lit(forms.len());
    let initial = if parts.has_initial { quote!(Some((&INITIAL_Q, &INITIAL_QDOT))) } else { quote!(None) };
    let run = if parts.has_run { quote!(Some((T_START, T_END, DT_OUT))) } else { quote!(None) };
    let has = |f: Function| parts.functions.contains(&f);
    let mut fields = Vec::new();
    if has(Function::Energy) {
        fields.push(quote! {
            energy: |t, q, qdot, params, out| {
                let p = Params::from_values(#seam::array("params", params)?);
                #seam::array_mut::<1>("out", out)?[0] = energy(t, #seam::array("q", q)?, #seam::array("qdot", qdot)?, &p);
                Ok(())
            },
        });
    }
    if has(Function::WorkRate) {
        fields.push(quote! {
            work_rate: |t, q, qdot, params, out| {
                let p = Params::from_values(#seam::array("params", params)?);
                #seam::array_mut::<1>("out", out)?[0] = work_rate(t, #seam::array("q", q)?, #seam::array("qdot", qdot)?, &p);
                Ok(())
            },
        });
    }
    if has(Function::Momenta) {
        fields.push(quote! {
            momenta: |t, q, qdot, params, out| {
                let p = Params::from_values(#seam::array("params", params)?);
                *#seam::array_mut::<NUM_IGNORABLE>("out", out)? = momenta(t, #seam::array("q", q)?, #seam::array("qdot", qdot)?, &p);
                Ok(())
            },
        });
    }
    if has(Function::Constraints) {
        fields.push(quote! {
            constraint_residuals: |t, q, qdot, params, out| {
                let p = Params::from_values(#seam::array("params", params)?);
                *#seam::array_mut::<NUM_CONSTRAINTS>("out", out)? = constraint_residuals(t, #seam::array("q", q)?, #seam::array("qdot", qdot)?, &p);
                Ok(())
            },
            position_residuals: |t, q, _qdot, params, out| {
                let p = Params::from_values(#seam::array("params", params)?);
                *#seam::array_mut::<NUM_HOLONOMIC>("out", out)? = position_residuals(t, #seam::array("q", q)?, &p);
                Ok(())
            },
        });
    }
    if parts.has_inputs {
        fields.push(quote!(inputs: &INPUTS,));
    }
    if parts.has_gimbals {
        fields.push(quote!(gimbals: &GIMBALS,));
    }
    if parts.has_events {
        fields.push(quote! {
            events: &EVENTS,
            event_values: |t, q, qdot, params, out| {
                let p = Params::from_values(#seam::array("params", params)?);
                *#seam::array_mut::<NUM_EVENTS>("out", out)? = event_values(t, #seam::array("q", q)?, #seam::array("qdot", qdot)?, &p);
                Ok(())
            },
            event_resets: |t, q, qdot, params, out| {
                let p = Params::from_values(#seam::array("params", params)?);
                *#seam::array_mut("out", out)? = event_resets(t, #seam::array("q", q)?, #seam::array("qdot", qdot)?, &p);
                Ok(())
            },
        });
    }
    // The fields not written (functions left out of the module, events it does not have) are
    // the empty model's, which fail with `Failure::Missing`.
    let rest = quote!(..#seam::StaticModel::EMPTY);
    quote! {
        #[doc = "Every emitted formulation through slices."]
        pub const FORMULATIONS: [#seam::StaticFormulation; #nf] = [#(#forms::FORMULATION),*];
        #[doc = "This module as a `seam::Model`: sizes, names, parameter values and every function through slices (a function left out of the module fails with `Failure::Missing`)."]
        pub fn model() -> #seam::Model {
            #seam::Model::from(#seam::StaticModel {
                module: #module,
                name: MODEL,
                coordinates: &COORDINATES,
                constraints: &CONSTRAINTS,
                ignorable: &IGNORABLE,
                holonomic: NUM_HOLONOMIC,
                parameter_names: &Params::NAMES,
                default_params: &DEFAULT_PARAMS,
                initial: #initial,
                run: #run,
                paper_settings: PAPER_SETTINGS,
                energy_balance: ENERGY_BALANCE,
                #(#fields)*
                formulations: &FORMULATIONS,
                #rest
            })
        }
    }
}
