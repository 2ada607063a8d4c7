//! The screenshot key: the window's PNG and the frame's metrics against the exact reference, and
//! the unattended run's summary.

use refract_eval::atomic_write::{write_png_rgb8, write_text_atomically};
use refract_eval::metrics::evaluate_method;
use refract_scene::tonemap::to_srgb8;
use refract_scene::{Frame, FrameOutputs, MethodId, MethodParams, Renderer};
use refract_trace::ReferenceRenderer;

use crate::{Viewer, pass_time, reference_origin};

impl Viewer {
    /// The unattended run's frame times: the median after the first frame (which compiles and
    /// allocates), how the last frame reached the window.
    pub(crate) fn frame_summary(&self) -> String {
        let mut ms: Vec<f64> = self.frame_ms.iter().skip(1).copied().collect();
        ms.sort_by(f64::total_cmp);
        let median = ms.get(ms.len() / 2).copied().unwrap_or(f64::NAN);
        let path = match (self.use_gpu, self.shown_from_gpu) {
            (true, true) => "GPU frames drawn into the window on the GPU, no readback",
            (true, false) => "GPU frames read back and uploaded to the window",
            (false, _) => "CPU frames uploaded to the window",
        };
        let reference = self
            .reference_level
            .as_ref()
            .map(|l| {
                format!(
                    "; split-view reference traced on the {}",
                    reference_origin(l)
                )
            })
            .unwrap_or_default();
        let passes = if self.pass_times.is_empty() {
            String::new()
        } else {
            let passes: Vec<String> = self.pass_times.iter().map(pass_time).collect();
            format!("; last frame's GPU passes: {}", passes.join(", "))
        };
        format!(
            "frames: {}, median {median:.2} ms a frame from redraw to present after the first ({path}){reference}{passes}",
            self.frames_done
        )
    }

    /// Writes the last frame as PNG and its metrics against the exact reference as JSON.
    pub(crate) fn screenshot(&mut self) -> anyhow::Result<()> {
        if self.shown_from_gpu {
            // The frame never left the GPU: read it back once, for the file and the metrics.
            if let Some(display) = &self.display {
                let (width, height) = (display.config.width, display.config.height);
                let camera = self.camera(width, height)?;
                let params = self.params();
                let mut frame = std::mem::take(&mut self.frame);
                self.renderer()
                    .render(&camera, &params, FrameOutputs::Color, &mut frame)?;
                self.frame = frame;
            }
        }
        let (width, height) = (self.frame.width, self.frame.height);
        if width == 0 {
            return Ok(());
        }
        // The window's pixels when they were read back, else the frame's (the same bytes).
        let (pixels, source): (Vec<u8>, &str) = match &self.captured {
            Some((w, h, rgb)) if (*w, *h) == (width, height) => (rgb.clone(), "the window"),
            _ => (
                self.frame.color.iter().flat_map(|&c| to_srgb8(c)).collect(),
                "the frame",
            ),
        };
        let path = self.args.screenshot.clone();
        write_png_rgb8(&path, width, height, &pixels)?;
        let camera = self.camera(width, height)?;
        // The split view's full level when it is of this view, else traced here on the CPU.
        let level = self.reference_level.take().filter(|l| {
            l.full
                && l.generation == self.reference_generation
                && (l.frame.width, l.frame.height) == (width, height)
        });
        let truth = match level {
            Some(level) => level.frame,
            None => {
                let mut reference = ReferenceRenderer::new();
                reference.prepare(&self.scene)?;
                let mut truth = Frame::default();
                reference.render(
                    &camera,
                    &MethodParams::defaults(MethodId::Reference),
                    FrameOutputs::ColorAndAovs,
                    &mut truth,
                )?;
                truth
            }
        };
        let params = self.params();
        let mut frame = Frame::default();
        self.renderer()
            .render(&camera, &params, FrameOutputs::ColorAndAovs, &mut frame)?;
        let (mut record, _) = evaluate_method(&truth, &frame, &camera, &self.scene, &params);
        record.scene.clone_from(&self.scene.name);
        record.method = params.id().name().to_owned();
        record.backend = if self.use_gpu { "gpu" } else { "cpu" }.to_owned();
        record.params = params.describe();
        record.ms_per_frame = Some(self.last_ms);
        write_text_atomically(
            &path.with_extension("json"),
            &serde_json::to_string_pretty(&record)?,
        )?;
        eprintln!(
            "screenshot of {source}: {} ({width}x{height}), metrics: {}",
            path.display(),
            path.with_extension("json").display()
        );
        Ok(())
    }
}
