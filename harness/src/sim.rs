//! One task's MuJoCo work cell: load the generated scene, place part B per trial, and run
//! contact motions (approach along a with the imposed force until the contact settles).
//!
//! A contact motion starts from a reset state: the lift and the transfer to the next
//! approach point happen in free space and are not simulated; the carriage is placed
//! `APPROACH_CLEARANCE` above part B's top at the commanded (x, y) and the press motor
//! pushes with the imposed force against the feed's damping, a slow guarded approach.
//! Heights are measured along part B's axis, in its frame (part B may be tilted). When
//! part A has dropped into part B by [`ENTRY_DEPTH`], the feed drives it down at
//! [`INSERTION_SPEED`] until it is less than [`SUCCESS_HEIGHT`] above the goal, where the
//! motion ends: inserted (a tilted part A feeds along its own axis: the carriage's x, y
//! follow its height). A slide moves, and a twist turns the wrist, under force once the
//! press has settled; one that finds no hole ends as its speed settles. So each
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
use nalgebra::{Rotation3, UnitQuaternion, Vector3};

use crate::error::{HarnessError, Result};
use crate::scene::{
    APPROACH_CLEARANCE, SceneSpec, WRIST_JOINTS, scene_file_is, scene_path, write_scene,
    write_scene_of,
};
use crate::world::{Contact, Slid, World, foot, lean};

/// Longest contact motion (s of simulated time) before it is reported as not settled.
pub const MAX_TIME: f64 = 2.0;
/// The contact has settled when the approach speed stays below this (m/s) ...
pub const SETTLE_SPEED: f64 = 1.0e-4;
/// ... for this long (s) with at least one contact ...
pub const SETTLE_TIME: f64 = 0.01;
/// A contact that settled by its speed and stays out of part B is read once its torque
/// has changed by less than this over a [`TORQUE_WINDOW`] (N.m; half the F/T sensor's
/// noise): while part A still moves, the contacts' damping, the same for every sphere of
/// the bed, holds a share of its load by sphere count, not by area. Read by the speed
/// alone, an octagon 0.2 mm off and turned by 2 degrees read twice the static torque across
/// its offset (0.050 against 0.025 N.m, 0.025 after 0.1 s more). Whether the part went in
/// is decided when the speed settles: pressed on, MuJoCo's soft friction lets a part
/// resting on the hole's edge creep in (10-15 µm beyond the fit); a part that drops while
/// its torque settles is read as it was when its speed settled.
pub const SETTLE_TORQUE: f64 = 1.0e-3;
/// The window over which the torque must hold still (s), the first one starting when the
/// speed has settled. The bed's softest spheres (those standing for the thinnest slivers
/// of part A's face, at its outline) carry nothing at first: part A still rises out of the
/// bed at micrometres a second after the impact, and the damping of such a sphere outweighs
/// its spring, so that it would pull. They take their share over tens of milliseconds (a
/// square peg 0.1 mm off across a flat and 0.4 mm along it, on a strip 40 µm wide:
/// none of the load 10 ms after the speed settled, 12 % after 0.1 s, the map's centroid
/// model 11 %): a window of [`SETTLE_TIME`] could see no change there and read too early.
pub const TORQUE_WINDOW: f64 = 0.03;
/// Part A has entered part B once its frame is this far below part B's top and its
/// chamfers (m).
pub const ENTRY_DEPTH: f64 = 0.0001;
/// The feed's speed down to the goal once part A has entered (m/s) ...
pub const INSERTION_SPEED: f64 = 0.1;
/// ... at most the height left over this time (s): a part A that dropped in while its
/// torque settled is fed on to the goal and read as it was at rest on part B's top.
pub const INSERTION_TIME: f64 = 0.01;
/// Speed of a slide under force (m/s).
pub const SLIDE_SPEED: f64 = 0.005;
/// The largest Euler angle about an axis without a hinge that a TCP rotation may ask for
/// and have dropped (rad): two tilts' rotation vector [rx, ry, 0] holds a yaw of about
/// rx ry / 2 in the wrist's Euler angles, 0.6 mrad at 2 degrees each.
pub const UNHINGED: f64 = 1e-3;
/// Turning speed of a twist under force (rad/s): a degree in 87 time steps.
pub const TWIST_SPEED: f64 = 1.0;
/// A slide stops where part A has dropped this far below part B's top (m).
pub const DROP_DEPTH: f64 = 0.00001;
/// A contact motion that brings the task frame below this height above the goal has
/// inserted part A (m): fed in, it ends there (settling on the goal took 0.03-0.06 s
/// more of simulated time, for nothing the trial reads).
pub const SUCCESS_HEIGHT: f64 = 0.001;

