//! Assembly tasks as described by `models_mjcf/<task>/task.toml`: the two parts' meshes,
//! the approach vector, imposed force, friction, sensor origin, the tolerance space Omega
//! and the depth-map settings. One source of truth for the map, the FMU and the scene.

use std::path::{Path, PathBuf};

use serde::Deserialize;

use crate::dof::{Axis, Dof, Pose};
use crate::error::{MapError, Result};
use crate::grid::{Grid, GridAxis};

/// A part of the task: its mesh file (relative to the task file).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Part {
    /// Binary or ASCII STL, metres, in the part's own frame.
    pub mesh: PathBuf,
}

/// How contact is made: along `approach` with `force`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Contact {
    /// Approach vector a in the nominal task frame (normalised on load).
    pub approach: [f64; 3],
    /// Imposed force along a (N).
    pub force: f64,
    /// Friction coefficient between the parts.
    pub friction: f64,
    /// Origin of the F/T sensor in the nominal task frame (m).
    pub sensor_origin: [f64; 3],
}

/// The tolerance space Omega (paper, Definition 2.1.1) as a box grid.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Omega {
    /// Uncertain axes of the grip pose r1 (`x` .. `rz`).
    #[serde(default)]
    pub grip: Vec<String>,
    /// Uncertain axes of the task-to-object pose r2 (`x` .. `rz`).
    #[serde(default)]
    pub object: Vec<String>,
    /// Translational bound: values lie in [-size_trans, size_trans] (m).
    pub size_trans: f64,
    /// Translational step (m).
    pub delta_trans: f64,
    /// Rotational bound (rad).
    #[serde(default)]
    pub size_rot: f64,
    /// Rotational step (rad).
    #[serde(default = "default_delta_rot")]
    pub delta_rot: f64,
}

fn default_delta_rot() -> f64 {
    0.5f64.to_radians()
}

/// Settings of the z-buffer computation.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DepthSettings {
    /// Pixel size (m); must divide the translational step.
    pub pixel: f64,
    /// Pixels within this distance of the minimal gap are contacts (m).
    pub tolerance: f64,
}

/// A task file as written.
#[derive(Debug, Clone, Deserialize)]
struct TaskFile {
    name: String,
    #[serde(default)]
    description: String,
    part_a: Part,
    part_b: Part,
    contact: Contact,
    omega: Omega,
    depth: DepthSettings,
    #[serde(flatten)]
    extra: toml::Table,
}

/// A loaded task with resolved paths.
#[derive(Debug, Clone)]
pub struct Task {
    /// Task name.
    pub name: String,
    /// One line on what is assembled.
    pub description: String,
    /// The task file.
    pub path: PathBuf,
    /// Active (gripped) part A; its frame is the task frame, the tip at its origin.
    pub part_a: Part,
    /// Passive (fixed) part B; its frame is the goal frame (mated: both frames coincide).
    pub part_b: Part,
    /// Approach, force, friction and sensor.
    pub contact: Contact,
    /// The tolerance space.
    pub omega: Omega,
    /// Depth-map settings.
    pub depth: DepthSettings,
    /// Sections other crates read (geometry, scene, vision).
    pub extra: toml::Table,
}

/// The folder holding one sub-folder per task: `$FTFUSION_MODELS`, else the nearest
/// `models_mjcf/` above the working directory, else the one of this source tree.
pub fn models_root() -> PathBuf {
    if let Some(dir) = std::env::var_os("FTFUSION_MODELS") {
        return PathBuf::from(dir);
    }
    if let Ok(cwd) = std::env::current_dir() {
        for dir in cwd.ancestors() {
            let candidate = dir.join("models_mjcf");
            if candidate.is_dir() {
                return candidate;
            }
        }
    }
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../models_mjcf")
}

impl Task {
    /// Loads a task by name (`peg_in_hole`), folder, or path of a `task.toml`.
    pub fn find(name_or_path: &str) -> Result<Self> {
        let given = Path::new(name_or_path);
        let path = if given.is_file() {
            given.to_owned()
        } else if given.is_dir() {
            given.join("task.toml")
        } else {
            models_root().join(name_or_path).join("task.toml")
        };
        if !path.is_file() {
            let known = Self::names().join(", ");
            return Err(MapError::Task {
                path: given.to_owned(),
                reason: format!("no such task file or task name (known tasks: {known})"),
            });
        }
        Self::load(&path)
    }

