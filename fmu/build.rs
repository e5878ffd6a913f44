//! Hides `fmi-sys`'s `callback_log` symbol from the cdylib's exports, so that the shared
//! library exports only the 34 `fmi2*` functions.

fn main() {
    let script = std::path::Path::new(&std::env::var("CARGO_MANIFEST_DIR").expect("set by cargo"))
        .join("exports.map");
    println!("cargo::rerun-if-changed={}", script.display());
    println!(
        "cargo::rustc-cdylib-link-arg=-Wl,--version-script={}",
        script.display()
    );
}
