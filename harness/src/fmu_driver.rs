//! `FtFusion.fmu` driven through the `fmi` crate's FMI 2.0 Co-Simulation importer, the way
//! any system simulator would: variables looked up by name in its modelDescription.xml,
//! one instance per trial, a new measurement on each rising edge of `contact`.

use std::ffi::CString;
use std::path::{Path, PathBuf};

use fmi::fmi2::import::Fmi2Import;
use fmi::fmi2::instance::{CoSimulation, Common, InstanceCS};
use fmi::traits::FmiImport;

use model_description as md;

use crate::error::{HarnessError, Result};
use crate::fmu_log;
use crate::vision::Features;

/// Communication step of the FMU (s).
const STEP: f64 = 0.001;

/// The FMU as `cargo xtask fmu` builds it, in this source tree.
pub fn default_fmu_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/fmu/FtFusion.fmu")
}

/// Estimator settings handed to the FMU's parameters (`None`: the FMU's default).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Settings {
    /// `map`: an absolute path of an FT-Map file.
    pub map: Option<PathBuf>,
    /// `centre_map`: an absolute path of the map's centre map.
    pub centre_map: Option<PathBuf>,
    /// `seed`.
    pub seed: Option<i32>,
    /// `particles`.
    pub particles: Option<i32>,
    /// `iterations` per measurement.
    pub iterations: Option<i32>,
    /// `sigma_torque` (N m).
    pub sigma_torque: Option<f64>,
    /// `sigma_force` (N).
    pub sigma_force: Option<f64>,
    /// `sigma_depth` (m).
    pub sigma_depth: Option<f64>,
    /// `mismatch` (share of the measured magnitudes).
    pub mismatch: Option<f64>,
    /// `mismatch_angle` (rad).
    pub mismatch_angle: Option<f64>,
    /// `mismatch_position` (m).
    pub mismatch_position: Option<f64>,
    /// `mismatch_interpolation` (share of the lookup's interpolation error).
    pub mismatch_interpolation: Option<f64>,
    /// `mismatch_lever` (m: the pressure centre's miss).
    pub mismatch_lever: Option<f64>,
    /// `mismatch_reach` (grid steps; 0: every contact's mismatch afresh).
    pub mismatch_reach: Option<f64>,
    /// `tilt_floor` (rad; negative: off).
    pub tilt_floor: Option<f64>,
    /// `lost` (prior probability per measurement that the particles lost the truth).
    pub lost: Option<f64>,
    /// `vision`: an absolute path of a vision model file.
    pub vision: Option<PathBuf>,
    /// `sigma_vision` (px).
    pub sigma_vision: Option<f64>,
    /// `vision_method` (0 relative, 1 recalibration).
    pub vision_method: Option<i32>,
    /// `trace`: an absolute path of a file the particles are appended to at every
    /// measurement ([`crate::campaign::run_campaign`] traces a campaign's first trial only).
    pub trace: Option<PathBuf>,
}

/// The FMU's estimate after a measurement.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct Estimate {
    /// `object.x`, `object.y` (m).
    pub object: [f64; 2],
    /// `object.x_std`, `object.y_std` (m).
    pub std: [f64; 2],
    /// `object.xy_corr`: the correlation of the two.
    pub corr: f64,
    /// `grip.x`, `grip.y` (m; 0 where the map's grip is certain).
    pub grip: [f64; 2],
    /// `grip.x_std`, `grip.y_std` (m).
    pub grip_std: [f64; 2],
    /// `object.rx`, `object.ry`, `object.rz` (rad; 0 where the map's rotations are certain).
    pub rot: [f64; 3],
    /// `object.rx_std`, `object.ry_std`, `object.rz_std` (rad).
    pub rot_std: [f64; 3],
    /// `confidence` (0..1).
    pub confidence: f64,
    /// `converged`.
    pub converged: bool,
    /// `ess`.
    pub ess: f64,
    /// `measurements`.
    pub measurements: i32,
    /// `clusters`.
    pub clusters: i32,
}

/// A slide or twist under force that a contact followed: where the TCP's x, y (m) and rz
/// (rad) stood when it started, and where it ended when part A was pressed elsewhere after
/// it (none: the contact is where it ended).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Swept {
    /// Where it started (inputs `slide_start.*`).
    pub start: [f64; 3],
    /// Where it ended, the contact pressed elsewhere after it (inputs `slide_end.*`).
    pub end: Option<[f64; 3]>,
}

