//! Campaign shards: a campaign's trials split by index over runs on other machines (shard I
//! of N runs trial i where i mod N = I, with the seed and true offsets the whole campaign
//! gives it), each run writing `shard.json`, and `merge`, which joins the shards into the
//! report that one run of the whole campaign writes. A shard carries its results exactly
//! (JSON numbers that read back to the same f64) and the FMU's trace of trial 0 where it
//! ran it, so that merging needs no file system shared with the machines that ran them.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::campaign::{CampaignOptions, Outcome, Plan, shard_indices};
use crate::error::{HarnessError, Result, create_dir};
use crate::mismatch::Given;
use crate::report::Pace;
use crate::trial::TrialResult;

/// The version of the `shard.json` layout.
pub const VERSION: u32 = 1;

/// The file a shard's run writes in its output folder.
pub const FILE: &str = "shard.json";

/// One shard's run of a campaign.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Shard {
    /// The layout's version ([`VERSION`]).
    pub version: u32,
    /// The campaign's options; those of all its shards agree but for `out`, `jobs` and
    /// `shard`.
    pub options: CampaignOptions,
    /// Trials of the whole campaign.
    pub trials: usize,
    /// This shard: I of N.
    pub shard: [usize; 2],
    /// Its trials: (trial index, result), ascending.
    pub results: Vec<(usize, TrialResult)>,
    /// How long its trials took, on how many workers.
    pub pace: Pace,
    /// The FMU's trace of trial 0 (`trace.csv`), in the shard that ran it with a trace.
    pub trace: Option<String>,
    /// The `mismatch` and `mismatch_angle` its FMU ran with (absent in shards written
    /// before they were recorded).
    #[serde(default)]
    pub mismatch: Option<Given>,
}

impl Shard {
    /// The shard of `plan` (its options name it) that ran `outcome`, with the FMU's trace
    /// where the shard ran trial 0.
    ///
    /// # Errors
    /// When the trace cannot be read.
    pub fn of(plan: &Plan, outcome: &Outcome) -> Result<Self> {
        let options = plan.options();
        let (shard, trials) = (options.shard.unwrap_or([0, 1]), plan.trials());
        let trace = match plan.trace_file()? {
            Some(file) if shard[0] == 0 && file.is_file() => {
                Some(std::fs::read_to_string(&file).map_err(|e| HarnessError::io(&file, e))?)
            }
            _ => None,
        };
        Ok(Self {
            version: VERSION,
            options: options.clone(),
            trials,
            shard,
            results: shard_indices(shard, trials)
                .zip(outcome.results.iter().cloned())
                .collect(),
            pace: outcome.pace,
            trace,
            mismatch: outcome.mismatch,
        })
    }

    /// Writes the shard to `<out>/shard.json`; returns the file.
    ///
    /// # Errors
    /// When the folder or file cannot be written.
    pub fn write(&self) -> Result<PathBuf> {
        create_dir(&self.options.out)?;
        let file = self.options.out.join(FILE);
        let text = serde_json::to_string(self).map_err(|e| HarnessError::Invalid {
            what: "shard",
            reason: e.to_string(),
        })?;
        std::fs::write(&file, text).map_err(|e| HarnessError::io(&file, e))?;
        Ok(file)
    }

    /// Reads a shard from `path`: a `shard.json` or a folder holding one.
    ///
    /// # Errors
    /// When the file cannot be read, is not a shard, or has another layout version.
    pub fn read(path: &Path) -> Result<Self> {
        let file = if path.is_dir() {
            path.join(FILE)
        } else {
            path.to_owned()
        };
        let text = std::fs::read_to_string(&file).map_err(|e| HarnessError::io(&file, e))?;
        let bad = |reason: String| HarnessError::Invalid {
            what: "shard",
            reason: format!("{}: {reason}", file.display()),
        };
        let shard: Self = serde_json::from_str(&text).map_err(|e| bad(e.to_string()))?;
        if shard.version != VERSION {
            return Err(bad(format!(
                "layout version {}, this harness reads {VERSION}",
                shard.version
            )));
        }
        Ok(shard)
    }
}

