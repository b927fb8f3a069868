//! `linearize MODEL [--formulation F] [--q NAME=V].. [--qdot NAME=V].. [--param NAME=V]..
//! [--sweep NAME --from A --to B [--steps N] [--out DIR]]`: the linear model of a formulation
//! about an operating point and its eigenvalues, or their sweep over one parameter or rate
//! (CSV, JSON, SVG). MODEL is a model file or a name in `models/` (see `runtime::driver`).

fn main() -> std::process::ExitCode {
    runtime::driver::main(runtime::driver::Tool::Linearize)
}
