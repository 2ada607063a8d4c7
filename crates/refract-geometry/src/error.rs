//! The one error type of refract-geometry. Every variant names the file (or built-in shape) and
//! says what was expected.

use std::path::PathBuf;

/// Why a mesh could not be loaded, built or validated.
#[derive(Debug, thiserror::Error)]
pub enum GeometryError {
    /// The file could not be read.
    #[error("{}: cannot read the file", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error.
        #[source]
        source: std::io::Error,
    },
    /// The file is empty.
    #[error("{}: the file is empty; expected a mesh", path.display())]
    EmptyFile {
        /// The file.
        path: PathBuf,
    },
    /// The file extension is not one we load.
    #[error("{}: unsupported mesh format; expected a .obj, .gltf or .glb file", path.display())]
    UnsupportedFormat {
        /// The file.
        path: PathBuf,
    },
    /// tobj rejected the OBJ file.
    #[error("{}: not a valid OBJ file: {message}", path.display())]
    Obj {
        /// The file.
        path: PathBuf,
        /// What tobj reported.
        message: String,
    },
    /// The gltf crate rejected the glTF file, or its content is unusable.
    #[error("{}: not a valid glTF file: {message}", path.display())]
    Gltf {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// A triangle refers to a vertex that does not exist.
    #[error(
        "{source_name}: triangle {triangle} uses vertex index {index}, but the mesh has only {vertex_count} vertices"
    )]
    IndexOutOfRange {
        /// The file or built-in shape.
        source_name: String,
        /// The triangle.
        triangle: usize,
        /// The offending index.
        index: u32,
        /// How many vertices there are.
        vertex_count: usize,
    },
    /// A vertex position or normal is NaN or infinite.
    #[error(
        "{source_name}: vertex {vertex} has a non-finite {attribute} {value:?}; expected finite numbers"
    )]
    NonFinite {
        /// The file or built-in shape.
        source_name: String,
        /// The vertex.
        vertex: usize,
        /// `position` or `normal`.
        attribute: &'static str,
        /// The value found.
        value: [f32; 3],
    },
    /// Coordinates too large for the BVH builder.
    #[error(
        "{source_name}: a vertex coordinate of magnitude {magnitude:e}; the BVH needs magnitudes below {limit:e} (normalise the mesh or scale it down)"
    )]
    CoordinatesTooLarge {
        /// The mesh.
        source_name: String,
        /// The largest coordinate magnitude found.
        magnitude: f32,
        /// The limit.
        limit: f32,
    },
    /// A BVH deeper than a GPU traversal's stack.
    #[error(
        "{source_name}: its BVH is {depth} levels deep; the GPU traversal's stack holds {limit} (a mesh of many coincident triangles? weld or clean it)"
    )]
    BvhTooDeep {
        /// The mesh.
        source_name: String,
        /// The tree's depth.
        depth: u32,
        /// The stack size.
        limit: u32,
    },
    /// Attribute arrays of different lengths.
    #[error("{source_name}: {attribute} has {found} entries for {vertex_count} vertices")]
    AttributeLength {
        /// The file or built-in shape.
        source_name: String,
        /// The attribute.
        attribute: &'static str,
        /// Its length.
        found: usize,
        /// How many vertices there are.
        vertex_count: usize,
    },
    /// Nothing is left to render.
    #[error(
        "{source_name}: no triangles left after removing {degenerate} degenerate ones; expected a mesh with area"
    )]
    NoTriangles {
        /// The file or built-in shape.
        source_name: String,
        /// How many degenerate triangles were removed.
        degenerate: usize,
    },
    /// An unknown `builtin:` name.
    #[error("unknown built-in shape `{name}`; expected one of: {valid}")]
    UnknownBuiltin {
        /// The name asked for.
        name: String,
        /// The valid names, comma-separated.
        valid: String,
    },
    /// Lens parameters that describe no physical lens.
    #[error("lens: {0}")]
    Lens(String),
    /// Shape parameters out of range.
    #[error("{shape}: {message}")]
    Shape {
        /// The shape.
        shape: &'static str,
        /// What was expected.
        message: String,
    },
}
