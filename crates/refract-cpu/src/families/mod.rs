//! One module per method family, each a [`CpuFamily`], and [`Families`]: one value of every
//! family and the backend's one exhaustive `match` from [`MethodParams`] to the family that
//! renders it, both generated from one list (`cpu_families!`). A new family is its module here
//! and its line in that list.

pub mod depth_peel;
pub mod distance_map;
pub mod engine;
pub mod image_space;
pub mod nearby_geometry;
pub mod pvrr;

use std::sync::Arc;

use refract_scene::{BackendId, Frame, MethodParams, RenderError, Scene};

use crate::family::{CpuFamily, FrameCx};

/// The backend's one list of families: each line is a [`Families`] field, the family type
/// (a [`CpuFamily`]) and the [`MethodParams`] variant it renders; the families this backend does
/// not render are declined by name. A family of [`MethodParams`] missing from both lists is a
/// non-exhaustive `match`: it does not compile.
macro_rules! cpu_families {
    (
        declined: [$($declined:ident),*],
        $($(#[doc = $doc:literal])* $field:ident: $family:ty => $variant:ident,)*
    ) => {
        /// Every family's passes, kept between frames.
        #[derive(Default)]
        pub struct Families {
            $($(#[doc = $doc])* pub $field: $family,)*
        }

        impl Families {
            /// Prepares every family for `scene`.
            pub fn prepare(&mut self, scene: &Arc<Scene>) {
                $(self.$field.prepare(scene);)*
            }

            /// One frame of `method` by its family; the declined families are
            /// [`RenderError::Unsupported`].
            pub fn render(
                &mut self,
                cx: &FrameCx<'_>,
                method: &MethodParams,
                frame: &mut Frame,
            ) -> Result<(), RenderError> {
                match method {
                    $(MethodParams::$variant(p) => self.$field.render(cx, p, frame),)*
                    $(MethodParams::$declined(_))|* => Err(RenderError::Unsupported {
                        backend: BackendId::Cpu,
                        method: cx.method,
                    }),
                }
            }
        }
    };
}

cpu_families! {
    // The reference is refract-trace's.
    declined: [Reference],
    /// Wyman 2005a.
    image_space: image_space::ImageSpacePasses => ImageSpace,
    /// Wyman 2005b.
    nearby: nearby_geometry::NearbyPasses => NearbyGeometry,
    /// Umenhoffer et al. 2007.
    distance_map: distance_map::DistancePasses => DistanceMap,
    /// Kakimoto et al. 2007.
    pvrr: pvrr::PvrrPasses => Pvrr,
    /// Today's engines (Godot, three.js, Bevy, Unity HDRP, Filament).
    engine: engine::EnginePasses => Engine,
    /// Glass behind glass: every refractor's surfaces depth-peeled.
    depth_peel: depth_peel::DepthPeelPasses => DepthPeel,
}
