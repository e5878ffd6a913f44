//! The MuJoCo library at run time: the version check every entry point makes first.

use crate::error::{HarnessError, Result};

/// The MuJoCo version mujoco-rs 7.0.0 binds (3.17.0), as `mj_version()` reports it: MuJoCo
/// 3.17 numbers versions major * 10^6 + minor * 10^3 + patch (3017000), not 3170; this is
/// the header version mujoco-rs was generated from.
pub const MUJOCO_VERSION: i32 = mujoco_rs::mujoco_c::mjVERSION_HEADER as i32;

/// Checks that the loaded MuJoCo library is 3.17.0.
///
/// # Errors
/// [`HarnessError::MujocoVersion`] naming `bash scripts/setup.sh` otherwise.
pub fn check_mujoco() -> Result<()> {
    // SAFETY: mj_version takes no arguments and only returns a constant.
    let got = unsafe { mujoco_rs::mujoco_c::mj_version() };
    if got == MUJOCO_VERSION {
        Ok(())
    } else {
        Err(HarnessError::MujocoVersion {
            expected: MUJOCO_VERSION,
            got,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_linked_library_is_mujoco_3_17_0() {
        check_mujoco().unwrap();
        assert_eq!(MUJOCO_VERSION, 3_017_000);
        assert_eq!(mujoco_rs::mujoco_version(), "3.17.0");
    }
}
