//! Generates `models/gantry_crane.ron` into `OUT_DIR`, as prost-build does for `.proto` files.
//! The builder prints `cargo:rerun-if-changed` itself; the emitted code names the seam through
//! the runtime (`runtime::seam`), so this crate depends on the runtime only.

fn main() {
    generator::Builder::new()
        .model("models/gantry_crane.ron")
        .seam_path("runtime::seam")
        .generate()
        // The error names the file, the line and column, the place in the model and the fix.
        .unwrap_or_else(|e| panic!("{e}"));
}
