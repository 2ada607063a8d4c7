//! The passes and plumbing that more than one method family uses: rasterising any mesh from any
//! camera (`raster`, `surfaces`), the refractor's front and back faces (`refractor`), the
//! opaque objects' surfaces from a camera and their readers (`object_surfaces`), the objects
//! drawn over an image-space frame (`objects_over_frame`), the kernels' output buffers and
//! their decoding (`outputs`), and compute pipelines per registry row (`pipelines`). No family
//! module imports another's; each imports from here.

pub(crate) mod object_surfaces;
pub(crate) mod objects_over_frame;
pub(crate) mod outputs;
pub(crate) mod pipelines;
pub(crate) mod raster;
pub(crate) mod refractor;
pub(crate) mod surfaces;
