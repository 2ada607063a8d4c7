//! The CPU backend's unit of extension: a method family. A family keeps its passes and buffers
//! between frames, prepares them once per scene and renders a frame of any of its methods from
//! a [`FrameCx`]. [`crate::CpuRenderer`] holds one value of every family and picks it with one
//! exhaustive `match` over [`refract_scene::MethodParams`]: a new parameter set does not compile
//! until that `match` handles or declines it.

use std::sync::Arc;

use refract_core::Camera;
use refract_scene::{Frame, FrameOutputs, MethodId, Refractor, RenderError, Scene};

/// What every family's frame reads: the scene, the camera, the method (its registry row names
/// the AOV layers to write) and what the frame writes.
#[derive(Clone, Copy)]
pub struct FrameCx<'a> {
    /// The prepared scene.
    pub scene: &'a Scene,
    /// The eye (its size is the frame's).
    pub camera: &'a Camera,
    /// The method rendered: its registry row lists the layers a
    /// [`FrameOutputs::ColorAndAovs`] frame gets.
    pub method: MethodId,
    /// Colour only, or colour and the row's layers.
    pub outputs: FrameOutputs,
    /// The wavelength the frame traces (nm), `None` for the d line: every refractor's index is
    /// [`Refractor::ior_at`] it ([`refract_scene::render_dispersive`]).
    pub lambda_nm: Option<f32>,
    /// The previous frame rendered the same scene, camera and method at another wavelength of
    /// one dispersive frame: the family may keep the passes that do not depend on the index
    /// (the distance map's layers, the depth-peeled layers).
    pub repeat: bool,
}

impl FrameCx<'_> {
    /// Whether the frame gets the method's AOV layers.
    pub fn with_aovs(&self) -> bool {
        self.outputs == FrameOutputs::ColorAndAovs
    }

    /// `refractor`'s index of refraction in this frame.
    pub fn ior(&self, refractor: &Refractor) -> f32 {
        refractor.ior_at(self.lambda_nm)
    }
}

/// A method family on the CPU.
pub trait CpuFamily {
    /// The parameters of one run of a method of the family.
    type Params;

    /// Prepares the family's per-scene state (meshes merged, plans reset); buffers are sized
    /// per frame.
    fn prepare(&mut self, scene: &Arc<Scene>);

    /// Renders one frame into `frame` (resized; its memory reused): the colour and, with
    /// [`FrameOutputs::ColorAndAovs`], exactly the layers of the method's registry row.
    fn render(
        &mut self,
        cx: &FrameCx<'_>,
        params: &Self::Params,
        frame: &mut Frame,
    ) -> Result<(), RenderError>;
}
