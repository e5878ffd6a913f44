//! One task's MuJoCo work cell: load the generated scene, place part B per trial, and run
//! contact motions (approach along a with the imposed force until the contact settles).
//!
//! A contact motion starts from a reset state: the lift and the transfer to the next
//! approach point happen in free space and are not simulated; the carriage is placed
//! `APPROACH_CLEARANCE` above part B's top at the commanded (x, y) and the press motor
//! pushes with the imposed force against the feed's damping, a slow guarded approach. When
//! part A has dropped into part B by [`ENTRY_DEPTH`], the feed drives it down at
//! [`INSERTION_SPEED`], slowing down over the last [`INSERTION_TIME`] (its speed the height
//! left over that time), until it settles on the goal under the imposed force. So each
//! contact is a pure function of the object offset and the commanded point (the FMPy
//! script reproduces it step for step).
//!
//! Why slow: MuJoCo's contacts are found by penetration after each step. A part arriving
//! fast sinks into the top face for a step, and where its edge overlaps the top by less
//! than that sinking the nearest face is the hole's wall, which pushes it in: the hole then
//! accepts the part farther off centre than the geometry does (`harness boundary`).

use std::path::{Path, PathBuf};

use ftmap::Task;
use mujoco_rs::prelude::*;

use crate::error::{HarnessError, Result};
use crate::scene::{APPROACH_CLEARANCE, SceneSpec, scene_path, write_scene};
use crate::world::{Contact, World};

/// Longest contact motion (s of simulated time) before it is reported as not settled.
pub const MAX_TIME: f64 = 2.0;
/// The contact has settled when the approach speed stays below this (m/s) ...
pub const SETTLE_SPEED: f64 = 1.0e-4;
/// ... for this long (s) with at least one contact.
pub const SETTLE_TIME: f64 = 0.01;
/// Part A has entered part B once its frame is this far below part B's top and its
/// chamfers (m).
pub const ENTRY_DEPTH: f64 = 0.0001;
/// The feed's speed down to the goal once part A has entered (m/s) ...
pub const INSERTION_SPEED: f64 = 0.1;
/// ... at most the height left over this time (s).
pub const INSERTION_TIME: f64 = 0.01;
/// Speed of a slide under force (m/s).
pub const SLIDE_SPEED: f64 = 0.005;
/// A slide stops where part A has dropped this far below part B's top (m).
pub const DROP_DEPTH: f64 = 0.00001;
/// A contact motion ending with the task frame below this height above the goal has
/// inserted part A (m).
pub const SUCCESS_HEIGHT: f64 = 0.001;

/// A loaded scene with its data, ready for contact motions.
pub struct Sim {
    data: MjData<Box<MjModel>>,
    spec: SceneSpec,
    qpos: [usize; 3],
    dof_z: usize,
    actuators: [usize; 4],
    sensors: [usize; 2],
    mocap: usize,
    /// Body `part_a` and site `ft`: a grip offset moves the one in the carriage and the
    /// other back, so that the sensor stays where the hand holds it.
    grip_ids: [usize; 2],
    object: [f64; 2],
    grip: [f64; 2],
    simulated: f64,
}

fn id(model: &MjModel, kind: MjtObjBase, what: &'static str, name: &'static str) -> Result<usize> {
    model
        .name_to_id(kind, name)
        .ok_or(HarnessError::SceneElement { kind: what, name })
}

