//! `harness-core`: the harness itself (links MuJoCo 3.17.0); users run it through the
//! `harness` launcher, which first checks that the library is there. It parses the command
//! line, calls the library's work and prints what it did; errors are reported with their
//! causes (`anyhow`).

mod cli;

use anyhow::{Context, bail};
use clap::Parser;

use harness::campaign::{Campaign, CampaignOptions, Offsets, Outcome, Plan, SetupNote};
use harness::compare::{MapComparison, RunsComparison};
use harness::render::{RenderOptions, View};
use harness::scan::{ScanOptions, scan_to_file};
use harness::shard::{self, Shard};
use harness::{boundary, runtime, scene, sim};

use cli::{Cli, Command, mm};

fn main() -> anyhow::Result<()> {
    ftmap::process::die_quietly_on_broken_pipe();
    run(Cli::parse())
}

/// Runs one command.
fn run(cli: Cli) -> anyhow::Result<()> {
    runtime::check_mujoco()?;
    match cli.command {
        Command::Scene { task, check } => {
            let tasks = scene::tasks_named(task.as_deref())?;
            if check {
                scene::check_scenes(&tasks)?;
            } else {
                for t in &tasks {
                    let path = sim::regenerate_scene(t)?;
                    println!("wrote {}", path.display());
                }
            }
        }
        Command::Render {
            task,
            out,
            object_mm,
            tcp_mm,
            noise,
            seed,
            detector,
            bench,
        } => {
            let mut view = View::open(RenderOptions {
                task,
                object: parse_mm(&object_mm)?,
                tcp: parse_mm(&tcp_mm)?,
                noise,
                seed,
                detector: detector.into(),
            })?;
            if let Some(n) = bench {
                print!("{}", view.bench(n)?);
            } else {
                let detected = view.detect();
                print!("{detected}");
                detected.save(&out)?;
                println!(
                    "image {} (blue: expected CAD edges, red: detected lines, yellow: endpoints)",
                    out.display()
                );
            }
        }
        Command::Trials {
            run,
            trials,
            range_mm,
        } => campaign(run.options(Offsets::Random {
            trials,
            half_width: range_mm.map(mm),
        }))?,
        Command::Bench { run, trials } => bench(run.options(Offsets::Random {
            trials,
            half_width: None,
        }))?,
        Command::Sweep {
            run,
            grid,
            range_mm,
        } => campaign(run.options(Offsets::Grid {
            points: grid,
            half_width: range_mm.map(mm),
        }))?,
        Command::Scan {
            task,
            out,
            step,
            size,
            yaw_step,
            yaw_size,
        } => {
            let scanned = scan_to_file(&ScanOptions {
                task,
                out,
                step: mm(step),
                half_width: size.map(mm),
                yaw_step: yaw_step.map(f64::to_radians),
                yaw_size: yaw_size.map(f64::to_radians),
            })?;
            println!("{scanned}");
        }
        Command::Boundary { task, directions } => {
            for t in scene::tasks_named(task.as_deref())? {
                let mut sim = sim::Sim::of_task(&t)?;
                let found = boundary::boundaries(&mut sim, &t, &boundary::directions(directions))?;
                print!("{found}");
            }
        }
        Command::CompareMaps { a, b, plot } => {
            let comparison = MapComparison::of_files(&a, &b)?;
            print!("{comparison}");
            comparison.plot(&plot)?;
            println!("plot {}", plot.display());
        }
        Command::Merge { shards, out } => {
            let shards = shards
                .iter()
                .map(|p| Shard::read(p))
                .collect::<harness::Result<Vec<_>>>()?;
            let n = shards.len();
            let (options, outcome, trace) = shard::merge(shards, &out)?;
            let plan = Plan::new(options)?;
            if let (Some(text), Some(file)) = (trace, plan.trace_file()?) {
                std::fs::create_dir_all(&out)
                    .and_then(|()| std::fs::write(&file, text))
                    .with_context(|| format!("writing {}", file.display()))?;
            }
            println!("merged {n} shards: {} trials", outcome.results.len());
            report(&plan, &outcome)?;
        }
        Command::Table { dirs } => {
            print!("{}", harness::table::CampaignTable::read(&dirs)?);
        }
        Command::CompareRuns { a, b, plot } => {
            let comparison = RunsComparison::read(&a, &b)?;
            print!("{comparison}");
            comparison.plot(&plot)?;
            println!("plot {}", plot.display());
        }
    }
    Ok(())
}

