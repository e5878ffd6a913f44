//! `harness`: the command-line front of the MuJoCo validation harness.

use clap::Parser;

fn main() -> anyhow::Result<()> {
    harness::cli::run(harness::cli::Cli::parse())
}