impl Sim {
    /// Loads `scene` (a generated scene file) for the task described by `spec`.
    ///
    /// # Errors
    /// When MuJoCo is not 3.17.0, refuses the file, or a named element is missing.
    pub fn load(scene: &Path, spec: SceneSpec) -> Result<Self> {
        crate::runtime::check_mujoco()?;
        if !scene.is_file() {
            return Err(HarnessError::SceneMissing {
                path: scene.to_owned(),
                task: spec.task.clone(),
            });
        }
        let model = MjModel::from_xml(scene).map_err(|source| HarnessError::SceneLoad {
            path: scene.to_owned(),
            source,
        })?;
        let joint = |name| id(&model, MjtObjBase::mjOBJ_JOINT, "joint", name);
        let (jx, jy, jz) = (joint("x")?, joint("y")?, joint("z")?);
        let adr = model.jnt_qposadr();
        let qpos = [adr[jx] as usize, adr[jy] as usize, adr[jz] as usize];
        let dof_z = model.jnt_dofadr()[jz] as usize;
        let act = |name| id(&model, MjtObjBase::mjOBJ_ACTUATOR, "actuator", name);
        let actuators = [
            act("servo_x")?,
            act("servo_y")?,
            act("press")?,
            act("feed")?,
        ];
        let sensor = |name| id(&model, MjtObjBase::mjOBJ_SENSOR, "sensor", name);
        let sensors = [
            model.sensor_adr()[sensor("ft_force")?] as usize,
            model.sensor_adr()[sensor("ft_torque")?] as usize,
        ];
        let body_b = id(&model, MjtObjBase::mjOBJ_BODY, "body", "part_b")?;
        let mocap =
            usize::try_from(model.body_mocapid()[body_b]).map_err(|_| HarnessError::Scene {
                path: scene.to_owned(),
                reason: "body part_b is not a mocap body".into(),
            })?;
        let grip_ids = [
            id(&model, MjtObjBase::mjOBJ_BODY, "body", "part_a")?,
            id(&model, MjtObjBase::mjOBJ_SITE, "site", "ft")?,
        ];
        let data = MjData::new(Box::new(model));
        Ok(Self {
            data,
            spec,
            qpos,
            dof_z,
            actuators,
            sensors,
            mocap,
            grip_ids,
            object: [0.0; 2],
            grip: [0.0; 2],
            simulated: 0.0,
        })
    }

    /// Loads a task's committed scene.
    ///
    /// # Errors
    /// As [`Sim::load`], and when the task has no `[geometry]`.
    pub fn of_task(task: &Task) -> Result<Self> {
        Self::load(&scene_path(task), SceneSpec::of_task(task)?)
    }

    /// The scene description this simulation was generated from.
    pub fn spec(&self) -> &SceneSpec {
        &self.spec
    }

    /// Each contact's normal force (N) at the end of the last motion, with the stiffness of
    /// the contact carrying it (N/m, from its `solref`).
    pub fn contact_loads(&self) -> Vec<(f64, f64)> {
        self.data
            .contact()
            .iter()
            .enumerate()
            .map(|(i, c)| (self.data.contact_force(i)[0], -c.solref[0]))
            .collect()
    }

    /// A contact motion at `xy`, then a slide to `slide`, if any.
    fn motion(&mut self, xy: [f64; 2], mut slide: Option<[f64; 2]>) -> Contact {
        let d = &mut self.data;
        d.reset();
        // The object offset is where the TCP aligns the parts: part B sits that far off, and
        // the grip's offset farther, under part A.
        let b = [self.object[0] + self.grip[0], self.object[1] + self.grip[1]];
        d.mocap_pos_mut()[self.mocap] = [b[0], b[1], 0.0];
        let start = [xy[0], xy[1], self.spec.top + APPROACH_CLEARANCE];
        for (k, &q) in self.qpos.iter().enumerate() {
            d.qpos_mut()[q] = start[k];
        }
        let ctrl = [xy[0], xy[1], -self.spec.force, 0.0];
        for (k, &a) in self.actuators.iter().enumerate() {
            d.ctrl_mut()[a] = ctrl[k];
        }
        let dt = d.model().opt().timestep;
        let (max_steps, settle_steps) = (
            (MAX_TIME / dt).round() as usize,
            (SETTLE_TIME / dt).round() as usize,
        );
        let entered = self.spec.top - self.spec.chamfers - ENTRY_DEPTH;
        let dropped = self.spec.top - DROP_DEPTH;
        // The slide: its end and length, and when it started (steps), once the press settled.
        let mut sliding: Option<([f64; 2], f64, usize)> = None;
        let (mut calm, mut steps) = (0, 0);
        while steps < max_steps {
            d.step();
            steps += 1;
            let z = d.qpos()[self.qpos[2]];
            if z < entered {
                d.ctrl_mut()[self.actuators[3]] = -INSERTION_SPEED.min(z.max(0.0) / INSERTION_TIME);
            }
            if let Some((to, len, t0)) = sliding {
                let done = ((steps - t0) as f64 * dt * SLIDE_SPEED / len).min(1.0);
                if z < dropped {
                    // The edge dropped in: hold the carriage where part A is.
                    let here = [d.qpos()[self.qpos[0]], d.qpos()[self.qpos[1]]];
                    d.ctrl_mut()[self.actuators[0]] = here[0];
                    d.ctrl_mut()[self.actuators[1]] = here[1];
                    sliding = None;
                } else if done < 1.0 {
                    for k in 0..2 {
                        d.ctrl_mut()[self.actuators[k]] = xy[k] + done * (to[k] - xy[k]);
                    }
                    calm = 0;
                    continue;
                } else {
                    d.ctrl_mut()[self.actuators[0]] = to[0];
                    d.ctrl_mut()[self.actuators[1]] = to[1];
                    sliding = None;
                }
            }
            if d.qvel()[self.dof_z].abs() < SETTLE_SPEED && d.ncon() > 0 {
                calm += 1;
            } else {
                calm = 0;
            }
            if calm >= settle_steps {
                match slide.take() {
                    Some(to) if z > entered => {
                        let len = (to[0] - xy[0]).hypot(to[1] - xy[1]).max(f64::MIN_POSITIVE);
                        sliding = Some((to, len, steps));
                        calm = 0;
                    }
                    _ => break,
                }
            }
        }
        let s = d.sensordata();
        let (f, t) = (self.sensors[0], self.sensors[1]);
        let raw = [s[f], s[f + 1], s[f + 2], s[t], s[t + 1], s[t + 2]];
        let q = d.qpos();
        let tcp = [q[self.qpos[0]], q[self.qpos[1]], q[self.qpos[2]]];
        let time = d.time();
        self.simulated += time;
        let settled = calm >= settle_steps;
        Contact {
            raw,
            tcp,
            settled,
            inserted: settled && tcp[2] < SUCCESS_HEIGHT,
            time,
        }
    }
}

