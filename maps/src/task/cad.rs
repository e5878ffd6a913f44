//! Parametric CAD solids of the assembly tasks (the paper's Fig. 7). A task's `[geometry]`
//! table in its `task.toml` gives the dimensions (m); from them the two parts are built as
//! closed, outward-facing (counter-clockwise seen from outside) triangle meshes and written
//! as binary STL next to the task file.
//!
//! Frames: part A (active, gripped) lies in the task frame: origin at its tip on the part
//! axis, +z up along the part, the part in z >= 0, approach a = (0, 0, -1). Part B (passive,
//! fixed) lies in the goal frame: origin where A's origin sits when fully mated, +z up.
//!
//! Circles are regular polygons with `segments` vertices on the nominal radius, the first at
//! angle 0; their flats lie r (1 - cos(pi / segments)) inside the circle: 0.38 µm at r = 5 mm
//! and 0.83 µm at r = 11 mm for 256 segments. A peg and its hole share the vertex angles, so
//! the nominal clearance holds at the vertices, and (r_hole - r_peg) cos(pi / segments) across
//! the flats.

use std::f64::consts::{PI, TAU};

use serde::Deserialize;

/// The dimensions of a task's two parts, the `[geometry]` table of its task file (m).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Geometry {
    /// A round peg (A, `peg.stl`) into a blind round hole of a block (B, `block.stl`).
    RoundPeg {
        /// Radius of the peg (m).
        peg_radius: f64,
        /// Length of the peg (m).
        peg_length: f64,
        /// Radius of the hole (m).
        hole_radius: f64,
        /// Depth of the hole (m); the block's top is at z = hole_depth.
        hole_depth: f64,
        /// Block size x, y, z (m), centred on the hole's axis.
        block: [f64; 3],
        /// Vertices per circle.
        segments: u32,
        /// 45-degree chamfer on the peg's tip edge, its leg (m); 0: a sharp edge.
        #[serde(default)]
        peg_chamfer: f64,
        /// 45-degree chamfer on the hole's top edge, its leg (m); 0: a sharp edge.
        #[serde(default)]
        hole_chamfer: f64,
    },
    /// An octagonal peg (A, `peg.stl`) into a blind octagonal hole (B, `block.stl`), flats
    /// facing +-x and +-y.
    OctagonPeg {
        /// Distance between opposite flats of the peg (m).
        peg_across_flats: f64,
        /// Distance between opposite flats of the hole (m).
        hole_across_flats: f64,
        /// Length of the peg (m).
        peg_length: f64,
        /// Depth of the hole (m); the block's top is at z = hole_depth.
        hole_depth: f64,
        /// Block size x, y, z (m), centred on the hole's axis.
        block: [f64; 3],
        /// 45-degree chamfer on the peg's tip edges, its leg (m); 0: sharp edges.
        #[serde(default)]
        peg_chamfer: f64,
        /// 45-degree chamfer on the hole's top edges, its leg (m); 0: sharp edges.
        #[serde(default)]
        hole_chamfer: f64,
    },
    /// A spur gear wheel with a bore (A, `gear.stl`) onto a shaft standing on a round base
    /// (B, `shaft.stl`); the teeth are trapezoids, the first centred on +x.
    GearOnShaft {
        /// Number of teeth.
        teeth: u32,
        /// Radius of the tooth tips (m).
        tip_radius: f64,
        /// Radius of the tooth roots (m).
        root_radius: f64,
        /// Width of a tooth at the tip circle as a fraction of the pitch angle.
        tooth_tip_fraction: f64,
        /// Width of a tooth at the root circle as a fraction of the pitch angle.
        tooth_root_fraction: f64,
        /// Radius of the gear's bore (m).
        bore_radius: f64,
        /// Thickness of the gear (m).
        thickness: f64,
        /// Radius of the shaft (m).
        shaft_radius: f64,
        /// Height of the shaft above the base (m).
        shaft_length: f64,
        /// Radius of the base cylinder (m).
        base_radius: f64,
        /// Height of the base cylinder (m); its top is at z = 0.
        base_height: f64,
        /// Vertices per circle.
        segments: u32,
    },
    /// A housing block with a through bore (A, `housing.stl`) onto a bearing seat standing on
    /// a base plate (B, `seat.stl`).
    BearingHousing {
        /// Housing block size x, y, z (m), centred on the bore's axis.
        housing: [f64; 3],
        /// Radius of the housing's bore (m).
        bore_radius: f64,
        /// Radius of the seat cylinder (m).
        seat_radius: f64,
        /// Height of the seat above the plate (m).
        seat_height: f64,
        /// Base plate size x, y, z (m), centred on the seat's axis; its top is at z = 0.
        plate: [f64; 3],
        /// Vertices per circle.
        segments: u32,
    },
}

/// Which part of the task a mesh is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    /// The active, gripped part, in the task frame.
    A,
    /// The passive, fixed part, in the goal frame.
    B,
}

/// One generated part: the file it is written to, its role and its triangles (m).
#[derive(Debug, Clone)]
pub struct NamedMesh {
    /// File name next to `task.toml`, e.g. `peg.stl`.
    pub file: &'static str,
    /// Part A or part B.
    pub role: Role,
    /// Triangles, counter-clockwise seen from outside.
    pub triangles: Vec<[[f32; 3]; 3]>,
}

