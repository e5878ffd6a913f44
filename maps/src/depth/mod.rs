//! Orthographic depth images along the approach vector (the paper's z-buffer method) and
//! the backend trait that renders them and reduces their shifted differences to contacts.

use nalgebra::{Isometry3, Point3, Vector3};

use crate::error::Result;
use crate::mesh::Mesh;

pub mod cpu;
#[cfg(feature = "gpu")]
pub mod gpu;

/// Height value of a pixel where A has no surface (never in contact).
pub const EMPTY_A: f32 = f32::INFINITY;
/// Height value of a pixel where B has no surface (nothing to rest on).
pub const EMPTY_B: f32 = f32::NEG_INFINITY;

/// An orthonormal frame whose w axis points against the approach vector: images are
/// taken in (u, v), heights along w.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct View {
    /// Image x axis.
    pub u: Vector3<f64>,
    /// Image y axis.
    pub v: Vector3<f64>,
    /// Height axis, -a.
    pub w: Vector3<f64>,
}

impl View {
    /// The view for approach vector `a` (any length > 0): w = -a, u chosen from x (or y
    /// when a is near x), v = w x u.
    pub fn along(a: Vector3<f64>) -> Self {
        let w = -a.normalize();
        let seed = if w.x.abs() < 0.9 {
            Vector3::x()
        } else {
            Vector3::y()
        };
        let u = (seed - w * seed.dot(&w)).normalize();
        let v = w.cross(&u);
        Self { u, v, w }
    }

    /// (u, v, w) coordinates of a point.
    pub fn project(&self, p: &Point3<f64>) -> [f64; 3] {
        [
            p.coords.dot(&self.u),
            p.coords.dot(&self.v),
            p.coords.dot(&self.w),
        ]
    }

    /// The point with view coordinates (u, v, w).
    pub fn unproject(&self, c: [f64; 3]) -> Point3<f64> {
        Point3::from(self.u * c[0] + self.v * c[1] + self.w * c[2])
    }
}

/// Which surface a depth image keeps.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Surface {
    /// The highest point along w (part B seen against the approach).
    Top,
    /// The lowest point along w (part A seen along the approach).
    Bottom,
}

/// A rectangle of the global pixel lattice: pixel (i, j) has its centre at
/// (i * pixel, j * pixel) in view coordinates.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PixelWindow {
    /// Lattice column of the first image column.
    pub i0: i64,
    /// Lattice row of the first image row.
    pub j0: i64,
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
}

impl PixelWindow {
    /// The smallest window holding every pixel centre inside the (u, v) box, grown by `margin` pixels.
    pub fn covering(umin: f64, umax: f64, vmin: f64, vmax: f64, pixel: f64, margin: i64) -> Self {
        let i0 = (umin / pixel).ceil() as i64 - margin;
        let i1 = (umax / pixel).floor() as i64 + margin;
        let j0 = (vmin / pixel).ceil() as i64 - margin;
        let j1 = (vmax / pixel).floor() as i64 + margin;
        Self {
            i0,
            j0,
            width: (i1 - i0 + 1).max(0) as usize,
            height: (j1 - j0 + 1).max(0) as usize,
        }
    }

    /// Number of pixels.
    pub fn len(&self) -> usize {
        self.width * self.height
    }

    /// True when the window has no pixel.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// What to render: a mesh at a pose, seen in a view, over a window.
#[derive(Debug, Clone, Copy)]
pub struct RenderJob<'a> {
    /// The mesh in its own frame.
    pub mesh: &'a Mesh,
    /// Pose of the mesh's frame in the task frame.
    pub pose: Isometry3<f64>,
    /// The view frame (in task-frame coordinates).
    pub view: View,
    /// Which surface to keep.
    pub surface: Surface,
    /// The pixel window.
    pub window: PixelWindow,
    /// Pixel size (m).
    pub pixel: f64,
}

/// A rendered depth image: a height along w and the triangle that made it, per pixel.
#[derive(Debug, Clone, PartialEq)]
pub struct DepthImage {
    /// Where it lies on the lattice.
    pub window: PixelWindow,
    /// Pixel size (m).
    pub pixel: f64,
    /// Heights along w (m), row-major; [`EMPTY_A`] / [`EMPTY_B`] where no surface.
    pub height: Vec<f32>,
    /// Index of the triangle seen at each pixel; `u32::MAX` where none.
    pub tri: Vec<u32>,
}

impl DepthImage {
    /// An image with no surface anywhere.
    pub fn empty(window: PixelWindow, pixel: f64, surface: Surface) -> Self {
        let fill = match surface {
            Surface::Top => EMPTY_B,
            Surface::Bottom => EMPTY_A,
        };
        Self {
            window,
            pixel,
            height: vec![fill; window.len()],
            tri: vec![u32::MAX; window.len()],
        }
    }

    /// Number of pixels with a surface.
    pub fn covered(&self) -> usize {
        self.height.iter().filter(|h| h.is_finite()).count()
    }
}

/// A translation of B across the view, in whole pixels.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shift {
    /// Columns B moves by (+u).
    pub du: i64,
    /// Rows B moves by (+v).
    pub dv: i64,
}

/// The reduced contact set of one configuration: what the wrench models need, never the
/// contact pixels themselves.
#[derive(Debug, Clone, PartialEq)]
pub struct ContactSummary {
    /// Minimal gap hA - hB over the image (m); +inf when A and B never meet.
    pub gap: f32,
    /// Contact pixels (gap within tolerance of the minimum).
    pub count: u32,
    /// Sum of contact pixels' lattice columns relative to A's window (i - i0).
    pub sum_col: f64,
    /// Sum of contact pixels' lattice rows relative to A's window (j - j0).
    pub sum_row: f64,
    /// Sum of A's heights at the contact pixels (m).
    pub sum_height: f64,
    /// Sum of B's unit normals at the contact pixels, in view coordinates (u, v, w).
    pub sum_normal: [f64; 3],
    /// Per image row of A with a contact: (row, first contact column, last contact column).
    pub rows: Vec<(u32, u32, u32)>,
}

/// Renders depth images and reduces shifted image pairs to contact summaries.
pub trait DepthBackend: Sync {
    /// Short name for reports (`cpu`, `gpu:<adapter>`).
    fn name(&self) -> String;

    /// Renders one depth image.
    fn render(&self, job: &RenderJob<'_>) -> Result<DepthImage>;

    /// For each shift of B against A, the contact summary; `b_normals` are B's triangle
    /// normals in view coordinates, `tolerance` the contact tolerance (m). B's window must
    /// hold A's window under every shift.
    fn contacts(
        &self,
        a: &DepthImage,
        b: &DepthImage,
        b_normals: &[[f32; 3]],
        shifts: &[Shift],
        tolerance: f32,
    ) -> Result<Vec<ContactSummary>>;
}
