//! Shared helpers of refract's cross-crate integration tests.
//!
//! Tests that read the real meshes and environment maps of `../shared/data` call
//! [`shared_data`]: on a user's fresh clone that directory does not exist, so the test prints
//! `skipped: ../shared/data not found` and passes, unless `REFRACT_REQUIRE_DATA=1` (set by CI),
//! where a missing directory fails the test.

use std::path::PathBuf;

pub mod scenes;

/// The workspace root (the parent of this crate's directory).
pub fn workspace_root() -> PathBuf {
    let here = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    here.parent().map(PathBuf::from).unwrap_or(here)
}

/// `../shared/data` relative to the workspace root, or `REFRACT_DATA_DIR` when set.
pub fn shared_data_dir() -> PathBuf {
    std::env::var_os("REFRACT_DATA_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| workspace_root().join("../shared/data"))
}

/// Whether `REFRACT_REQUIRE_DATA=1`.
pub fn data_required() -> bool {
    std::env::var("REFRACT_REQUIRE_DATA").is_ok_and(|v| v == "1")
}

/// The shared data directory if it exists. Otherwise prints the skip notice and returns `None`,
/// or panics when `REFRACT_REQUIRE_DATA=1`.
pub fn shared_data() -> Option<PathBuf> {
    let dir = shared_data_dir();
    if dir.is_dir() {
        return Some(dir);
    }
    assert!(
        !data_required(),
        "REFRACT_REQUIRE_DATA=1 but {} does not exist",
        dir.display()
    );
    println!("skipped: ../shared/data not found");
    None
}
