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
/// The largest header a map file may have (bytes).
pub const MAX_HEADER: u32 = 1 << 20;
/// The largest map file this build reads (bytes): 16 GiB, 600 million cells.
pub const MAX_FILE: u64 = 16 << 30;
/// The largest magnitude of a map value and of a grid coordinate: beyond it a force (N),
/// torque (N.m), depth (m) or coordinate (m, rad) is a corrupt file, not a measurement.
pub const MAX_VALUE: f64 = 1.0e6;

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

impl Header {
    /// Checks every value a reader relies on; the field and the problem if one is wrong.
    pub fn check(&self) -> std::result::Result<(), String> {
        let bounded = |name: &str, v: f64| {
            if v.is_finite() && v.abs() <= MAX_VALUE {
                Ok(())
            } else {
                Err(format!(
                    "{name} = {v} is not a finite value within ±{MAX_VALUE}"
                ))
            }
        };
        if self.grid.ndim() == 0 {
            return Err("grid.axes is empty: a map needs at least one uncertain DOF".into());
        }
        for a in self.grid.axes() {
            bounded(&format!("grid axis {} min", a.dof), a.min)?;
            bounded(
                &format!("grid axis {} max (min + step x (count - 1))", a.dof),
                a.max(),
            )?;
        }
        let m = &self.meta;
        for (k, &v) in m.approach.iter().enumerate() {
            bounded(&format!("meta.approach[{k}]"), v)?;
        }
        let norm = m.approach.iter().map(|v| v * v).sum::<f64>().sqrt();
        if (norm - 1.0).abs() > 1e-6 {
            return Err(format!("meta.approach has length {norm}, not 1"));
        }
        for (k, &v) in m.sensor_origin.iter().enumerate() {
            bounded(&format!("meta.sensor_origin[{k}]"), v)?;
        }
        let positive = |name: &str, v: f64, zero_ok: bool| {
            bounded(name, v)?;
            if v > 0.0 || (zero_ok && v == 0.0) {
                Ok(())
            } else {
                Err(format!(
                    "{name} = {v} must be {}",
                    if zero_ok { ">= 0" } else { "> 0" }
                ))
            }
        };
        positive("meta.force", m.force, false)?;
        positive("meta.friction", m.friction, true)?;
        positive("meta.pixel", m.pixel, true)?;
        if let Some(c) = m.clearance {
            positive("meta.clearance", c, true)?;
        }
        for (k, &p) in m.play.iter().flatten().enumerate() {
            let name = format!("meta.play[{k}]");
            positive(&name, p, true)?;
            if p > std::f64::consts::PI {
                return Err(format!("{name} = {p} rad is more than a half turn"));
            }
        }
        match self.shard {
            Some([i, n]) if n == 0 || i >= n => Err(format!(
                "shard [{i}, {n}]: shard i of n needs n >= 1 and i < n"
            )),
            _ => Ok(()),
        }
    }
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
    whole(load_any(path)?, path)
}

/// Decodes the bytes of a complete map file; `path` names the file in errors.
pub fn from_bytes(bytes: &[u8], path: &Path) -> Result<FtMap> {
    whole(decode(bytes, path)?, path)
}

/// The map of a decoded file, refusing a shard.
fn whole(decoded: (FtMap, Option<[usize; 2]>), path: &Path) -> Result<FtMap> {
    match decoded {
        (map, None) => Ok(map),
        (_, Some([i, n])) => Err(MapError::BadHeader {
            path: path.to_owned(),
            reason: format!(
                "this is shard {i} of {n}, not a whole map: merge the shards first (`ftmap merge`)"
            ),
        }),
    }
}

/// Reads a map or shard file: the map and, for a shard, `[i, n]`. Only a regular file is
/// read, and only as many bytes as its header says it holds (checked against its size
/// before the data is read).
pub fn load_any(path: &Path) -> Result<(FtMap, Option<[usize; 2]>)> {
    let (mut file, size) = crate::file::open_regular(path)?;
    if size > MAX_FILE {
        return Err(MapError::TooLarge {
            path: path.to_owned(),
            size,
            max: MAX_FILE,
            what: "an FT-Map file",
        });
    }
    let mut bytes = Vec::new();
    crate::file::read_more(&mut file, path, size.min(16), &mut bytes)?;
    let hlen = match bytes.get(12..16) {
        Some(b) => u64::from(u32::from_le_bytes(b.try_into().expect("4 bytes"))),
        None => return decode(&bytes, path),
    };
    let hlen = hlen.min(u64::from(MAX_HEADER) + 1).min(size - 16);
    crate::file::read_more(&mut file, path, hlen, &mut bytes)?;
    let (header, data_at, total) = prefix(&bytes, path, size)?;
    crate::file::read_more(&mut file, path, total - data_at as u64, &mut bytes)?;
    body(&bytes, path, header, data_at)
}

