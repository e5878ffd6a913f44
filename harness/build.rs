//! Emits an rpath to the project's MuJoCo 3.17.0 library (`.deps/mujoco`, or
//! `MUJOCO_DYNAMIC_LINK_DIR` when set) so that the harness binaries and tests run without
//! `LD_LIBRARY_PATH`.

use std::path::PathBuf;

fn main() {
    println!("cargo::rerun-if-env-changed=MUJOCO_DYNAMIC_LINK_DIR");
    let dir = match std::env::var_os("MUJOCO_DYNAMIC_LINK_DIR") {
        Some(d) => PathBuf::from(d),
        None => PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../.deps/mujoco"),
    };
    let dir = dir.canonicalize().unwrap_or(dir);
    // Searched before the system folders that other build scripts add (Debian's
    // libmujoco-dev puts MuJoCo 2.2.2's libmujoco.so there): `-lmujoco` must find 3.17.0.
    println!("cargo::rustc-link-search=native={}", dir.display());
    println!("cargo::rustc-link-arg=-Wl,-rpath,{}", dir.display());
    println!("cargo::rustc-env=HARNESS_MUJOCO_DIR={}", dir.display());
}