/// Value references of the variables the harness uses.
#[derive(Debug, Clone)]
struct Refs {
    wrench: [u32; 6],
    tcp: [u32; 6],
    contact: u32,
    slide: u32,
    slide_start: [u32; 3],
    slide_end_valid: u32,
    slide_end: [u32; 3],
    object: [u32; 2],
    std: [u32; 2],
    /// grip.x, grip.y, grip.x_std, grip.y_std.
    grip: [u32; 4],
    /// object.rx, ry, rz, then their std.
    rot: [u32; 6],
    /// confidence, ess, object.xy_corr.
    reals: [u32; 3],
    ints: [u32; 2],
    converged: u32,
    map: u32,
    centre_map: u32,
    seed: u32,
    particles: u32,
    iterations: u32,
    sigma_torque: u32,
    mismatch: u32,
    mismatch_angle: u32,
    mismatch_position: u32,
    mismatch_interpolation: u32,
    mismatch_lever: u32,
    mismatch_reach: u32,
    tilt_floor: u32,
    lost: u32,
    sigma_force: u32,
    sigma_depth: u32,
    vision: u32,
    sigma_vision: u32,
    vision_method: u32,
    trace: u32,
    /// vision.left_distance, right_distance, passive_left, passive_right.
    features: [u32; 4],
    vision_valid: u32,
}

/// A loaded (unpacked) FMU, from which trials instantiate estimators.
pub struct Fmu {
    import: Fmi2Import,
    refs: Refs,
    path: PathBuf,
}

fn fmi_err(what: impl Into<String>) -> impl FnOnce(fmi::fmi2::Fmi2Error) -> HarnessError {
    let what = what.into();
    move |e| HarnessError::Fmu {
        what,
        log: fmu_log::take(),
        source: e.into(),
    }
}

/// The value references of a named group of variables, in the group's order.
fn group<const N: usize>(names: [&str; N], vr: impl Fn(&str) -> Result<u32>) -> Result<[u32; N]> {
    let mut refs = [0; N];
    for (r, name) in refs.iter_mut().zip(names) {
        *r = vr(name)?;
    }
    Ok(refs)
}

impl Fmu {
    /// Loads the FMU at `path`.
    ///
    /// # Errors
    /// [`HarnessError::FmuMissing`] (naming `cargo xtask fmu`) when there is no file;
    /// [`HarnessError::Fmu`] when it cannot be unpacked or lacks a variable.
    pub fn load(path: &Path) -> Result<Self> {
        fmu_log::install();
        if !path.is_file() {
            return Err(HarnessError::FmuMissing {
                path: path.to_owned(),
            });
        }
        let import = fmi::import::from_path::<Fmi2Import>(path).map_err(|e| HarnessError::Fmu {
            what: format!("import {}", path.display()),
            log: Vec::new(),
            source: e.into(),
        })?;
        let md = import.model_description();
        let vr = |name: &str| {
            md.model_variable_by_name(name)
                .map(|v| v.value_reference)
                .map_err(|e| HarnessError::Fmu {
                    what: format!("variable `{name}`"),
                    log: Vec::new(),
                    source: e.into(),
                })
        };
        let refs = Refs {
            wrench: group(md::WRENCH, vr)?,
            tcp: group(md::TCP, vr)?,
            contact: vr(md::CONTACT)?,
            slide: vr(md::SLIDE)?,
            slide_start: group(md::SLIDE_START, vr)?,
            slide_end_valid: vr(md::SLIDE_END_VALID)?,
            slide_end: group(md::SLIDE_END, vr)?,
            object: [vr(md::OBJECT[0])?, vr(md::OBJECT[1])?],
            std: [vr(md::OBJECT_STD[0])?, vr(md::OBJECT_STD[1])?],
            grip: [
                vr(md::GRIP[0])?,
                vr(md::GRIP[1])?,
                vr(md::GRIP_STD[0])?,
                vr(md::GRIP_STD[1])?,
            ],
            rot: [
                vr(md::OBJECT[3])?,
                vr(md::OBJECT[4])?,
                vr(md::OBJECT[5])?,
                vr(md::OBJECT_STD[3])?,
                vr(md::OBJECT_STD[4])?,
                vr(md::OBJECT_STD[5])?,
            ],
            reals: [vr("confidence")?, vr("ess")?, vr(md::OBJECT_XY_CORR)?],
            ints: [vr("measurements")?, vr("clusters")?],
            converged: vr("converged")?,
            map: vr("map")?,
            centre_map: vr("centre_map")?,
            seed: vr("seed")?,
            particles: vr("particles")?,
            iterations: vr("iterations")?,
            sigma_torque: vr("sigma_torque")?,
            mismatch: vr("mismatch")?,
            mismatch_angle: vr("mismatch_angle")?,
            mismatch_position: vr("mismatch_position")?,
            mismatch_interpolation: vr("mismatch_interpolation")?,
            mismatch_lever: vr("mismatch_lever")?,
            mismatch_reach: vr("mismatch_reach")?,
            tilt_floor: vr("tilt_floor")?,
            lost: vr("lost")?,
            sigma_force: vr("sigma_force")?,
            sigma_depth: vr("sigma_depth")?,
            vision: vr("vision")?,
            sigma_vision: vr("sigma_vision")?,
            vision_method: vr("vision_method")?,
            trace: vr("trace")?,
            features: group(md::VISION_FEATURES, vr)?,
            vision_valid: vr(md::VISION_VALID)?,
        };
        Ok(Self {
            import,
            refs,
            path: path.to_owned(),
        })
    }

