//! Regenerates the STL meshes of every task under `models_mjcf/` that has a `[geometry]`
//! table (or of the tasks named on the command line) and prints the files written:
//! `cargo run -p ftmap --example write_cad [task ...]`.

use anyhow::Context;
use ftmap::cad;
use ftmap::task::models_root;

fn main() -> anyhow::Result<()> {
    let root = models_root();
    let named: Vec<String> = std::env::args().skip(1).collect();
    let dirs = if named.is_empty() {
        cad::task_dirs_with_geometry(&root)?
    } else {
        named.iter().map(|n| root.join(n)).collect()
    };
    for dir in dirs {
        let written = cad::write_task_meshes(&dir)
            .with_context(|| format!("generating the meshes of {}", dir.display()))?;
        for path in written {
            println!("{}", path.display());
        }
    }
    Ok(())
}
