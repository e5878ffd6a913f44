//! Where a trial's contact motions happen: the MuJoCo work cell ([`crate::sim::Sim`]) or a
//! world that is the FT-Map itself ([`MapWorld`]), which answers a contact with the map's
//! wrench at the true offset and takes part A in where the geometry does. The map world
//! measures the estimator and the strategy with no simulator between the map and the
//! measurement (and runs a campaign in a fraction of MuJoCo's time).

use std::sync::Arc;

use ftmap::task::fit::Fit;
use ftmap::{Axis, FtMap, NCH, Pose};

use crate::error::{HarnessError, Result};

/// Which world a campaign's trials run in.
#[derive(Debug, Clone, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum WorldKind {
    /// The task's MuJoCo scene.
    #[default]
    Mujoco,
    /// An FT-Map file as the world: the given one, or the FMU's map when `None`.
    Map(Option<std::path::PathBuf>),
}

/// How far a TCP turned by `rot` stands beside the point where its tool's axis meets the
/// goal's height, per metre of height (x, y): a contact motion is commanded at that point,
/// and its [`Contact::tcp`] stands `lean * height` off it.
pub fn lean(rot: &nalgebra::Rotation3<f64>) -> [f64; 2] {
    let tool = rot * nalgebra::Vector3::z();
    [tool.x / tool.z, tool.y / tool.z]
}

/// Where the tool's axis of a TCP at `tcp` (x, y and its height, m) turned by `rot` meets
/// the goal's height (x, y, m): where the contact motion that left it there was commanded.
pub fn foot(tcp: [f64; 3], rot: &nalgebra::Rotation3<f64>) -> [f64; 2] {
    let l = lean(rot);
    [tcp[0] - l[0] * tcp[2], tcp[1] - l[1] * tcp[2]]
}

/// What one contact motion ends with.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Contact {
    /// Raw sensor values: MuJoCo's force and torque sensors at site `ft`, in the site frame
    /// (the negated wrench of the map's convention, [`crate::sensor::map_wrench`]).
    pub raw: [f64; 6],
    /// Task frame position relative to the nominal goal frame at the end (m).
    pub tcp: [f64; 3],
    /// Task frame rotation relative to the nominal goal frame at the end (rotation
    /// vector, rad).
    pub rot: [f64; 3],
    /// Whether the motion came to an end: at rest, or fed in (not: out of time).
    pub settled: bool,
    /// Whether part A came within `sim::SUCCESS_HEIGHT` of the goal: inserted.
    pub inserted: bool,
    /// Simulated time of the motion (s).
    pub time: f64,
}

/// What a slide under force ends with: the press it started from, read at rest before it
/// slid (none where it went in there, or where the world reads none), and its end.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Slid {
    /// The press at the slide's start.
    pub start: Option<Contact>,
    /// Where part A went in, else the press after the slide.
    pub end: Contact,
    /// Where the slide stopped, as commanded (m): its far end, or short of it where part A
    /// dropped into part B.
    pub stopped: [f64; 2],
}

/// A work cell that runs contact motions against part B at a true offset.
pub trait World {
    /// Places part B at the true object offset (x, y) relative to the nominal goal (m): the
    /// TCP position at which the parts align (with a grip offset, part B sits that much
    /// farther off, under part A).
    fn set_object(&mut self, xy: [f64; 2]);

    /// Holds part A off-centre in the hand by `xy` (m): the paper's grip offset r1; the F/T
    /// sensor stays with the hand.
    fn set_grip(&mut self, xy: [f64; 2]);

    /// Turns part B about its frame's origin by the rotation vector `rot` (rad): the
    /// object's true rotation relative to the nominal goal.
    ///
    /// # Errors
    /// When the world cannot turn part B that way.
    fn set_object_rotation(&mut self, rot: [f64; 3]) -> Result<()>;

    /// Turns the task frame (the robot's wrist) to the rotation vector `rot` (rad) relative
    /// to the nominal goal for the motions that follow (Algorithm 1, step 14: the TCP goes
    /// to the estimate, rotations included).
    ///
    /// # Errors
    /// When the robot has no joint for a rotation that `rot` asks for.
    fn set_tcp_rotation(&mut self, rot: [f64; 3]) -> Result<()>;

    /// One contact motion: approach at the commanded task-frame position `xy` (relative to
    /// the nominal goal) with the imposed force until the contact settles.
    fn contact_motion(&mut self, xy: [f64; 2]) -> Contact;

