//! The values of the FMU's variables, kept in the order of the variable table, and the
//! parameters read from them and checked against the table's ranges.

use model_description::{Start, VARIABLES, VarType, Variable};

use crate::error::{FusionError, Result};
use crate::filter::VisionMethod;
use crate::filter::{Config, Interpolation, MAX_PARTICLES};

/// The value of one variable.
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    /// A Real.
    Real(f64),
    /// An Integer.
    Integer(i32),
    /// A Boolean.
    Boolean(bool),
    /// A String.
    String(String),
}

/// One value per variable of [`VARIABLES`], in table order.
#[derive(Debug, Clone, PartialEq)]
pub struct Store {
    values: Vec<Value>,
}

impl Default for Store {
    fn default() -> Self {
        let values = VARIABLES
            .iter()
            .map(|v| match (v.ty, v.start) {
                (_, Start::Real(x)) => Value::Real(x),
                (_, Start::Integer(x)) => Value::Integer(x),
                (_, Start::Boolean(x)) => Value::Boolean(x),
                (_, Start::String(x)) => Value::String(x.to_owned()),
                (VarType::Real, Start::None) => Value::Real(0.0),
                (VarType::Integer, Start::None) => Value::Integer(0),
                (VarType::Boolean, Start::None) => Value::Boolean(false),
                (VarType::String, Start::None) => Value::String(String::new()),
            })
            .collect();
        Self { values }
    }
}

/// Table position of the variable called `name` (a name of the table: panics otherwise,
/// which the tests of every caller exercise).
pub fn index_of(name: &str) -> usize {
    VARIABLES
        .iter()
        .position(|v| v.name == name)
        .unwrap_or_else(|| panic!("`{name}` is not in the variable table"))
}

/// Table position of value reference `vr`.
pub fn index_of_vr(vr: u32) -> Option<usize> {
    VARIABLES.iter().position(|v| v.vr == vr)
}

impl Store {
    /// The value at table position `i`.
    pub fn get(&self, i: usize) -> &Value {
        &self.values[i]
    }

    /// The value at table position `i`, mutable.
    pub fn get_mut(&mut self, i: usize) -> &mut Value {
        &mut self.values[i]
    }

    /// The Real at table position `i` (0 for other types).
    pub fn real(&self, i: usize) -> f64 {
        match self.values[i] {
            Value::Real(x) => x,
            _ => 0.0,
        }
    }

    /// Sets the Real at table position `i`.
    pub fn set_real(&mut self, i: usize, x: f64) {
        self.values[i] = Value::Real(x);
    }

    /// The Integer at table position `i` (0 for other types).
    pub fn integer(&self, i: usize) -> i32 {
        match self.values[i] {
            Value::Integer(x) => x,
            _ => 0,
        }
    }

    /// The Boolean at table position `i` (false for other types).
    pub fn boolean(&self, i: usize) -> bool {
        matches!(self.values[i], Value::Boolean(true))
    }

    /// The String at table position `i` ("" for other types).
    pub fn string(&self, i: usize) -> &str {
        match &self.values[i] {
            Value::String(s) => s,
            _ => "",
        }
    }

    /// Writes the values as bytes (for saved FMU states).
    pub fn save(&self, w: &mut crate::filter::Writer) {
        for v in &self.values {
            match v {
                Value::Real(x) => w.f64(*x),
                Value::Integer(x) => w.u32(*x as u32),
                Value::Boolean(x) => w.u32(u32::from(*x)),
                Value::String(s) => w.bytes(s.as_bytes()),
            }
        }
    }

    /// Reads values written by [`Store::save`].
    pub fn restore(r: &mut crate::filter::Reader<'_>) -> Result<Self> {
        let mut store = Self::default();
        for v in &mut store.values {
            *v = match v {
                Value::Real(_) => Value::Real(r.f64()?),
                Value::Integer(_) => Value::Integer(r.u32()? as i32),
                Value::Boolean(_) => Value::Boolean(r.u32()? != 0),
                Value::String(_) => Value::String(
                    String::from_utf8(r.bytes()?.to_vec())
                        .map_err(|_| FusionError::State("a string value is not UTF-8".into()))?,
                ),
            };
        }
        Ok(store)
    }
}

/// The parameters of the FMU, checked.
#[derive(Debug, Clone, PartialEq)]
pub struct Params {
    /// The `map` parameter as given.
    pub map: String,
    /// The `centre_map` parameter (`None`: empty, no centre map).
    pub centre_map: Option<String>,
    /// The `vision` parameter (`None`: empty, no vision).
    pub vision: Option<String>,
    /// `sigma_vision` (px).
    pub sigma_vision: f64,
    /// `vision_method`.
    pub vision_method: VisionMethod,
    /// The filter settings.
    pub config: Config,
    /// The `trace` parameter (`None`: empty, no trace).
    pub trace: Option<std::path::PathBuf>,
}

/// The fewest particles a user may ask for (fewer, but 0, is refused).
const MIN_PARTICLES: usize = 10;

/// `[min, max]` of a table variable as text.
fn range(v: &Variable) -> String {
    let fmt = |b: Option<f64>, inf: &str| b.map_or(inf.to_owned(), |x| format!("{x}"));
    format!("[{}, {}]", fmt(v.min, "-inf"), fmt(v.max, "inf"))
}

