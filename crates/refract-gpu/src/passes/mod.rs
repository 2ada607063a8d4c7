//! The passes every method family draws with.

pub(crate) mod raster;
pub(crate) mod surfaces;
