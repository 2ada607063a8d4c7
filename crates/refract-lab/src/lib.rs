//! # refract-lab
//!
//! The experiments of refract as a library, typed in and typed out, without printing: what the
//! `refract` CLI (and, next, the Python package) calls.
//!
//! * [`compare`]: every method against the exact reference on each scene: images, error maps,
//!   `metrics.json`, `report.md`, `index.html` ([`report`]).
//! * [`sweep`]: a sweep file expanded into jobs, run in shards with resume and a reference
//!   cache; [`sweep_report`] gathers shards into tables and plots.
//! * [`claims`]: the papers' testable claims, measured, with computed verdicts
//!   (`docs/claims.md`).
//! * [`bench`](mod@bench): the papers' timing tables on this machine.
//! * [`engines`]: the engines' own renderers (three.js, ...) beside the methods.
//! * [`render`](mod@render): one frame of one method, as `refract render` and Python render it.
//! * [`backends`], [`memory`], [`timing`], [`data_scenes`], [`output_dirs`], [`provenance`]:
//!   what they share.
//!
//! Progress and notes go through [`Progress`] ([`Quiet`] ignores them); errors are
//! [`LabError`]. Modules depend downward only: `report` and `sweep_report` render results,
//! `compare` and `sweep` produce them, the shared types ([`jobs`]) sit below both.

pub mod backends;
pub mod bench;
pub mod claims;
pub mod compare;
pub mod data_scenes;
pub mod engines;
#[macro_use]
pub mod error;
pub mod html;
pub mod jobs;
pub mod memory;
pub mod output_dirs;
pub mod overview;
pub mod plots;
pub mod progress;
pub mod provenance;
pub mod render;
pub mod report;
pub mod sweep;
pub mod sweep_report;
pub mod timing;

pub use error::{Context, LabError, Result};
pub use progress::{Note, Progress, Quiet};
