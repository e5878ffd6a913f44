//! Soundness of a part's mesh before anything is computed from it: a closed surface,
//! consistently oriented with its normals outward, no degenerate or duplicate triangles,
//! and a size a part held by a robot can have. Each defect is reported with how many
//! triangles show it and a sample of their indices.

use std::collections::HashMap;
use std::fmt;

use nalgebra::Point3;

/// Largest extent of a plausible part (m): a part whose bounding box is larger was most
/// likely written in millimetres and read as metres.
pub const MAX_EXTENT: f64 = 2.0;
/// Smallest extent of a plausible part (m): a smaller one was most likely written in
/// metres and read as millimetres (or inches).
pub const MIN_EXTENT: f64 = 1e-4;
/// A triangle whose area is below this share of its longest edge squared covers no area
/// (its corners are collinear to the precision of the file).
const SLIVER: f64 = 1e-10;
/// Whether the triangle with corners `p` covers no area: [`SLIVER`].
pub fn sliver([a, b, c]: [Point3<f64>; 3]) -> bool {
    let longest = (b - a).norm().max((c - b).norm()).max((a - c).norm());
    (b - a).cross(&(c - a)).norm() / 2.0 <= SLIVER * longest * longest
}

/// Triangles named in a defect's sample.
const SAMPLE: usize = 5;

/// What is wrong with a mesh.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DefectKind {
    /// Edges used by one triangle only: the surface has a hole.
    OpenEdges,
    /// Edges that two triangles run in the same direction: a triangle is flipped.
    Flipped,
    /// Edges shared by more than two triangles.
    NonManifold,
    /// The surface encloses a negative volume: every normal points inward.
    InsideOut,
    /// Triangles with a repeated corner or collinear corners: they cover no area.
    Degenerate,
    /// Triangles with the same three corners as an earlier one (dropped on load).
    Duplicate,
    /// The part is implausibly large or small for the units it is read in.
    Size,
}

/// One kind of defect found in a mesh.
#[derive(Debug, Clone, PartialEq)]
pub struct Defect {
    /// Its kind.
    pub kind: DefectKind,
    /// How many triangles (edges, for open and non-manifold edges) show it.
    pub count: usize,
    /// Indices (0-based, in file order) of up to five triangles that show it.
    pub triangles: Vec<usize>,
    /// Whether the mesh is refused for it (otherwise it is a warning).
    pub fatal: bool,
    /// What it means and what to do about it.
    pub advice: String,
}

impl fmt::Display for Defect {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let what = match self.kind {
            DefectKind::OpenEdges => {
                "open edges (used by one triangle only: a hole in the surface)"
            }
            DefectKind::Flipped => {
                "flipped triangles (sharing an edge in the same direction as a neighbour)"
            }
            DefectKind::NonManifold => "non-manifold edges (shared by more than two triangles)",
            DefectKind::InsideOut => "inside-out surface",
            DefectKind::Degenerate => "degenerate triangles (no area)",
            DefectKind::Duplicate => "duplicate triangles",
            DefectKind::Size => "implausible size",
        };
        match self.kind {
            DefectKind::InsideOut => write!(f, "{what} (all {} triangles)", self.count)?,
            DefectKind::Size => write!(f, "{what}")?,
            _ => write!(f, "{} {what}", self.count)?,
        }
        if !self.triangles.is_empty() {
            let list: Vec<String> = self.triangles.iter().map(usize::to_string).collect();
            let more = if self.count > self.triangles.len() {
                ", ..."
            } else {
                ""
            };
            write!(f, " (triangles {}{more})", list.join(", "))?;
        }
        write!(f, ": {}", self.advice)
    }
}

