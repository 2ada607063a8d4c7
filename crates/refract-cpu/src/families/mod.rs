//! One module per method family, each a [`CpuFamily`], and [`Families`]: one value of every
//! family and the backend's one exhaustive `match` from [`MethodParams`] to the family that
//! renders it. A new family is its module here, its field in [`Families`] and its arm.

pub mod distance_map;
pub mod engine;
pub mod image_space;
pub mod nearby_geometry;
pub mod pvrr;

use std::sync::Arc;

use refract_scene::{BackendId, Frame, MethodParams, RenderError, Scene};

use crate::family::{CpuFamily, FrameCx};

/// Every family's passes, kept between frames.
#[derive(Default)]
pub struct Families {
    /// Wyman 2005a.
    pub image_space: image_space::ImageSpacePasses,
    /// Wyman 2005b.
    pub nearby: nearby_geometry::NearbyPasses,
    /// Umenhoffer et al. 2007.
    pub distance_map: distance_map::DistancePasses,
    /// Kakimoto et al. 2007.
    pub pvrr: pvrr::PvrrPasses,
    /// Today's engines (Godot, three.js, Bevy, Unity HDRP, Filament).
    pub engine: engine::EnginePasses,
}

impl Families {
    /// Prepares every family for `scene`.
    pub fn prepare(&mut self, scene: &Arc<Scene>) {
        self.image_space.prepare(scene);
        self.nearby.prepare(scene);
        self.distance_map.prepare(scene);
        self.pvrr.prepare(scene);
        self.engine.prepare(scene);
    }

    /// One frame of `method` by its family; the reference is declined.
    pub fn render(
        &mut self,
        cx: &FrameCx<'_>,
        method: &MethodParams,
        frame: &mut Frame,
    ) -> Result<(), RenderError> {
        match method {
            MethodParams::Reference(_) => Err(RenderError::Unsupported {
                backend: BackendId::Cpu,
                method: cx.method,
            }),
            MethodParams::ImageSpace(p) => self.image_space.render(cx, p, frame),
            MethodParams::NearbyGeometry(p) => self.nearby.render(cx, p, frame),
            MethodParams::DistanceMap(p) => self.distance_map.render(cx, p, frame),
            MethodParams::Pvrr(p) => self.pvrr.render(cx, p, frame),
            MethodParams::Engine(p) => self.engine.render(cx, p, frame),
        }
    }
}
