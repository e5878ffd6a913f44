//! The work cell's calibrated camera: a pinhole model built from the MJCF `<camera>` (its
//! `fovy`, the offscreen resolution, and its pose `cam_xpos`/`cam_xmat` after `mj_forward`),
//! used to project CAD points to pixels, and headless offscreen rendering of the same camera
//! through mujoco-rs's renderer (Mesa's software EGL on machines without a GPU).
//!
//! Pixel coordinates: `u` to the right, `v` down, the centre of pixel (column i, row j) at
//! (i, j); the image spans [-0.5, w - 0.5] x [-0.5, h - 0.5].

use std::path::Path;

use mujoco_rs::prelude::*;
use mujoco_rs::renderer::{MjRenderer, png};

use crate::error::{HarnessError, Result, create_parent};
use crate::scene::{LOOK_CLEARANCE, SceneSpec};

pub use ftmap::vision::Camera;

/// The camera `cam` of a model whose data went through `mj_forward` (or a step): MuJoCo's
/// own calibration of it.
pub fn from_data(data: &MjData<Box<MjModel>>, cam: usize) -> Camera {
    let model = data.model();
    let g = &model.vis().global;
    Camera {
        width: g.offwidth as usize,
        height: g.offheight as usize,
        fovy: model.cam_fovy()[cam],
        pos: data.cam_xpos()[cam],
        xmat: data.cam_xmat()[cam],
    }
}

/// An 8-bit RGB image, rows top to bottom.
#[derive(Debug, Clone, PartialEq)]
pub struct RgbImage {
    /// Width (px).
    pub width: usize,
    /// Height (px).
    pub height: usize,
    /// `width * height * 3` bytes.
    pub data: Vec<u8>,
}

impl RgbImage {
    /// Grey values (ITU-R BT.601 luma), one f32 per pixel, 0..255.
    pub fn to_gray(&self) -> Vec<f32> {
        self.data
            .chunks_exact(3)
            .map(|p| 0.299 * f32::from(p[0]) + 0.587 * f32::from(p[1]) + 0.114 * f32::from(p[2]))
            .collect()
    }

    /// An image showing grey values (clamped to 0..255).
    pub fn from_gray(width: usize, height: usize, gray: &[f32]) -> Self {
        let data = gray
            .iter()
            .flat_map(|&g| [g.clamp(0.0, 255.0).round() as u8; 3])
            .collect();
        Self {
            width,
            height,
            data,
        }
    }

    /// Sets a pixel (ignored outside the image).
    pub fn put(&mut self, x: i64, y: i64, rgb: [u8; 3]) {
        if x >= 0 && y >= 0 && (x as usize) < self.width && (y as usize) < self.height {
            let i = 3 * (y as usize * self.width + x as usize);
            self.data[i..i + 3].copy_from_slice(&rgb);
        }
    }

    /// Draws a line between two pixel positions (one pixel wide).
    pub fn line(&mut self, a: [f64; 2], b: [f64; 2], rgb: [u8; 3]) {
        let n = (b[0] - a[0])
            .abs()
            .max((b[1] - a[1]).abs())
            .ceil()
            .clamp(1.0, 1.0e5) as usize;
        for k in 0..=n {
            let t = k as f64 / n as f64;
            self.put(
                (a[0] + t * (b[0] - a[0])).round() as i64,
                (a[1] + t * (b[1] - a[1])).round() as i64,
                rgb,
            );
        }
    }

    /// Draws a small cross at a pixel position.
    pub fn cross(&mut self, p: [f64; 2], rgb: [u8; 3]) {
        let (x, y) = (p[0].round() as i64, p[1].round() as i64);
        for d in -3..=3 {
            self.put(x + d, y, rgb);
            self.put(x, y + d, rgb);
        }
    }

    /// Writes the image as PNG.
    ///
    /// # Errors
    /// When the file cannot be written.
    pub fn save_png(&self, path: &Path) -> Result<()> {
        create_parent(path)?;
        let file = std::fs::File::create(path).map_err(|e| HarnessError::io(path, e))?;
        let mut enc = png::Encoder::new(
            std::io::BufWriter::new(file),
            self.width as u32,
            self.height as u32,
        );
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let fail = |e: png::EncodingError| HarnessError::plot(path, e);
        let mut w = enc.write_header().map_err(fail)?;
        w.write_image_data(&self.data).map_err(fail)?;
        w.finish().map_err(fail)
    }
}

