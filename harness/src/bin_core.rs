//! `harness-core`: the harness itself (links MuJoCo 3.17.0); users run it through the
//! `harness` launcher, which first checks that the library is there.

use clap::Parser;

fn main() -> anyhow::Result<()> {
    harness::cli::run(harness::cli::Cli::parse())
}
