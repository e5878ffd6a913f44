//! What the project's command-line tools share about their process.

/// Lets the process end by SIGPIPE, as Unix tools do, when the reader of its output goes
/// away (`ftmap info F | head -1`): Rust's runtime ignores the signal, and printing then
/// panics. Call it first thing in `main`.
pub fn die_quietly_on_broken_pipe() {
    // SAFETY: restoring a signal's default disposition, before any thread is spawned, has
    // no memory effects.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}