impl Geometry {
    /// Checks that the dimensions describe parts that exist and fit; the reason if not.
    pub fn check(&self) -> std::result::Result<(), String> {
        let positive = |pairs: &[(&str, f64)]| {
            pairs.iter().try_for_each(|&(name, v)| {
                if v > 0.0 && v.is_finite() {
                    Ok(())
                } else {
                    Err(format!("{name} = {v} must be > 0"))
                }
            })
        };
        let less = |(a, va): (&str, f64), (b, vb): (&str, f64)| {
            if va < vb {
                Ok(())
            } else {
                Err(format!("{a} = {va} must be less than {b} = {vb}"))
            }
        };
        let chamfers = |peg: f64, hole: f64| {
            [("peg_chamfer", peg), ("hole_chamfer", hole)]
                .iter()
                .try_for_each(|&(name, v)| {
                    if v >= 0.0 && v.is_finite() {
                        Ok(())
                    } else {
                        Err(format!("{name} = {v} must be >= 0"))
                    }
                })
        };
        let circles = |n: u32| {
            if n >= 8 && n.is_multiple_of(4) {
                Ok(())
            } else {
                Err(format!("segments = {n} must be a multiple of 4, >= 8"))
            }
        };
        match *self {
            Self::RoundPeg {
                peg_radius,
                peg_length,
                hole_radius,
                hole_depth,
                block,
                segments,
                peg_chamfer,
                hole_chamfer,
            } => {
                positive(&[
                    ("peg_radius", peg_radius),
                    ("peg_length", peg_length),
                    ("hole_depth", hole_depth),
                ])?;
                positive(&[
                    ("block x", block[0]),
                    ("block y", block[1]),
                    ("block z", block[2]),
                ])?;
                chamfers(peg_chamfer, hole_chamfer)?;
                less(("peg_radius", peg_radius), ("hole_radius", hole_radius))?;
                less(
                    ("hole_radius + hole_chamfer", hole_radius + hole_chamfer),
                    (
                        "half the block's smaller side",
                        block[0].min(block[1]) / 2.0,
                    ),
                )?;
                less(("hole_depth", hole_depth), ("block z", block[2]))?;
                less(("peg_chamfer", peg_chamfer), ("peg_radius", peg_radius))?;
                less(("peg_chamfer", peg_chamfer), ("peg_length", peg_length))?;
                less(("hole_chamfer", hole_chamfer), ("hole_depth", hole_depth))?;
                circles(segments)
            }
            Self::OctagonPeg {
                peg_across_flats,
                hole_across_flats,
                peg_length,
                hole_depth,
                block,
                peg_chamfer,
                hole_chamfer,
            } => {
                positive(&[
                    ("peg_across_flats", peg_across_flats),
                    ("peg_length", peg_length),
                    ("hole_depth", hole_depth),
                ])?;
                positive(&[
                    ("block x", block[0]),
                    ("block y", block[1]),
                    ("block z", block[2]),
                ])?;
                chamfers(peg_chamfer, hole_chamfer)?;
                less(
                    ("peg_across_flats", peg_across_flats),
                    ("hole_across_flats", hole_across_flats),
                )?;
                let corner = (hole_across_flats / 2.0 + hole_chamfer) / (PI / 8.0).cos();
                less(
                    ("the chamfered hole's corner radius", corner),
                    (
                        "half the block's smaller side",
                        block[0].min(block[1]) / 2.0,
                    ),
                )?;
                less(("hole_depth", hole_depth), ("block z", block[2]))?;
                less(
                    ("peg_chamfer", peg_chamfer),
                    ("half peg_across_flats", peg_across_flats / 2.0),
                )?;
                less(("peg_chamfer", peg_chamfer), ("peg_length", peg_length))?;
                less(("hole_chamfer", hole_chamfer), ("hole_depth", hole_depth))
            }
            Self::GearOnShaft {
                teeth,
                tip_radius,
                root_radius,
                tooth_tip_fraction,
                tooth_root_fraction,
                bore_radius,
                thickness,
                shaft_radius,
                shaft_length,
                base_radius,
                base_height,
                segments,
            } => {
                positive(&[
                    ("shaft_radius", shaft_radius),
                    ("thickness", thickness),
                    ("tooth_tip_fraction", tooth_tip_fraction),
                ])?;
                positive(&[("shaft_length", shaft_length), ("base_height", base_height)])?;
                less(("shaft_radius", shaft_radius), ("bore_radius", bore_radius))?;
                less(("bore_radius", bore_radius), ("root_radius", root_radius))?;
                less(("root_radius", root_radius), ("tip_radius", tip_radius))?;
                less(
                    ("tooth_tip_fraction", tooth_tip_fraction),
                    ("tooth_root_fraction", tooth_root_fraction),
                )?;
                less(("tooth_root_fraction", tooth_root_fraction), ("1", 1.0))?;
                less(("shaft_radius", shaft_radius), ("base_radius", base_radius))?;
                if teeth < 3 {
                    return Err(format!("teeth = {teeth} must be >= 3"));
                }
                circles(segments)
            }
            Self::BearingHousing {
                housing,
                bore_radius,
                seat_radius,
                seat_height,
                plate,
                segments,
            } => {
                positive(&[
                    ("housing x", housing[0]),
                    ("housing y", housing[1]),
                    ("housing z", housing[2]),
                ])?;
                positive(&[
                    ("plate x", plate[0]),
                    ("plate y", plate[1]),
                    ("plate z", plate[2]),
                ])?;
                positive(&[("seat_radius", seat_radius), ("seat_height", seat_height)])?;
                less(("seat_radius", seat_radius), ("bore_radius", bore_radius))?;
                less(
                    ("bore_radius", bore_radius),
                    (
                        "half the housing's smaller side",
                        housing[0].min(housing[1]) / 2.0,
                    ),
                )?;
                less(
                    ("seat_radius", seat_radius),
                    (
                        "half the plate's smaller side",
                        plate[0].min(plate[1]) / 2.0,
                    ),
                )?;
                circles(segments)
            }
        }
    }

    /// How far part B may sit off centre along direction `theta` (rad, goal frame) with
    /// part A still going in, by the geometry (m): the radial clearance for round fits; for
    /// the octagon, the flats' clearance over the cosine to the nearest flat normal. Circles
    /// as true circles (their polygons differ by under a micrometre).
    pub fn insertion_limit(&self, theta: f64) -> f64 {
        match *self {
            Self::RoundPeg {
                peg_radius,
                hole_radius,
                ..
            } => hole_radius - peg_radius,
            Self::OctagonPeg {
                peg_across_flats,
                hole_across_flats,
                ..
            } => {
                // Flat normals at k pi / 4; the nearest is at most pi / 8 away.
                let off = (theta.rem_euclid(PI / 4.0) - PI / 8.0).abs() - PI / 8.0;
                (hole_across_flats - peg_across_flats) / 2.0 / off.cos()
            }
            Self::GearOnShaft {
                bore_radius,
                shaft_radius,
                ..
            } => bore_radius - shaft_radius,
            Self::BearingHousing {
                bore_radius,
                seat_radius,
                ..
            } => bore_radius - seat_radius,
        }
    }

    /// Whether part A goes in with part B at `offset` (x, y, m, goal frame) off the TCP, by
    /// the geometry: within the insertion limit of its direction.
    pub fn inserts(&self, offset: [f64; 2]) -> bool {
        offset[0].hypot(offset[1]) <= self.insertion_limit(offset[1].atan2(offset[0]))
    }

    /// Whether part A goes in with part B at `offset` (m) off the TCP and turned by `yaw`
    /// (rad) about the approach, by the geometry: round fits whatever the yaw; the octagon
    /// where every corner of the peg lies within every flat of the hole (both convex prisms
    /// along the approach).
    pub fn inserts_turned(&self, offset: [f64; 2], yaw: f64) -> bool {
        match *self {
            Self::OctagonPeg {
                peg_across_flats,
                hole_across_flats,
                ..
            } => {
                let eighth = PI / 4.0;
                let corner = peg_across_flats / 2.0 / (PI / 8.0).cos();
                (0..8).all(|k| {
                    let a = PI / 8.0 + f64::from(k) * eighth;
                    let v = [corner * a.cos() - offset[0], corner * a.sin() - offset[1]];
                    (0..8).all(|j| {
                        let n = f64::from(j) * eighth + yaw;
                        n.cos() * v[0] + n.sin() * v[1] <= hole_across_flats / 2.0
                    })
                })
            }
            _ => self.inserts(offset),
        }
    }

    /// The smallest insertion limit over all directions, the fit's radial clearance (m):
    /// along +x, a flat normal of the octagon.
    pub fn clearance(&self) -> f64 {
        self.insertion_limit(0.0)
    }