    /// A slide under force: a contact motion at `from` (its static contact read before it
    /// slides), then, still pressing, a straight move to `to` that stops where part A drops
    /// into part B, else settles at `to` and presses again for a static contact: where it
    /// stopped when `press` is `to`, else at `press`.
    fn slide_motion(&mut self, from: [f64; 2], to: [f64; 2], press: [f64; 2]) -> Slid;

    /// A twist under force: a contact motion at `xy` with the task frame turned to yaw
    /// `from` (rad, about z), then, still pressing, a turn to `to` that stops where part A
    /// drops into part B, else settles at `to`. The task frame stays turned where it ended.
    ///
    /// # Errors
    /// When the robot cannot turn about z.
    fn twist_motion(&mut self, xy: [f64; 2], from: f64, to: f64) -> Result<Contact>;

    /// Total simulated time so far (s); 0 for a world that does not simulate.
    fn simulated(&self) -> f64;
}

/// Refuses a rotation other than none in a world without rotations.
fn no_rotation(what: &str, rot: [f64; 3]) -> Result<()> {
    if rot == [0.0; 3] {
        Ok(())
    } else {
        Err(HarnessError::MapWorld(format!(
            "its maps have no rotation axes: {what} cannot turn by {rot:?} rad"
        )))
    }
}

/// Points a slide in the map world checks per radial clearance of the fit.
const SLIDE_SAMPLES_PER_CLEARANCE: f64 = 8.0;
/// Yaw between the points a twist in the map world checks (rad): a fiftieth of a degree,
/// well within the octagon's ±0.7 degrees of play.
const TWIST_STEP: f64 = 3.5e-4;

/// The FT-Map as the world: a contact reads the map's wrench at the object's pose relative
/// to the TCP (interpolated over the cells where part A rests on part B), at the map's
/// contact depth; part A goes in where the task's geometry says it does (on a map of part
/// B's tilts, where the map's cells say so).
pub struct MapWorld {
    map: FtMap,
    /// The map's [`FtMap::contact_depth`].
    contact_depth: Option<f32>,
    fit: Arc<dyn Fit>,
    /// Whether the map's first two axes are `grip.x`, `grip.y`.
    has_grip: bool,
    /// The yaw's period, when the map's third axis is `object.rz` (2 pi where the fit has
    /// no symmetry about the approach).
    yaw_period: Option<f64>,
    /// Where the map's last two axes are `object.rx`, `object.ry` (part B tilts, and the TCP
    /// stays upright: a tilted TCP moves the contact along its axis, which this world does
    /// not follow), the tilt below which the force and torque are read where the tilt's
    /// direction meets this radius, as the FMU reads them by default (its `tilt_floor`: the
    /// diagonal of the wider tilt step, docs/fmu.md).
    tilt_floor: Option<f64>,
    object: [f64; 2],
    grip: [f64; 2],
    /// Part B's yaw and the TCP's (rad).
    yaw: [f64; 2],
    /// Part B's tilt: its rotation vector's x and y (rad).
    tilt: [f64; 2],
}