impl World for Sim {
    fn set_object(&mut self, xy: [f64; 2]) {
        self.object = xy;
    }

    /// Moves part A by `xy` in the carriage and the sensor's site back by as much (a copy
    /// of the model with the new offsets replaces the running one: same layout).
    fn set_grip(&mut self, xy: [f64; 2]) {
        if xy == self.grip {
            return;
        }
        let mut model = self.data.model().clone();
        let [body, site] = self.grip_ids;
        let [sx, sy, sz] = self.spec.sensor_origin;
        model.body_pos_mut()[body] = [xy[0], xy[1], 0.0];
        model.site_pos_mut()[site] = [sx - xy[0], sy - xy[1], sz];
        // The copy has the running model's layout, so the swap cannot be refused.
        let _ = self.data.try_swap_model(Box::new(model));
        self.grip = xy;
    }

    fn contact_motion(&mut self, xy: [f64; 2]) -> Contact {
        self.motion(xy, None)
    }

    /// The slide moves at [`SLIDE_SPEED`] and stops where part A drops by [`DROP_DEPTH`]
    /// (the edge found the hole: the carriage holds there and part A goes in). A slide that
    /// found no hole ends with a fresh press where it stopped: after sliding, static friction
    /// holds part A against the stiff servos with up to mu times the imposed force sideways
    /// (15 N at 50 N and mu 0.3: 0.9 N.m about a sensor 60 mm up), which no map of static
    /// contacts explains; lifted by the approach clearance and pressed again, it reads the
    /// static contact there.
    fn slide_motion(&mut self, from: [f64; 2], to: [f64; 2]) -> Contact {
        let slid = self.motion(from, Some(to));
        if slid.inserted {
            return slid;
        }
        let pressed = self.motion([slid.tcp[0], slid.tcp[1]], None);
        Contact {
            time: slid.time + pressed.time,
            ..pressed
        }
    }

    fn simulated(&self) -> f64 {
        self.simulated
    }
}

/// The task `name` (a name or a task.toml path) and a simulation of its committed scene.
///
/// # Errors
/// When the task cannot be read or its scene cannot be loaded.
pub fn open_task(name: &str) -> Result<(Task, Sim)> {
    let task = Task::find(name)?;
    let sim = Sim::of_task(&task)?;
    Ok((task, sim))
}

/// Writes a task's scene from its `task.toml` and loads it back (MuJoCo accepts it and the
/// harness finds its elements); returns its path.
///
/// # Errors
/// When the scene cannot be written, or [`HarnessError::NewScene`] when it does not load.
pub fn regenerate_scene(task: &Task) -> Result<PathBuf> {
    let path = write_scene(task)?;
    let spec = SceneSpec::of_task(task)?;
    Sim::load(&path, spec).map_err(|e| HarnessError::NewScene {
        path: path.clone(),
        source: Box::new(e),
    })?;
    Ok(path)
}