/// One hinge joint of the wrist: the axis it turns about (0 x, 1 y, 2 z), its position
/// and its servo.
#[derive(Debug, Clone, Copy)]
struct Hinge {
    axis: usize,
    qpos: usize,
    actuator: usize,
}

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
    /// The wrist's hinges the scene has (those of the task's rotational DOFs).
    wrist: Vec<Hinge>,
    object: [f64; 2],
    /// Part B's rotation (rotation vector, rad).
    object_rot: [f64; 3],
    grip: [f64; 2],
    /// The wrist's commanded angles about x, y, z (Euler, R = Rz Ry Rx).
    wrist_angles: [f64; 3],
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
        // The hinges the task needs (the others are absent from its scene).
        let wrist = WRIST_JOINTS
            .iter()
            .filter_map(|&(name, servo, axis)| {
                let j = model.name_to_id(MjtObjBase::mjOBJ_JOINT, name)?;
                Some(act(servo).map(|actuator| Hinge {
                    axis,
                    qpos: adr[j] as usize,
                    actuator,
                }))
            })
            .collect::<Result<Vec<_>>>()?;
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
            wrist,
            object: [0.0; 2],
            object_rot: [0.0; 3],
            grip: [0.0; 2],
            wrist_angles: [0.0; 3],
            simulated: 0.0,
        })
    }

    /// Loads a task's scene: the committed one, which must be what its `task.toml`
    /// generates (a `[scene]` edited since `harness scene` wrote it is not run); a task
    /// without `[geometry]`, whose scene comes from its meshes and is not committed, gets it
    /// written first where it has none or another.
    ///
    /// # Errors
    /// As [`Sim::load`]; [`HarnessError::ScenesStale`] for a committed scene its task no
    /// longer generates; when the scene cannot be made or written.
    pub fn of_task(task: &Task) -> Result<Self> {
        let spec = SceneSpec::of_task(task)?;
        let path = scene_path(task);
        if !scene_file_is(task, &spec) {
            if task.geometry().is_err() {
                write_scene_of(task, &spec)?;
            } else if path.is_file() {
                return Err(HarnessError::ScenesStale { paths: vec![path] });
            }
        }
        Self::load(&path, spec)
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

    /// A contact motion at `xy`, then a slide or a twist, if any: where it ended, and the
    /// press a sweep started from, read at rest.
    fn motion(&mut self, xy: [f64; 2], mut sweep: Option<Sweep>) -> Slid {
        let d = &mut self.data;
        d.reset();
        // The object offset is where the TCP aligns the parts: part B sits that far off, and
        // the grip's offset farther, under part A.
        let b = [self.object[0] + self.grip[0], self.object[1] + self.grip[1]];
        d.mocap_pos_mut()[self.mocap] = [b[0], b[1], 0.0];
        let q = UnitQuaternion::from_scaled_axis(Vector3::from(self.object_rot));
        d.mocap_quat_mut()[self.mocap] = [q.w, q.i, q.j, q.k];
        // Heights are part B's: the task frame's z in part B's frame, the height above its
        // goal along its axis. On a tilted part B the top face's world height changes
        // across it (0.35 mm over 10 mm at 2 degrees), more than the depth at which part A
        // counts as having entered: read in the world, a press on the low side of the top
        // started the feed, which drove part A into the top with 1000 N.
        let origin = Vector3::new(b[0], b[1], 0.0);
        let height = |p: [f64; 3]| q.inverse_transform_vector(&(Vector3::from(p) - origin)).z;
        let axis_b = q * Vector3::z();
        // A tilted part A feeds along its own axis (the map's approach is the tool's): the
        // carriage's x, y follow its height by `lean`, so that `xy` is where the task frame
        // meets the goal's height (z = 0; at the top it is `lean` times that height off).
        // It starts the approach clearance above part B's top plane, higher by how far its
        // face's edge dips across that plane.
        let [ax, ay, az] = self.wrist_angles;
        let turn = Rotation3::from_euler_angles(ax, ay, az);
        let tool = turn * Vector3::z();
        let lean = lean(&turn);
        let tilted = lean != [0.0, 0.0];
        let dip = self.spec.face.reach * axis_b.cross(&tool).norm();
        let rise = self.spec.top + APPROACH_CLEARANCE + dip
            - axis_b.x * (xy[0] - b[0])
            - axis_b.y * (xy[1] - b[1]);
        let start = [
            xy[0],
            xy[1],
            rise / (axis_b.x * lean[0] + axis_b.y * lean[1] + axis_b.z),
        ];
        let follow = |z: f64, k: usize| z * lean[k];
        let mut planned = xy;
        let start = [
            xy[0] + follow(start[2], 0),
            xy[1] + follow(start[2], 1),
            start[2],
        ];
        for (k, &q) in self.qpos.iter().enumerate() {
            d.qpos_mut()[q] = start[k];
        }
        let ctrl = [start[0], start[1], -self.spec.force, 0.0];
        for (k, &a) in self.actuators.iter().enumerate() {
            d.ctrl_mut()[a] = ctrl[k];
        }
        for h in &self.wrist {
            d.qpos_mut()[h.qpos] = self.wrist_angles[h.axis];
            d.ctrl_mut()[h.actuator] = self.wrist_angles[h.axis];
        }
        let dt = d.model().opt().timestep;
        let (max_steps, settle_steps, torque_steps) = (
            (MAX_TIME / dt).round() as usize,
            (SETTLE_TIME / dt).round() as usize,
            (TORQUE_WINDOW / dt).round() as usize,
        );
        let entered = self.spec.top - self.spec.chamfers - ENTRY_DEPTH;
        let dropped = self.spec.top - DROP_DEPTH;
        // The sweep: where it goes, its speed (m/s or rad/s) and length (m or rad), and when
        // it started (steps), once the press settled.
        let mut sliding: Option<(Sweep, f64, f64, usize)> = None;
        let twist = self.wrist.iter().find(|h| h.axis == 2).copied();
        let yaw = self.wrist_angles[2];
        let (mut calm, mut steps) = (0, 0);
        let read = |d: &MjData<Box<MjModel>>| Reading::of(d, self.sensors, self.qpos, &self.wrist);
        // The reading when the speed settled, and the torque when the calm began.
        let mut first: Option<Reading> = None;
        let mut calm_torque = [0.0; 3];
        let mut pressed: Option<(Reading, f64)> = None;
        // Whether a sweep ran to its end without part A dropping: its end is pressed again.
        let mut swept = false;
        // Whether the feed brought part A within `SUCCESS_HEIGHT` of the goal: inserted.
        let mut fed_home = false;
        while steps < max_steps {
            d.step();
            steps += 1;
            let z = d.qpos()[self.qpos[2]];
            let h = height(self.qpos.map(|k| d.qpos()[k]));
            if h < entered {
                d.ctrl_mut()[self.actuators[3]] = -INSERTION_SPEED.min(h.max(0.0) / INSERTION_TIME);
                if h < SUCCESS_HEIGHT && first.is_none() {
                    fed_home = true;
                    break;
                }
            }
            if tilted {
                for (k, p) in planned.iter().enumerate() {
                    d.ctrl_mut()[self.actuators[k]] = p + follow(z, k);
                }
            }
            if let Some((to, speed, len, t0)) = sliding {
                let done = ((steps - t0) as f64 * dt * speed / len).min(1.0);
                let at = |k: usize, d: &MjData<Box<MjModel>>| d.qpos()[k];
                if h < dropped {
                    // The edge dropped in: hold the carriage (and wrist) where part A is.
                    for (k, p) in planned.iter_mut().enumerate() {
                        let here = at(self.qpos[k], d);
                        d.ctrl_mut()[self.actuators[k]] = here;
                        *p = here - follow(z, k);
                    }
                    if let Some(h) = twist {
                        d.ctrl_mut()[h.actuator] = at(h.qpos, d);
                    }
                    sliding = None;
                } else {
                    // Along the way, then exactly at its end.
                    let way = |from: f64, end: f64| {
                        if done < 1.0 {
                            from + done * (end - from)
                        } else {
                            end
                        }
                    };
                    match to {
                        Sweep::Line(end) => {
                            for (k, p) in planned.iter_mut().enumerate() {
                                *p = way(xy[k], end[k]);
                                d.ctrl_mut()[self.actuators[k]] = *p + follow(z, k);
                            }
                        }
                        Sweep::Turn(end) => {
                            if let Some(h) = twist {
                                d.ctrl_mut()[h.actuator] = way(yaw, end);
                            }
                        }
                    }
                    if done < 1.0 {
                        calm = 0;
                        continue;
                    }
                    sliding = None;
                    swept = true;
                }
            }
            if d.qvel()[self.dof_z].abs() < SETTLE_SPEED && d.ncon() > 0 {
                if calm == 0 {
                    calm_torque = read(d).torque();
                }
                calm += 1;
            } else if first.is_none() {
                calm = 0;
            }
            // Settled by the speed, then (a press that stays out, before a sweep too) by the
            // torque over a window from there.
            let torque_window = first.is_some();
            if calm
                >= if torque_window {
                    torque_steps
                } else {
                    settle_steps
                }
            {
                if h > entered {
                    let now = read(d);
                    if swept {
                        // A sweep that found no hole is read by the speed alone: its
                        // reading gives way to a fresh press (`pressed_again`), and held
                        // by static friction its torque drifts on for the whole
                        // `MAX_TIME` (1.5 s more of a 2.4 s trial on peg_in_hole).
                        first = Some(now);
                        break;
                    }
                    let at_rest = *first.get_or_insert(now);
                    if at_rest.tcp[2] - z > DROP_DEPTH {
                        break;
                    }
                    let change = (0..3).map(|k| (now.torque()[k] - calm_torque[k]).powi(2));
                    if !torque_window || change.sum::<f64>().sqrt() >= SETTLE_TORQUE {
                        calm_torque = now.torque();
                        calm = 1;
                        continue;
                    }
                    first = Some(now);
                }
                match sweep.take() {
                    Some(to) if h > entered => {
                        // The press the sweep starts from, read at rest.
                        pressed = first.take().map(|r| (r, d.time()));
                        let (speed, len) = match to {
                            Sweep::Line(end) => {
                                (SLIDE_SPEED, (end[0] - xy[0]).hypot(end[1] - xy[1]))
                            }
                            Sweep::Turn(end) => (TWIST_SPEED, (end - yaw).abs()),
                        };
                        sliding = Some((to, speed, len.max(f64::MIN_POSITIVE), steps));
                        calm = 0;
                    }
                    _ => break,
                }
            }
        }
        let settled = calm >= settle_steps || first.is_some() || fed_home;
        let contact = |r: Reading, settled: bool, time: f64| Contact {
            raw: r.raw,
            tcp: r.tcp,
            rot: Rotation3::from_euler_angles(r.angles[0], r.angles[1], r.angles[2])
                .scaled_axis()
                .into(),
            settled,
            inserted: settled && height(r.tcp) < SUCCESS_HEIGHT,
            time,
        };
        let time = d.time();
        self.simulated += time;
        Slid {
            end: contact(first.unwrap_or_else(|| read(d)), settled, time),
            start: pressed.map(|(r, t)| contact(r, true, t)),
            stopped: planned,
        }
    }
}

