//! Reading the files a user names (maps, vision models): regular files only, opened without
//! blocking, so that a FIFO or a device is refused before a byte is read (reading a FIFO
//! would wait for a writer forever, `/dev/zero` would never end), and never more bytes
//! than the caller allows.

use std::fs::{File, OpenOptions};
use std::io::Read;
use std::os::unix::fs::{FileTypeExt, OpenOptionsExt};
use std::path::Path;

use crate::error::{MapError, Result};

/// Opens `path` for reading if it is a regular file; returns it and its size (bytes).
///
/// # Errors
/// [`MapError::Io`] when it cannot be opened, [`MapError::NotAFile`] when it is not a
/// regular file.
pub fn open_regular(path: &Path) -> Result<(File, u64)> {
    // O_NONBLOCK: opening a FIFO for reading returns at once instead of waiting for a
    // writer; on a regular file it changes nothing.
    let file = OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK)
        .open(path)
        .map_err(MapError::io(path))?;
    let meta = file.metadata().map_err(MapError::io(path))?;
    let t = meta.file_type();
    let kind = if t.is_file() {
        return Ok((file, meta.len()));
    } else if t.is_dir() {
        "a folder"
    } else if t.is_fifo() {
        "a FIFO (named pipe)"
    } else if t.is_char_device() {
        "a character device"
    } else if t.is_block_device() {
        "a block device"
    } else if t.is_socket() {
        "a socket"
    } else {
        "not a file"
    };
    Err(MapError::NotAFile {
        path: path.to_owned(),
        kind,
    })
}

/// Reads exactly `len` more bytes of `file` (`path` names it in errors) onto `out`.
///
/// # Errors
/// [`MapError::Io`], also when the file ends early (it shrank while being read).
pub fn read_more(file: &mut File, path: &Path, len: u64, out: &mut Vec<u8>) -> Result<()> {
    let start = out.len();
    let want = usize::try_from(len).map_err(|_| MapError::TooLarge {
        path: path.to_owned(),
        size: len,
        max: usize::MAX as u64,
        what: "this machine's address space",
    })?;
    out.try_reserve_exact(want)
        .map_err(|e| MapError::io(path)(std::io::Error::new(std::io::ErrorKind::OutOfMemory, e)))?;
    file.take(len)
        .read_to_end(out)
        .map_err(MapError::io(path))?;
    if out.len() - start != want {
        return Err(MapError::io(path)(std::io::Error::new(
            std::io::ErrorKind::UnexpectedEof,
            format!("ended after {} of {len} bytes", out.len() - start),
        )));
    }
    Ok(())
}

/// The whole of the regular file `path`, read as `what`, refused unread above `max` bytes.
///
/// # Errors
/// As [`open_regular`] and [`read_more`]; [`MapError::TooLarge`] above `max`.
pub fn read_regular(path: &Path, max: u64, what: &'static str) -> Result<Vec<u8>> {
    let (mut file, size) = open_regular(path)?;
    if size > max {
        return Err(MapError::TooLarge {
            path: path.to_owned(),
            size,
            max,
            what,
        });
    }
    let mut out = Vec::new();
    read_more(&mut file, path, size, &mut out)?;
    Ok(out)
}

/// The name of a cache entry: the first 8 bytes, in hex, of the SHA-256 of the files `files`
/// (their bytes, in order), the crate's version and `extra` (what else the entry depends
/// on).
///
/// # Errors
/// [`MapError::Io`] when a file cannot be read.
pub fn cache_hash(files: &[&Path], extra: &[&[u8]]) -> Result<String> {
    use sha2::{Digest, Sha256};
    let mut h = Sha256::new();
    for f in files {
        h.update(std::fs::read(f).map_err(MapError::io(f))?);
    }
    h.update(env!("CARGO_PKG_VERSION"));
    for e in extra {
        h.update(e);
    }
    Ok(h.finalize()
        .iter()
        .take(8)
        .map(|b| format!("{b:02x}"))
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fifos_devices_and_folders_are_refused_without_blocking() {
        let dir = std::env::temp_dir().join(format!("ftmap-file-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("scratch");
        let fifo = dir.join("pipe");
        let c = std::ffi::CString::new(fifo.as_os_str().as_encoded_bytes()).expect("path");
        // SAFETY: a valid NUL-terminated path and a mode.
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
        for (path, kind) in [
            (fifo.as_path(), "a FIFO (named pipe)"),
            (Path::new("/dev/zero"), "a character device"),
            (dir.as_path(), "a folder"),
        ] {
            match read_regular(path, 1 << 20, "a test file") {
                Err(MapError::NotAFile { kind: k, .. }) => assert_eq!(k, kind),
                other => panic!("{}: {other:?}", path.display()),
            }
        }
        std::fs::remove_dir_all(dir).ok();
    }

    #[test]
    fn a_file_above_the_limit_is_refused_and_one_within_it_read_whole() {
        let dir = std::env::temp_dir().join(format!("ftmap-file-size-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("scratch");
        let path = dir.join("f");
        std::fs::write(&path, [7u8; 100]).expect("write");
        match read_regular(&path, 99, "a test file") {
            Err(MapError::TooLarge {
                size: 100, max: 99, ..
            }) => {}
            other => panic!("{other:?}"),
        }
        assert_eq!(
            read_regular(&path, 100, "a test file").expect("read"),
            [7u8; 100]
        );
        std::fs::remove_dir_all(dir).ok();
    }
}