/// Checks the fixed header and the JSON header at the start of `bytes` (a file of `size`
/// bytes): the header, where the data starts and the file's whole length by the header.
fn prefix(bytes: &[u8], path: &Path, size: u64) -> Result<(Header, usize, u64)> {
    let p = || path.to_owned();
    let truncated = |what, expected: u64| MapError::Truncated {
        path: p(),
        what,
        expected,
        got: size,
    };
    let head = bytes.get(..MAGIC.len()).unwrap_or(bytes);
    if head != MAGIC.as_slice() {
        if MAGIC.starts_with(head) {
            return Err(truncated("the magic bytes", MAGIC.len() as u64));
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
            .ok_or_else(|| truncated("the fixed header", at as u64 + 4))?;
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
    let bad = |reason: String| MapError::BadHeader { path: p(), reason };
    let hlen = u32_at(12)?;
    if hlen > MAX_HEADER {
        return Err(bad(format!(
            "header length {hlen} bytes, at most {MAX_HEADER}"
        )));
    }
    let hlen = hlen as usize;
    let json = bytes
        .get(16..16 + hlen)
        .ok_or_else(|| truncated("the header", 16 + hlen as u64))?;
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
    header.check().map_err(bad)?;
    let data_at = 16 + hlen;
    let total = (header.grid.cells() as u64)
        .checked_mul((NCH * 4) as u64)
        .and_then(|d| d.checked_add(data_at as u64 + 4))
        .filter(|&t| t <= MAX_FILE)
        .ok_or_else(|| {
            bad(format!(
                "{} cells are more than a map file may hold ({MAX_FILE} bytes)",
                header.grid.cells()
            ))
        })?;
    if size < total {
        return Err(truncated("the data and checksum", total));
    }
    if size > total {
        return Err(bad(format!("{} bytes after the checksum", size - total)));
    }
    Ok((header, data_at, total))
}

/// Decodes the bytes of a map or shard file.
pub fn decode(bytes: &[u8], path: &Path) -> Result<(FtMap, Option<[usize; 2]>)> {
    let (header, data_at, _) = prefix(bytes, path, bytes.len() as u64)?;
    body(bytes, path, header, data_at)
}

/// The checksum and the data of a whole file's `bytes` whose prefix (`header`, data from
/// `data_at`) [`prefix`] has checked against their length.
fn body(
    bytes: &[u8],
    path: &Path,
    header: Header,
    data_at: usize,
) -> Result<(FtMap, Option<[usize; 2]>)> {
    let total = bytes.len();
    let p = || path.to_owned();
    let bad = |reason: String| MapError::BadHeader { path: p(), reason };
    let stored = u32::from_le_bytes(bytes[total - 4..].try_into().expect("4 bytes"));
    let computed = crc32fast::hash(&bytes[..total - 4]);
    if stored != computed {
        return Err(MapError::Checksum {
            path: p(),
            stored,
            computed,
        });
    }
    let data: Vec<f32> = bytes[data_at..total - 4]
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes(c.try_into().expect("4 bytes")))
        .collect();
    // A shard holds NaN in the cells of other shards; a whole map holds none.
    if let Some(i) = data.iter().position(|&v| {
        if v.is_nan() {
            header.shard.is_none()
        } else {
            f64::from(v).abs() > MAX_VALUE
        }
    }) {
        return Err(MapError::BadData {
            path: p(),
            cell: i / NCH,
            channel: CHANNELS[i % NCH],
            value: data[i],
            max: MAX_VALUE,
        });
    }
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

    /// The file bytes of the sample map with its JSON header edited by `edit` (the CRC
    /// recomputed, so that only the header's values can be refused).
    fn with_header(edit: impl FnOnce(&mut serde_json::Value)) -> Vec<u8> {
        let bytes = to_bytes(&sample_map());
        let hlen = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
        let mut header: serde_json::Value = serde_json::from_slice(&bytes[16..16 + hlen]).unwrap();
        edit(&mut header);
        let json = serde_json::to_vec(&header).unwrap();
        let mut out = bytes[..12].to_vec();
        out.extend_from_slice(&(json.len() as u32).to_le_bytes());
        out.extend_from_slice(&json);
        out.extend_from_slice(&bytes[16 + hlen..bytes.len() - 4]);
        let crc = crc32fast::hash(&out);
        out.extend_from_slice(&crc.to_le_bytes());
        out
    }

    #[test]
    fn a_cell_count_that_overflows_the_size_is_refused_by_the_header() {
        // One axis of 2^60 cells: 2^60 x 28 bytes wraps a u64. With 20 bytes of data.
        let bytes = with_header(|h| {
            h["grid"]["axes"] = serde_json::json!([{
                "dof": "object.x", "min": 0.0, "step": 1e-16, "count": 1u64 << 60
            }]);
        });
        let e = roundtrip_err(&bytes);
        assert!(
            matches!(&e, MapError::BadHeader { reason, .. } if reason.contains("more than a map file may hold")),
            "{e}"
        );
    }

    #[test]
    fn degenerate_header_values_are_refused_by_field() {
        type Edit = fn(&mut serde_json::Value);
        let cases: [(Edit, &str); 9] = [
            (
                |h| h["grid"]["axes"][0]["step"] = 1e308.into(),
                "max (min + step",
            ),
            (|h| h["grid"]["axes"][0]["min"] = (-1e7).into(), "grid axis"),
            (
                |h| h["grid"]["axes"] = serde_json::json!([]),
                "grid.axes is empty",
            ),
            (
                |h| h["meta"]["approach"] = serde_json::json!([1e308, 0.0, 0.0]),
                "meta.approach[0]",
            ),
            (
                |h| h["meta"]["approach"] = serde_json::json!([0.0, 0.0, -2.0]),
                "length 2",
            ),
            (
                |h| h["meta"]["force"] = 0.0.into(),
                "meta.force = 0 must be > 0",
            ),
            (|h| h["shard"] = serde_json::json!([5, 2]), "shard [5, 2]"),
            (
                |h| h["meta"]["play"] = serde_json::json!([0.005, -0.005, 0.0]),
                "meta.play[1] = -0.005 must be >= 0",
            ),
            (
                |h| h["meta"]["play"] = serde_json::json!([0.0, 0.0, 7.0]),
                "meta.play[2] = 7 rad is more than a half turn",
            ),
        ];
        for (edit, want) in cases {
            let e = roundtrip_err(&with_header(edit));
            assert!(e.to_string().contains(want), "want `{want}`: {e}");
        }
        let e = roundtrip_err(&with_header(|h| h["shard"] = serde_json::json!([0, 0])));
        assert!(e.to_string().contains("shard [0, 0]"), "{e}");
    }

    #[test]
    fn nan_and_absurd_cells_are_refused_by_cell_and_channel() {
        for (bad, at) in [(f32::NAN, 9), (f32::MAX, 3), (-2e6, 13)] {
            let mut map = sample_map();
            map.cell_mut(at / NCH)[at % NCH] = bad;
            match roundtrip_err(&to_bytes(&map)) {
                MapError::BadData { cell, channel, .. } => {
                    assert_eq!((cell, channel), (at / NCH, CHANNELS[at % NCH]));
                }
                e => panic!("{bad}: {e}"),
            }
        }
    }

    #[test]
    fn devices_and_fifos_are_refused_before_reading() {
        let e = load(Path::new("/dev/zero")).expect_err("a device");
        assert!(matches!(e, MapError::NotAFile { .. }), "{e}");
        let e = load(Path::new("/dev/urandom")).expect_err("a device");
        assert!(e.to_string().contains("not a regular file"), "{e}");
    }

    #[test]
    fn a_file_is_read_only_as_far_as_its_header_says() {
        // A valid prefix claiming more data than the file has: refused by the size check,
        // not after reading; and the whole map loads from a file.
        let dir = std::env::temp_dir().join(format!("ftmap-prefix-{}", std::process::id()));
        let path = dir.join("m.ftmap");
        let bytes = to_bytes(&sample_map());
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(&path, &bytes[..bytes.len() - 9]).unwrap();
        match load(&path).expect_err("truncated") {
            MapError::Truncated { what, .. } => assert_eq!(what, "the data and checksum"),
            e => panic!("{e}"),
        }
        std::fs::write(&path, &bytes).unwrap();
        assert_eq!(load(&path).unwrap(), sample_map());
        std::fs::remove_dir_all(&dir).ok();
    }
}
