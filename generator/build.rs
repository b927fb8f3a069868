//! Tells the library its own optimization level, so that `Builder` can warn a build script
//! that runs it unoptimized (cargo's default for build dependencies).

fn main() {
    println!("cargo:rustc-env=GENERATOR_OPT_LEVEL={}", std::env::var("OPT_LEVEL").unwrap_or_default());
    println!("cargo:rerun-if-changed=build.rs");
}