/// What the sensors and joints read at one moment of a contact motion.
#[derive(Debug, Clone, Copy)]
struct Reading {
    /// Force and torque at site `ft`, the site frame.
    raw: [f64; 6],
    /// Task frame position.
    tcp: [f64; 3],
    /// The wrist's Euler angles.
    angles: [f64; 3],
}

impl Reading {
    /// The reading of `d`, whose force and torque sensors start at `sensors`, task frame
    /// joints are at `qpos` and wrist hinges are `wrist`.
    fn of(
        d: &MjData<Box<MjModel>>,
        sensors: [usize; 2],
        qpos: [usize; 3],
        wrist: &[Hinge],
    ) -> Self {
        let s = d.sensordata();
        let (f, t) = (sensors[0], sensors[1]);
        let q = d.qpos();
        let mut angles = [0.0; 3];
        for h in wrist {
            angles[h.axis] = q[h.qpos];
        }
        Self {
            raw: [s[f], s[f + 1], s[f + 2], s[t], s[t + 1], s[t + 2]],
            tcp: [q[qpos[0]], q[qpos[1]], q[qpos[2]]],
            angles,
        }
    }

    /// The torque, the site frame.
    fn torque(&self) -> [f64; 3] {
        [self.raw[3], self.raw[4], self.raw[5]]
    }
}

