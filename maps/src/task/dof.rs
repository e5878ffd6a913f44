//! The twelve degrees of freedom a tolerance space can hold: six of the grip pose r1
//! (`grip.*`) and six of the task-to-object pose r2 (`object.*`).

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use crate::error::MapError;

/// Which relative pose of a particle a DOF belongs to (paper, Eq. 1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Pose {
    /// r1: the gripped part's task frame relative to its nominal place in the hand.
    Grip,
    /// r2: the mating part's frame relative to the task frame.
    Object,
}

/// One coordinate of a relative pose: a translation (m) or a rotation-vector component (rad).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Axis {
    /// Translation along x.
    X,
    /// Translation along y.
    Y,
    /// Translation along z.
    Z,
    /// Rotation-vector component about x.
    Rx,
    /// Rotation-vector component about y.
    Ry,
    /// Rotation-vector component about z.
    Rz,
}

impl Axis {
    /// The six axes in pose order.
    pub const ALL: [Axis; 6] = [Axis::X, Axis::Y, Axis::Z, Axis::Rx, Axis::Ry, Axis::Rz];

    /// Position 0..6 in a pose vector (x, y, z, rx, ry, rz).
    pub fn index(self) -> usize {
        self as usize
    }

    /// True for rx, ry, rz.
    pub fn is_rotation(self) -> bool {
        self.index() >= 3
    }

    /// Short name (`x` .. `rz`).
    pub fn name(self) -> &'static str {
        ["x", "y", "z", "rx", "ry", "rz"][self.index()]
    }
}

/// A degree of freedom of a particle: a pose and an axis, named like `object.rx`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Dof {
    /// Which relative pose.
    pub pose: Pose,
    /// Which coordinate of it.
    pub axis: Axis,
}

impl Dof {
    /// Builds a DOF.
    pub const fn new(pose: Pose, axis: Axis) -> Self {
        Self { pose, axis }
    }

    /// Position 0..12 in a full particle vector (grip x..rz, then object x..rz).
    pub fn index(self) -> usize {
        match self.pose {
            Pose::Grip => self.axis.index(),
            Pose::Object => 6 + self.axis.index(),
        }
    }

    /// The DOF at position 0..12 of a full particle vector.
    pub fn from_index(i: usize) -> Option<Self> {
        let pose = match i / 6 {
            0 => Pose::Grip,
            1 => Pose::Object,
            _ => return None,
        };
        Some(Self::new(pose, Axis::ALL[i % 6]))
    }

    /// True for rotational DOFs.
    pub fn is_rotation(self) -> bool {
        self.axis.is_rotation()
    }

    /// SI unit of the DOF's values.
    pub fn unit(self) -> &'static str {
        if self.is_rotation() { "rad" } else { "m" }
    }

    /// Factor and unit of the values as people read them: mm for translations, degrees
    /// for rotations (CLI flags, plot axes).
    pub fn display_unit(self) -> (f64, &'static str) {
        if self.is_rotation() {
            (180.0 / std::f64::consts::PI, "deg")
        } else {
            (1e3, "mm")
        }
    }

    /// A value in display units, e.g. `+2.500 mm` or `-0.500 deg`.
    pub fn display(self, v: f64) -> String {
        let (factor, unit) = self.display_unit();
        format!("{:+.3} {unit}", v * factor)
    }
}

impl fmt::Display for Dof {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let pose = match self.pose {
            Pose::Grip => "grip",
            Pose::Object => "object",
        };
        write!(f, "{pose}.{}", self.axis.name())
    }
}

impl FromStr for Dof {
    type Err = MapError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let unknown = || MapError::UnknownDof(s.to_owned());
        let (pose, axis) = s.split_once('.').ok_or_else(unknown)?;
        let pose = match pose {
            "grip" => Pose::Grip,
            "object" => Pose::Object,
            _ => return Err(unknown()),
        };
        let axis = Axis::ALL
            .into_iter()
            .find(|a| a.name() == axis)
            .ok_or_else(unknown)?;
        Ok(Self::new(pose, axis))
    }
}

impl Serialize for Dof {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

impl<'de> Deserialize<'de> for Dof {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let s = String::deserialize(d)?;
        s.parse().map_err(serde::de::Error::custom)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_for_all_twelve() {
        for i in 0..12 {
            let dof = Dof::from_index(i).expect("index in range");
            assert_eq!(dof.index(), i);
            let parsed: Dof = dof.to_string().parse().expect("own name parses");
            assert_eq!(parsed, dof);
        }
        assert!(Dof::from_index(12).is_none());
        assert!("object.q".parse::<Dof>().is_err());
        assert!("hand.x".parse::<Dof>().is_err());
        assert!("x".parse::<Dof>().is_err());
    }
}
