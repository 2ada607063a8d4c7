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
    for dir in take_created(|_| true).iter().rev() {
        let _ = std::fs::remove_dir_all(dir);
    }
}

/// Whether `path` belongs to the experiment writing under `roots`: a root, inside one, or a
/// directory created to hold one.
fn under(path: &Path, roots: &[&Path]) -> bool {
    roots
        .iter()
        .any(|root| path.starts_with(root) || root.starts_with(path))
}

/// Removes what one experiment writing under `roots` created (its temporaries, then its
/// directories, innermost first) and nothing of another experiment running beside it in
/// another thread: what a library caller (the Python package) does when an experiment fails.
pub fn remove_created_under(roots: &[&Path]) {
    refract_eval::atomic_write::remove_temporaries_where(|path| under(path, roots));
    for dir in take_created(|dir| under(dir, roots)).iter().rev() {
        let _ = std::fs::remove_dir_all(dir);
    }
}

/// Forgets the directories of an experiment writing under `roots` that finished: they stay.
pub fn keep_created_under(roots: &[&Path]) {
    take_created(|dir| under(dir, roots));
}

/// Removes the remembered directories `select` picks from the record and returns them.
fn take_created(select: impl Fn(&Path) -> bool) -> Vec<PathBuf> {
    let mut created = CREATED
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let (taken, kept) = std::mem::take(&mut *created)
        .into_iter()
        .partition(|dir| select(dir));
    *created = kept;
    taken
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
    take_created(|_| true);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_experiment_removes_only_what_it_created() {
        let base = tempfile::tempdir().expect("tempdir");
        let (ours, theirs) = (base.path().join("a/ours"), base.path().join("theirs"));
        create_dir(&ours.join("images")).expect("create ours");
        create_dir(&theirs.join("images")).expect("create theirs");
        remove_created_under(&[&ours]);
        assert!(
            !base.path().join("a").exists(),
            "ours and the parent made for it go"
        );
        assert!(
            theirs.join("images").is_dir(),
            "another experiment's directories stay"
        );
        keep_created_under(&[&theirs]);
        remove_created_under(&[&theirs]);
        assert!(theirs.is_dir(), "a kept directory is no longer removed");
    }
}
