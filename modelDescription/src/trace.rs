//! The trace file the FMU appends to when its `trace` parameter names one: at every
//! measurement, each particle's pose in every uncertain DOF of the map and its normalised
//! weight, then the estimate. CSV with a header, one row per particle:
//!
//! ```text
//! measurement,particle,object.x,object.y,weight
//! 1,0,0.0012,-0.0031,0.00025
//! ...
//! 1,-1,0.0011,-0.0030,1
//! ```
//!
//! `measurement` counts from 1 within the instance, `particle` is the particle's index, -1
//! for the estimate's row (whose `weight` is the confidence); poses in m and rad, as the
//! FMU's outputs. Several instances may append to one file one after the other (a
//! campaign's trials): each starts its measurements at 1 again, and a header repeats
//! where the DOFs change.

use std::io::{Read, Write};

/// The row index that marks the estimate.
pub const ESTIMATE_ROW: i64 = -1;

/// One measurement's particles and estimate, as read back.
#[derive(Debug, Clone, PartialEq)]
pub struct TraceMeasurement {
    /// 1 for the first measurement of its instance, 2 for the next, ...
    pub measurement: u32,
    /// The uncertain DOFs (`object.x`, ...), the columns of `poses` and `estimate`.
    pub dofs: Vec<String>,
    /// Each particle's pose, one value per DOF.
    pub poses: Vec<Vec<f64>>,
    /// Each particle's normalised weight.
    pub weights: Vec<f64>,
    /// The estimate, one value per DOF.
    pub estimate: Vec<f64>,
    /// The confidence that went with the estimate.
    pub confidence: f64,
}

/// Why a trace file could not be read.
#[derive(Debug)]
pub enum TraceError {
    /// The file could not be read.
    Io(std::io::Error),
    /// A row is not what the format says (the line's number and why).
    Format {
        /// 1-based line number.
        line: u64,
        /// What is wrong.
        reason: String,
    },
}

impl std::fmt::Display for TraceError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Io(e) => write!(f, "{e}"),
            Self::Format { line, reason } => write!(f, "line {line}: {reason}"),
        }
    }
}

impl std::error::Error for TraceError {}

/// The header row for `dofs`.
pub fn header(dofs: &[String]) -> Vec<String> {
    let mut h = vec!["measurement".to_owned(), "particle".to_owned()];
    h.extend(dofs.iter().cloned());
    h.push("weight".to_owned());
    h
}

/// Appends one measurement to `out`: each particle's pose (one value per DOF) with its
/// weight, then the estimate with its confidence; `header` first, when given.
///
/// # Errors
/// When writing fails.
pub fn append<W: Write>(
    out: W,
    header: Option<&[String]>,
    measurement: u32,
    poses: impl Iterator<Item = (Vec<f64>, f64)>,
    estimate: (&[f64], f64),
) -> std::io::Result<()> {
    let mut w = csv::WriterBuilder::new().flexible(true).from_writer(out);
    let io = |e: csv::Error| std::io::Error::other(e.to_string());
    if let Some(h) = header {
        w.write_record(h).map_err(io)?;
    }
    let row = |index: i64, pose: &[f64], weight: f64| {
        let mut r = vec![measurement.to_string(), index.to_string()];
        r.extend(pose.iter().map(|v| format!("{v:e}")));
        r.push(format!("{weight:e}"));
        r
    };
    for (i, (pose, weight)) in poses.enumerate() {
        w.write_record(row(i as i64, &pose, weight)).map_err(io)?;
    }
    w.write_record(row(ESTIMATE_ROW, estimate.0, estimate.1))
        .map_err(io)?;
    w.flush()
}

