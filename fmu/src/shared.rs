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

/// The prepared maps by canonical path of the map and of its centre map, with the stamps
/// of the files each was read from.
type Table = HashMap<(PathBuf, Option<PathBuf>), (Vec<Stamp>, Weak<Lookup>)>;

/// The maps some instance holds (or held: entries whose map was freed are dropped).
static MAPS: Mutex<Option<Table>> = Mutex::new(None);

/// The prepared map of the file `path`, with the centre map of the file `centre` where
/// given: the copy another instance holds when the files are unchanged since they were
/// read, else read now (and kept for the next instance).
///
/// # Errors
/// As the map loader, [`Lookup::new`] and [`Lookup::with_centre`].
pub fn map(path: &Path, centre: Option<&Path>) -> Result<Arc<Lookup>> {
    let (canonical, stamp) = identify(path)?;
    let (centre_canonical, centre_stamp) = centre.map(identify).transpose()?.unzip();
    let stamps: Vec<Stamp> = std::iter::once(stamp).chain(centre_stamp).collect();
    let key = (canonical, centre_canonical);
    // A panic elsewhere while holding the lock leaves the map table whole: go on with it.
    let mut maps = MAPS.lock().unwrap_or_else(|e| e.into_inner());
    let maps = maps.get_or_insert_with(HashMap::new);
    maps.retain(|_, (_, weak)| weak.strong_count() > 0);
    if let Some((s, weak)) = maps.get(&key)
        && *s == stamps
        && let Some(lookup) = weak.upgrade()
    {
        return Ok(lookup);
    }
    let load = |p: &Path| ftmap::map::format::load(p).map_err(FusionError::MapFile);
    let map = load(path)?;
    let lookup = Arc::new(match centre {
        Some(c) => Lookup::with_centre(&map, path, &load(c)?, c)?,
        None => Lookup::new(&map, path)?,
    });
    maps.insert(key, (stamps, Arc::downgrade(&lookup)));
    Ok(lookup)
}

/// The canonical path of the file `path` and what identifies its contents.
fn identify(path: &Path) -> Result<(PathBuf, Stamp)> {
    use std::os::unix::fs::MetadataExt;
    let file_err = |e: std::io::Error| FusionError::MapFile(ftmap::MapError::io(path)(e));
    let canonical = path.canonicalize().map_err(file_err)?;
    let m = std::fs::metadata(&canonical).map_err(file_err)?;
    Ok((canonical, (m.dev(), m.ino(), m.len(), m.modified().ok())))
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
        let a = super::map(&path, None).expect("loads");
        let b = super::map(&dir.join(".").join("m.ftmap"), None).expect("loads");
        assert!(Arc::ptr_eq(&a, &b), "the same file, one copy");
        // Rewritten (a new inode): read again.
        ftmap::map::format::save(&map, &path).expect("write");
        let c = super::map(&path, None).expect("loads");
        assert!(!Arc::ptr_eq(&a, &c));
        drop((a, b, c));
        let gone = MAPS.lock().expect("lock").as_ref().and_then(|m| {
            m.get(&(path.canonicalize().expect("path"), None))
                .map(|(_, w)| w.strong_count())
        });
        assert_eq!(gone, Some(0), "nobody holds it: it is freed");
        std::fs::remove_dir_all(&dir).ok();
    }
}
