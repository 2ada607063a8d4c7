//! How an experiment reports while it runs: stages with a step count, and notes. The library
//! never prints; the CLI draws progress bars and prints the notes, a script passes [`Quiet`] or
//! its own [`Progress`].

use std::fmt;

/// Something the user of an experiment should know.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Note {
    /// A problem that did not stop the run (a scene's warning, a job that failed in a sweep).
    Warning(String),
    /// A (method, scene) pair, a model or a backend left out, and why.
    Skipped(String),
    /// What is being used (the GPU adapter) or what a run will do (jobs to run, cached).
    Info(String),
    /// A line of a table an experiment produces as it goes (`refract bench` rows).
    Row(String),
}

impl fmt::Display for Note {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Note::Warning(text) => write!(f, "warning: {text}"),
            Note::Skipped(text) => write!(f, "note: {text}"),
            Note::Info(text) | Note::Row(text) => f.write_str(text),
        }
    }
}

/// The receiver of an experiment's progress (called from the experiment's thread).
pub trait Progress {
    /// Stage `stage` (e.g. `reference`, `methods`, `jobs`) starts with `total` steps.
    fn start(&self, _stage: &str, _total: u64) {}
    /// `steps` more steps of `stage` are done.
    fn advance(&self, _stage: &str, _steps: u64) {}
    /// `stage` is done.
    fn finish(&self, _stage: &str) {}
    /// A note.
    fn note(&self, _note: Note) {}
    /// Whether the caller wants the experiment to stop: asked between frames (compare) and
    /// between jobs (sweep), which then return [`crate::LabError::Cancelled`]. The Python
    /// package answers from Python's signal handlers, so that Ctrl-C stops a long run.
    fn cancelled(&self) -> bool {
        false
    }
}

/// A [`Progress`] that ignores everything.
#[derive(Clone, Copy, Debug, Default)]
pub struct Quiet;

impl Progress for Quiet {}

/// A [`Progress`] that keeps the notes (for tests and scripts).
#[derive(Debug, Default)]
pub struct Notes(pub std::sync::Mutex<Vec<Note>>);

impl Progress for Notes {
    fn note(&self, note: Note) {
        if let Ok(mut notes) = self.0.lock() {
            notes.push(note);
        }
    }
}