    /// The FMU file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// A new, initialised estimator instance with `settings`.
    ///
    /// # Errors
    /// When the FMU refuses to instantiate, a parameter, or initialisation.
    pub fn estimator(&self, settings: &Settings) -> Result<Estimator> {
        let mut inst = self
            .import
            .instantiate_cs("harness", false, false)
            .map_err(|e| HarnessError::Fmu {
                what: "fmi2Instantiate".into(),
                log: fmu_log::take(),
                source: e.into(),
            })?;
        let r = &self.refs;
        for (vr, file, name) in [
            (r.map, &settings.map, "map"),
            (r.centre_map, &settings.centre_map, "centre_map"),
            (r.vision, &settings.vision, "vision"),
            (r.trace, &settings.trace, "trace"),
        ] {
            if let Some(file) = file {
                let text = file.to_string_lossy().into_owned();
                let c = CString::new(text).map_err(|e| HarnessError::Fmu {
                    what: format!("parameter {name}"),
                    log: Vec::new(),
                    source: e.into(),
                })?;
                inst.set_string(&[vr], &[c])
                    .map_err(fmi_err(format!("set {name}")))?;
            }
        }
        let ints = [
            (r.seed, settings.seed, "seed"),
            (r.particles, settings.particles, "particles"),
            (r.iterations, settings.iterations, "iterations"),
            (r.vision_method, settings.vision_method, "vision_method"),
        ];
        for (vr, v, name) in ints {
            if let Some(v) = v {
                inst.set_integer(&[vr], &[v])
                    .map_err(fmi_err(format!("set {name}")))?;
            }
        }
        let reals = [
            (r.sigma_torque, settings.sigma_torque, "sigma_torque"),
            (r.sigma_force, settings.sigma_force, "sigma_force"),
            (r.sigma_depth, settings.sigma_depth, "sigma_depth"),
            (r.mismatch, settings.mismatch, "mismatch"),
            (r.mismatch_angle, settings.mismatch_angle, "mismatch_angle"),
            (
                r.mismatch_position,
                settings.mismatch_position,
                "mismatch_position",
            ),
            (
                r.mismatch_interpolation,
                settings.mismatch_interpolation,
                "mismatch_interpolation",
            ),
            (r.mismatch_lever, settings.mismatch_lever, "mismatch_lever"),
            (r.mismatch_reach, settings.mismatch_reach, "mismatch_reach"),
            (r.tilt_floor, settings.tilt_floor, "tilt_floor"),
            (r.lost, settings.lost, "lost"),
            (r.sigma_vision, settings.sigma_vision, "sigma_vision"),
        ];
        for (vr, v, name) in reals {
            if let Some(v) = v {
                inst.set_real(&[vr], &[v])
                    .map_err(fmi_err(format!("set {name}")))?;
            }
        }
        inst.setup_experiment(None, 0.0, None)
            .map_err(fmi_err("fmi2SetupExperiment"))?;
        Common::enter_initialization_mode(&mut inst)
            .map_err(fmi_err("fmi2EnterInitializationMode"))?;
        Common::exit_initialization_mode(&mut inst)
            .map_err(fmi_err("fmi2ExitInitializationMode"))?;
        Ok(Estimator {
            inst,
            refs: r.clone(),
            time: 0.0,
        })
    }
}

/// One FMU instance estimating one trial's object pose.
pub struct Estimator {
    inst: InstanceCS,
    refs: Refs,
    time: f64,
}

impl Estimator {
    fn step(&mut self) -> Result<()> {
        self.inst
            .do_step(self.time, STEP, true)
            .map_err(fmi_err("fmi2DoStep"))?;
        self.time += STEP;
        Ok(())
    }

