//! GPU frame times from timestamp queries: one at the start of the first pass, one at the end
//! of the last.

use crate::context::{GpuContext, GpuError};

/// The query set and buffers of a frame's two timestamps.
pub(crate) struct Timestamps {
    set: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    read: wgpu::Buffer,
}

impl Timestamps {
    /// `None` when the adapter has no TIMESTAMP_QUERY.
    pub(crate) fn new(context: &GpuContext) -> Option<Self> {
        let device = &context.device;
        context.timestamps.then(|| Self {
            set: device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("frame timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: 2,
            }),
            resolve: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamp resolve"),
                size: 16,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
            read: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamp readback"),
                size: 16,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
        })
    }

    /// The write at the beginning of the frame's first (render) pass.
    pub(crate) fn begin_render(&self) -> wgpu::RenderPassTimestampWrites<'_> {
        wgpu::RenderPassTimestampWrites {
            query_set: &self.set,
            beginning_of_pass_write_index: Some(0),
            end_of_pass_write_index: None,
        }
    }

    /// The writes of a compute pass: the frame's start when it is the frame's first pass, its
    /// end when it is the last (a frame that is one compute pass is both).
    pub(crate) fn compute(
        &self,
        first_pass: bool,
        last_pass: bool,
    ) -> wgpu::ComputePassTimestampWrites<'_> {
        wgpu::ComputePassTimestampWrites {
            query_set: &self.set,
            beginning_of_pass_write_index: first_pass.then_some(0),
            end_of_pass_write_index: last_pass.then_some(1),
        }
    }

    /// The write at the end of the frame's last pass, a compute pass.
    pub(crate) fn end_compute(&self) -> wgpu::ComputePassTimestampWrites<'_> {
        self.compute(false, true)
    }

    /// Resolves the queries into the readback buffer (after the last pass).
    pub(crate) fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        encoder.resolve_query_set(&self.set, 0..2, &self.resolve, 0);
        encoder.copy_buffer_to_buffer(&self.resolve, 0, &self.read, 0, 16);
    }

    /// Milliseconds between the two timestamps of the last submitted frame.
    pub(crate) fn read_ms(&self, context: &GpuContext) -> Result<f64, GpuError> {
        let bytes = context.read_buffer(&self.read)?;
        let ticks: &[u64] = bytemuck::cast_slice(&bytes);
        let ns = ticks[1].saturating_sub(ticks[0]) as f64
            * f64::from(context.queue.get_timestamp_period());
        Ok(ns / 1e6)
    }
}