/// What a contact motion does once the press has settled.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Sweep {
    /// Slides the carriage to this x, y (m).
    Line([f64; 2]),
    /// Turns the wrist about z to this yaw (rad).
    Turn(f64),
}

impl Sim {
    /// A sweep's end: itself where part A went in, else a fresh press at `at` (none: where
    /// it stopped; after sliding or turning, static friction holds part A against the stiff
    /// servos with up to mu times the imposed force, which no map of static contacts
    /// explains; lifted by the approach clearance and pressed again, it reads the static
    /// contact).
    fn pressed_again(&mut self, swept: Contact, at: Option<[f64; 2]>) -> Contact {
        if swept.inserted {
            return swept;
        }
        // Where a motion is commanded: a tilted carriage stands beside it.
        let [ax, ay, az] = self.wrist_angles;
        let at = at.unwrap_or_else(|| foot(swept.tcp, &Rotation3::from_euler_angles(ax, ay, az)));
        let pressed = self.motion(at, None).end;
        Contact {
            time: swept.time + pressed.time,
            ..pressed
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

    fn set_object_rotation(&mut self, rot: [f64; 3]) -> Result<()> {
        self.object_rot = rot;
        Ok(())
    }

    /// The wrist's hinges take the rotation's Euler angles (R = Rz Ry Rx). Without a yaw
    /// hinge the two tilts point the tool's axis exactly where R does, and what is left is
    /// a turn about that axis: Euler angles with their yaw dropped would tilt the axis by
    /// about that yaw times the tilt (4 microradians at 1 and -1 degrees), and a flat face
    /// on a rim shifts its load over such a tilt. An angle about an axis the scene has no
    /// hinge for is dropped up to [`UNHINGED`], refused beyond.
    fn set_tcp_rotation(&mut self, rot: [f64; 3]) -> Result<()> {
        let r = Rotation3::from_scaled_axis(Vector3::from(rot));
        let mut angles = if self.wrist.iter().any(|h| h.axis == 2) {
            let (rx, ry, rz) = r.euler_angles();
            [rx, ry, rz]
        } else {
            let n = r * Vector3::z();
            let (rx, ry) = ((-n.y).clamp(-1.0, 1.0).asin(), n.x.atan2(n.z));
            let about_axis = (Rotation3::from_euler_angles(rx, ry, 0.0).inverse() * r).angle();
            [rx, ry, about_axis]
        };
        for (k, a) in angles.iter_mut().enumerate() {
            if self.wrist.iter().all(|h| h.axis != k) && a.abs() <= UNHINGED {
                *a = 0.0;
            }
        }
        if let Some(axis) =
            (0..3).find(|&k| angles[k] != 0.0 && self.wrist.iter().all(|h| h.axis != k))
        {
            return Err(HarnessError::Invalid {
                what: "TCP rotation",
                reason: format!(
                    "the scene of task {} has no wrist joint `{}` to turn {} rad about",
                    self.spec.task,
                    ["rx", "ry", "rz"][axis],
                    angles[axis]
                ),
            });
        }
        self.wrist_angles = angles;
        Ok(())
    }

    fn contact_motion(&mut self, xy: [f64; 2]) -> Contact {
        self.motion(xy, None).end
    }

    /// The slide moves at [`SLIDE_SPEED`] and stops where part A drops by [`DROP_DEPTH`]
    /// (the edge found the hole: the carriage holds there and part A goes in). A slide that
    /// found no hole ends with a fresh press, where it stopped or at `press`: after sliding,
    /// static friction holds part A against the stiff servos with up to mu times the
    /// imposed force sideways (15 N at 50 N and mu 0.3: 0.9 N.m about a sensor 60 mm up),
    /// which no map of static contacts explains; lifted by the approach clearance and
    /// pressed again, it reads a static contact.
    fn slide_motion(&mut self, from: [f64; 2], to: [f64; 2], press: [f64; 2]) -> Slid {
        let slid = self.motion(from, Some(Sweep::Line(to)));
        Slid {
            end: self.pressed_again(slid.end, (press != to).then_some(press)),
            ..slid
        }
    }

    /// The twist turns at [`TWIST_SPEED`] and, like a slide, stops where part A drops by
    /// [`DROP_DEPTH`]; one that found no hole ends with a fresh press where it stopped.
    fn twist_motion(&mut self, xy: [f64; 2], from: f64, to: f64) -> Result<Contact> {
        // Either end refused where the scene has no hinge about z; the wrist starts at `from`.
        self.set_tcp_rotation([0.0, 0.0, to])?;
        self.set_tcp_rotation([0.0, 0.0, from])?;
        let twisted = self.motion(xy, Some(Sweep::Turn(to))).end;
        self.wrist_angles[2] = twisted.rot[2];
        Ok(self.pressed_again(twisted, None))
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
