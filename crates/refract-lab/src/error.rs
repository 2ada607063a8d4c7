//! The one error type of the experiments: every variant says what failed and, where a file or a
//! field is involved, names it.

use std::fmt::Display;
use std::path::PathBuf;

use refract_gpu::GpuError;
use refract_scene::{RenderError, SceneError};

/// Why an experiment could not run or finish.
#[derive(Debug, thiserror::Error)]
pub enum LabError {
    /// A scene, an environment map, a parameter or a frame file.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// A renderer could not prepare a scene or render a frame.
    #[error(transparent)]
    Render(#[from] RenderError),
    /// A mesh could not be loaded or built.
    #[error(transparent)]
    Geometry(#[from] refract_geometry::GeometryError),
    /// The GPU backend could not start.
    #[error(transparent)]
    Gpu(#[from] GpuError),
    /// A file could not be read or written.
    #[error("{}: {action}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What was attempted.
        action: String,
        /// The OS error.
        #[source]
        source: std::io::Error,
    },
    /// An input out of range or of the wrong kind (a sweep file's field, an option, a model
    /// name), or a run that cannot be done (not enough memory, nothing to do).
    #[error("{0}")]
    Invalid(String),
    /// An OS error without a file to name (the context around it names one).
    #[error(transparent)]
    Os(std::io::Error),
    /// The caller asked the experiment to stop ([`crate::Progress::cancelled`]).
    #[error("interrupted")]
    Cancelled,
    /// An error with what was being done when it happened.
    #[error("{context}")]
    Context {
        /// What was being done.
        context: String,
        /// What went wrong.
        #[source]
        source: Box<LabError>,
    },
}

impl LabError {
    /// [`LabError::Invalid`].
    pub fn invalid(message: impl Display) -> Self {
        Self::Invalid(message.to_string())
    }
}

impl From<std::io::Error> for LabError {
    fn from(source: std::io::Error) -> Self {
        Self::Os(source)
    }
}

impl From<serde_json::Error> for LabError {
    fn from(err: serde_json::Error) -> Self {
        Self::Invalid(format!("JSON: {err}"))
    }
}

/// The result of an experiment.
pub type Result<T, E = LabError> = std::result::Result<T, E>;

/// Adds what was being done to an error (as `anyhow::Context` does, into a [`LabError`]).
pub trait Context<T> {
    /// The error, with `context` before it.
    fn context(self, context: impl Display) -> Result<T>;
    /// The error, with `context()` before it (computed only on error).
    fn with_context<C: Display>(self, context: impl FnOnce() -> C) -> Result<T>;
}

impl<T, E: Into<LabError>> Context<T> for std::result::Result<T, E> {
    fn context(self, context: impl Display) -> Result<T> {
        self.map_err(|err| LabError::Context {
            context: context.to_string(),
            source: Box::new(err.into()),
        })
    }

    fn with_context<C: Display>(self, context: impl FnOnce() -> C) -> Result<T> {
        self.map_err(|err| LabError::Context {
            context: context().to_string(),
            source: Box::new(err.into()),
        })
    }
}

impl<T> Context<T> for Option<T> {
    fn context(self, context: impl Display) -> Result<T> {
        self.ok_or_else(|| LabError::invalid(context))
    }

    fn with_context<C: Display>(self, context: impl FnOnce() -> C) -> Result<T> {
        self.ok_or_else(|| LabError::invalid(context()))
    }
}

/// Returns a [`LabError::Invalid`] with a formatted message.
#[macro_export]
macro_rules! bail {
    ($($arg:tt)*) => {
        return Err($crate::LabError::Invalid(format!($($arg)*)))
    };
}

/// Returns a [`LabError::Invalid`] with a formatted message unless `condition` holds.
#[macro_export]
macro_rules! ensure {
    ($condition:expr, $($arg:tt)*) => {
        if !$condition {
            $crate::bail!($($arg)*);
        }
    };
}

impl From<toml::de::Error> for LabError {
    fn from(err: toml::de::Error) -> Self {
        Self::Invalid(err.to_string())
    }
}

impl From<refract_scene::registry::UnknownMethod> for LabError {
    fn from(err: refract_scene::registry::UnknownMethod) -> Self {
        Self::Invalid(err.to_string())
    }
}