/// Sets a campaign up, runs it, writes its report and plot (a shard: its `shard.json`),
/// printing each step.
fn campaign(options: CampaignOptions) -> anyhow::Result<()> {
    let mut campaign = Campaign::open(options, &mut |note| println!("{note}"))?;
    let outcome = campaign.run()?;
    let plan = campaign.plan();
    match plan.options().shard {
        Some([i, n]) => {
            let shard = Shard::of(plan, &outcome)?;
            let file = shard.write()?;
            println!(
                "shard {i} of {n}: {} of {} trials in {} (join the shards with `harness merge`)",
                outcome.results.len(),
                shard.trials,
                file.display()
            );
            Ok(())
        }
        None => report(plan, &outcome),
    }
}

/// The campaign benchmark: `options` on one worker (in `<out>/serial`), then on its jobs
/// (in `<out>/parallel`), and the lever's accuracy at those settings: how far the scene's
/// torques miss the map's ([`harness::mismatch`]).
fn bench(options: CampaignOptions) -> anyhow::Result<()> {
    if options.shard.is_some() {
        bail!("the benchmark runs the whole campaign: drop --shard");
    }
    let mut lever = None;
    Campaign::open(
        CampaignOptions {
            out: options.out.join("lever"),
            measure_mismatch: true,
            mismatch: None,
            mismatch_angle: None,
            ..options.clone()
        },
        &mut |note| match note {
            SetupNote::Mismatch { misses, .. } => lever = Some(misses.to_string()),
            SetupNote::MismatchUnmeasured(why) => lever = Some(format!("not measured: {why}")),
            _ => {}
        },
    )?;
    let run = |name: &str, jobs| -> anyhow::Result<(Outcome, harness::report::Summary)> {
        let mut campaign = Campaign::open(
            CampaignOptions {
                out: options.out.join(name),
                jobs,
                ..options.clone()
            },
            &mut |_| {},
        )?;
        let outcome = campaign.run()?;
        let summary = campaign.plan().write_report(&outcome)?;
        Ok((outcome, summary))
    };
    let (a, sa) = run("serial", Some(1))?;
    let (b, sb) = run("parallel", options.jobs)?;
    let untimed = |o: &Outcome| -> Vec<_> { o.results.iter().map(|r| r.untimed()).collect() };
    let same = untimed(&a) == untimed(&b);
    println!(
        "campaign benchmark: {}, {} trials (reports in {})",
        sa.task,
        a.results.len(),
        options.out.display()
    );
    for (s, label) in [(&sa, "serial"), (&sb, "parallel")] {
        let realtime = match s.realtime_factor {
            0.0 => "nothing simulated".to_owned(),
            f => format!(
                "real-time factor {f:.1} x in MuJoCo, {:.1} x overall",
                s.realtime_factor_overall
            ),
        };
        println!(
            "  {label:<9} {} workers: {:.2} trials/s, {realtime}",
            s.jobs, s.trials_per_second
        );
    }
    if let Some(lever) = lever {
        println!("  lever: the scene's torques miss the map's {lever}");
    }
    println!(
        "  speed-up {:.2} x; results {}",
        sb.trials_per_second / sa.trials_per_second,
        if same {
            "identical to the serial run's"
        } else {
            "DIFFER from the serial run's"
        }
    );
    if !same {
        bail!("the parallel run's results differ from the serial run's");
    }
    Ok(())
}

/// Writes a campaign's report and plot, printing its summary.
fn report(plan: &Plan, outcome: &Outcome) -> anyhow::Result<()> {
    let summary = plan.write_report(outcome)?;
    println!("{}", summary.table());
    if let Some(plot) = plan.plot(outcome)? {
        println!("{plot}");
    }
    Ok(())
}

/// "x,y" in mm, in m.
fn parse_mm(s: &str) -> anyhow::Result<[f64; 2]> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .with_context(|| format!("\"{s}\": want x,y in mm"))?;
    match v.as_slice() {
        [x, y] => Ok([mm(*x), mm(*y)]),
        _ => bail!("\"{s}\": want x,y in mm"),
    }
}
