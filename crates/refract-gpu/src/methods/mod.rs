//! One module per method family, the same names as the CPU backend's.

pub(crate) mod image_space;
pub(crate) mod nearby_geometry;
