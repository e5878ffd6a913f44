//! The FT-Map file format, version 1 (little-endian):
//!
//! | bytes | content |
//! |---|---|
//! | 8 | magic `FTMAP\0\r\n` |
//! | 4 | format version (u32) |
//! | 4 | header length H (u32) |
//! | H | header, UTF-8 JSON: kind `ftmap`, grid, channels, units, meta |
//! | cells x 7 x 4 | data, f32, cell-major (last grid axis fastest), channels in header order |
//! | 4 | CRC-32 (IEEE) of everything before it |

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::error::{MapError, Result};
use crate::map::{CHANNELS, FtMap, MapMeta, NCH, UNITS};
use crate::task::omega::Grid;

/// First bytes of every FT-Map file.
pub const MAGIC: [u8; 8] = *b"FTMAP\0\r\n";
/// The format version this build writes and reads.
pub const VERSION: u32 = 1;
/// The header's `kind` field.
pub const KIND: &str = "ftmap";

/// The self-describing header of a map file.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Header {
    /// Always [`KIND`].
    pub kind: String,
    /// The grid over Omega.
    pub grid: Grid,
    /// Channel names in storage order.
    pub channels: Vec<String>,
    /// SI unit of each channel.
    pub units: Vec<String>,
    /// What the map was made from.
    pub meta: MapMeta,
    /// `[i, n]` when the file holds only shard i of n (cells of other shards are NaN).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shard: Option<[usize; 2]>,
}

/// Encodes a map into the bytes of a file.
pub fn to_bytes(map: &FtMap) -> Vec<u8> {
    encode(map, None)
}

/// Encodes a map, or shard `[i, n]` of one, into the bytes of a file.
pub fn encode(map: &FtMap, shard: Option<[usize; 2]>) -> Vec<u8> {
    let header = Header {
        kind: KIND.into(),
        grid: map.grid().clone(),
        channels: CHANNELS.iter().map(|s| s.to_string()).collect(),
        units: UNITS.iter().map(|s| s.to_string()).collect(),
        meta: map.meta().clone(),
        shard,
    };
    let json = serde_json::to_vec(&header).expect("header serializes");
    let mut out = Vec::with_capacity(20 + json.len() + map.data().len() * 4);
    out.extend_from_slice(&MAGIC);
    out.extend_from_slice(&VERSION.to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(&json);
    for v in map.data() {
        out.extend_from_slice(&v.to_le_bytes());
    }
    let crc = crc32fast::hash(&out);
    out.extend_from_slice(&crc.to_le_bytes());
    out
}

/// Writes a map file (through a temporary file, so a failed write leaves no half file).
pub fn save(map: &FtMap, path: &Path) -> Result<()> {
    write_bytes(&to_bytes(map), path)
}

/// Writes bytes to `path` through a temporary file beside it, renamed into place: a reader
/// never sees a partial map, and writers of the same path (threads, or processes filling a
/// map cache) each use their own temporary file, the last rename winning.
pub fn write_bytes(bytes: &[u8], path: &Path) -> Result<()> {
    static WRITES: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(MapError::io(path))?;
    }
    let n = WRITES.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let tmp = path.with_extension(format!("ftmap.{}-{n}.partial", std::process::id()));
    std::fs::write(&tmp, bytes).map_err(MapError::io(path))?;
    std::fs::rename(&tmp, path).map_err(|e| {
        std::fs::remove_file(&tmp).ok();
        MapError::io(path)(e)
    })
}

/// Reads a complete map file, refusing foreign, truncated, corrupted, wrong-version and
/// shard files.
pub fn load(path: &Path) -> Result<FtMap> {
    let bytes = std::fs::read(path).map_err(MapError::io(path))?;
    from_bytes(&bytes, path)
}

/// Decodes the bytes of a complete map file; `path` names the file in errors.
pub fn from_bytes(bytes: &[u8], path: &Path) -> Result<FtMap> {
    match decode(bytes, path)? {
        (map, None) => Ok(map),
        (_, Some([i, n])) => Err(MapError::BadHeader {
            path: path.to_owned(),
            reason: format!(
                "this is shard {i} of {n}, not a whole map: merge the shards first (`ftmap merge`)"
            ),
        }),
    }
}

/// Reads a map or shard file: the map and, for a shard, `[i, n]`.
pub fn load_any(path: &Path) -> Result<(FtMap, Option<[usize; 2]>)> {
    let bytes = std::fs::read(path).map_err(MapError::io(path))?;
    decode(&bytes, path)
}