    /// Hands one settled contact to the FMU (wrench in the map's convention, TCP position
    /// and rotation vector relative to the nominal goal; `swept`, the slide or twist under
    /// force it followed), with an image's features when there are any, and returns its
    /// new estimate.
    ///
    /// # Errors
    /// When the FMU refuses an input or the step.
    pub fn measure(
        &mut self,
        wrench: [f64; 6],
        tcp: [f64; 3],
        rot: [f64; 3],
        swept: Option<Swept>,
        image: Option<&Features>,
    ) -> Result<Estimate> {
        let r = &self.refs;
        self.inst
            .set_real(&r.wrench, &wrench)
            .map_err(fmi_err("set wrench"))?;
        let end = swept.and_then(|s| s.end);
        self.inst
            .set_real(&r.slide_start, &swept.map_or([0.0; 3], |s| s.start))
            .map_err(fmi_err("set slide_start"))?;
        self.inst
            .set_real(&r.slide_end, &end.unwrap_or([0.0; 3]))
            .map_err(fmi_err("set slide_end"))?;
        self.inst
            .set_boolean(
                &[r.slide, r.slide_end_valid],
                &[i32::from(swept.is_some()), i32::from(end.is_some())],
            )
            .map_err(fmi_err("set slide"))?;
        self.pulse(
            r.contact,
            [tcp[0], tcp[1], tcp[2], rot[0], rot[1], rot[2]],
            image,
        )
    }

    /// Hands an image's features alone (no contact; the task frame at `tcp`, unturned) to
    /// the FMU and returns its new estimate.
    ///
    /// # Errors
    /// When the FMU refuses an input or the step.
    pub fn look(&mut self, tcp: [f64; 3], image: &Features) -> Result<Estimate> {
        let valid = self.refs.vision_valid;
        self.pulse(valid, [tcp[0], tcp[1], tcp[2], 0.0, 0.0, 0.0], Some(image))
    }

    /// Sets the TCP pose (x, y, z, rotation vector) and the image inputs, raises the
    /// Boolean `trigger` for one step (the FMU measures on its rising edge), reads the
    /// estimate and lowers everything again.
    fn pulse(&mut self, trigger: u32, tcp: [f64; 6], image: Option<&Features>) -> Result<Estimate> {
        let r = self.refs.clone();
        self.inst
            .set_real(&r.tcp, &tcp)
            .map_err(fmi_err("set tcp"))?;
        if let Some(f) = image {
            let v = [f.distances[0], f.distances[1], f.passive[0], f.passive[1]];
            self.inst
                .set_real(&r.features, &v)
                .map_err(fmi_err("set vision features"))?;
            self.inst
                .set_boolean(&[r.vision_valid], &[1])
                .map_err(fmi_err("set vision.valid"))?;
        }
        self.inst
            .set_boolean(&[trigger], &[1])
            .map_err(fmi_err("set contact / vision.valid"))?;
        self.step()?;
        let estimate = self.estimate()?;
        self.inst
            .set_boolean(&[r.contact, r.vision_valid], &[0, 0])
            .map_err(fmi_err("lower contact, vision.valid"))?;
        self.step()?;
        Ok(estimate)
    }

    /// The FMU's current outputs.
    ///
    /// # Errors
    /// When the FMU refuses a get call.
    pub fn estimate(&mut self) -> Result<Estimate> {
        let r = &self.refs;
        let (mut object, mut std, mut grip, mut rot, mut reals, mut ints, mut conv) = (
            [0.0; 2],
            [0.0; 2],
            [0.0; 4],
            [0.0; 6],
            [0.0; 3],
            [0; 2],
            [0],
        );
        self.inst
            .get_real(&r.object, &mut object)
            .map_err(fmi_err("get object"))?;
        self.inst
            .get_real(&r.std, &mut std)
            .map_err(fmi_err("get object std"))?;
        self.inst
            .get_real(&r.grip, &mut grip)
            .map_err(fmi_err("get grip and its std"))?;
        self.inst
            .get_real(&r.rot, &mut rot)
            .map_err(fmi_err("get object rotations and their std"))?;
        self.inst
            .get_real(&r.reals, &mut reals)
            .map_err(fmi_err("get confidence, ess, object.xy_corr"))?;
        self.inst
            .get_integer(&r.ints, &mut ints)
            .map_err(fmi_err("get measurements, clusters"))?;
        self.inst
            .get_boolean(&[r.converged], &mut conv)
            .map_err(fmi_err("get converged"))?;
        Ok(Estimate {
            object,
            std,
            corr: reals[2],
            grip: [grip[0], grip[1]],
            grip_std: [grip[2], grip[3]],
            rot: [rot[0], rot[1], rot[2]],
            rot_std: [rot[3], rot[4], rot[5]],
            confidence: reals[0],
            converged: conv[0] != 0,
            ess: reals[1],
            measurements: ints[0],
            clusters: ints[1],
        })
    }
}

impl Drop for Estimator {
    fn drop(&mut self) {
        // The instance is freed by its own Drop; terminate first as FMI 2.0 asks.
        let _ = Common::terminate(&mut self.inst);
    }
}
