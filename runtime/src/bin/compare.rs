//! `compare MODEL [options]`: every formulation of a model under the same integrator settings,
//! as a table shaped like the paper's Tables 2, 3 and 6. MODEL is a model file or a name in
//! `models/`; the model runs as compiled, optimized code (see `runtime::driver`).

fn main() -> std::process::ExitCode {
    runtime::driver::main(runtime::driver::Tool::Compare)
}