/// The defects of a mesh of `vertices` and `faces`, and the faces without the duplicates.
pub fn check(vertices: &[Point3<f64>], faces: &[[u32; 3]]) -> (Vec<Defect>, Vec<[u32; 3]>) {
    let mut defects = Vec::new();
    let mut push = |kind, list: Vec<usize>, fatal, advice: &str| {
        if !list.is_empty() {
            defects.push(Defect {
                kind,
                count: list.len(),
                triangles: list.iter().copied().take(SAMPLE).collect(),
                fatal,
                advice: advice.to_owned(),
            });
        }
    };
    let (mut seen, mut kept, mut duplicates) = (HashMap::new(), Vec::new(), Vec::new());
    for (i, f) in faces.iter().enumerate() {
        let mut key = *f;
        key.sort_unstable();
        if seen.insert(key, i).is_some() {
            duplicates.push(i);
        } else {
            kept.push((i, *f));
        }
    }
    let degenerate: Vec<usize> = kept
        .iter()
        .filter(|(_, f)| {
            f[0] == f[1] || f[1] == f[2] || f[2] == f[0] || sliver(f.map(|v| vertices[v as usize]))
        })
        .map(|&(i, _)| i)
        .collect();
    // Directed edges of the triangles with three distinct corners (collinear ones still
    // close the surface at a T-junction).
    let mut edges: HashMap<(u32, u32), Vec<usize>> = HashMap::new();
    for &(i, f) in &kept {
        if f[0] == f[1] || f[1] == f[2] || f[2] == f[0] {
            continue;
        }
        for k in 0..3 {
            edges.entry((f[k], f[(k + 1) % 3])).or_default().push(i);
        }
    }
    let (mut open, mut flipped, mut non_manifold) = (Vec::new(), Vec::new(), Vec::new());
    for (&(p, q), along) in &edges {
        if p > q && edges.contains_key(&(q, p)) {
            continue; // counted from the other direction
        }
        let against = edges.get(&(q, p)).map_or(&[][..], Vec::as_slice);
        match (along.len(), against.len()) {
            (1, 1) => {}
            (1, 0) => open.push(along[0]),
            (0, 1) => open.push(against[0]),
            (2, 0) => flipped.push(along[1]),
            (0, 2) => flipped.push(against[1]),
            _ => non_manifold.push(along.first().or(against.first()).copied().unwrap_or(0)),
        }
    }
    for list in [&mut open, &mut flipped, &mut non_manifold] {
        list.sort_unstable();
    }
    let closed = open.is_empty() && flipped.is_empty() && non_manifold.is_empty();
    push(
        DefectKind::OpenEdges,
        open,
        true,
        "the part must be a closed solid; close the surface in the CAD system or export it as a solid",
    );
    push(
        DefectKind::Flipped,
        flipped,
        true,
        "every triangle must run counter-clockwise seen from outside; re-export, or fix the normals (e.g. MeshLab's re-orient filter)",
    );
    push(
        DefectKind::NonManifold,
        non_manifold,
        true,
        "the surface touches itself along an edge; export each part as one solid",
    );
    let volume: f64 = kept
        .iter()
        .map(|(_, f)| {
            let [a, b, c] = f.map(|v| vertices[v as usize].coords);
            a.dot(&b.cross(&c)) / 6.0
        })
        .sum();
    push(
        DefectKind::Degenerate,
        degenerate,
        false,
        "they cover no area and are ignored",
    );
    push(
        DefectKind::Duplicate,
        duplicates,
        false,
        "the copies are dropped",
    );
    if closed && volume <= 0.0 {
        defects.push(Defect {
            kind: DefectKind::InsideOut,
            count: kept.len(),
            triangles: Vec::new(),
            fatal: true,
            advice:
                "every normal points inward (the enclosed volume is negative); flip all triangles"
                    .into(),
        });
    }
    if let Some(defect) = size(vertices) {
        defects.push(defect);
    }
    (defects, kept.into_iter().map(|(_, f)| f).collect())
}

/// A size defect when the bounding box's largest extent is outside
/// [[`MIN_EXTENT`], [`MAX_EXTENT`]].
fn size(vertices: &[Point3<f64>]) -> Option<Defect> {
    let extent = (0..3)
        .map(|k| {
            let (lo, hi) = vertices
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                    (lo.min(v[k]), hi.max(v[k]))
                });
            hi - lo
        })
        .fold(0.0, f64::max);
    let advice = if extent > MAX_EXTENT {
        format!(
            "the part is {extent:.3} m across, more than a robot's part of {MAX_EXTENT} m: likely millimetres read as metres; say `units = \"mm\"` for the part in task.toml (`ftmap task new --units mm`)"
        )
    } else if extent < MIN_EXTENT {
        format!(
            "the part is {:.3} µm across, less than {} mm: likely metres read as millimetres or inches; say `units = \"m\"`",
            extent * 1e6,
            MIN_EXTENT * 1e3
        )
    } else {
        return None;
    };
    Some(Defect {
        kind: DefectKind::Size,
        count: 1,
        triangles: Vec::new(),
        fatal: true,
        advice,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A closed tetrahedron of edge `s` (m), counter-clockwise from outside.
    fn tetrahedron(s: f64) -> (Vec<Point3<f64>>, Vec<[u32; 3]>) {
        let v = vec![
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(s, 0.0, 0.0),
            Point3::new(0.0, s, 0.0),
            Point3::new(0.0, 0.0, s),
        ];
        (v, vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    }

    fn kinds(defects: &[Defect]) -> Vec<DefectKind> {
        defects.iter().map(|d| d.kind).collect()
    }

    #[test]
    fn a_closed_outward_solid_has_no_defects() {
        let (v, f) = tetrahedron(0.01);
        assert_eq!(check(&v, &f).0, vec![]);
    }

    #[test]
    fn each_defect_is_found_and_names_its_triangles() {
        let (v, f) = tetrahedron(0.01);
        let open = check(&v, &f[..3]).0;
        assert_eq!(kinds(&open), vec![DefectKind::OpenEdges]);
        assert_eq!(open[0].count, 3);
        let mut flipped = f.clone();
        flipped[3] = [1, 3, 2];
        let d = check(&v, &flipped).0;
        assert_eq!(kinds(&d), vec![DefectKind::Flipped]);
        assert!(d[0].to_string().contains("3 flipped triangles"), "{}", d[0]);
        let inward: Vec<[u32; 3]> = f.iter().map(|t| [t[0], t[2], t[1]]).collect();
        assert_eq!(kinds(&check(&v, &inward).0), vec![DefectKind::InsideOut]);
        let mut doubled = f.clone();
        doubled.push(f[1]);
        let (d, kept) = check(&v, &doubled);
        assert_eq!(kinds(&d), vec![DefectKind::Duplicate]);
        assert_eq!((d[0].triangles.clone(), kept), (vec![4], f.clone()));
        let (big, _) = tetrahedron(10.0);
        let d = check(&big, &f).0;
        assert_eq!(kinds(&d), vec![DefectKind::Size]);
        assert!(
            d[0].advice.contains("millimetres read as metres"),
            "{}",
            d[0]
        );
    }
}
