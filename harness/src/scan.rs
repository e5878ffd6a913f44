//! Measured FT-Maps (the paper's scanned maps): one contact motion in MuJoCo per cell of
//! Omega, written in the same file format as computed maps (model `Measured`). A task whose
//! Omega turns part B about the approach (`object.rz`) is scanned over its yaw too, the TCP
//! unturned, as the FMU reads a press at a relative yaw.

use std::fmt;
use std::path::PathBuf;

use indicatif::{ProgressBar, ProgressStyle};

use ftmap::{Axis, FtMap, Grid, GridAxis, MapMeta, NCH, SourceMesh, Task, WrenchModel};

use crate::error::{HarnessError, Result, create_parent};
use crate::sensor::map_wrench;
use crate::sim::{Sim, open_task};
use crate::world::World;

/// What the `scan` command measures (SI units).
#[derive(Debug, Clone, PartialEq)]
pub struct ScanOptions {
    /// Task name or task.toml path.
    pub task: String,
    /// Output map file.
    pub out: PathBuf,
    /// Grid step (m).
    pub step: f64,
    /// Half width of the scanned square (m); default: Omega's size_trans.
    pub half_width: Option<f64>,
    /// Yaw step (rad) where Omega holds `object.rz`; default: Omega's delta_rot.
    pub yaw_step: Option<f64>,
    /// Half width of the scanned yaws (rad); default: Omega's size_rot.
    pub yaw_size: Option<f64>,
}

/// The scanned yaws of part B (rad).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Yaw {
    /// Grid step (rad).
    pub step: f64,
    /// Half width (rad).
    pub size: f64,
}

/// A measured map written to a file.
#[derive(Debug, Clone, PartialEq)]
pub struct Scanned {
    /// The map file.
    pub path: PathBuf,
    /// Cells measured.
    pub cells: usize,
    /// Simulated time of all contact motions (s).
    pub simulated: f64,
}

impl fmt::Display for Scanned {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "measured map {} ({} cells, {:.1} s simulated)",
            self.path.display(),
            self.cells,
            self.simulated
        )
    }
}

/// Measures a task's map by contact motions ([`scan`]) and writes it to `options.out`.
///
/// # Errors
/// When the task, its scene or the grid is invalid, or the file cannot be written.
pub fn scan_to_file(options: &ScanOptions) -> Result<Scanned> {
    let (task, mut sim) = open_task(&options.task)?;
    let size = options.half_width.unwrap_or(task.omega.size_trans);
    let yaw = Yaw {
        step: options.yaw_step.unwrap_or(task.omega.delta_rot),
        size: options.yaw_size.unwrap_or(task.omega.size_rot),
    };
    let map = scan(&mut sim, &task, options.step, size, yaw)?;
    create_parent(&options.out)?;
    ftmap::map::format::save(&map, &options.out)?;
    Ok(Scanned {
        path: options.out.clone(),
        cells: map.grid().cells(),
        simulated: sim.simulated(),
    })
}

/// Scans Omega's object translation at `step` over ±`size` (m), and where Omega holds
/// `object.rz`, part B's yaw at `yaw`: for each cell part B is placed at the cell's offset
/// and yaw, and one contact motion is made at the nominal goal with the TCP unturned.
///
/// # Errors
/// When the task's Omega has other DOFs than object.x, object.y and object.rz, or the grid
/// is invalid.
pub fn scan(sim: &mut Sim, task: &Task, step: f64, size: f64, yaw: Yaw) -> Result<FtMap> {
    let dofs = task.dofs()?;
    let names: Vec<String> = dofs.iter().map(|d| d.to_string()).collect();
    if names != ["object.x", "object.y"] && names != ["object.x", "object.y", "object.rz"] {
        return Err(HarnessError::Invalid {
            what: "scan",
            reason: format!(
                "scans object.x, object.y and object.rz only; task {} has {}",
                task.name,
                names.join(", ")
            ),
        });
    }
    let axes = dofs
        .iter()
        .map(|d| match d.axis {
            Axis::Rz => GridAxis::symmetric(*d, yaw.size, yaw.step),
            _ => GridAxis::symmetric(*d, size, step),
        })
        .collect::<ftmap::Result<Vec<_>>>()?;
    let grid = Grid::new(axes)?;
    let mut map = FtMap::zeros(grid.clone(), meta(task)?);
    let bar = ProgressBar::new(grid.cells() as u64);
    bar.set_style(
        ProgressStyle::with_template("scan [{bar:30}] {pos}/{len} contacts ({elapsed}, eta {eta})")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
    );
    sim.set_tcp_rotation([0.0; 3])?;
    for cell in 0..grid.cells() {
        let c = grid.coords(cell);
        sim.set_object([c[0], c[1]]);
        sim.set_object_rotation([0.0, 0.0, c.get(2).copied().unwrap_or(0.0)])?;
        let contact = sim.contact_motion([0.0, 0.0]);
        let w = map_wrench(contact.raw);
        let out = map.cell_mut(cell);
        for k in 0..6 {
            out[k] = w[k] as f32;
        }
        out[NCH - 1] = contact.tcp[2] as f32;
        bar.inc(1);
    }
    bar.finish();
    Ok(map)
}

fn meta(task: &Task) -> Result<MapMeta> {
    let source = |role: &str, part: &ftmap::task::Part| -> Result<SourceMesh> {
        Ok(SourceMesh {
            role: role.into(),
            file: part
                .mesh
                .file_name()
                .map(|f| f.to_string_lossy().into_owned())
                .unwrap_or_default(),
            sha256: part.load()?.sha256,
        })
    };
    Ok(MapMeta {
        task: task.name.clone(),
        model: WrenchModel::Measured,
        approach: task.contact.approach,
        force: task.contact.force,
        friction: task.contact.friction,
        sensor_origin: task.contact.sensor_origin,
        pixel: 0.0,
        sources: vec![source("A", &task.part_a)?, source("B", &task.part_b)?],
        generator: format!(
            "harness {} scan (MuJoCo {})",
            env!("CARGO_PKG_VERSION"),
            mujoco_rs::mujoco_version()
        ),
        clearance: Some(task.fit()?.clearance()),
        symmetry: task.omega.symmetry,
        play: None,
    })
}
