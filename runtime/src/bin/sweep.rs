//! `sweep MODEL [--out DIR] [--repeats N] [--quick] [--formulations LIST]`: the work-precision
//! sweep of a model, written as CSV, JSON and an SVG diagram; progress on stderr. MODEL is a
//! model file or a name in `models/` (see `runtime::driver`).

fn main() -> std::process::ExitCode {
    runtime::driver::main(runtime::driver::Tool::Sweep)
}
