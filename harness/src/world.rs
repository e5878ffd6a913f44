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
    /// Whether the motion settled.
    pub settled: bool,
    /// Whether part A settled on the goal: inserted.
    pub inserted: bool,
    /// Simulated time of the motion (s).
    pub time: f64,
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

    /// A slide under force: a contact motion at `from`, then, still pressing, a straight
    /// move to `to` that stops where part A drops into part B, else settles at `to`.
    fn slide_motion(&mut self, from: [f64; 2], to: [f64; 2]) -> Contact;

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

/// The FT-Map as the world: a contact reads the map's wrench at the object's offset from the
/// TCP (interpolated over the cells where part A rests on part B), at the map's contact
/// depth; part A goes in where the task's geometry says it does.
pub struct MapWorld {
    map: FtMap,
    /// The map's [`FtMap::contact_depth`].
    contact_depth: Option<f32>,
    fit: Arc<dyn Fit>,
    /// Whether the map's first two axes are `grip.x`, `grip.y`.
    has_grip: bool,
    object: [f64; 2],
    grip: [f64; 2],
}

impl MapWorld {
    /// The world of `map` (over `object.x`, `object.y`, after `grip.x`, `grip.y` where the
    /// grip is uncertain) for parts that fit as `fit` says.
    ///
    /// # Errors
    /// [`HarnessError::MapWorld`] when the map's axes are not exactly `object.x`, `object.y`
    /// or `grip.x`, `grip.y`, `object.x`, `object.y`.
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
        if !(has_grip || planar) {
            return Err(HarnessError::MapWorld(format!(
                "its axes are {}, the map world needs object.x, object.y, after grip.x, grip.y or alone",
                map.grid()
                    .axes()
                    .iter()
                    .map(|a| a.dof.to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            )));
        }
        Ok(Self {
            contact_depth: map.contact_depth(),
            map,
            fit,
            has_grip,
            object: [0.0; 2],
            grip: [0.0; 2],
        })
    }

    /// Part B's offset from a TCP at `xy` (m).
    fn offset(&self, xy: [f64; 2]) -> [f64; 2] {
        [self.object[0] - xy[0], self.object[1] - xy[1]]
    }

    /// The contact at `xy`: inserted (the task frame on the goal), or resting on part B
    /// with the map's wrench and depth.
    fn contact_at(&self, xy: [f64; 2]) -> Contact {
        let offset = self.offset(xy);
        let inserted = self.fit.inserts(offset);
        // The map's axes were checked: the coordinates fit its grid.
        let coords = if self.has_grip {
            vec![self.grip[0], self.grip[1], offset[0], offset[1]]
        } else {
            offset.to_vec()
        };
        let cell = self
            .map
            .interpolate_contact(&coords, self.contact_depth)
            .unwrap_or([0.0; NCH]);
        let mut raw = [0.0; 6];
        for (r, w) in raw.iter_mut().zip(&cell) {
            *r = -w;
        }
        Contact {
            raw,
            tcp: [xy[0], xy[1], if inserted { 0.0 } else { cell[NCH - 1] }],
            rot: [0.0; 3],
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

    /// The map world's maps have no rotation axes: only no rotation is accepted.
    fn set_object_rotation(&mut self, rot: [f64; 3]) -> Result<()> {
        no_rotation("part B", rot)
    }

    /// As [`MapWorld::set_object_rotation`].
    fn set_tcp_rotation(&mut self, rot: [f64; 3]) -> Result<()> {
        no_rotation("the TCP", rot)
    }

    fn contact_motion(&mut self, xy: [f64; 2]) -> Contact {
        self.contact_at(xy)
    }

    fn slide_motion(&mut self, from: [f64; 2], to: [f64; 2]) -> Contact {
        let len = (to[0] - from[0]).hypot(to[1] - from[1]);
        let samples = (len / self.fit.clearance() * SLIDE_SAMPLES_PER_CLEARANCE).ceil() as usize;
        (0..=samples)
            .map(|k| {
                let t = k as f64 / samples.max(1) as f64;
                [
                    from[0] + t * (to[0] - from[0]),
                    from[1] + t * (to[1] - from[1]),
                ]
            })
            .find(|&p| self.fit.inserts(self.offset(p)))
            .map_or_else(|| self.contact_at(to), |p| self.contact_at(p))
    }

    /// Its maps have no yaw: a twist that turns is refused, one that does not is a press.
    fn twist_motion(&mut self, xy: [f64; 2], from: f64, to: f64) -> Result<Contact> {
        no_rotation("the TCP", [0.0, 0.0, from])?;
        no_rotation("the TCP", [0.0, 0.0, to])?;
        Ok(self.contact_at(xy))
    }

    fn simulated(&self) -> f64 {
        0.0
    }
}