/// A task's scene loaded for the vision camera: places part B and part A, renders.
pub struct CameraScene {
    data: MjData<Box<MjModel>>,
    renderer: Option<MjRenderer>,
    spec: SceneSpec,
    cam: usize,
    qpos: [usize; 3],
    mocap: usize,
}

fn missing(kind: &'static str, name: &'static str) -> HarnessError {
    HarnessError::SceneElement { kind, name }
}

impl CameraScene {
    /// Loads `scene` (the generated scene of `spec`, or any MJCF text with the same names
    /// given through `xml`) and finds its camera `vision`.
    ///
    /// # Errors
    /// When MuJoCo refuses the scene or the camera, the joints or part B are missing.
    pub fn load(scene: &Path, spec: SceneSpec) -> Result<Self> {
        crate::runtime::check_mujoco()?;
        let model = MjModel::from_xml(scene).map_err(|source| HarnessError::SceneLoad {
            path: scene.to_owned(),
            source,
        })?;
        Self::with_model(model, spec)
    }

    /// As [`CameraScene::load`], from MJCF text (mesh paths must be absolute or `meshdir` set).
    ///
    /// # Errors
    /// As [`CameraScene::load`].
    pub fn from_xml_string(xml: &str, spec: SceneSpec) -> Result<Self> {
        crate::runtime::check_mujoco()?;
        let model = MjModel::from_xml_string(xml).map_err(|source| HarnessError::SceneLoad {
            path: "<string>".into(),
            source,
        })?;
        Self::with_model(model, spec)
    }

    fn with_model(model: MjModel, spec: SceneSpec) -> Result<Self> {
        let name = spec
            .camera
            .as_ref()
            .map(|c| c.name.clone())
            .ok_or(missing("camera", "vision"))?;
        let cam = model
            .name_to_id(MjtObjBase::mjOBJ_CAMERA, &name)
            .ok_or(missing("camera", "vision"))?;
        let joint = |n: &'static str| {
            model
                .name_to_id(MjtObjBase::mjOBJ_JOINT, n)
                .ok_or(missing("joint", n))
        };
        let adr = model.jnt_qposadr();
        let qpos = [
            adr[joint("x")?] as usize,
            adr[joint("y")?] as usize,
            adr[joint("z")?] as usize,
        ];
        let body_b = model
            .name_to_id(MjtObjBase::mjOBJ_BODY, "part_b")
            .ok_or(missing("body", "part_b"))?;
        let mocap = usize::try_from(model.body_mocapid()[body_b])
            .map_err(|_| missing("mocap body", "part_b"))?;
        let mut data = MjData::new(Box::new(model));
        data.forward();
        Ok(Self {
            data,
            renderer: None,
            spec,
            cam,
            qpos,
            mocap,
        })
    }

    /// The scene description.
    pub fn spec(&self) -> &SceneSpec {
        &self.spec
    }

    /// Places part B at `object` (x, y) and the task frame at `tcp` (x, y, z) relative to the
    /// nominal goal (m), then runs `mj_forward`.
    pub fn place(&mut self, object: [f64; 2], tcp: [f64; 3]) {
        let d = &mut self.data;
        d.reset();
        d.mocap_pos_mut()[self.mocap] = [object[0], object[1], 0.0];
        for (k, &q) in self.qpos.iter().enumerate() {
            d.qpos_mut()[q] = tcp[k];
        }
        d.forward();
    }

    /// The task frame's height where a first image is taken (m): part A hovers
    /// [`LOOK_CLEARANCE`] above part B.
    pub fn look_height(&self) -> f64 {
        self.spec.top + LOOK_CLEARANCE
    }

    /// The pinhole model of the camera, as placed.
    pub fn camera(&self) -> Camera {
        from_data(&self.data, self.cam)
    }

    /// Renders the camera's image of the scene as placed.
    ///
    /// # Errors
    /// When no OpenGL context can be made (no EGL device) or rendering fails.
    pub fn render(&mut self) -> Result<RgbImage> {
        let fail = |source| HarnessError::Render { source };
        let r = match self.renderer.as_mut() {
            Some(r) => r,
            None => self.renderer.insert(
                MjRenderer::builder()
                    .camera(MjvCamera::new_fixed(self.cam))
                    .build(self.data.model())
                    .map_err(fail)?,
            ),
        };
        r.sync_data(&mut self.data).map_err(fail)?;
        r.render().map_err(fail)?;
        let data = r.rgb_flat().map(<[u8]>::to_vec).unwrap_or_default();
        let cam = from_data(&self.data, self.cam);
        Ok(RgbImage {
            width: cam.width,
            height: cam.height,
            data,
        })
    }
}