impl MapWorld {
    /// The world of `map` (over `object.x`, `object.y`, after `grip.x`, `grip.y` where the
    /// grip is uncertain, or followed by `object.rz` where the fit answers at every yaw, or
    /// by `object.rx`, `object.ry`) for parts that fit as `fit` says.
    ///
    /// # Errors
    /// [`HarnessError::MapWorld`] when the map's axes are not exactly `object.x`, `object.y`,
    /// `grip.x`, `grip.y`, `object.x`, `object.y`, `object.x`, `object.y`, `object.rz` or
    /// `object.x`, `object.y`, `object.rx`, `object.ry`, or `object.rz` without a fit known
    /// at every yaw (a task without `[geometry]`).
    pub fn new(map: FtMap, fit: Arc<dyn Fit>) -> Result<Self> {
        let is = |k: usize, pose, axis| {
            map.grid()
                .axes()
                .get(k)
                .is_some_and(|a| a.dof.pose == pose && a.dof.axis == axis)
        };
        let object_at = |k| is(k, Pose::Object, Axis::X) && is(k + 1, Pose::Object, Axis::Y);
        let has_grip = map.grid().ndim() == 4
            && is(0, Pose::Grip, Axis::X)
            && is(1, Pose::Grip, Axis::Y)
            && object_at(2);
        let planar = map.grid().ndim() == 2 && object_at(0);
        let turned = map.grid().ndim() == 3 && object_at(0) && is(2, Pose::Object, Axis::Rz);
        let tilted = map.grid().ndim() == 4
            && object_at(0)
            && is(2, Pose::Object, Axis::Rx)
            && is(3, Pose::Object, Axis::Ry);
        if turned && fit.inserts_turned([0.0; 2], TWIST_STEP).is_none() {
            return Err(HarnessError::MapWorld(
                "its object.rz needs the fit at every yaw, which only a task's [geometry] gives"
                    .into(),
            ));
        }
        if !(has_grip || planar || turned || tilted) {
            return Err(HarnessError::MapWorld(format!(
                "its axes are {}, the map world needs object.x, object.y, after grip.x, grip.y, before object.rz, before object.rx, object.ry or alone",
                map.grid()
                    .axes()
                    .iter()
                    .map(|a| a.dof.to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            )));
        }
        let tilt_floor = tilted.then(|| {
            let axes = map.grid().axes();
            axes[2].step.max(axes[3].step) * std::f64::consts::SQRT_2
        });
        let yaw_period = turned.then(|| {
            map.meta().symmetry.map_or(std::f64::consts::TAU, |n| {
                std::f64::consts::TAU / f64::from(n)
            })
        });
        Ok(Self {
            contact_depth: map.contact_depth(),
            map,
            fit,
            has_grip,
            yaw_period,
            tilt_floor,
            object: [0.0; 2],
            grip: [0.0; 2],
            yaw: [0.0; 2],
            tilt: [0.0; 2],
        })
    }

    /// Part B's pose relative to a TCP at `xy` (T_tcp^-1 T_object): its offset in the TCP's
    /// frame (m) and its yaw relative to the TCP's (rad, within half a period of zero).
    fn relative(&self, xy: [f64; 2]) -> ([f64; 2], f64) {
        let d = [self.object[0] - xy[0], self.object[1] - xy[1]];
        let (s, c) = self.yaw[1].sin_cos();
        let yaw = self.yaw[0] - self.yaw[1];
        let yaw = self.yaw_period.map_or(yaw, |p| yaw - p * (yaw / p).round());
        ([c * d[0] + s * d[1], c * d[1] - s * d[0]], yaw)
    }

    /// The yaw of rotation vector `rot`, refused on a map without one or where `rot` tilts.
    fn yaw_of(&self, what: &str, rot: [f64; 3]) -> Result<f64> {
        match self.yaw_period {
            Some(_) if rot[0] == 0.0 && rot[1] == 0.0 => Ok(rot[2]),
            Some(_) => Err(HarnessError::MapWorld(format!(
                "its map turns about z only: {what} cannot tilt by {rot:?} rad"
            ))),
            None => no_rotation(what, rot).map(|()| 0.0),
        }
    }

    /// The map's coordinates of a contact at `xy` (its axes were checked: they fit).
    fn coords(&self, xy: [f64; 2]) -> Vec<f64> {
        let (offset, yaw) = self.relative(xy);
        match (self.has_grip, self.yaw_period, self.tilt_floor.is_some()) {
            (true, ..) => vec![self.grip[0], self.grip[1], offset[0], offset[1]],
            (false, Some(_), _) => vec![offset[0], offset[1], yaw],
            // With the TCP upright, part B's tilt relative to it is its own.
            (false, None, true) => vec![offset[0], offset[1], self.tilt[0], self.tilt[1]],
            (false, None, false) => offset.to_vec(),
        }
    }

    /// The map's coordinates at which to read the force and torque of a contact at
    /// `coords` ([`MapWorld::coords`]): on a map of tilts, a tilt below the floor scaled
    /// along its direction up to it, and no farther than the map's range on either axis;
    /// elsewhere `coords` themselves.
    fn wrench_coords(&self, coords: &[f64]) -> Vec<f64> {
        let Some(floor) = self.tilt_floor else {
            return coords.to_vec();
        };
        let size = coords[2].hypot(coords[3]);
        if size == 0.0 || size >= floor {
            return coords.to_vec();
        }
        let axes = self.map.grid().axes();
        let mut scale = floor / size;
        for k in [2, 3] {
            let bound = if coords[k] > 0.0 {
                axes[k].max()
            } else {
                axes[k].min
            };
            if coords[k] * scale / bound > 1.0 {
                scale = bound / coords[k];
            }
        }
        let mut out = coords.to_vec();
        out[2] *= scale;
        out[3] *= scale;
        out
    }

    /// Whether part A goes in at `xy`: where the fit says, or on a map of tilts (which the
    /// fit does not know) where most of the multilinear weight lies on inserted cells.
    fn goes_in(&self, xy: [f64; 2]) -> bool {
        if self.tilt_floor.is_some() {
            return self
                .map
                .inserted_share(&self.coords(xy), self.contact_depth)
                .is_ok_and(|share| share > 0.5);
        }
        let (offset, yaw) = self.relative(xy);
        // A fit known at zero yaw only serves maps without a yaw, where the yaw is zero.
        self.fit.inserts_turned(offset, yaw).unwrap_or(false)
    }

    /// The contact at `xy`: inserted (the task frame on the goal), or resting on part B
    /// with the map's wrench and depth.
    fn contact_at(&self, xy: [f64; 2]) -> Contact {
        let inserted = self.goes_in(xy);
        let coords = self.coords(xy);
        let read = |at: &[f64]| {
            self.map
                .interpolate_contact(at, self.contact_depth)
                .unwrap_or([0.0; NCH])
        };
        let at = self.wrench_coords(&coords);
        let mut cell = read(&at);
        if at != coords {
            // The depth where the contact lies: it grows with the tilt's size.
            cell[NCH - 1] = read(&coords)[NCH - 1];
        }
        let mut raw = [0.0; 6];
        for (r, w) in raw.iter_mut().zip(&cell) {
            *r = -w;
        }
        Contact {
            raw,
            tcp: [xy[0], xy[1], if inserted { 0.0 } else { cell[NCH - 1] }],
            rot: [0.0, 0.0, self.yaw[1]],
            settled: true,
            inserted,
            time: 0.0,
        }
    }
}

impl World for MapWorld {
    fn set_object(&mut self, xy: [f64; 2]) {
        self.object = xy;
    }

