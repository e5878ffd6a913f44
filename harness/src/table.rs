//! One table of many campaigns (`harness table`): per campaign folder, the task, its
//! uncertain DOFs, the trials, the success rate, contacts per trial (mean, median, p95,
//! max), the calibration of the reported spreads and the last approach's error per DOF,
//! read back from its `summary.json`.

use std::fmt;
use std::path::{Path, PathBuf};

use serde::Deserialize;

use crate::error::{HarnessError, Result};
use crate::report::{ContactStats, DofError};

/// What the table reads of a campaign's `summary.json`.
#[derive(Debug, Clone, Deserialize, PartialEq)]
pub struct CampaignRow {
    /// Task name.
    pub task: String,
    /// The task's uncertain DOFs.
    pub dofs: Vec<String>,
    /// Trials run.
    pub trials: usize,
    /// Fraction of trials that went in.
    pub success_rate: f64,
    /// Contact motions per trial.
    pub contacts: ContactStats,
    /// Whether a camera took part.
    pub vision: bool,
    /// The last approach's error per DOF.
    pub final_errors: Vec<DofError>,
    /// How well the reported spreads held the truth (absent without the estimator, and in
    /// summaries written before the table showed it).
    #[serde(default)]
    pub calibration: Option<CalibrationRow>,
}

/// What the table reads of a summary's calibration.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq)]
pub struct CalibrationRow {
    /// Fraction of contact measurements whose truth lay within the 2-sigma ellipse.
    pub within_2sigma: f64,
    /// Mean NEES.
    pub nees_mean: f64,
    /// Its ideal, the DOF count.
    pub nees_ideal: f64,
}

impl fmt::Display for CalibrationRow {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{:.1} %, {:.2} ({})",
            100.0 * self.within_2sigma,
            self.nees_mean,
            self.nees_ideal
        )
    }
}

impl CampaignRow {
    /// Reads `<dir>/summary.json`.
    ///
    /// # Errors
    /// When the file cannot be read or lacks a field (a summary written before the table
    /// existed: run the campaign again).
    pub fn read(dir: &Path) -> Result<Self> {
        let path = dir.join("summary.json");
        let text = std::fs::read_to_string(&path).map_err(|e| HarnessError::io(&path, e))?;
        serde_json::from_str(&text).map_err(|source| HarnessError::Json { path, source })
    }
}

/// Campaigns side by side, one row each, in the order given.
#[derive(Debug, Clone, PartialEq)]
pub struct CampaignTable {
    /// The folders and what their summaries say.
    pub rows: Vec<(PathBuf, CampaignRow)>,
}

impl CampaignTable {
    /// Reads every folder's summary.
    ///
    /// # Errors
    /// As [`CampaignRow::read`].
    pub fn read(dirs: &[PathBuf]) -> Result<Self> {
        let rows = dirs
            .iter()
            .map(|d| Ok((d.clone(), CampaignRow::read(d)?)))
            .collect::<Result<_>>()?;
        Ok(Self { rows })
    }
}

impl fmt::Display for CampaignTable {
    /// A Markdown table.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "| campaign | task | DOFs | sensors | trials | success | contacts mean / median / p95 / max | within 2 sigma, NEES (ideal) | final |error| mean / max per DOF |"
        )?;
        writeln!(f, "|---|---|---|---|---|---|---|---|---|")?;
        for (dir, r) in &self.rows {
            let c = &r.contacts;
            let errors: Vec<String> = r.final_errors.iter().map(DofError::text).collect();
            writeln!(
                f,
                "| {} | {} | {} | {} | {} | {:.1} % | {:.2} / {} / {} / {} | {} | {} |",
                dir.display(),
                r.task,
                r.dofs.join(", "),
                if r.vision { "F/T + camera" } else { "F/T" },
                r.trials,
                100.0 * r.success_rate,
                c.mean,
                c.median,
                c.p95,
                c.max,
                r.calibration.map_or("n/a".to_owned(), |c| c.to_string()),
                errors.join("; ")
            )?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_summary_reads_back_into_a_row_and_a_line_of_the_table() {
        let dir = std::env::temp_dir().join(format!("table-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("scratch folder");
        let json = r#"{"task": "octagon_yaw", "dofs": ["object.x", "object.y", "object.rz"],
            "trials": 4, "success_rate": 0.75, "vision": false,
            "contacts": {"mean": 5.5, "median": 5.0, "p95": 9.0, "max": 9.0},
            "final_errors": [{"dof": "object.x", "mean": 1.2e-5, "max": 2.0e-5},
                             {"dof": "object.rz", "mean": 0.001, "max": 0.004}],
            "calibration": {"measurements": 20, "within_1sigma": 0.4, "within_2sigma": 0.85,
                            "per_dof": [], "nees_mean": 2.456, "nees_ideal": 3.0},
            "world": "mujoco"}"#;
        std::fs::write(dir.join("summary.json"), json).expect("write");
        let table = CampaignTable::read(std::slice::from_ref(&dir)).expect("reads");
        let text = table.to_string();
        let line = text.lines().nth(2).expect("one row");
        assert!(line.contains("| octagon_yaw | object.x, object.y, object.rz | F/T | 4 | 75.0 % | 5.50 / 5 / 9 / 9 | 85.0 %, 2.46 (3) |"), "{line}");
        assert!(
            line.contains("object.x 0.0120 / 0.0200 mm; object.rz 0.057 / 0.229 deg"),
            "{line}"
        );
        // A summary without the table's fields is named.
        std::fs::write(dir.join("summary.json"), r#"{"task": "x"}"#).expect("write");
        let e = CampaignTable::read(std::slice::from_ref(&dir)).expect_err("fields missing");
        assert!(e.to_string().contains("summary.json"), "{e}");
        std::fs::remove_dir_all(&dir).ok();
    }
}
