//! Generates the module of `models/cart_pendulum.ron` into `OUT_DIR`, as prost-build does for
//! `.proto` files.

fn main() {
    let model = concat!(env!("CARGO_MANIFEST_DIR"), "/../../models/cart_pendulum.ron");
    let out = std::path::Path::new(&std::env::var("OUT_DIR").expect("cargo sets OUT_DIR")).join("cart_pendulum.rs");
    if let Err(e) = generator::emit::write_module(model, &out) {
        // The error names the file, the place and the fix.
        panic!("{e}");
    }
    println!("cargo:rerun-if-changed={model}");
}
