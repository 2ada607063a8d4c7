//! A frame of an approximate method on dispersive glass, written once for both backends: the
//! method's own frame at each wavelength of its [`DispersionWavelengths`] bins, the colours
//! summed with the bins' weights ([`refract_core::spectral::WavelengthBins`]); the AOV layers
//! are the frame at the glass's index at the d line, as the reference's are.

use refract_core::spectral::WavelengthBins;

use crate::frame::Frame;
use crate::registry::{DispersionWavelengths, MethodParams};
use crate::renderer::{FrameOutputs, FrameTiming, RenderError};
use crate::scene::Scene;

/// The wavelength bins a frame of `method` on `scene` traces: `None` where one frame at the
/// d line is the answer (no dispersive refractor, a method that disperses its own way or not at
/// all, or `wavelengths = 1`).
pub fn dispersion_bins(scene: &Scene, method: &MethodParams) -> Option<WavelengthBins> {
    if !scene.has_dispersion() {
        return None;
    }
    method.wavelengths().and_then(DispersionWavelengths::bins)
}

/// Renders a frame of `method` into `frame` through `render_at(lambda_nm, outputs, frame,
/// repeat)`, which renders one frame with every refractor at its index at `lambda_nm` (`None`:
/// at the d line, [`crate::Refractor::ior_at`]); `repeat` says that the previous call rendered
/// the same scene, camera and method at another wavelength of this frame, so that the passes
/// that do not depend on the index may be kept. Without [`dispersion_bins`] that is one call.
/// With them, a [`FrameOutputs::ColorAndAovs`] frame first renders the d line for the layers,
/// then each bin's wavelength renders colour only into `scratch` (its memory kept between
/// frames) and `frame`'s colour becomes `Σᵢ Wᵢ ⊙ Cᵢ`. The time is the sum of the calls' times.
pub fn render_dispersive(
    scene: &Scene,
    method: &MethodParams,
    outputs: FrameOutputs,
    frame: &mut Frame,
    scratch: &mut Frame,
    mut render_at: impl FnMut(
        Option<f32>,
        FrameOutputs,
        &mut Frame,
        bool,
    ) -> Result<FrameTiming, RenderError>,
) -> Result<FrameTiming, RenderError> {
    let Some(bins) = dispersion_bins(scene, method) else {
        return render_at(None, outputs, frame, false);
    };
    let mut total: Option<FrameTiming> = None;
    let mut add = |timing: FrameTiming| {
        total = Some(match total {
            Some(t) => FrameTiming {
                ms: t.ms + timing.ms,
                source: t.source,
            },
            None => timing,
        });
    };
    let with_aovs = outputs == FrameOutputs::ColorAndAovs;
    if with_aovs {
        add(render_at(None, FrameOutputs::ColorAndAovs, frame, false)?);
    }
    for (i, bin) in bins.as_slice().iter().enumerate() {
        let repeat = with_aovs || i > 0;
        add(render_at(
            Some(bin.lambda),
            FrameOutputs::Color,
            scratch,
            repeat,
        )?);
        if i == 0 {
            if outputs == FrameOutputs::Color {
                frame.resize_for_overwrite(scratch.width, scratch.height);
            }
            for (c, s) in frame.color.iter_mut().zip(&scratch.color) {
                *c = bin.weight * *s;
            }
        } else {
            for (c, s) in frame.color.iter_mut().zip(&scratch.color) {
                *c += bin.weight * *s;
            }
        }
    }
    total.ok_or_else(|| RenderError::Parameter("no wavelength to render".into()))
}
