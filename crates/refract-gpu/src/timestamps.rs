//! GPU frame times from timestamp queries: a pair around each of the frame's passes (each
//! render and compute pass a family encodes asks for its own), read back as the frame's span
//! (the first pass's start to the last pass's end) and the time of each pass, summed per label
//! (`docs/viewer.md`: the viewer's title and panel show them).

use std::sync::Mutex;

use refract_scene::PassTime;

use crate::context::{GpuContext, GpuError};

/// At most this many passes of a frame are timed; later ones run untimed (the frame's span
/// still ends at the last timed pass).
const MAX_PASSES: u32 = 64;

/// The query set and buffers of a frame's timestamps.
pub(crate) struct Timestamps {
    set: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    read: wgpu::Buffer,
    /// The labels of the frame's timed passes, in encoding order (pass k: queries 2k, 2k + 1).
    labels: Mutex<Vec<&'static str>>,
    /// The last frame's pass times.
    last: Mutex<Vec<PassTime>>,
}

impl Timestamps {
    /// `None` when the adapter has no TIMESTAMP_QUERY.
    pub(crate) fn new(context: &GpuContext) -> Option<Self> {
        let device = &context.device;
        let bytes = u64::from(2 * MAX_PASSES) * 8;
        context.timestamps.then(|| Self {
            set: device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("frame timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: 2 * MAX_PASSES,
            }),
            resolve: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamp resolve"),
                size: bytes,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
            read: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamp readback"),
                size: bytes,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            labels: Mutex::new(Vec::new()),
            last: Mutex::new(Vec::new()),
        })
    }

    /// Starts a frame: no pass timed yet.
    pub(crate) fn begin_frame(&self) {
        if let Ok(mut labels) = self.labels.lock() {
            labels.clear();
        }
    }

    /// The next pair of queries, for a pass labelled `label`; `None` past [`MAX_PASSES`].
    fn next_pair(&self, label: &'static str) -> Option<u32> {
        let mut labels = self.labels.lock().ok()?;
        let k = labels.len() as u32;
        (k < MAX_PASSES).then(|| {
            labels.push(label);
            k
        })
    }

    /// The writes around a render pass labelled `label`.
    pub(crate) fn render_pass(
        &self,
        label: &'static str,
    ) -> Option<wgpu::RenderPassTimestampWrites<'_>> {
        let k = self.next_pair(label)?;
        Some(wgpu::RenderPassTimestampWrites {
            query_set: &self.set,
            beginning_of_pass_write_index: Some(2 * k),
            end_of_pass_write_index: Some(2 * k + 1),
        })
    }

    /// The writes around a compute pass labelled `label`.
    pub(crate) fn compute_pass(
        &self,
        label: &'static str,
    ) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        let k = self.next_pair(label)?;
        Some(wgpu::ComputePassTimestampWrites {
            query_set: &self.set,
            beginning_of_pass_write_index: Some(2 * k),
            end_of_pass_write_index: Some(2 * k + 1),
        })
    }

    /// Resolves the frame's queries into the readback buffer (after its last pass).
    pub(crate) fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        let passes = self.labels.lock().map_or(0, |l| l.len() as u32);
        if passes == 0 {
            return;
        }
        encoder.resolve_query_set(&self.set, 0..2 * passes, &self.resolve, 0);
        encoder.copy_buffer_to_buffer(&self.resolve, 0, &self.read, 0, u64::from(passes) * 16);
    }

    /// Milliseconds from the first timed pass's start to the last one's end in the last
    /// submitted frame; the passes' own times are kept for [`Self::last_passes`].
    pub(crate) fn read_ms(&self, context: &GpuContext) -> Result<f64, GpuError> {
        let labels = self.labels.lock().map(|l| l.clone()).unwrap_or_default();
        if labels.is_empty() {
            return Ok(0.0);
        }
        let bytes = context.read_buffer(&self.read)?;
        let ticks: &[u64] = bytemuck::cast_slice(&bytes);
        let period_ns = f64::from(context.queue.get_timestamp_period());
        let ms = |from: u64, to: u64| to.saturating_sub(from) as f64 * period_ns / 1e6;
        let mut passes: Vec<PassTime> = Vec::new();
        for (k, label) in labels.iter().enumerate() {
            let t = ms(ticks[2 * k], ticks[2 * k + 1]);
            match passes.iter_mut().find(|p| p.label == *label) {
                Some(p) => {
                    p.count += 1;
                    p.ms += t;
                }
                None => passes.push(PassTime {
                    label,
                    count: 1,
                    ms: t,
                }),
            }
        }
        if let Ok(mut last) = self.last.lock() {
            *last = passes;
        }
        Ok(ms(ticks[0], ticks[2 * labels.len() - 1]))
    }

    /// The last frame's passes, summed per label in the order first encoded.
    pub(crate) fn last_passes(&self) -> Vec<PassTime> {
        self.last.lock().map(|l| l.clone()).unwrap_or_default()
    }
}
