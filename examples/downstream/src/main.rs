//! `cargo run --release --manifest-path examples/downstream/Cargo.toml`: the comparison table of the crate's own model.

fn main() -> std::process::ExitCode {
    match downstream::comparison(5) {
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
