//! The threads Rust work runs on from Python, rebuilt in a forked child.
//!
//! `os.fork()` (multiprocessing's default start method on Linux before Python 3.14) copies
//! only the calling thread. rayon's global pool would survive in the child as bookkeeping
//! without threads: the first parallel loop there waits forever for workers that do not exist.
//! So every call from Python runs inside a pool this module owns, keyed by the process id: a
//! child finds a pool built by another process, leaks it (its threads are gone, so neither
//! joining nor signalling them is safe) and builds its own.
//!
//! The same holds for a scene's prepared renderers (a GPU device and its driver's threads):
//! [`ForkLocal`] keeps a value with the process that made it and hands a child a fresh one.

use std::sync::{Arc, Mutex, PoisonError};

/// This process's pool, built on first use.
static POOL: Mutex<Option<(u32, Arc<rayon::ThreadPool>)>> = Mutex::new(None);

/// The rayon pool of this process: the one built here, or a new one if the pool on record
/// was built before a fork.
fn pool() -> Result<Arc<rayon::ThreadPool>, rayon::ThreadPoolBuildError> {
    let pid = std::process::id();
    let mut slot = POOL.lock().unwrap_or_else(PoisonError::into_inner);
    if let Some((owner, pool)) = slot.as_ref()
        && *owner == pid
    {
        return Ok(pool.clone());
    }
    let pool = Arc::new(
        rayon::ThreadPoolBuilder::new()
            .thread_name(|i| format!("refract-{i}"))
            .build()?,
    );
    if let Some(inherited) = slot.replace((pid, pool.clone())) {
        // Built by the parent: its threads do not exist here.
        std::mem::forget(inherited);
    }
    Ok(pool)
}

/// Runs `work` on this process's pool (every rayon loop inside it runs there).
pub fn run<T: Send>(work: impl FnOnce() -> T + Send) -> Result<T, rayon::ThreadPoolBuildError> {
    Ok(pool()?.install(work))
}

/// A value that belongs to the process that made it: a forked child gets a fresh one from
/// `make` and leaks the parent's (dropping a GPU device whose driver threads were not copied
/// may block).
pub struct ForkLocal<T> {
    owner: u32,
    value: T,
}

impl<T> ForkLocal<T> {
    /// `value`, owned by this process.
    pub fn new(value: T) -> Self {
        Self {
            owner: std::process::id(),
            value,
        }
    }

    /// The value, replaced by `make()` first if it was made by another process.
    pub fn get_mut(&mut self, make: impl FnOnce() -> T) -> &mut T {
        let pid = std::process::id();
        if self.owner != pid {
            std::mem::forget(std::mem::replace(&mut self.value, make()));
            self.owner = pid;
        }
        &mut self.value
    }
}
