//! `harness-core`: the harness itself (links MuJoCo 3.17.0); users run it through the
//! `harness` launcher, which first checks that the library is there. It parses the command
//! line, calls the library's work and prints what it did; errors are reported with their
//! causes (`anyhow`).

mod cli;

use anyhow::{Context, bail};
use clap::Parser;

use harness::campaign::{Campaign, CampaignOptions, Offsets};
use harness::compare::{MapComparison, RunsComparison};
use harness::render::{RenderOptions, View};
use harness::scan::{ScanOptions, scan_to_file};
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
        } => {
            let scanned = scan_to_file(&ScanOptions {
                task,
                out,
                step: mm(step),
                half_width: size.map(mm),
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

/// Sets a campaign up, runs it, writes its report and plot, printing each step.
fn campaign(options: CampaignOptions) -> anyhow::Result<()> {
    let mut campaign = Campaign::open(options, &mut |note| println!("{note}"))?;
    let outcome = campaign.run()?;
    let summary = campaign.write_report(&outcome)?;
    println!("{}", summary.table());
    if let Some(plot) = campaign.plot(&outcome)? {
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
