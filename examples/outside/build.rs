//! Generates the acrobot's module into `OUT_DIR`. The builder prints `cargo:rerun-if-changed`
//! for the model itself; the emitted code reaches the seam through the runtime.

fn main() {
    generator::Builder::new()
        .model("models/acrobot.ron")
        .seam_path("runtime::seam")
        .generate()
        .unwrap_or_else(|e| panic!("{e}"));
}
