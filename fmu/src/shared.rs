//! Maps shared between instances: every instance that loads the same map file (the same
//! file, unchanged since) uses one read-only copy of it, prepared once. A copy lives while
//! an instance uses it.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, Weak};
use std::time::SystemTime;

use crate::error::{FusionError, Result};
use crate::filter::Lookup;

/// What identifies a file's contents without reading it: device, inode, size, mtime.
type Stamp = (u64, u64, u64, Option<SystemTime>);

/// The prepared maps by canonical path, with the stamp of the file each was read from.
type Table = HashMap<PathBuf, (Stamp, Weak<Lookup>)>;

/// The maps some instance holds (or held: entries whose map was freed are dropped).
static MAPS: Mutex<Option<Table>> = Mutex::new(None);

/// The prepared map of the file `path`: the copy another instance holds when the file is
/// unchanged since it was read, else read now (and kept for the next instance).
///
/// # Errors
/// As the map loader, and [`Lookup::new`].
pub fn map(path: &Path) -> Result<Arc<Lookup>> {
    use std::os::unix::fs::MetadataExt;
    let file_err = |e: std::io::Error| FusionError::MapFile(ftmap::MapError::io(path)(e));
    let canonical = path.canonicalize().map_err(file_err)?;
    let m = std::fs::metadata(&canonical).map_err(file_err)?;
    let stamp = (m.dev(), m.ino(), m.len(), m.modified().ok());
    // A panic elsewhere while holding the lock leaves the map table whole: go on with it.
    let mut maps = MAPS.lock().unwrap_or_else(|e| e.into_inner());
    let maps = maps.get_or_insert_with(HashMap::new);
    maps.retain(|_, (_, weak)| weak.strong_count() > 0);
    if let Some((s, weak)) = maps.get(&canonical)
        && *s == stamp
        && let Some(lookup) = weak.upgrade()
    {
        return Ok(lookup);
    }
    let map = ftmap::map::format::load(path).map_err(FusionError::MapFile)?;
    let lookup = Arc::new(Lookup::new(&map, path)?);
    maps.insert(canonical, (stamp, Arc::downgrade(&lookup)));
    Ok(lookup)
}

/// Drops the table once no instance holds a map: an FMU unloaded after its last instance
/// was freed leaves no allocation behind.
pub fn release_unused() {
    let mut maps = MAPS.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(table) = maps.as_mut() {
        table.retain(|_, (_, weak)| weak.strong_count() > 0);
        if table.is_empty() {
            *maps = None;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_file_gives_one_copy_until_it_changes_or_nobody_holds_it() {
        let dir = std::env::temp_dir().join(format!("ftfusion-shared-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("scratch");
        let path = dir.join("m.ftmap");
        let map = ftfusion_testkit::peg_map(2e-3, 5e-4, None).expect("map");
        ftmap::map::format::save(&map, &path).expect("write");
        let a = super::map(&path).expect("loads");
        let b = super::map(&dir.join(".").join("m.ftmap")).expect("loads");
        assert!(Arc::ptr_eq(&a, &b), "the same file, one copy");
        // Rewritten (a new inode): read again.
        ftmap::map::format::save(&map, &path).expect("write");
        let c = super::map(&path).expect("loads");
        assert!(!Arc::ptr_eq(&a, &c));
        drop((a, b, c));
        let gone = MAPS.lock().expect("lock").as_ref().and_then(|m| {
            m.get(&path.canonicalize().expect("path"))
                .map(|(_, w)| w.strong_count())
        });
        assert_eq!(gone, Some(0), "nobody holds it: it is freed");
        std::fs::remove_dir_all(&dir).ok();
    }
}
