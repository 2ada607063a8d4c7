//! Wyman 2005a image-space refraction on the CPU (methods `single`, `wyman`, `wyman-dv`,
//! `wyman-dn`): the back faces rasterised and resolved, then the front faces rasterised band by
//! band, each band shaded by refract-core's eight-lane kernels right after it is rasterised.
//!
//! A scene's opaque objects are drawn where they are the nearest surface (the eye's object pass,
//! the engine family's screen texture); the refraction sees the environment only, as in the
//! paper, so the metrics over the refractor's pixels do not depend on them.

use std::sync::Arc;

use glam::Vec3;
use rayon::iter::Either;
use rayon::prelude::*;
use refract_core::kernel::ImageSpaceParams;
use refract_core::{BackSurface, Camera};
use refract_scene::{
    Environment, Frame, FrameOutputs, ImageSpaceMethod, MethodId, RenderError, Scene,
};

use crate::buffers::{BackFaces, front_faces_into, raster_mesh};
use crate::family::{CpuFamily, FrameCx};
use crate::object_surfaces::NearbyTexture;
use crate::raster::{Band, DepthTest, Faces, SurfaceBuffer, band_pixels, rasterize_bands};
use crate::scene_meshes::SceneMeshes;
use crate::shade::{BandRow, BufferRow, MethodAov, ShadeContext};

/// The buffers of one frame: front faces always, back faces for two-interface methods, the
/// opaque objects seen from the eye where the scene has any.
#[derive(Default)]
pub struct FrameBuffers {
    /// Front faces (P1, N1, d_N).
    pub front: SurfaceBuffer,
    /// Back faces of the chosen surface.
    pub back: Option<BackFaces>,
    /// The opaque objects from the eye (nearest surface, colour); `None` without objects.
    pub objects: Option<NearbyTexture>,
}

/// Pass 1 and 2 of Wyman 2005a §4, stored whole (the two-step path of tests and stage benches;
/// [`ImageSpacePasses`] fuses the second pass with the kernel): the back faces of `back` (none
/// for `single`), the front faces, and the opaque objects from the eye (none in the paper's
/// scenes).
pub fn render_buffers_into(
    scene: &Scene,
    camera: &Camera,
    back: Option<BackSurface>,
    buffers: &mut FrameBuffers,
) {
    let refractor = &scene.refractor;
    buffers.objects = (!scene.objects.is_empty()).then(|| {
        let mut objects = buffers.objects.take().unwrap_or_default();
        objects.render_into(scene, &SceneMeshes::objects(scene), camera);
        objects
    });
    match back {
        None => buffers.back = None,
        Some(surface) => buffers
            .back
            .get_or_insert_with(BackFaces::default)
            .render_into(refractor, camera, surface),
    }
    front_faces_into(refractor, camera, &mut buffers.front);
}

/// [`render_buffers_into`] into new buffers.
pub fn render_buffers(scene: &Scene, camera: &Camera, back: Option<BackSurface>) -> FrameBuffers {
    let mut buffers = FrameBuffers::default();
    render_buffers_into(scene, camera, back, &mut buffers);
    buffers
}

/// The per-pixel kernel over stored buffers, and the environment lookup (the two-step path):
/// writes the colour and, with [`FrameOutputs::ColorAndAovs`], the layers of `method`.
pub fn shade_into(
    buffers: &FrameBuffers,
    environment: &Environment,
    camera: &Camera,
    kernel: &ImageSpaceParams,
    method: MethodId,
    outputs: FrameOutputs,
    frame: &mut Frame,
) -> Result<(), RenderError> {
    let (width, height) = (camera.width(), camera.height());
    frame.resize_for_overwrite(width, height);
    let mut aovs = Vec::new();
    aovs.resize((width * height) as usize, MethodAov::BACKGROUND);
    let context = ShadeContext {
        back: buffers.back.as_ref(),
        environment,
        objects: buffers.objects.as_ref(),
        camera,
        kernel,
    };
    frame
        .color
        .par_chunks_mut(width as usize)
        .zip(aovs.par_chunks_mut(width as usize))
        .enumerate()
        .for_each(|(y, (colors, aovs))| {
            let y = y as u32;
            let front = BufferRow {
                buffer: &buffers.front,
                y,
            };
            context.row(y, &front, colors, Some(aovs));
        });
    if outputs == FrameOutputs::ColorAndAovs {
        frame.write_row_layers(method, &aovs)?;
    }
    Ok(())
}

