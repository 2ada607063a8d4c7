//! Leaving nothing half-made behind: the output directories an experiment creates are
//! remembered, so that a program can remove them when the experiment fails or is interrupted
//! (the CLI does on SIGINT and SIGTERM), together with every temporary file being written
//! (`refract_eval::atomic_write::remove_temporaries`).

use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};

/// Directories this run created, outermost first.
static CREATED: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Set once by [`interrupt`]: no directory is created after it.
static INTERRUPTED: AtomicBool = AtomicBool::new(false);

/// `create_dir_all(dir)`, remembering each level this run creates. After [`interrupt`] it
/// creates nothing and returns `ErrorKind::Interrupted`, so that a worker still running cannot
/// recreate a directory the interrupt has just removed.
pub fn create_dir(dir: &Path) -> std::io::Result<()> {
    if interrupted() {
        return Err(std::io::Error::new(
            std::io::ErrorKind::Interrupted,
            "the run was interrupted",
        ));
    }
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

/// Marks the run interrupted (see [`interrupted`]), then removes what it created. Called from a
/// signal handler's thread while the experiment may still be running on others.
pub fn interrupt() {
    INTERRUPTED.store(true, Ordering::SeqCst);
    remove_created();
}

/// Whether [`interrupt`] has been called: a program that sees an error or a finished run after
/// this leaves the exit to the interrupt's handler (the error is likely the interrupt's removal
/// of a directory the run was writing into).
pub fn interrupted() -> bool {
    INTERRUPTED.load(Ordering::SeqCst)
}

/// Forgets the directories of a run that finished: they stay.
pub fn keep_created() {
    if let Ok(mut created) = CREATED.lock() {
        created.clear();
    }
}