    /// Reads the map at the grip offset; ignored on a map without grip axes.
    fn set_grip(&mut self, xy: [f64; 2]) {
        self.grip = xy;
    }

    /// A yaw on a map with `object.rz`, a tilt on one with `object.rx`, `object.ry`; no
    /// rotation otherwise.
    fn set_object_rotation(&mut self, rot: [f64; 3]) -> Result<()> {
        if self.tilt_floor.is_some() {
            if rot[2] != 0.0 {
                return Err(HarnessError::MapWorld(format!(
                    "its map tilts part B about x and y only: part B cannot turn by {rot:?} rad"
                )));
            }
            self.tilt = [rot[0], rot[1]];
            return Ok(());
        }
        self.yaw[0] = self.yaw_of("part B", rot)?;
        Ok(())
    }

    /// As [`MapWorld::set_object_rotation`]; upright only on a map of tilts.
    fn set_tcp_rotation(&mut self, rot: [f64; 3]) -> Result<()> {
        if self.tilt_floor.is_some() && rot != [0.0; 3] {
            return Err(HarnessError::MapWorld(format!(
                "it reads part B's tilts with the TCP upright only: the TCP cannot turn by {rot:?} rad"
            )));
        }
        self.yaw[1] = self.yaw_of("the TCP", rot)?;
        Ok(())
    }

    fn contact_motion(&mut self, xy: [f64; 2]) -> Contact {
        self.contact_at(xy)
    }

    fn slide_motion(&mut self, from: [f64; 2], to: [f64; 2], press: [f64; 2]) -> Slid {
        let start = self.contact_at(from);
        if start.inserted {
            return Slid {
                start: None,
                end: start,
                stopped: from,
            };
        }
        let len = (to[0] - from[0]).hypot(to[1] - from[1]);
        let samples = (len / self.fit.clearance() * SLIDE_SAMPLES_PER_CLEARANCE).ceil() as usize;
        let dropped = (0..=samples)
            .map(|k| {
                let t = k as f64 / samples.max(1) as f64;
                [
                    from[0] + t * (to[0] - from[0]),
                    from[1] + t * (to[1] - from[1]),
                ]
            })
            .find(|&p| self.goes_in(p));
        Slid {
            start: Some(start),
            end: self.contact_at(dropped.unwrap_or(press)),
            stopped: dropped.unwrap_or(to),
        }
    }

    /// Turns through the yaws from `from` to `to`, stopping where part A goes in; on a map
    /// without a yaw a twist that turns is refused, one that does not is a press.
    fn twist_motion(&mut self, xy: [f64; 2], from: f64, to: f64) -> Result<Contact> {
        for yaw in [from, to] {
            self.yaw_of("the TCP", [0.0, 0.0, yaw])?;
        }
        let samples = ((to - from).abs() / TWIST_STEP).ceil() as usize;
        for k in 0..=samples {
            self.yaw[1] = from + (to - from) * k as f64 / samples.max(1) as f64;
            if self.goes_in(xy) {
                break;
            }
        }
        Ok(self.contact_at(xy))
    }

    fn simulated(&self) -> f64 {
        0.0
    }
}
