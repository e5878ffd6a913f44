//! What a Rust test does when something it needs is missing (a Vulkan adapter, the packaged
//! FMU, Debian's MuJoCo 2.2.2): under CI (`CI=true`) it fails, so that a green run means the
//! test ran; elsewhere it says what is missing and how to get it, and is skipped.
//! Test crates include this file with `#[path]`.

/// Fails under `CI=true`, else prints that the test is skipped; the caller then returns.
pub fn missing(what: &str, fix: &str) {
    let ci = std::env::var("CI").is_ok_and(|v| v == "true");
    assert!(
        !ci,
        "{what} ({fix}); under CI=true a missing prerequisite fails the test"
    );
    eprintln!("skipped: {what} ({fix})");
}