/// Reads a trace: every measurement in file order.
///
/// # Errors
/// [`TraceError::Io`] when the reader fails, [`TraceError::Format`] naming the line of a
/// malformed row (no header before it, a wrong column count, a value that is not a number,
/// particles without their estimate row).
pub fn read<R: Read>(input: R) -> Result<Vec<TraceMeasurement>, TraceError> {
    let mut r = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .from_reader(input);
    let mut out = Vec::new();
    let mut dofs: Option<Vec<String>> = None;
    let mut open: Option<TraceMeasurement> = None;
    for rec in r.records() {
        let rec = rec.map_err(|e| {
            let line = e.position().map_or(0, csv::Position::line);
            match e.into_kind() {
                csv::ErrorKind::Io(io) => TraceError::Io(io),
                other => TraceError::Format {
                    line,
                    reason: format!("{other:?}"),
                },
            }
        })?;
        let line = rec.position().map_or(0, csv::Position::line);
        let bad = |reason: String| TraceError::Format { line, reason };
        if rec.get(0) == Some("measurement") {
            if open.is_some() {
                return Err(bad("a header within a measurement's rows".into()));
            }
            let n = rec.len();
            if n < 3 || rec.get(1) != Some("particle") || rec.get(n - 1) != Some("weight") {
                return Err(bad(format!(
                    "header {rec:?}: expected measurement,particle,DOFs..,weight"
                )));
            }
            dofs = Some(rec.iter().skip(2).take(n - 3).map(str::to_owned).collect());
            continue;
        }
        let Some(names) = &dofs else {
            return Err(bad("a row before the header".into()));
        };
        if rec.len() != names.len() + 3 {
            return Err(bad(format!(
                "{} values, the header has {}",
                rec.len(),
                names.len() + 3
            )));
        }
        let number = |k: usize| -> Result<f64, TraceError> {
            let text = &rec[k];
            text.parse::<f64>()
                .map_err(|_| bad(format!("column {} is `{text}`, not a number", k + 1)))
        };
        let measurement = number(0)? as u32;
        let index = number(1)? as i64;
        let pose = (2..2 + names.len())
            .map(number)
            .collect::<Result<Vec<_>, _>>()?;
        let weight = number(names.len() + 2)?;
        let m = open.get_or_insert_with(|| TraceMeasurement {
            measurement,
            dofs: names.clone(),
            poses: Vec::new(),
            weights: Vec::new(),
            estimate: Vec::new(),
            confidence: 0.0,
        });
        if m.measurement != measurement {
            return Err(bad(format!(
                "measurement {measurement} before measurement {}'s estimate row",
                m.measurement
            )));
        }
        if index == ESTIMATE_ROW {
            let mut done = open.take().expect("opened above");
            done.estimate = pose;
            done.confidence = weight;
            out.push(done);
        } else {
            m.poses.push(pose);
            m.weights.push(weight);
        }
    }
    match open {
        Some(m) => Err(TraceError::Format {
            line: 0,
            reason: format!(
                "measurement {} ends without its estimate row",
                m.measurement
            ),
        }),
        None => Ok(out),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_trace_round_trips_through_its_reader() {
        let dofs: Vec<String> = ["object.x", "object.y", "object.rz"]
            .map(String::from)
            .to_vec();
        let mut file = Vec::new();
        let poses = vec![
            (vec![1.5e-3, -2.25e-3, 0.3], 0.75),
            (vec![-4e-4, 1e-17, -0.39], 0.25),
        ];
        append(
            &mut file,
            Some(&header(&dofs)),
            1,
            poses.clone().into_iter(),
            (&[1e-3, -2e-3, 0.29], 0.8),
        )
        .expect("written");
        append(
            &mut file,
            None,
            2,
            poses.clone().into_iter().take(1),
            (&[1.4e-3, -2.2e-3, 0.3], 1.0),
        )
        .expect("written");
        let back = read(file.as_slice()).expect("reads");
        assert_eq!(back.len(), 2);
        assert_eq!(back[0].dofs, dofs);
        assert_eq!(back[0].measurement, 1);
        assert_eq!(back[0].poses, vec![poses[0].0.clone(), poses[1].0.clone()]);
        assert_eq!(back[0].weights, vec![0.75, 0.25]);
        assert_eq!(
            (back[0].estimate.clone(), back[0].confidence),
            (vec![1e-3, -2e-3, 0.29], 0.8)
        );
        assert_eq!((back[1].measurement, back[1].poses.len()), (2, 1));
    }

    #[test]
    fn a_broken_trace_is_refused_with_its_line() {
        let good = "measurement,particle,object.x,weight\n1,0,0.5,1\n1,-1,0.5,1\n";
        assert_eq!(read(good.as_bytes()).expect("reads").len(), 1);
        for (text, line, needle) in [
            ("1,0,0.5,1\n", 1, "before the header"),
            (
                "measurement,particle,object.x,weight\n1,0,0.5\n",
                2,
                "3 values",
            ),
            (
                "measurement,particle,object.x,weight\n1,0,zero,1\n",
                2,
                "`zero`",
            ),
            (
                "measurement,particle,object.x,weight\n1,0,0.5,1\n",
                0,
                "without its estimate",
            ),
            (
                "measurement,particle,object.x,weight\n1,0,0.5,1\n2,0,0.5,1\n",
                3,
                "before measurement 1",
            ),
        ] {
            let e = read(text.as_bytes()).expect_err(needle);
            let msg = e.to_string();
            assert!(msg.contains(needle), "{msg}");
            match e {
                TraceError::Format { line: l, .. } => assert_eq!(l, line, "{msg}"),
                TraceError::Io(_) => panic!("{msg}"),
            }
        }
    }
}
