//! One module per method family, the same names as the CPU backend's, each a
//! [`GpuFamily`](crate::family::GpuFamily); and [`Families`]: one [`FamilySlot`] per family and
//! the backend's one exhaustive `match` from [`MethodParams`] to the family that renders it,
//! both generated from one list (`gpu_families!`). A new family is its module here and its line
//! in that list.

pub(crate) mod depth_peel;
pub(crate) mod distance_map;
pub(crate) mod engine;
pub(crate) mod image_space;
pub(crate) mod nearby_geometry;
pub(crate) mod pvrr;
pub(crate) mod reference;

use std::sync::Arc;

use refract_scene::{Frame, FrameTiming, RenderError, Scene};

use refract_scene::MethodParams;

use crate::family::{FamilySlot, GpuFamily, GpuFrameCx};
use crate::passes::raster::RasterPipelines;
use crate::shaders::ShaderModule;

/// The backend's one list of families: each line is a [`Families`] slot, the family's module
/// and type (a [`GpuFamily`], built by [`GpuFamily::create`]) and the [`MethodParams`] variant
/// it renders. The list also makes [`shaders`] (each family module's `SHADERS`, then the shared
/// modules the list names), so a family's shader cannot be left out of naga's validation; the
/// families rendered elsewhere are declined by name. A family of [`MethodParams`] missing from
/// both lists is a non-exhaustive `match`: it does not compile.
macro_rules! gpu_families {
    (
        declined: [$($declined:ident),*],
        shared_shaders: [$($shared:path),*],
        $($(#[doc = $doc:literal])* $field:ident: $module:ident::$family:ident => $variant:ident,)*
    ) => {
        /// Every family with the targets of its last frame.
        pub(crate) struct Families {
            $($(#[doc = $doc])* $field: FamilySlot<$module::$family>,)*
        }

        impl Families {
            /// Compiles every family's pipelines.
            pub(crate) fn new(device: &wgpu::Device, raster: &RasterPipelines) -> Self {
                Self {
                    $($field: FamilySlot::new(<$module::$family as GpuFamily>::create(
                        device, raster,
                    )),)*
                }
            }

            /// Drops every family's targets (bound to the old scene) and prepares it for
            /// `scene`.
            pub(crate) fn prepare(&mut self, scene: &Arc<Scene>) {
                $(self.$field.prepare(scene);)*
            }

            /// One frame of `method` by its family ([`FamilySlot::run_frame`]); the declined
            /// families are [`RenderError::Unsupported`] here.
            pub(crate) fn render(
                &mut self,
                cx: &GpuFrameCx<'_>,
                method: &MethodParams,
                frame: Option<&mut Frame>,
            ) -> Result<FrameTiming, RenderError> {
                match method {
                    $(MethodParams::$variant(p) => self.$field.run_frame(cx, p, frame),)*
                    $(MethodParams::$declined(_) => Err(RenderError::Unsupported {
                        backend: refract_scene::BackendId::Gpu,
                        method: cx.method,
                    }),)*
                }
            }

            /// The colour buffer of the last frame of `method`'s family, `None` before its
            /// first frame (and for the declined families).
            pub(crate) fn color(&self, method: &MethodParams) -> Option<&wgpu::Buffer> {
                match method {
                    $(MethodParams::$variant(_) => self.$field.color(),)*
                    $(MethodParams::$declined(_) => None,)*
                }
            }
        }

        /// Every family's shader modules (its `SHADERS`: its pass and, where it has one, its
        /// conformance module), then the shared ones of the list (validated by naga in
        /// `tests/shaders.rs` with the backend's other modules).
        pub(crate) fn shaders() -> Vec<ShaderModule> {
            let mut modules = Vec::new();
            $(modules.extend_from_slice($module::SHADERS);)*
            modules.extend_from_slice(&[$($shared,)*]);
            modules
        }
    };
}

gpu_families! {
    declined: [],
    shared_shaders: [crate::passes::objects_over_frame::SHADER],
    /// Wyman 2005a.
    image_space: image_space::ImageSpacePipelines => ImageSpace,
    /// Wyman 2005b.
    nearby: nearby_geometry::NearbyPipelines => NearbyGeometry,
    /// Umenhoffer et al. 2007.
    distance_map: distance_map::DistanceMapPipelines => DistanceMap,
    /// Kakimoto et al. 2007.
    pvrr: pvrr::PvrrFamily => Pvrr,
    /// Today's engines.
    engine: engine::EnginePipelines => Engine,
    /// Glass behind glass: every refractor's surfaces depth-peeled.
    depth_peel: depth_peel::DepthPeelPipelines => DepthPeel,
    /// The exact reference (`crate::reference`).
    reference: reference::ReferenceFamily => Reference,
}
