//! Assembly tasks as described by `models_mjcf/<task>/task.toml`: the two parts' meshes,
//! the approach vector, imposed force, friction, sensor origin, the tolerance space Omega,
//! the depth-map settings, the parts' parametric geometry and the camera. One source of
//! truth for the map, the FMU and the scene: the file is parsed once, into [`Task`].

use std::path::{Path, PathBuf};
use std::sync::Arc;

use serde::Deserialize;

use crate::error::{MapError, Result};
use crate::mesh::Mesh;

pub mod cad;
pub mod create;
pub mod dof;
pub mod fit;
pub mod omega;

use cad::Geometry;
use dof::{Axis, Dof, Pose};
use omega::{Grid, GridAxis};

/// A part of the task: its mesh file (relative to the task file) and the file's units.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Part {
    /// Binary or ASCII STL in the part's own frame.
    pub mesh: PathBuf,
    /// The length unit of the mesh file's coordinates (default metres).
    #[serde(default)]
    pub units: Units,
}

impl Part {
    /// The part's mesh in metres, checked ([`Mesh::load_scaled`]).
    pub fn load(&self) -> Result<Mesh> {
        Mesh::load_scaled(&self.mesh, self.units.metres())
    }
}

/// The length unit of a mesh file: CAD systems mostly export STL in millimetres.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Units {
    /// Metres.
    #[default]
    M,
    /// Millimetres.
    Mm,
    /// Inches.
    In,
}

impl Units {
    /// One unit in metres.
    pub fn metres(self) -> f64 {
        match self {
            Self::M => 1.0,
            Self::Mm => 0.001,
            Self::In => 0.0254,
        }
    }

    /// The unit's name as `task.toml` writes it.
    pub fn name(self) -> &'static str {
        match self {
            Self::M => "m",
            Self::Mm => "mm",
            Self::In => "in",
        }
    }
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
    /// Bound of the grip's translations (m): values lie in [-size_grip, size_grip];
    /// default `size_trans`.
    #[serde(default)]
    pub size_grip: Option<f64>,
    /// Step of the grip's translations (m); default `delta_trans`. A grip translation moves
    /// only the sensor's lever, to which the wrench is linear: the map's interpolation is
    /// exact across it at any step.
    #[serde(default)]
    pub delta_grip: Option<f64>,
    /// Rotational bound (rad).
    #[serde(default)]
    pub size_rot: f64,
    /// Rotational step (rad).
    #[serde(default = "default_delta_rot")]
    pub delta_rot: f64,
    /// How far the map samples the object's x and y, in Omega's half-widths (default 2,
    /// at least 1): the filter reads the map at the part's pose relative to the TCP, and a
    /// part anywhere in Omega seen from a TCP anywhere in Omega lies up to twice Omega's
    /// half-width off. 1 samples Omega alone (a quarter of the cells over x and y; beyond
    /// it the lookup reads Omega's edge).
    #[serde(default = "default_reach")]
    pub reach: f64,
    /// n-fold symmetry of the fit about the approach axis (z): the parts look the same
    /// after 1/n of a turn, so `object.rz` wraps around with period 2 pi / n. Omega's
    /// rotational bound must then be half that period (pi / n).
    #[serde(default)]
    pub symmetry: Option<u32>,
}

fn default_delta_rot() -> f64 {
    0.5f64.to_radians()
}

/// A part anywhere in Omega seen from a TCP anywhere in Omega.
fn default_reach() -> f64 {
    2.0
}

/// The largest `omega.reach`: farther than a part and a TCP in Omega can be apart is waste.
const MAX_REACH: f64 = 2.0;

/// Checks `omega.reach`: within [1, [`MAX_REACH`]].
fn check_reach(reach: f64) -> std::result::Result<(), String> {
    if (1.0..=MAX_REACH).contains(&reach) {
        Ok(())
    } else {
        Err(format!("omega.reach {reach} must lie in [1, {MAX_REACH}]"))
    }
}