/// Decodes the bytes of a map or shard file.
pub fn decode(bytes: &[u8], path: &Path) -> Result<(FtMap, Option<[usize; 2]>)> {
    let p = || path.to_owned();
    let truncated = |what, expected: usize| MapError::Truncated {
        path: p(),
        what,
        expected: expected as u64,
        got: bytes.len() as u64,
    };
    let head = bytes.get(..MAGIC.len()).unwrap_or(bytes);
    if head != MAGIC.as_slice() {
        if MAGIC.starts_with(head) {
            return Err(truncated("the magic bytes", MAGIC.len()));
        }
        return Err(MapError::NotAMap {
            path: p(),
            found: head.to_vec(),
            expected: MAGIC.to_vec(),
        });
    }
    let u32_at = |at: usize| -> Result<u32> {
        let b = bytes
            .get(at..at + 4)
            .ok_or_else(|| truncated("the fixed header", at + 4))?;
        Ok(u32::from_le_bytes(b.try_into().expect("4 bytes")))
    };
    let version = u32_at(8)?;
    if version != VERSION {
        return Err(MapError::UnsupportedVersion {
            path: p(),
            found: version,
            supported: VERSION,
        });
    }
    let hlen = u32_at(12)? as usize;
    let json = bytes
        .get(16..16 + hlen)
        .ok_or_else(|| truncated("the header", 16 + hlen))?;
    let bad = |reason: String| MapError::BadHeader { path: p(), reason };
    let header: Header = serde_json::from_slice(json).map_err(|e| bad(e.to_string()))?;
    if header.kind != KIND {
        return Err(bad(format!("kind is `{}`, expected `{KIND}`", header.kind)));
    }
    if header.channels != CHANNELS || header.units != UNITS {
        return Err(bad(format!(
            "channels {:?} in units {:?}, this build reads {CHANNELS:?} in {UNITS:?}",
            header.channels, header.units
        )));
    }
    let data_at = 16 + hlen;
    let total = data_at + header.grid.cells() * NCH * 4 + 4;
    if bytes.len() < total {
        return Err(truncated("the data and checksum", total));
    }
    if bytes.len() > total {
        return Err(bad(format!(
            "{} bytes after the checksum",
            bytes.len() - total
        )));
    }
    let stored = u32::from_le_bytes(bytes[total - 4..].try_into().expect("4 bytes"));
    let computed = crc32fast::hash(&bytes[..total - 4]);
    if stored != computed {
        return Err(MapError::Checksum {
            path: p(),
            stored,
            computed,
        });
    }
    let data = bytes[data_at..total - 4]
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes(c.try_into().expect("4 bytes")))
        .collect();
    let map = FtMap::from_data(header.grid, header.meta, data).map_err(|e| bad(e.to_string()))?;
    Ok((map, header.shard))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::map::tests::sample_map;

    fn roundtrip_err(bytes: &[u8]) -> MapError {
        from_bytes(bytes, Path::new("t.ftmap")).expect_err("must be refused")
    }

    #[test]
    fn save_and_load_round_trip() {
        let map = sample_map();
        let dir = std::env::temp_dir().join(format!("ftmap-format-{}", std::process::id()));
        let path = dir.join("m.ftmap");
        save(&map, &path).unwrap();
        assert_eq!(load(&path).unwrap(), map);
        std::fs::remove_dir_all(dir).ok();
    }

    #[test]
    fn every_truncation_is_refused_as_truncated() {
        let bytes = to_bytes(&sample_map());
        for cut in [0, 3, 8, 12, 15, 40, bytes.len() - 5, bytes.len() - 1] {
            match roundtrip_err(&bytes[..cut]) {
                MapError::Truncated { .. } => {}
                e => panic!("cut at {cut}: {e}"),
            }
        }
    }

    #[test]
    fn a_flipped_data_bit_is_a_checksum_error() {
        let mut bytes = to_bytes(&sample_map());
        let at = bytes.len() - 10;
        bytes[at] ^= 0x10;
        assert!(matches!(roundtrip_err(&bytes), MapError::Checksum { .. }));
    }

    #[test]
    fn foreign_and_future_files_are_refused_by_name() {
        let png = b"\x89PNG\r\n\x1a\n0000000000000000";
        assert!(matches!(roundtrip_err(png), MapError::NotAMap { .. }));
        let mut bytes = to_bytes(&sample_map());
        bytes[8] = 2;
        let e = roundtrip_err(&bytes);
        assert!(
            matches!(
                e,
                MapError::UnsupportedVersion {
                    found: 2,
                    supported: 1,
                    ..
                }
            ),
            "{e}"
        );
        let mut extra = to_bytes(&sample_map());
        extra.push(0);
        assert!(matches!(roundtrip_err(&extra), MapError::BadHeader { .. }));
    }

    #[test]
    fn a_header_of_another_kind_is_refused() {
        let mut bytes = to_bytes(&sample_map());
        let at = bytes
            .windows(14)
            .position(|w| w == b"\"kind\":\"ftmap\"")
            .expect("kind in header");
        bytes[at + 11] = b'o';
        let e = roundtrip_err(&bytes);
        assert!(e.to_string().contains("kind is `ftmop`"), "{e}");
    }

    #[test]
    fn concurrent_writers_of_one_path_all_succeed_and_leave_a_whole_map() {
        let dir = std::env::temp_dir().join(format!("ftmap-race-{}", std::process::id()));
        let path = dir.join("m.ftmap");
        let map = sample_map();
        std::thread::scope(|s| {
            for _ in 0..8 {
                s.spawn(|| {
                    for _ in 0..20 {
                        save(&map, &path).expect("every write succeeds");
                    }
                });
            }
        });
        assert_eq!(load(&path).expect("a whole map"), map);
        let left: Vec<_> = std::fs::read_dir(&dir).expect("dir").flatten().collect();
        assert_eq!(left.len(), 1, "temporary files left: {left:?}");
        std::fs::remove_dir_all(&dir).ok();
    }
}
