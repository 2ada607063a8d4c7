//! The one error type of refract-scene's I/O and validation. Every variant names the file or
//! field and says what was expected.

use std::path::PathBuf;

use refract_geometry::GeometryError;

/// Why a scene, an environment map or a frame file could not be read, built or written.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The file could not be read or written.
    #[error("{}: {action}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What was attempted.
        action: &'static str,
        /// The OS error.
        #[source]
        source: std::io::Error,
    },
    /// The file is not a readable file of the expected kind.
    #[error("{}: {message}", path.display())]
    Format {
        /// The file.
        path: PathBuf,
        /// What was wrong and what was expected.
        message: String,
    },
    /// A field (of a scene file, or a parameter) out of range or of the wrong kind.
    #[error("{origin}: {field} = {value}: {expected}")]
    Field {
        /// The scene file, built-in scene or command-line option.
        origin: String,
        /// The field.
        field: String,
        /// Its value.
        value: String,
        /// What was expected.
        expected: String,
    },
    /// The scene file is not valid TOML for a scene.
    #[error("{origin}: {message}")]
    Parse {
        /// The scene file or built-in scene.
        origin: String,
        /// What the TOML parser said.
        message: String,
    },
    /// An unknown built-in scene name, or a path that is not a scene file.
    #[error(
        "unknown scene `{name}`: expected a built-in scene ({builtins}), a .toml scene file or a .gltf/.glb file"
    )]
    UnknownScene {
        /// The name or path given.
        name: String,
        /// The built-in scenes' names, comma-separated.
        builtins: String,
    },
    /// A mesh could not be loaded or built.
    #[error("{origin}")]
    Geometry {
        /// The scene file or built-in scene.
        origin: String,
        /// What went wrong.
        #[source]
        source: GeometryError,
    },
}

/// An error and every error behind it (its `source()` chain), `": "`-separated: the whole
/// message, as the CLI prints it. By the rule every error type here follows, a wrapper's own
/// message does not repeat its source's, so each part appears once.
pub fn full_message(error: &(dyn std::error::Error + 'static)) -> String {
    let mut message = error.to_string();
    let mut source = error.source();
    while let Some(inner) = source {
        message.push_str(": ");
        message.push_str(&inner.to_string());
        source = inner.source();
    }
    message
}

impl SceneError {
    /// A [`SceneError::Field`].
    pub fn field(
        origin: impl Into<String>,
        field: impl Into<String>,
        value: impl ToString,
        expected: impl Into<String>,
    ) -> Self {
        Self::Field {
            origin: origin.into(),
            field: field.into(),
            value: value.to_string(),
            expected: expected.into(),
        }
    }
}