/// Checks an n-fold symmetry about the approach: n >= 2, the approach along z (the axis
/// of `rz`), and Omega's rotations spanning exactly one period in whole steps.
fn check_symmetry(n: u32, o: &Omega, approach: [f64; 3]) -> std::result::Result<(), String> {
    if n < 2 {
        return Err(format!("omega.symmetry {n} must be >= 2"));
    }
    if approach[2].abs() < 1.0 - 1e-9 {
        return Err(format!(
            "omega.symmetry is about the approach axis, which must be z (rz's axis); contact.approach is {approach:?}"
        ));
    }
    let half = std::f64::consts::PI / f64::from(n);
    let steps = half / o.delta_rot;
    if (o.size_rot - half).abs() > 1e-9 || (steps - steps.round()).abs() > 1e-6 {
        return Err(format!(
            "omega.symmetry {n}: size_rot {} must be half the period (pi / {n} = {half}) and a whole multiple of delta_rot {}",
            o.size_rot, o.delta_rot
        ));
    }
    Ok(())
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

/// A task's `[camera]` table: a calibrated camera set up as in experiment D, in front of
/// the goal along -x, looking along +x, tilted down so that its optical axis meets the
/// goal's x = 0 plane at `aim_z`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraSetup {
    /// Distance in front of the goal along -x (m).
    pub distance: f64,
    /// Height at which the optical axis meets the goal's x = 0 plane (m).
    pub aim_z: f64,
    /// Downward tilt (degrees).
    pub pitch_deg: f64,
    /// Vertical field of view (degrees).
    pub fovy: f64,
    /// Image width and height (px).
    pub size: [usize; 2],
}

impl CameraSetup {
    /// Checks that the table describes a usable camera; the reason if not.
    fn check(&self) -> std::result::Result<(), String> {
        if !(self.distance > 0.0 && self.distance.is_finite()) {
            return Err(format!("distance {} must be > 0", self.distance));
        }
        if !self.aim_z.is_finite() {
            return Err(format!("aim_z {} must be finite", self.aim_z));
        }
        if self.pitch_deg.is_nan() || self.pitch_deg.abs() >= 90.0 {
            return Err(format!("|pitch_deg| {} must be < 90", self.pitch_deg));
        }
        if !(self.fovy > 0.0 && self.fovy < 180.0) {
            return Err(format!("fovy {} degrees must lie in (0, 180)", self.fovy));
        }
        if self.size[0] < 2 || self.size[1] < 2 {
            return Err(format!(
                "size {}x{} px: need at least 2x2",
                self.size[0], self.size[1]
            ));
        }
        Ok(())
    }
}

/// A task's `[scene]` table: how the harness's MuJoCo work cell discretises the parts'
/// contact (the scene's own defaults where absent).
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneSettings {
    /// Lattice pitch of part A's sphere bed (m): a coarser bed has fewer spheres to collide
    /// each step, and presses its face less evenly by area.
    pub bed_pitch: Option<f64>,
}

impl SceneSettings {
    /// Checks that the table's values are usable; the reason if not.
    fn check(&self) -> std::result::Result<(), String> {
        match self.bed_pitch {
            Some(p) if !(p > 0.0 && p.is_finite()) => Err(format!("bed_pitch {p} must be > 0")),
            _ => Ok(()),
        }
    }
}

