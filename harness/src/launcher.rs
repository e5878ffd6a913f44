//! `harness`: checks that the MuJoCo 3.17.0 library can be found, then runs `harness-core`
//! (which links it) with the same arguments. Without this check a missing library would
//! stop the program in the system loader, before any message of ours.
//! `FTFUSION_MUJOCO_DIR` names another folder holding `libmujoco.so.3.17.0`.

use std::os::unix::process::CommandExt;
use std::path::PathBuf;
use std::process::{Command, ExitCode};

/// The library file mujoco-rs 7.0.0 links.
const LIBRARY: &str = "libmujoco.so.3.17.0";

fn main() -> ExitCode {
    let override_dir = std::env::var_os("FTFUSION_MUJOCO_DIR").map(PathBuf::from);
    let dir = override_dir
        .clone()
        .unwrap_or_else(|| PathBuf::from(env!("HARNESS_MUJOCO_DIR")));
    let on_loader_path = std::env::var_os("LD_LIBRARY_PATH")
        .map(|p| std::env::split_paths(&p).any(|d| d.join(LIBRARY).is_file()))
        .unwrap_or(false);
    if !dir.join(LIBRARY).is_file() && (override_dir.is_some() || !on_loader_path) {
        eprintln!(
            "error: the MuJoCo 3.17.0 library is missing: {} does not exist{}.\n\
             Install it with `bash scripts/setup.sh` (it takes the library from the PyPI wheel mujoco==3.17.0).",
            dir.join(LIBRARY).display(),
            if override_dir.is_some() {
                " (FTFUSION_MUJOCO_DIR)"
            } else {
                " and LD_LIBRARY_PATH has none"
            }
        );
        return ExitCode::from(2);
    }
    let core = match std::env::current_exe() {
        Ok(exe) => exe.with_file_name("harness-core"),
        Err(e) => {
            eprintln!("error: cannot locate the harness executable: {e}");
            return ExitCode::from(2);
        }
    };
    let mut cmd = Command::new(&core);
    cmd.args(std::env::args_os().skip(1));
    if let Some(d) = override_dir {
        let mut paths = vec![d];
        paths.extend(
            std::env::var_os("LD_LIBRARY_PATH")
                .iter()
                .flat_map(std::env::split_paths),
        );
        if let Ok(joined) = std::env::join_paths(paths) {
            cmd.env("LD_LIBRARY_PATH", joined);
        }
    }
    let err = cmd.exec();
    eprintln!("error: cannot run {}: {err}", core.display());
    ExitCode::from(2)
}
