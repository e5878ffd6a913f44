//! What the project's command-line tools share about their process and arguments.

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

/// A shard `I/N` on the command line (`0/4`): shard I of N, N >= 1 and 0 <= I < N.
///
/// # Errors
/// When the text is not two such whole numbers.
pub fn parse_shard(s: &str) -> Result<[usize; 2], String> {
    let (i, n) = s.split_once('/').ok_or("expected I/N, e.g. 0/4")?;
    let (i, n) = (
        i.parse::<usize>().map_err(|e| e.to_string())?,
        n.parse::<usize>().map_err(|e| e.to_string())?,
    );
    if n == 0 || i >= n {
        return Err(format!("shard {i}/{n}: need N >= 1 and 0 <= I < N"));
    }
    Ok([i, n])
}