/// The campaign the shards ran, written to `out`: its options (with `out`, no shard), the
/// outcome of all its trials in trial order (the longest shard's wall-clock time, the
/// shards' workers summed), and trial 0's trace.
///
/// # Errors
/// When there is no shard, the shards ran different campaigns or splits, a shard is
/// missing or given twice, or a shard's trials are not those its index names.
pub fn merge(shards: Vec<Shard>, out: &Path) -> Result<(CampaignOptions, Outcome, Option<String>)> {
    let bad = |reason: String| HarnessError::Invalid {
        what: "shards",
        reason,
    };
    let first = shards.first().ok_or_else(|| bad("no shard given".into()))?;
    let campaign = |s: &Shard| CampaignOptions {
        out: PathBuf::new(),
        jobs: None,
        shard: None,
        ..s.options.clone()
    };
    let (options, trials, [first_i, n]) = (campaign(first), first.trials, first.shard);
    let mismatch = first.mismatch;
    let mut seen = vec![false; n];
    let mut results: Vec<Option<TrialResult>> = vec![None; trials];
    let mut trace = None;
    let (mut wall, mut jobs) = (0.0f64, 0);
    for s in shards {
        let [i, m] = s.shard;
        if campaign(&s) != options
            || s.trials != trials
            || m != n
            || i >= n
            || s.mismatch != mismatch
        {
            return Err(bad(format!(
                "shard {i}/{m} ran another campaign or split than shard {first_i}/{n} (options, trial count, N and the FMU's mismatch must agree)"
            )));
        }
        if std::mem::replace(&mut seen[i], true) {
            return Err(bad(format!("shard {i}/{n} is given twice")));
        }
        for (k, r) in s.results {
            // Shard I's trials are those with i mod N = I ([`shard_indices`]).
            if k >= trials || k % n != i {
                return Err(bad(format!(
                    "shard {i}/{n} holds trial {k}, not one of its own"
                )));
            }
            results[k] = Some(r);
        }
        trace = trace.or(s.trace);
        wall = wall.max(s.pace.wall);
        jobs += s.pace.jobs;
    }
    if let Some(i) = seen.iter().position(|s| !s) {
        return Err(bad(format!("shard {i}/{n} is missing")));
    }
    let results: Vec<TrialResult> = results
        .into_iter()
        .enumerate()
        .map(|(k, r)| r.ok_or_else(|| bad(format!("trial {k} is in no shard"))))
        .collect::<Result<_>>()?;
    Ok((
        CampaignOptions {
            out: out.to_owned(),
            ..options
        },
        Outcome {
            results,
            pace: Pace { wall, jobs },
            mismatch,
        },
        trace,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::campaign::Offsets;
    use crate::mismatch::Source;

    /// A result whose figures need all 17 digits of an f64.
    fn result(k: usize) -> TrialResult {
        TrialResult {
            offset: [0.1 + k as f64 / 3.0, -1.0 / 7.0],
            grip: [0.0; 2],
            rot: [0.0; 3],
            symmetry: None,
            contacts: k,
            success: true,
            final_error: 2f64.sqrt() * 1e-5,
            final_rot_error: [0.0; 3],
            wall: 0.5,
            sim_time: 0.1 + 0.2,
            sim_wall: 0.25,
            steps: Vec::new(),
            first_look: None,
            images_missed: 0,
        }
    }

    fn options(shard: [usize; 2]) -> CampaignOptions {
        let mut cli = serde_json::json!({
            "task": "peg_in_hole", "out": format!("s{}", shard[0]), "seed": 4,
            "offsets": Offsets::Random { trials: 5, half_width: None },
            "map": null, "vision": false, "vision_method": "Recalibration",
            "sigma_vision": null, "image_noise": 2.0, "detector": "Gradient",
            "strategy": "pf", "sensor_noise": true, "slide": true, "twist": true, "fmu": null,
            "max_contacts": null, "max_sim_time": null, "particles": null, "iterations": null,
            "sigma_torque": null, "sigma_force": null, "sigma_depth": null, "mismatch": null,
            "mismatch_angle": null, "lost": null, "world": "mujoco", "jobs": null,
        });
        cli["shard"] = serde_json::json!(shard);
        serde_json::from_value(cli).expect("options")
    }

    /// Shard i of n of a 5-trial campaign.
    fn shard(i: usize, n: usize) -> Shard {
        Shard {
            version: VERSION,
            options: options([i, n]),
            trials: 5,
            shard: [i, n],
            results: (i..5).step_by(n).map(|k| (k, result(k))).collect(),
            pace: Pace {
                wall: 1.0 + i as f64,
                jobs: 2,
            },
            trace: (i == 0).then(|| "trace".into()),
            mismatch: Some(Given {
                along: Source::Measured(0.022),
                across: Source::Given(0.011),
            }),
        }
    }

    #[test]
    fn a_shard_reads_back_exactly() {
        let s = shard(1, 2);
        let text = serde_json::to_string(&s).expect("written");
        assert_eq!(serde_json::from_str::<Shard>(&text).expect("read"), s);
    }

    #[test]
    fn shards_merge_in_trial_order_in_any_order() {
        let (options, outcome, trace) =
            merge(vec![shard(2, 3), shard(0, 3), shard(1, 3)], Path::new("m")).expect("merged");
        assert_eq!(outcome.results, (0..5).map(result).collect::<Vec<_>>());
        assert_eq!(outcome.pace, Pace { wall: 3.0, jobs: 6 });
        assert_eq!(trace.as_deref(), Some("trace"));
        assert_eq!(outcome.mismatch, shard(0, 3).mismatch);
        assert_eq!((options.out, options.shard), (PathBuf::from("m"), None));
    }

    #[test]
    fn missing_doubled_and_foreign_shards_are_refused_by_name() {
        let refused = |shards: Vec<Shard>| {
            merge(shards, Path::new("m"))
                .expect_err("refused")
                .to_string()
        };
        assert!(refused(vec![shard(0, 3), shard(2, 3)]).contains("shard 1/3 is missing"));
        assert!(refused(vec![shard(0, 2), shard(0, 2), shard(1, 2)]).contains("given twice"));
        assert!(refused(vec![shard(0, 2), shard(1, 3)]).contains("another campaign or split"));
        let mut other_seed = shard(1, 2);
        other_seed.options.seed = 5;
        assert!(refused(vec![shard(0, 2), other_seed]).contains("another campaign"));
        let mut other_mismatch = shard(1, 2);
        other_mismatch.mismatch = None;
        assert!(refused(vec![shard(0, 2), other_mismatch]).contains("the FMU's mismatch"));
        let mut stray = shard(1, 2);
        stray.results.push((2, result(2)));
        assert!(refused(vec![shard(0, 2), stray]).contains("holds trial 2"));
        assert!(refused(Vec::new()).contains("no shard"));
    }
}