/// The value of parameter `name` checked against the table's range.
fn checked(store: &Store, name: &'static str) -> Result<f64> {
    let i = index_of(name);
    let v = &VARIABLES[i];
    let x = match v.ty {
        VarType::Integer => f64::from(store.integer(i)),
        _ => store.real(i),
    };
    let ok = x.is_finite() && v.min.is_none_or(|m| x >= m) && v.max.is_none_or(|m| x <= m);
    if ok {
        Ok(x)
    } else {
        Err(FusionError::Parameter {
            name,
            value: format!("{x}"),
            range: range(v),
        })
    }
}

impl Params {
    /// Reads and checks every parameter in `store`.
    pub fn from_store(store: &Store) -> Result<Self> {
        let seed = checked(store, "seed")? as i32;
        let config = Config {
            particles: match checked(store, "particles")? as usize {
                n @ 1..MIN_PARTICLES => {
                    return Err(FusionError::Parameter {
                        name: "particles",
                        value: format!("{n}"),
                        range: format!("0 (automatic) or [{MIN_PARTICLES}, {MAX_PARTICLES}]"),
                    });
                }
                n => n,
            },
            seed: u64::from(seed as u32),
            iterations: checked(store, "iterations")? as usize,
            sigma_force: checked(store, "sigma_force")?,
            sigma_torque: checked(store, "sigma_torque")?,
            sigma_depth: match checked(store, "sigma_depth")? {
                s if s > 0.0 && s < 1e-9 => {
                    return Err(FusionError::Parameter {
                        name: "sigma_depth",
                        value: format!("{s}"),
                        range: "0 (depth unused) or [1e-9, 1]".into(),
                    });
                }
                s => s,
            },
            jitter: checked(store, "jitter")?,
            confidence_radius: checked(store, "confidence_radius")?,
            threshold: checked(store, "threshold")?,
            interpolation: if checked(store, "interpolation")? == 0.0 {
                Interpolation::Nearest
            } else {
                Interpolation::Multilinear
            },
            tail: checked(store, "tail")?,
            clearance: checked(store, "clearance")?,
            mismatch: checked(store, "mismatch")?,
            mismatch_angle: checked(store, "mismatch_angle")?,
            mismatch_position: checked(store, "mismatch_position")?,
            mismatch_interpolation: checked(store, "mismatch_interpolation")?,
            mismatch_lever: checked(store, "mismatch_lever")?,
            mismatch_reach: checked(store, "mismatch_reach")?,
            tilt_floor: checked(store, "tilt_floor")?,
            lost: checked(store, "lost")?,
        };
        let map = store.string(index_of("map")).to_owned();
        if map.trim().is_empty() {
            return Err(FusionError::Parameter {
                name: "map",
                value: "\"\"".into(),
                range: "a file name in the resources folder or an absolute path".into(),
            });
        }
        let named =
            |name| Some(store.string(index_of(name)).trim().to_owned()).filter(|v| !v.is_empty());
        let centre_map = named("centre_map");
        let vision = named("vision");
        let sigma_vision = checked(store, "sigma_vision")?;
        let vision_method = if checked(store, "vision_method")? == 0.0 {
            VisionMethod::Relative
        } else {
            VisionMethod::Recalibration
        };
        let trace = Some(store.string(index_of("trace")).trim())
            .filter(|t| !t.is_empty())
            .map(std::path::PathBuf::from);
        Ok(Self {
            map,
            centre_map,
            config,
            vision,
            sigma_vision,
            vision_method,
            trace,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_the_table_start_values_and_valid() {
        let p = Params::from_store(&Store::default()).expect("defaults are valid");
        assert_eq!(p.map, "peg_in_hole.ftmap");
        assert_eq!(
            p.config,
            Config {
                seed: 1,
                ..Config::default()
            }
        );
    }

    #[test]
    fn out_of_range_parameters_are_named_with_their_range() {
        let mut s = Store::default();
        *s.get_mut(index_of("particles")) = Value::Integer(5);
        let e = Params::from_store(&s).expect_err("5 particles").to_string();
        assert!(
            e.contains("`particles`") && e.contains("0 (automatic) or [10, 1000000]"),
            "{e}"
        );
        *s.get_mut(index_of("particles")) = Value::Integer(2_000_000);
        let e = Params::from_store(&s)
            .expect_err("2 M particles")
            .to_string();
        assert!(
            e.contains("`particles`") && e.contains("[0, 1000000]"),
            "{e}"
        );
        let mut s = Store::default();
        s.set_real(index_of("threshold"), f64::NAN);
        let e = Params::from_store(&s).expect_err("NaN").to_string();
        assert!(e.contains("`threshold`") && e.contains("[0, 1]"), "{e}");
        let mut s = Store::default();
        s.set_real(index_of("sigma_torque"), 0.0);
        assert!(Params::from_store(&s).is_err());
    }

    #[test]
    fn the_store_round_trips_through_bytes() {
        let mut s = Store::default();
        s.set_real(index_of("tcp.x"), 1.25e-3);
        *s.get_mut(index_of("map")) = Value::String("/tmp/a map.ftmap".into());
        let mut w = crate::filter::Writer::default();
        s.save(&mut w);
        let mut r = crate::filter::Reader::new(&w.0);
        assert_eq!(Store::restore(&mut r).expect("own bytes"), s);
        assert!(r.done());
    }
}