    /// The sum of the 45-degree chamfers' legs on part A's tip and part B's mouth (m).
    pub fn chamfers(&self) -> f64 {
        match *self {
            Self::RoundPeg {
                peg_chamfer,
                hole_chamfer,
                ..
            }
            | Self::OctagonPeg {
                peg_chamfer,
                hole_chamfer,
                ..
            } => peg_chamfer + hole_chamfer,
            Self::GearOnShaft { .. } | Self::BearingHousing { .. } => 0.0,
        }
    }

    /// How far part B may sit off centre along `theta` (rad) with part A's tip still landing
    /// on a chamfer or in the hole (m): the insertion limit widened by the chamfers (on the
    /// octagon, along theta, by their legs over the cosine to the nearest flat normal).
    /// Whether the part then slides in depends on friction and on how far the robot yields.
    pub fn chamfer_reach(&self, theta: f64) -> f64 {
        self.insertion_limit(theta) * (1.0 + self.chamfers() / self.clearance())
    }
}

/// Builds the two parts of a task.
pub fn meshes(g: &Geometry) -> Vec<NamedMesh> {
    let named = |file, role, triangles: Vec<Tri>| NamedMesh {
        file,
        role,
        triangles: to_f32(&triangles),
    };
    match *g {
        Geometry::RoundPeg {
            peg_radius,
            peg_length,
            hole_radius,
            hole_depth,
            block,
            segments,
            peg_chamfer,
            hole_chamfer,
        } => {
            let (peg, hole) = (
                polygon(peg_radius, segments, 0.0),
                polygon(hole_radius, segments, 0.0),
            );
            vec![
                named(
                    "peg.stl",
                    Role::A,
                    tipped(&peg, peg_radius, peg_chamfer, peg_length),
                ),
                named(
                    "block.stl",
                    Role::B,
                    pocket(
                        &rect(block),
                        &hole,
                        hole_radius,
                        hole_chamfer,
                        [hole_depth - block[2], 0.0, hole_depth],
                    ),
                ),
            ]
        }
        Geometry::OctagonPeg {
            peg_across_flats,
            hole_across_flats,
            peg_length,
            hole_depth,
            block,
            peg_chamfer,
            hole_chamfer,
        } => {
            let octagon = |across: f64| polygon(across / 2.0 / (PI / 8.0).cos(), 8, PI / 8.0);
            vec![
                named(
                    "peg.stl",
                    Role::A,
                    tipped(
                        &octagon(peg_across_flats),
                        peg_across_flats / 2.0,
                        peg_chamfer,
                        peg_length,
                    ),
                ),
                named(
                    "block.stl",
                    Role::B,
                    pocket(
                        &rect(block),
                        &octagon(hole_across_flats),
                        hole_across_flats / 2.0,
                        hole_chamfer,
                        [hole_depth - block[2], 0.0, hole_depth],
                    ),
                ),
            ]
        }
        Geometry::GearOnShaft {
            teeth,
            tip_radius,
            root_radius,
            tooth_tip_fraction,
            tooth_root_fraction,
            bore_radius,
            thickness,
            shaft_radius,
            shaft_length,
            base_radius,
            base_height,
            segments,
        } => {
            let wheel = gear(
                teeth,
                tip_radius,
                root_radius,
                tooth_tip_fraction,
                tooth_root_fraction,
            );
            let bore = polygon(bore_radius, segments, 0.0);
            let (base, shaft) = (
                polygon(base_radius, segments, 0.0),
                polygon(shaft_radius, segments, 0.0),
            );
            vec![
                named(
                    "gear.stl",
                    Role::A,
                    prism(&wheel, Some(&bore[..]), 0.0, thickness),
                ),
                named(
                    "shaft.stl",
                    Role::B,
                    boss(&base, &shaft, -base_height, 0.0, shaft_length),
                ),
            ]
        }
        Geometry::BearingHousing {
            housing,
            bore_radius,
            seat_radius,
            seat_height,
            plate,
            segments,
        } => {
            let (bore, seat) = (
                polygon(bore_radius, segments, 0.0),
                polygon(seat_radius, segments, 0.0),
            );
            vec![
                named(
                    "housing.stl",
                    Role::A,
                    prism(&rect(housing), Some(&bore[..]), 0.0, housing[2]),
                ),
                named(
                    "seat.stl",
                    Role::B,
                    boss(&rect(plate), &seat, -plate[2], 0.0, seat_height),
                ),
            ]
        }
    }
}

/// Binary STL of the triangles: zero header, normals from the winding; same input, same bytes.
pub fn stl_bytes(triangles: &[[[f32; 3]; 3]]) -> Vec<u8> {
    let stl: Vec<stl_io::Triangle> = triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| v.map(f64::from));
            let (u, v) = (sub(b, a), sub(c, a));
            let n = [
                u[1] * v[2] - u[2] * v[1],
                u[2] * v[0] - u[0] * v[2],
                u[0] * v[1] - u[1] * v[0],
            ];
            let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            let unit = if len > 0.0 {
                n.map(|c| (c / len) as f32)
            } else {
                [0.0; 3]
            };
            stl_io::Triangle {
                normal: stl_io::Normal::new(unit),
                vertices: t.map(stl_io::Vertex::new),
            }
        })
        .collect();
    let mut bytes = Vec::with_capacity(84 + 50 * stl.len());
    stl_io::write_stl(&mut bytes, stl.iter()).expect("writing to memory does not fail");
    bytes
}

/// A triangle in f64 (m).
type Tri = [[f64; 3]; 3];
/// A closed polygon in the xy plane, counter-clockwise, star-shaped about the origin.
type Loop = Vec<[f64; 2]>;

