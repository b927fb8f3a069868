//! `cargo run --release`: the acrobot's comparison table.

fn main() -> std::process::ExitCode {
    match outside::comparison() {
        Ok(table) => {
            print!("{table}");
            std::process::ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}