    /// Names of the tasks under [`models_root`].
    pub fn names() -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(models_root())
            .into_iter()
            .flatten()
            .flatten()
            .filter(|e| e.path().join("task.toml").is_file())
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    /// Loads and checks a task file.
    pub fn load(path: &Path) -> Result<Self> {
        let err = |reason: String| MapError::Task {
            path: path.to_owned(),
            reason,
        };
        let text = std::fs::read_to_string(path).map_err(|e| err(e.to_string()))?;
        let file: TaskFile = toml::from_str(&text).map_err(|e| err(e.to_string()))?;
        let dir = path.parent().unwrap_or(Path::new("."));
        let mut contact = file.contact;
        let a = contact.approach;
        let norm = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
        if !(norm > 1e-9 && norm.is_finite()) {
            return Err(err(format!("contact.approach {a:?} is not a direction")));
        }
        contact.approach = a.map(|v| v / norm);
        if !(contact.force > 0.0 && contact.force.is_finite()) {
            return Err(err(format!("contact.force {} must be > 0", contact.force)));
        }
        if !(contact.friction >= 0.0 && contact.friction.is_finite()) {
            return Err(err(format!(
                "contact.friction {} must be >= 0",
                contact.friction
            )));
        }
        let d = &file.depth;
        if !(d.pixel > 0.0 && d.tolerance >= 0.0 && d.pixel.is_finite() && d.tolerance.is_finite())
        {
            return Err(err(format!(
                "depth.pixel {} must be > 0, depth.tolerance {} >= 0",
                d.pixel, d.tolerance
            )));
        }
        let task = Self {
            name: file.name,
            description: file.description,
            path: path.to_owned(),
            part_a: Part {
                mesh: dir.join(file.part_a.mesh),
            },
            part_b: Part {
                mesh: dir.join(file.part_b.mesh),
            },
            contact,
            omega: file.omega,
            depth: file.depth,
            extra: file.extra,
        };
        task.grid().map_err(|e| err(e.to_string()))?;
        Ok(task)
    }

    /// The uncertain DOFs in grid order: grip axes, then object axes, as listed.
    pub fn dofs(&self) -> Result<Vec<Dof>> {
        let parse = |pose, names: &[String], key: &str| -> Result<Vec<Dof>> {
            names
                .iter()
                .map(|n| {
                    Axis::ALL
                        .into_iter()
                        .find(|a| a.name() == n)
                        .map(|a| Dof::new(pose, a))
                        .ok_or_else(|| MapError::Task {
                            path: self.path.clone(),
                            reason: format!("omega.{key}: unknown axis `{n}`"),
                        })
                })
                .collect()
        };
        let mut dofs = parse(Pose::Grip, &self.omega.grip, "grip")?;
        dofs.extend(parse(Pose::Object, &self.omega.object, "object")?);
        Ok(dofs)
    }

    /// The grid over Omega; the pixel size must divide the translation step.
    pub fn grid(&self) -> Result<Grid> {
        let o = &self.omega;
        let ratio = o.delta_trans / self.depth.pixel;
        if (ratio - ratio.round()).abs() > 1e-6 || ratio.round() < 1.0 {
            return Err(MapError::Task {
                path: self.path.clone(),
                reason: format!(
                    "depth.pixel {} must divide omega.delta_trans {} (translations are whole-pixel shifts)",
                    self.depth.pixel, o.delta_trans
                ),
            });
        }
        let axes = self
            .dofs()?
            .into_iter()
            .map(|dof| {
                if dof.is_rotation() {
                    GridAxis::symmetric(dof, o.size_rot, o.delta_rot)
                } else {
                    GridAxis::symmetric(dof, o.size_trans, o.delta_trans)
                }
            })
            .collect::<Result<Vec<_>>>()?;
        Grid::new(axes)
    }
}