/// The pixels of a band of rows just rasterised: colours, and AOVs when asked for.
fn shade_band(
    context: &ShadeContext<'_>,
    band: &Band<'_>,
    colors: &mut [Vec3],
    mut aovs: Option<&mut [MethodAov]>,
) {
    let width = band.width() as usize;
    for (row, colors) in colors.chunks_exact_mut(width).enumerate() {
        let y = band.first_row + row as u32;
        let aovs = aovs
            .as_deref_mut()
            .map(|aovs| &mut aovs[row * width..][..width]);
        context.row(y, &BandRow { band, y }, colors, aovs);
    }
}

/// The passes of the image-space methods with their memory kept between frames, as a real-time
/// renderer keeps its render targets: after the first frame at a resolution, a colour-only
/// frame allocates nothing.
///
/// A frame is two passes (Wyman 2005a §4): the back faces are rasterised and resolved into
/// normals and distances; then the front faces are rasterised band by band, and each band of
/// rows is shaded by the kernel right after it is rasterised, while it is in cache (the front
/// surface is never stored as a whole G-buffer). Before them, in a scene with opaque objects,
/// the objects are rasterised from the eye. The result is bit-identical to [`render_buffers`]
/// followed by [`shade_into`].
#[derive(Default)]
pub struct ImageSpacePasses {
    front: SurfaceBuffer,
    back: BackFaces,
    object_meshes: SceneMeshes,
    objects: NearbyTexture,
    aovs: Vec<MethodAov>,
}

impl CpuFamily for ImageSpacePasses {
    type Params = ImageSpaceMethod;

    fn prepare(&mut self, scene: &Arc<Scene>) {
        self.object_meshes = SceneMeshes::objects(scene);
    }

    fn render(
        &mut self,
        cx: &FrameCx<'_>,
        method: &ImageSpaceMethod,
        frame: &mut Frame,
    ) -> Result<(), RenderError> {
        let FrameCx { scene, camera, .. } = *cx;
        let refractor = &scene.refractor;
        let kernel = &method.kernel(cx.ior(refractor))?;
        let back = match method {
            ImageSpaceMethod::Single(_) => None,
            ImageSpaceMethod::TwoInterface(p) => {
                self.back.render_into(refractor, camera, p.back);
                Some(&self.back)
            }
        };
        let objects = (!scene.objects.is_empty()).then(|| {
            self.objects.render_into(scene, &self.object_meshes, camera);
            &self.objects
        });
        let context = ShadeContext {
            back,
            environment: &scene.environment,
            objects,
            camera,
            kernel,
        };
        let (width, height) = (camera.width(), camera.height());
        let n = (width * height) as usize;
        frame.resize_for_overwrite(width, height);
        let band = band_pixels(width);
        let colors = frame.color.par_chunks_mut(band);
        let with_aovs = cx.with_aovs();
        let bands = if with_aovs {
            self.aovs.resize(n, MethodAov::BACKGROUND);
            Either::Left(colors.zip(self.aovs.par_chunks_mut(band).map(Some)))
        } else {
            Either::Right(colors.map(|colors| (colors, None)))
        };
        rasterize_bands(
            &raster_mesh(refractor),
            camera,
            Faces::Front,
            DepthTest::Nearest,
            &mut self.front,
            bands,
            |rows, (colors, aovs)| shade_band(&context, rows, colors, aovs),
        );
        if with_aovs {
            frame.write_row_layers(cx.method, &self.aovs[..n])?;
        }
        Ok(())
    }
}