/// A task file as written.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct TaskFile {
    name: String,
    #[serde(default)]
    description: String,
    part_a: Part,
    part_b: Part,
    contact: Contact,
    omega: Omega,
    depth: DepthSettings,
    geometry: Option<toml::Value>,
    camera: Option<toml::Value>,
    scene: Option<toml::Value>,
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
    /// The parts' dimensions when their meshes are generated from them (`[geometry]`).
    pub geometry: Option<Geometry>,
    /// The calibrated camera of a vision task (`[camera]`).
    pub camera: Option<CameraSetup>,
    /// How the harness's scene discretises the contact (`[scene]`).
    pub scene: SceneSettings,
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
        let text = std::fs::read_to_string(path).map_err(MapError::io(path))?;
        let file: TaskFile = toml::from_str(&text).map_err(|e| err(e.to_string()))?;
        // The optional tables are read on their own, so that an error names its table.
        fn table<T: serde::de::DeserializeOwned>(
            name: &str,
            value: Option<toml::Value>,
            check: impl Fn(&T) -> std::result::Result<(), String>,
        ) -> std::result::Result<Option<T>, String> {
            let Some(value) = value else {
                return Ok(None);
            };
            let t: T = value.try_into().map_err(|e| format!("[{name}]: {e}"))?;
            check(&t).map_err(|reason| format!("[{name}]: {reason}"))?;
            Ok(Some(t))
        }
        let geometry = table("geometry", file.geometry, Geometry::check).map_err(err)?;
        let camera = table("camera", file.camera, CameraSetup::check).map_err(err)?;
        let scene = table("scene", file.scene, SceneSettings::check).map_err(err)?;
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
        if let Some(n) = file.omega.symmetry {
            check_symmetry(n, &file.omega, contact.approach).map_err(err)?;
        }
        check_reach(file.omega.reach).map_err(err)?;
        let task = Self {
            name: file.name,
            description: file.description,
            path: path.to_owned(),
            part_a: Part {
                mesh: dir.join(file.part_a.mesh),
                ..file.part_a
            },
            part_b: Part {
                mesh: dir.join(file.part_b.mesh),
                ..file.part_b
            },
            contact,
            omega: file.omega,
            depth: file.depth,
            geometry,
            camera,
            scene: scene.unwrap_or_default(),
        };
        task.grid().map_err(|e| match e {
            // Already names this task file.
            MapError::Task { .. } => e,
            other => err(other.to_string()),
        })?;
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

    /// The map's grid: Omega, its object x and y sampled out to `omega.reach` times its
    /// half-width; the pixel size must divide the translation step.
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
        check_reach(o.reach).map_err(|reason| MapError::Task {
            path: self.path.clone(),
            reason,
        })?;
        let axes = self
            .dofs()?
            .into_iter()
            .map(|dof| {
                if dof.pose == Pose::Object && matches!(dof.axis, Axis::X | Axis::Y) {
                    GridAxis::reaching(dof, o.size_trans, o.reach, o.delta_trans)
                } else if dof.is_rotation() {
                    GridAxis::symmetric(dof, o.size_rot, o.delta_rot)
                } else if dof.pose == Pose::Grip {
                    GridAxis::symmetric(
                        dof,
                        o.size_grip.unwrap_or(o.size_trans),
                        o.delta_grip.unwrap_or(o.delta_trans),
                    )
                } else {
                    GridAxis::symmetric(dof, o.size_trans, o.delta_trans)
                }
            })
            .collect::<Result<Vec<_>>>()?;
        Grid::new(axes)
    }

    /// The task's `[geometry]`, or an error naming the task file when it has none.
    pub fn geometry(&self) -> Result<&Geometry> {
        self.geometry.as_ref().ok_or_else(|| MapError::Task {
            path: self.path.clone(),
            reason: "no [geometry] table: its meshes are not generated".into(),
        })
    }

    /// How the parts fit ([`fit::Fit`]): from the `[geometry]` where the task has one,
    /// else measured on its meshes with parry ([`fit::MeshFit`], about a second).
    ///
    /// # Errors
    /// When the meshes cannot be read or do not sit in a fit at the goal.
    pub fn fit(&self) -> Result<Arc<dyn fit::Fit>> {
        Ok(match &self.geometry {
            Some(g) => Arc::new(g.clone()),
            None => {
                let pair = crate::exact::Pair::new(&self.part_a.load()?, &self.part_b.load()?)?;
                Arc::new(fit::MeshFit::measure(self, &pair)?)
            }
        })
    }

    /// The folder of the task file, where its meshes lie.
    fn dir(&self) -> &Path {
        self.path.parent().unwrap_or(Path::new("."))
    }

    /// Generates the parts from the task's `[geometry]` and writes them as binary STL next
    /// to its task file; the paths written.
    pub fn write_meshes(&self) -> Result<Vec<PathBuf>> {
        cad::meshes(self.geometry()?)
            .into_iter()
            .map(|m| {
                let path = self.dir().join(m.file);
                std::fs::write(&path, cad::stl_bytes(&m.triangles)).map_err(MapError::io(&path))?;
                Ok(path)
            })
            .collect()
    }

    /// Names of the task's mesh files that are missing or differ from what its
    /// `[geometry]` gives.
    pub fn stale_meshes(&self) -> Result<Vec<String>> {
        Ok(cad::meshes(self.geometry()?)
            .into_iter()
            .filter(|m| {
                std::fs::read(self.dir().join(m.file)).ok() != Some(cad::stl_bytes(&m.triangles))
            })
            .map(|m| m.file.to_owned())
            .collect())
    }

    /// The tasks under [`models_root`] whose meshes are generated from a `[geometry]`.
    pub fn all_with_geometry() -> Result<Vec<Self>> {
        let mut tasks = Vec::new();
        for name in Self::names() {
            let task = Self::find(&name)?;
            if task.geometry.is_some() {
                tasks.push(task);
            }
        }
        Ok(tasks)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp_dir(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("ftmap-task-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        dir
    }

    /// A committed task file's text.
    fn text_of(task: &str) -> String {
        std::fs::read_to_string(Task::find(task).expect("committed task").path).expect("text")
    }

    #[test]
    fn the_whole_file_is_read_into_typed_fields() {
        let task = Task::find("bearing_housing").expect("task");
        assert!(matches!(
            task.geometry,
            Some(Geometry::BearingHousing { segments: 256, .. })
        ));
        let cam = task.camera.expect("experiment D's camera");
        assert_eq!((cam.distance, cam.size), (0.2, [640, 480]));
        let peg = Task::find("peg_in_hole").expect("task");
        assert!(peg.camera.is_none() && peg.geometry.is_some());
        assert_eq!(peg.scene, SceneSettings::default());
        assert!(
            Task::find("peg_in_hole_4dof")
                .expect("task")
                .geometry
                .is_none()
        );
    }

    #[test]
    fn the_map_samples_the_object_s_x_and_y_out_to_the_reach_and_the_rest_over_omega() {
        let tilted = Task::find("peg_in_hole_4dof").expect("task");
        let grid = tilted.grid().expect("grid");
        let axes = grid.axes();
        for a in &axes[..2] {
            // 5 mm Omega at 0.1 mm, sampled out to 10 mm.
            assert_eq!((a.count, a.omega), (201, Some(0.005)), "{}", a.dof);
            assert!((a.min + 0.01).abs() < 1e-12 && a.omega_bounds() == [-0.005, 0.005]);
        }
        for a in &axes[2..] {
            assert_eq!(
                (a.count, a.omega),
                (17, None),
                "{}: rotations over Omega",
                a.dof
            );
        }
        let mut alone = tilted.clone();
        alone.omega.reach = 1.0;
        let grid = alone.grid().expect("grid");
        assert!(grid.axes().iter().all(|a| a.omega.is_none()));
        assert_eq!(grid.axes()[0].count, 101);
    }

    #[test]
    fn broken_tables_are_named_with_the_file() {
        let dir = temp_dir("bad");
        let path = dir.join("task.toml");
        let bearing = text_of("bearing_housing");
        let peg = text_of("peg_in_hole");
        let yaw = text_of("octagon_yaw");
        let cases = [
            (
                yaw.replace("symmetry = 8 ", "symmetry = 6 "),
                "omega.symmetry",
                "half the period",
            ),
            (
                yaw.replace("symmetry = 8 ", "symmetry = 1 "),
                "omega.symmetry",
                ">= 2",
            ),
            (
                yaw.replace("approach = [0.0, 0.0, -1.0]", "approach = [1.0, 0.0, 0.0]"),
                "omega.symmetry",
                "must be z",
            ),
            (
                bearing.replace("fovy = 12.0", "fovy = 200.0"),
                "[camera]",
                "fovy",
            ),
            (
                bearing.replace("size = [640, 480]", "size = [640]"),
                "[camera]",
                "size",
            ),
            (
                bearing.replace("aim_z =", "aim_height ="),
                "[camera]",
                "aim_height",
            ),
            (
                bearing.replace("pitch_deg = 8.0", "pitch_deg = 95.0"),
                "[camera]",
                "pitch_deg",
            ),
            (
                peg.replace("kind = \"round_peg\"", "kind = \"hexagon\""),
                "[geometry]",
                "hexagon",
            ),
            (
                peg.replace("segments = 256", "segments = 256\ncolour = 1"),
                "[geometry]",
                "colour",
            ),
            (
                peg.replace("peg_radius = 0.00495", "peg_radius = 0.0051"),
                "[geometry]",
                "peg_radius",
            ),
            (
                peg.replace("segments = 256", "segments = 30"),
                "[geometry]",
                "segments",
            ),
            (
                format!("{peg}\n[scene]\nfloor = 1\n"),
                "[scene]",
                "unknown field",
            ),
            (
                format!("{peg}\n[scene]\nbed_pitch = 0.0\n"),
                "[scene]",
                "bed_pitch",
            ),
            (
                format!("{peg}\n[scene]\nbed_pitch = nan\n"),
                "[scene]",
                "bed_pitch",
            ),
            (
                peg.replace("size_trans = 0.005", "size_trans = 0.005\nreach = 0.5"),
                "omega.reach",
                "[1, 2]",
            ),
            (
                peg.replace("size_trans = 0.005", "size_trans = 0.005\nreach = 3.0"),
                "omega.reach",
                "[1, 2]",
            ),
        ];
        for (text, table, needle) in cases {
            assert!(
                text != bearing && text != peg && text != yaw,
                "{needle}: the case changes a file"
            );
            std::fs::write(&path, &text).expect("write");
            let e = Task::load(&path).expect_err(needle);
            assert!(matches!(e, MapError::Task { .. }), "{e}");
            let msg = e.to_string();
            assert!(
                msg.contains(table) && msg.contains(needle) && msg.contains("task.toml"),
                "{msg}"
            );
        }
        std::fs::remove_dir_all(dir).ok();
    }

    #[test]
    fn meshes_are_written_and_stale_or_missing_ones_reported() {
        let dir = temp_dir("stale");
        std::fs::write(dir.join("task.toml"), text_of("octagon")).expect("write");
        let task = Task::load(&dir.join("task.toml")).expect("task");
        let written = task.write_meshes().expect("write meshes");
        assert_eq!(written, [dir.join("peg.stl"), dir.join("block.stl")]);
        assert!(task.stale_meshes().expect("check").is_empty());
        let mut bytes = std::fs::read(dir.join("block.stl")).expect("read");
        bytes[100] ^= 1;
        std::fs::write(dir.join("block.stl"), bytes).expect("write");
        std::fs::remove_file(dir.join("peg.stl")).expect("remove");
        assert_eq!(
            task.stale_meshes().expect("check"),
            ["peg.stl", "block.stl"]
        );
        let no_geometry = Task::find("peg_in_hole_4dof").expect("task");
        let e = no_geometry
            .write_meshes()
            .expect_err("no [geometry]")
            .to_string();
        assert!(
            e.contains("no [geometry]") && e.contains("task.toml"),
            "{e}"
        );
        std::fs::remove_dir_all(dir).ok();
    }
}