fn to_f32(triangles: &[Tri]) -> Vec<[[f32; 3]; 3]> {
    triangles
        .iter()
        .map(|t| t.map(|v| v.map(|c| c as f32)))
        .collect()
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// Regular n-gon with its vertices on radius `r`, the first at angle `phase`.
fn polygon(r: f64, n: u32, phase: f64) -> Loop {
    (0..n)
        .map(|k| {
            let t = phase + TAU * f64::from(k) / f64::from(n);
            [r * t.cos(), r * t.sin()]
        })
        .collect()
}

/// Rectangle of the first two sizes, centred on the origin.
fn rect(size: [f64; 3]) -> Loop {
    let (x, y) = (size[0] / 2.0, size[1] / 2.0);
    vec![[x, -y], [x, y], [-x, y], [-x, -y]]
}

/// Gear outline: per tooth root, tip, tip, root corners, the first tooth centred on +x.
fn gear(teeth: u32, tip: f64, root: f64, tip_fraction: f64, root_fraction: f64) -> Loop {
    let pitch = TAU / f64::from(teeth);
    let corners = [
        (-root_fraction, root),
        (-tip_fraction, tip),
        (tip_fraction, tip),
        (root_fraction, root),
    ];
    (0..teeth)
        .flat_map(|k| {
            corners.map(|(f, r)| {
                let t = pitch * (f64::from(k) + f / 2.0);
                [r * t.cos(), r * t.sin()]
            })
        })
        .collect()
}

fn at(p: [f64; 2], z: f64) -> [f64; 3] {
    [p[0], p[1], z]
}

/// Pushes a triangle as given (`keep`) or reversed.
fn push(out: &mut Vec<Tri>, [a, b, c]: Tri, keep: bool) {
    out.push(if keep { [a, b, c] } else { [a, c, b] });
}

/// Side band of a loop from z0 up to z1, facing away from the axis (`outward`) or toward it.
fn wall(out: &mut Vec<Tri>, l: &[[f64; 2]], z0: f64, z1: f64, outward: bool) {
    frustum(out, l, l, z0, z1, outward);
}

/// Side band from loop `lower` at z0 up to loop `upper` at z1, the two sampled on the same
/// rays, facing away from the axis (`outward`) or toward it.
fn frustum(
    out: &mut Vec<Tri>,
    lower: &[[f64; 2]],
    upper: &[[f64; 2]],
    z0: f64,
    z1: f64,
    outward: bool,
) {
    for j in 0..lower.len() {
        let k = (j + 1) % lower.len();
        let [p0, q0, q1, p1] = [
            at(lower[j], z0),
            at(lower[k], z0),
            at(upper[k], z1),
            at(upper[j], z1),
        ];
        push(out, [p0, q0, q1], outward);
        push(out, [p0, q1, p1], outward);
    }
}

/// A regular loop of apothem (or radius) `apothem` moved `by` outwards (negative: inwards)
/// at every side: scaled about the axis, its vertices stay on their rays.
fn offset_loop(l: &[[f64; 2]], apothem: f64, by: f64) -> Vec<[f64; 2]> {
    let s = (apothem + by) / apothem;
    l.iter().map(|p| [p[0] * s, p[1] * s]).collect()
}

/// The face inside a loop at height z, fanned from the axis, facing +z (`up`) or -z.
fn disk(out: &mut Vec<Tri>, l: &[[f64; 2]], z: f64, up: bool) {
    for (j, &p) in l.iter().enumerate() {
        push(
            out,
            [[0.0, 0.0, z], at(p, z), at(l[(j + 1) % l.len()], z)],
            up,
        );
    }
}

/// The face between two loops sampled on the same rays (see [`matched`]), facing +z (`up`)
/// or -z. Between consecutive rays (less than 180 degrees apart) lies a convex quad: inner
/// point, outer point, next outer point, next inner point, counter-clockwise.
fn annulus(out: &mut Vec<Tri>, outer: &[[f64; 2]], inner: &[[f64; 2]], z: f64, up: bool) {
    for k in 0..outer.len() {
        let next = (k + 1) % outer.len();
        let [a, b, c, d] = [inner[k], outer[k], outer[next], inner[next]].map(|p| at(p, z));
        push(out, [a, b, c], up);
        push(out, [a, c, d], up);
    }
}

/// Polar angle in [0, 2 pi); angles within 1e-12 below 2 pi count as 0.
fn angle(p: [f64; 2]) -> f64 {
    let a = p[1].atan2(p[0]).rem_euclid(TAU);
    if a > TAU - 1e-12 { 0.0 } else { a }
}

/// Both loops resampled on the union of their vertex rays from the origin, so that the face
/// between them splits into quads between consecutive rays. Every original vertex is kept
/// (vertices of the two loops within 1e-9 rad share a ray); the added points lie on the
/// loops' edges, so the outlines do not change.
fn matched(outer: &[[f64; 2]], inner: &[[f64; 2]]) -> (Loop, Loop) {
    const TOL: f64 = 1e-9;
    let mut rays: Vec<(f64, [f64; 2])> =
        outer.iter().chain(inner).map(|&p| (angle(p), p)).collect();
    rays.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut unique: Vec<(f64, [f64; 2])> = Vec::with_capacity(rays.len());
    for ray in rays {
        if unique.last().is_none_or(|last| ray.0 - last.0 > TOL) {
            unique.push(ray);
        }
    }
    let resample = |l: &[[f64; 2]]| -> Loop {
        unique
            .iter()
            .map(|&(phi, dir)| {
                if let Some(&v) = l.iter().find(|&&v| (angle(v) - phi).abs() <= TOL) {
                    return v;
                }
                let j = (0..l.len())
                    .find(|&j| {
                        let (from, to) = (angle(l[j]), angle(l[(j + 1) % l.len()]));
                        (phi - from).rem_euclid(TAU) < (to - from).rem_euclid(TAU)
                    })
                    .expect("a star-shaped loop has an edge across every ray");
                let (a, b) = (l[j], l[(j + 1) % l.len()]);
                let e = [b[0] - a[0], b[1] - a[1]];
                let s = (dir[0] * a[1] - dir[1] * a[0]) / (e[0] * dir[1] - e[1] * dir[0]);
                [a[0] + s * e[0], a[1] + s * e[1]]
            })
            .collect()
    };
    (resample(outer), resample(inner))
}

/// A straight prism of `outer` from z0 up to z1, with an optional through hole.
fn prism(outer: &[[f64; 2]], hole: Option<&[[f64; 2]]>, z0: f64, z1: f64) -> Vec<Tri> {
    let mut out = Vec::new();
    match hole {
        None => {
            wall(&mut out, outer, z0, z1, true);
            disk(&mut out, outer, z0, false);
            disk(&mut out, outer, z1, true);
        }
        Some(hole) => {
            let (o, i) = matched(outer, hole);
            wall(&mut out, &o, z0, z1, true);
            wall(&mut out, &i, z0, z1, false);
            annulus(&mut out, &o, &i, z0, false);
            annulus(&mut out, &o, &i, z1, true);
        }
    }
    out
}

/// A prism of `lower` from z0 to z1 carrying a prism of `upper` (inside it) from z1 to z2.
fn boss(lower: &[[f64; 2]], upper: &[[f64; 2]], z0: f64, z1: f64, z2: f64) -> Vec<Tri> {
    let (o, i) = matched(lower, upper);
    let mut out = Vec::new();
    wall(&mut out, &o, z0, z1, true);
    disk(&mut out, &o, z0, false);
    annulus(&mut out, &o, &i, z1, true);
    wall(&mut out, &i, z1, z2, true);
    disk(&mut out, &i, z2, true);
    out
}

/// A peg: a prism of the regular loop `l` (apothem or radius `apothem`) from its tip at
/// z = 0 up to `length`, the tip's edge cut by a 45-degree chamfer of leg `chamfer`.
fn tipped(l: &[[f64; 2]], apothem: f64, chamfer: f64, length: f64) -> Vec<Tri> {
    if chamfer == 0.0 {
        return prism(l, None, 0.0, length);
    }
    let tip = offset_loop(l, apothem, -chamfer);
    let mut out = Vec::new();
    disk(&mut out, &tip, 0.0, false);
    frustum(&mut out, &tip, l, 0.0, chamfer, true);
    wall(&mut out, l, chamfer, length, true);
    disk(&mut out, l, length, true);
    out
}

/// A prism of `outer` from z0 to z2 with a blind hole from its top down to z1 (`[z0, z1,
/// z2]`): the regular loop `hole` (apothem or radius `apothem`), its top edge cut by a
/// 45-degree chamfer of leg `chamfer`.
fn pocket(
    outer: &[[f64; 2]],
    hole: &[[f64; 2]],
    apothem: f64,
    chamfer: f64,
    z: [f64; 3],
) -> Vec<Tri> {
    let [z0, z1, z2] = z;
    let (o, mouth) = matched(outer, &offset_loop(hole, apothem, chamfer));
    let mut out = Vec::new();
    wall(&mut out, &o, z0, z2, true);
    disk(&mut out, &o, z0, false);
    annulus(&mut out, &o, &mouth, z2, true);
    if chamfer > 0.0 {
        // The mouth resampled on the outer loop's rays too: the hole on the same rays.
        let bore = offset_loop(&mouth, apothem + chamfer, -chamfer);
        frustum(&mut out, &bore, &mouth, z2 - chamfer, z2, false);
        wall(&mut out, &bore, z1, z2 - chamfer, false);
        disk(&mut out, &bore, z1, true);
    } else {
        wall(&mut out, &mouth, z1, z2, false);
        disk(&mut out, &mouth, z1, true);
    }
    out
}

#[cfg(test)]
mod tests {
    use std::collections::HashMap;

    use super::*;
    use crate::Task;

    const MM: f64 = 1e-3;
    /// Half an f32 step at 40 mm is 1.9 nm: coordinates are compared to 5 nm.
    const EPS: f64 = 5e-9;
    const TASKS: [(&str, [&str; 2]); 4] = [
        ("peg_in_hole", ["peg.stl", "block.stl"]),
        ("octagon", ["peg.stl", "block.stl"]),
        ("gear", ["gear.stl", "shaft.stl"]),
        ("bearing_housing", ["housing.stl", "seat.stl"]),
    ];

    fn geometry(task: &str) -> Geometry {
        Task::find(task)
            .expect("committed task files load")
            .geometry
            .expect("committed task files have a [geometry]")
    }

    /// The triangles of one generated part, in f64.
    fn part(task: &str, file: &str) -> Vec<Tri> {
        let m = meshes(&geometry(task))
            .into_iter()
            .find(|m| m.file == file)
            .expect("the task has this part");
        m.triangles
            .iter()
            .map(|t| t.map(|v| v.map(f64::from)))
            .collect()
    }

    fn vertices(tris: &[Tri]) -> Vec<[f64; 3]> {
        tris.iter().flatten().copied().collect()
    }

    /// Signed volume by the divergence theorem.
    fn volume(tris: &[Tri]) -> f64 {
        tris.iter()
            .map(|[a, b, c]| {
                a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                    + a[2] * (b[0] * c[1] - b[1] * c[0])
            })
            .sum::<f64>()
            / 6.0
    }

    fn bbox(tris: &[Tri]) -> ([f64; 3], [f64; 3]) {
        vertices(tris)
            .iter()
            .fold(([f64::MAX; 3], [f64::MIN; 3]), |(lo, hi), v| {
                (
                    std::array::from_fn(|i| lo[i].min(v[i])),
                    std::array::from_fn(|i| hi[i].max(v[i])),
                )
            })
    }

    /// Every edge is used exactly once in each direction (closed, consistently wound), and no
    /// triangle has two equal corners. Vertices are welded by their exact f32 bits.
    fn watertight(tris: &[Tri]) -> std::result::Result<(), String> {
        let mut ids: HashMap<[u32; 3], usize> = HashMap::new();
        let mut edges: HashMap<(usize, usize), u32> = HashMap::new();
        for t in tris {
            let id = t.map(|v| {
                let n = ids.len();
                *ids.entry(v.map(|c| (c as f32).to_bits())).or_insert(n)
            });
            if id[0] == id[1] || id[1] == id[2] || id[0] == id[2] {
                return Err(format!("degenerate triangle {t:?}"));
            }
            for k in 0..3 {
                *edges.entry((id[k], id[(k + 1) % 3])).or_default() += 1;
            }
        }
        for (&(a, b), &count) in &edges {
            if count != 1 || edges.get(&(b, a)) != Some(&1) {
                return Err(format!(
                    "edge {a}->{b} used {count} times, {b}->{a} {:?} times",
                    edges.get(&(b, a))
                ));
            }
        }
        Ok(())
    }

    fn cross2(o: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
        (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
    }

    /// No folded faces: the flat faces at one height of these parts all face the same way
    /// (a triangle folded over its neighbours would keep the mesh closed and its volume).
    fn no_folds(tris: &[Tri]) -> std::result::Result<(), String> {
        let mut facing: HashMap<u64, f64> = HashMap::new();
        for t in tris
            .iter()
            .filter(|t| t[0][2] == t[1][2] && t[1][2] == t[2][2])
        {
            let [a, b, c] = t.map(|v| [v[0], v[1]]);
            let area = cross2(a, b, c);
            let first = *facing.entry(t[0][2].to_bits()).or_insert(area);
            if area * first <= 0.0 {
                return Err(format!(
                    "flat triangle {t:?} faces against its neighbours at z = {}",
                    t[0][2]
                ));
            }
        }
        Ok(())
    }

    /// Area of a regular n-gon with its vertices on radius r.
    fn ngon(r: f64, n: u32) -> f64 {
        f64::from(n) / 2.0 * r * r * (TAU / f64::from(n)).sin()
    }

    fn close(got: f64, want: f64, rel: f64) -> bool {
        (got - want).abs() <= rel * want.abs()
    }

    #[test]
    fn every_part_is_closed_and_faces_outward() {
        for (task, files) in TASKS {
            let parts = meshes(&geometry(task));
            assert_eq!(
                parts.iter().map(|m| m.file).collect::<Vec<_>>(),
                files,
                "{task}"
            );
            assert_eq!(
                parts.iter().map(|m| m.role).collect::<Vec<_>>(),
                [Role::A, Role::B],
                "{task}"
            );
            for file in files {
                let tris = part(task, file);
                watertight(&tris).unwrap_or_else(|e| panic!("{task}/{file}: not watertight: {e}"));
                assert!(volume(&tris) > 0.0, "{task}/{file}: faces point inward");
                no_folds(&tris).unwrap_or_else(|e| panic!("{task}/{file}: {e}"));
            }
        }
    }

    #[test]
    fn the_watertight_check_sees_holes_and_flipped_faces() {
        let tris = part("peg_in_hole", "peg.stl");
        assert!(watertight(&tris[1..]).is_err());
        let mut flipped = tris.clone();
        flipped[7].swap(1, 2);
        assert!(watertight(&flipped).is_err());
        assert!(no_folds(&tris).is_ok());
        let flat = tris
            .iter()
            .position(|t| t.iter().all(|v| v[2] == 0.0))
            .expect("the tip face");
        let mut folded = tris.clone();
        folded[flat].swap(1, 2);
        assert!(no_folds(&folded).is_err());
    }

    #[test]
    fn volumes_match_the_analytic_solids() {
        let n = 256;
        let octagon = |w: f64| 2.0 * (2f64.sqrt() - 1.0) * w * w;
        // Gear outline from the origin: per 18 degree pitch, two flank triangles (root to
        // tip corner, 0.125 pitch apart), the tip (0.25 pitch) and the root land (0.5 pitch).
        let p = TAU / 20.0;
        let gear = 20.0
            * 0.5
            * (2.0 * 17.5 * 20.0 * (0.125 * p).sin()
                + 20.0 * 20.0 * (0.25 * p).sin()
                + 17.5 * 17.5 * (0.5 * p).sin());
        let cases = [
            ("peg_in_hole", "peg.stl", ngon(4.95, n) * 40.0),
            (
                "peg_in_hole",
                "block.stl",
                40.0 * 40.0 * 20.0 - ngon(5.0, n) * 10.0,
            ),
            ("octagon", "peg.stl", octagon(10.0) * 40.0),
            (
                "octagon",
                "block.stl",
                40.0 * 40.0 * 20.0 - octagon(10.05) * 10.0,
            ),
            ("gear", "gear.stl", (gear - ngon(5.0, n)) * 8.0),
            (
                "gear",
                "shaft.stl",
                ngon(15.0, n) * 10.0 + ngon(4.95, n) * 15.0,
            ),
            (
                "bearing_housing",
                "housing.stl",
                (40.0 * 40.0 - ngon(11.0, n)) * 16.0,
            ),
            (
                "bearing_housing",
                "seat.stl",
                60.0 * 60.0 * 10.0 + ngon(10.95, n) * 12.0,
            ),
        ];
        for (task, file, mm3) in cases {
            let got = volume(&part(task, file));
            assert!(
                close(got, mm3 * 1e-9, 1e-6),
                "{task}/{file}: volume {got:e} m^3, analytic {:e}",
                mm3 * 1e-9
            );
        }
    }

    /// A task's geometry with chamfers of legs `peg` and `hole` (mm).
    fn chamfered(task: &str, peg: f64, hole: f64) -> Geometry {
        let mut g = geometry(task);
        match &mut g {
            Geometry::RoundPeg {
                peg_chamfer,
                hole_chamfer,
                ..
            }
            | Geometry::OctagonPeg {
                peg_chamfer,
                hole_chamfer,
                ..
            } => (*peg_chamfer, *hole_chamfer) = (peg * MM, hole * MM),
            _ => panic!("{task} has no chamfers"),
        }
        g.check().expect("the chamfered parts exist");
        g
    }

    #[test]
    fn chamfered_parts_are_closed_and_hold_the_frustums_volume() {
        // A frustum of a loop scaled by s0 at one end and s1 at the other, height h: the
        // loop's area times h (s0^2 + s0 s1 + s1^2) / 3.
        let frustum =
            |area: f64, s0: f64, s1: f64, h: f64| area * h * (s0 * s0 + s0 * s1 + s1 * s1) / 3.0;
        let octagon = |w: f64| 2.0 * (2f64.sqrt() - 1.0) * w * w;
        let (pc, hc) = (0.5, 0.8);
        let cases = [
            ("peg_in_hole", ngon(4.95, 256), 4.95, ngon(5.0, 256), 5.0),
            ("octagon", octagon(10.0), 5.0, octagon(10.05), 5.025),
        ];
        for (task, peg_area, peg_apothem, hole_area, hole_apothem) in cases {
            let parts = meshes(&chamfered(task, pc, hc));
            let tris = |i: usize| -> Vec<Tri> {
                parts[i]
                    .triangles
                    .iter()
                    .map(|t| t.map(|v| v.map(f64::from)))
                    .collect()
            };
            let (peg, block) = (tris(0), tris(1));
            for (file, t) in [("peg", &peg), ("block", &block)] {
                watertight(t).unwrap_or_else(|e| panic!("{task}/{file}: not watertight: {e}"));
                no_folds(t).unwrap_or_else(|e| panic!("{task}/{file}: {e}"));
            }
            let peg_mm3 = peg_area * (40.0 - pc)
                + frustum(peg_area, (peg_apothem - pc) / peg_apothem, 1.0, pc);
            let hole_mm3 = hole_area * (10.0 - hc)
                + frustum(hole_area, 1.0, (hole_apothem + hc) / hole_apothem, hc);
            let block_mm3 = 40.0 * 40.0 * 20.0 - hole_mm3;
            for (file, got, mm3) in [
                ("peg", volume(&peg), peg_mm3),
                ("block", volume(&block), block_mm3),
            ] {
                assert!(
                    close(got, mm3 * 1e-9, 1e-6),
                    "{task}/{file}: volume {got:e} m^3, analytic {:e}",
                    mm3 * 1e-9
                );
            }
            // The tip's face is the outline moved in by the chamfer; the mouth moved out.
            // Vertices at height z within 8 mm of the axis (not the block's outline): the
            // largest |x| or |y|, the apothem of both shapes (a vertex at angle 0 or pi / 8).
            let widest = |t: &[Tri], z: f64| {
                vertices(t)
                    .iter()
                    .filter(|v| (v[2] - z).abs() < EPS && v[0].hypot(v[1]) < 8.0 * MM)
                    .map(|v| v[0].abs().max(v[1].abs()))
                    .fold(0.0, f64::max)
            };
            let cases = [
                (widest(&peg, 0.0), peg_apothem - pc),
                (widest(&peg, pc * MM), peg_apothem),
                (widest(&block, 10.0 * MM), hole_apothem + hc),
                (widest(&block, (10.0 - hc) * MM), hole_apothem),
            ];
            for (got, mm) in cases {
                assert!(
                    (got - mm * MM).abs() < 1e-7,
                    "{task}: {got} m, want {mm} mm"
                );
            }
        }
    }

    #[test]
    fn chamfers_must_fit_the_parts() {
        let mut g = chamfered("peg_in_hole", 0.0, 0.0);
        if let Geometry::RoundPeg { peg_chamfer, .. } = &mut g {
            *peg_chamfer = 5.0 * MM;
        }
        let e = g.check().expect_err("a chamfer wider than the peg");
        assert!(e.contains("peg_chamfer"), "{e}");
        if let Geometry::RoundPeg {
            peg_chamfer,
            hole_chamfer,
            ..
        } = &mut g
        {
            (*peg_chamfer, *hole_chamfer) = (0.0, -1e-4);
        }
        let e = g.check().expect_err("a negative chamfer");
        assert!(e.contains("hole_chamfer = -0.0001 must be >= 0"), "{e}");
    }

    #[test]
    fn bounding_boxes_are_the_specified_dimensions() {
        let cases = [
            (
                "peg_in_hole",
                "peg.stl",
                [-4.95, -4.95, 0.0],
                [4.95, 4.95, 40.0],
            ),
            (
                "peg_in_hole",
                "block.stl",
                [-20.0, -20.0, -10.0],
                [20.0, 20.0, 10.0],
            ),
            ("octagon", "peg.stl", [-5.0, -5.0, 0.0], [5.0, 5.0, 40.0]),
            (
                "octagon",
                "block.stl",
                [-20.0, -20.0, -10.0],
                [20.0, 20.0, 10.0],
            ),
            (
                "gear",
                "shaft.stl",
                [-15.0, -15.0, -10.0],
                [15.0, 15.0, 15.0],
            ),
            (
                "bearing_housing",
                "housing.stl",
                [-20.0, -20.0, 0.0],
                [20.0, 20.0, 16.0],
            ),
            (
                "bearing_housing",
                "seat.stl",
                [-30.0, -30.0, -10.0],
                [30.0, 30.0, 12.0],
            ),
        ];
        for (task, file, lo, hi) in cases {
            let (got_lo, got_hi) = bbox(&part(task, file));
            for i in 0..3 {
                assert!(
                    (got_lo[i] - lo[i] * MM).abs() < EPS && (got_hi[i] - hi[i] * MM).abs() < EPS,
                    "{task}/{file}: box {got_lo:?}..{got_hi:?}, specified {lo:?}..{hi:?} mm"
                );
            }
        }
        // The gear's teeth are flat-topped, so its box is inside the tip circle: check radii.
        let gear = part("gear", "gear.stl");
        let (lo, hi) = bbox(&gear);
        assert!(
            lo[2].abs() < EPS && (hi[2] - 8.0 * MM).abs() < EPS,
            "gear z {lo:?}..{hi:?}"
        );
        let r_max = vertices(&gear)
            .iter()
            .map(|v| v[0].hypot(v[1]))
            .fold(0.0, f64::max);
        assert!((r_max - 20.0 * MM).abs() < EPS, "gear tip radius {r_max}");
    }

    /// Vertices between radii lo and hi (mm) with z in [z0, z1] (mm), as (angle, radius).
    fn rim(tris: &[Tri], lo: f64, hi: f64, z0: f64, z1: f64) -> Vec<(f64, f64)> {
        let mut v: Vec<(f64, f64)> = vertices(tris)
            .iter()
            .filter(|v| v[2] >= z0 * MM - EPS && v[2] <= z1 * MM + EPS)
            .map(|v| (angle([v[0], v[1]]), v[0].hypot(v[1])))
            .filter(|&(_, r)| r > lo * MM && r < hi * MM)
            .collect();
        v.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
        v.dedup();
        v
    }

    /// The rim is the regular 256-gon on radius r (mm), first vertex at angle 0, possibly
    /// with extra points on its edges.
    fn on_circle(what: &str, rim: &[(f64, f64)], r: f64) -> f64 {
        let n = 256;
        let nominal: Vec<f64> = rim
            .iter()
            .filter(|p| (p.1 - r * MM).abs() < 1e-9)
            .map(|p| p.0)
            .collect();
        assert_eq!(nominal.len(), n, "{what}: vertices on r = {r} mm");
        for (k, a) in nominal.iter().enumerate() {
            let want = TAU * k as f64 / n as f64;
            assert!(
                (a - want).abs() < 1e-6,
                "{what}: vertex {k} at {a} rad, expected {want}"
            );
        }
        let flat = r * MM * (PI / n as f64).cos();
        assert!(
            rim.iter().all(|p| p.1 > flat - 1e-9 && p.1 < r * MM + 1e-9),
            "{what}: a point off the polygon"
        );
        rim.iter().map(|p| p.1).fold(0.0, f64::max)
    }

    #[test]
    fn round_clearances_are_kept_at_every_vertex() {
        // (task, A file, A rim radius and z range, B file, B rim radius and z range), mm.
        let cases = [
            (
                "peg_in_hole",
                "peg.stl",
                4.95,
                (0.0, 40.0),
                "block.stl",
                5.0,
                (0.0, 10.0),
            ),
            (
                "gear",
                "shaft.stl",
                4.95,
                (0.0, 15.0),
                "gear.stl",
                5.0,
                (0.0, 8.0),
            ),
            (
                "bearing_housing",
                "seat.stl",
                10.95,
                (0.0, 12.0),
                "housing.stl",
                11.0,
                (0.0, 16.0),
            ),
        ];
        for (task, inner_file, r_in, (z0, z1), outer_file, r_out, (w0, w1)) in cases {
            let inner = on_circle(
                &format!("{task}/{inner_file}"),
                &rim(&part(task, inner_file), 1.0, r_in + 0.01, z0, z1),
                r_in,
            );
            let outer = on_circle(
                &format!("{task}/{outer_file}"),
                &rim(&part(task, outer_file), 1.0, r_out + 0.01, w0, w1),
                r_out,
            );
            // Same vertex angles: the radial gap is 0.05 mm at the vertices and
            // 0.05 mm x cos(pi / 256) across the flats.
            assert!(
                (outer - inner - 0.05 * MM).abs() < 2e-9,
                "{task}: radial clearance {} mm",
                (outer - inner) / MM
            );
        }
    }

    #[test]
    fn a_turned_octagon_goes_in_within_its_yaw_play() {
        let g = geometry("octagon");
        // At zero offset a corner at R = a / cos(pi/8) meets the hole's flat a_h when
        // R cos(pi/8 - play) = a_h: play = pi/8 - acos((a_h / a) cos(pi/8)), 0.70 degrees.
        let (a, a_h) = (5.0 * MM, 5.025 * MM);
        let play = PI / 8.0 - (a_h / a * (PI / 8.0).cos()).acos();
        assert!(
            (play.to_degrees() - 0.70).abs() < 0.01,
            "{}",
            play.to_degrees()
        );
        for sign in [1.0, -1.0] {
            assert!(g.inserts_turned([0.0, 0.0], sign * 0.999 * play));
            assert!(!g.inserts_turned([0.0, 0.0], sign * 1.001 * play));
            // An eighth of a turn away is the same fit.
            assert!(g.inserts_turned([0.0, 0.0], sign * 0.999 * play + PI / 4.0));
        }
        // Unturned: the insertion limit of every direction, either side of it.
        for k in 0..16 {
            let theta = f64::from(k) * TAU / 16.0 + 0.1;
            let r = g.insertion_limit(theta);
            let at = |s: f64| [s * r * theta.cos(), s * r * theta.sin()];
            assert!(g.inserts_turned(at(0.999), 0.0), "{theta}");
            assert!(!g.inserts_turned(at(1.001), 0.0), "{theta}");
        }
        // A round fit goes in at any yaw.
        let peg = geometry("peg_in_hole");
        assert!(peg.inserts_turned([0.01 * MM, 0.0], 0.3));
    }

    #[test]
    fn octagon_flats_are_the_specified_distances() {
        let width = |tris: &[Tri], dir: f64| {
            let d = [dir.cos(), dir.sin()];
            let proj: Vec<f64> = vertices(tris)
                .iter()
                .map(|v| v[0] * d[0] + v[1] * d[1])
                .collect();
            proj.iter().fold(f64::MIN, |a, &b| a.max(b))
                - proj.iter().fold(f64::MAX, |a, &b| a.min(b))
        };
        let peg = part("octagon", "peg.stl");
        let block = part("octagon", "block.stl");
        let hole: Vec<Tri> = block
            .iter()
            .filter(|t| t.iter().all(|v| v[0].hypot(v[1]) < 8.0 * MM && v[2] > -EPS))
            .copied()
            .collect();
        assert!(!hole.is_empty());
        for k in 0..4 {
            let dir = f64::from(k) * PI / 4.0;
            let (p, h) = (width(&peg, dir), width(&hole, dir));
            assert!(
                (p - 10.0 * MM).abs() < EPS,
                "peg across flats at {k} x 45 deg: {p}"
            );
            assert!(
                (h - 10.05 * MM).abs() < EPS,
                "hole across flats at {k} x 45 deg: {h}"
            );
        }
    }

    #[test]
    fn the_gear_has_twenty_trapezoid_teeth() {
        let top = rim(&part("gear", "gear.stl"), 10.0, 21.0, 8.0, 8.0);
        let tips: Vec<f64> = top
            .iter()
            .filter(|p| (p.1 - 20.0 * MM).abs() < 1e-9)
            .map(|p| p.0)
            .collect();
        let roots = top
            .iter()
            .filter(|p| (p.1 - 17.5 * MM).abs() < 1e-9)
            .count();
        assert_eq!((tips.len(), roots), (40, 40));
        for (k, a) in tips.iter().enumerate() {
            // Tip corners at tooth centre (k x 18 deg) +- 2.25 deg.
            let tooth = (k.div_ceil(2) % 20) as f64 * 18.0;
            let want = (tooth + if k % 2 == 0 { 2.25 } else { -2.25 })
                .rem_euclid(360.0)
                .to_radians();
            assert!(
                (a - want).abs() < 1e-6,
                "tip corner {k} at {} deg",
                a.to_degrees()
            );
        }
    }

    #[test]
    fn circles_are_fine_enough() {
        for (task, _) in TASKS {
            let (radii, n) = match geometry(task) {
                Geometry::RoundPeg {
                    peg_radius,
                    hole_radius,
                    segments,
                    ..
                } => (vec![peg_radius, hole_radius], segments),
                Geometry::GearOnShaft {
                    bore_radius,
                    shaft_radius,
                    base_radius,
                    segments,
                    ..
                } => (vec![bore_radius, shaft_radius, base_radius], segments),
                Geometry::BearingHousing {
                    bore_radius,
                    seat_radius,
                    segments,
                    ..
                } => (vec![bore_radius, seat_radius], segments),
                Geometry::OctagonPeg { .. } => continue,
            };
            for r in radii {
                let sagitta = r * (1.0 - (PI / f64::from(n)).cos());
                assert!(
                    sagitta < 2e-6,
                    "{task}: r {r} with {n} segments: flats {sagitta} m inside"
                );
            }
        }
    }

    #[test]
    fn stl_bytes_read_back_with_unit_normals_from_the_winding() {
        let m = meshes(&geometry("peg_in_hole")).remove(0);
        let bytes = stl_bytes(&m.triangles);
        assert_eq!(bytes.len(), 84 + 50 * m.triangles.len());
        assert_eq!(bytes, stl_bytes(&m.triangles));
        let stl = stl_io::read_stl(&mut std::io::Cursor::new(&bytes)).expect("readable STL");
        assert_eq!(stl.faces.len(), m.triangles.len());
        for f in &stl.faces {
            let [a, b, c] = f.vertices.map(|i| stl.vertices[i]);
            let n = f.normal;
            assert!((n[0] * n[0] + n[1] * n[1] + n[2] * n[2] - 1.0).abs() < 1e-5);
            if [a, b, c].iter().all(|v| v[2] == 0.0) {
                assert_eq!(n.0, [0.0, 0.0, -1.0], "the tip face points down");
            }
            if [a, b, c].iter().all(|v| v[2] > 0.0 && v[2] < 0.04) {
                let mid = [(a[0] + b[0] + c[0]) / 3.0, (a[1] + b[1] + c[1]) / 3.0];
                assert!(
                    mid[0] * n[0] + mid[1] * n[1] > 0.0,
                    "side faces point away from the axis"
                );
            }
        }
    }

    /// Points of a part's vertices at height `z` within `r` of the axis (a loop, sorted by angle).
    fn outline(tris: &[Tri], z: f64, r: f64) -> Vec<[f64; 2]> {
        let mut pts: Vec<[f64; 2]> = vertices(tris)
            .into_iter()
            .filter(|v| (v[2] - z).abs() < EPS && v[0].hypot(v[1]) < r)
            .map(|v| [v[0], v[1]])
            .collect();
        pts.sort_by(|a, b| a[1].atan2(a[0]).total_cmp(&b[1].atan2(b[0])));
        pts.dedup_by(|a, b| (a[0] - b[0]).hypot(a[1] - b[1]) < EPS);
        pts
    }

    /// Whether every point of `inner`, moved by `d`, lies inside the convex loop `outer`.
    fn contains(outer: &[[f64; 2]], inner: &[[f64; 2]], d: [f64; 2]) -> bool {
        (0..outer.len()).all(|i| {
            let (a, b) = (outer[i], outer[(i + 1) % outer.len()]);
            inner.iter().all(|p| {
                let q = [p[0] + d[0] - a[0], p[1] + d[1] - a[1]];
                (b[0] - a[0]) * q[1] - (b[1] - a[1]) * q[0] >= 0.0
            })
        })
    }

    #[test]
    fn the_insertion_limit_is_where_the_meshes_stop_fitting() {
        for (task, [file_a, file_b]) in TASKS {
            let g = geometry(task);
            let (a, b) = (part(task, file_a), part(task, file_b));
            // (outer loop, inner loop, sign of B's offset on the inner loop's points).
            let (outer, inner, sign) = match g {
                Geometry::RoundPeg {
                    hole_radius,
                    hole_depth,
                    ..
                } => (
                    outline(&b, hole_depth, 1.5 * hole_radius),
                    outline(&a, 0.0, 1.5 * hole_radius),
                    -1.0,
                ),
                Geometry::OctagonPeg {
                    hole_across_flats,
                    hole_depth,
                    ..
                } => (
                    outline(&b, hole_depth, hole_across_flats),
                    outline(&a, 0.0, hole_across_flats),
                    -1.0,
                ),
                Geometry::GearOnShaft {
                    bore_radius,
                    shaft_length,
                    ..
                } => (
                    outline(&a, 0.0, 1.01 * bore_radius),
                    outline(&b, shaft_length, 1.01 * bore_radius),
                    1.0,
                ),
                Geometry::BearingHousing {
                    bore_radius,
                    seat_height,
                    ..
                } => (
                    outline(&a, 0.0, 1.01 * bore_radius),
                    outline(&b, seat_height, 1.01 * bore_radius),
                    1.0,
                ),
            };
            assert!(outer.len() >= 8 && inner.len() >= 8, "{task}");
            for k in 0..8 {
                let theta = f64::from(k) * PI / 16.0;
                let fits = |d: f64| {
                    contains(
                        &outer,
                        &inner,
                        [sign * d * theta.cos(), sign * d * theta.sin()],
                    )
                };
                let (mut lo, mut hi) = (0.0, MM);
                assert!(fits(lo) && !fits(hi), "{task}");
                for _ in 0..50 {
                    let mid = 0.5 * (lo + hi);
                    if fits(mid) { lo = mid } else { hi = mid }
                }
                let limit = g.insertion_limit(theta);
                assert!(
                    (lo - limit).abs() < 1e-6,
                    "{task} at {theta}: meshes {lo}, geometry {limit}"
                );
            }
            assert!(g.clearance() <= g.insertion_limit(0.3), "{task}");
        }
    }
}
