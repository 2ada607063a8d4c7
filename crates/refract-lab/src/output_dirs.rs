//! Leaving nothing half-made behind: the output directories an experiment creates are
//! remembered, so that a program can remove them when the experiment fails or is interrupted
//! (the CLI does on SIGINT and SIGTERM), together with every temporary file being written
//! (`refract_eval::atomic_write::remove_temporaries`).

use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// Directories this run created, outermost first.
static CREATED: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// `create_dir_all(dir)`, remembering each level this run creates.
pub fn create_dir(dir: &Path) -> std::io::Result<()> {
    let mut missing = Vec::new();
    let mut at = Some(dir);
    while let Some(path) = at.filter(|p| !p.as_os_str().is_empty() && !p.exists()) {
        missing.push(path.to_owned());
        at = path.parent();
    }
    std::fs::create_dir_all(dir)?;
    if let Ok(mut created) = CREATED.lock() {
        created.extend(missing.into_iter().rev());
    }
    Ok(())
}

/// Removes what this run created (temporaries, then directories, innermost first).
pub fn remove_created() {
    refract_eval::atomic_write::remove_temporaries();
    let created = match CREATED.lock() {
        Ok(mut created) => std::mem::take(&mut *created),
        Err(_) => return,
    };
    for dir in created.iter().rev() {
        let _ = std::fs::remove_dir_all(dir);
    }
}

/// Forgets the directories of a run that finished: they stay.
pub fn keep_created() {
    if let Ok(mut created) = CREATED.lock() {
        created.clear();
    }
}
