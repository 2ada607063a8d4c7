//! What the conformance test files share: one adapter for the file, the proptest settings, unit
//! vectors, relative closeness.

#![allow(dead_code)]

use std::sync::OnceLock;

use glam::{Vec3, Vec4};
use proptest::prelude::*;
use refract_gpu::GpuContext;

/// One context for the whole file (adapters are slow to open on lavapipe).
pub fn context() -> Option<&'static GpuContext> {
    static CONTEXT: OnceLock<Option<GpuContext>> = OnceLock::new();
    CONTEXT.get_or_init(GpuContext::for_tests).as_ref()
}

pub const ROWS: usize = 256;

pub fn config() -> ProptestConfig {
    ProptestConfig {
        cases: 6,
        ..ProptestConfig::default()
    }
}

pub fn unit() -> impl Strategy<Value = Vec3> {
    (-1.0f32..=1.0, 0.0f32..std::f32::consts::TAU).prop_map(|(z, phi)| {
        let r = (1.0 - z * z).max(0.0).sqrt();
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    })
}

pub fn close(gpu: f32, rust: f32, relative: f32) -> bool {
    (gpu - rust).abs() <= relative * rust.abs().max(1.0)
}

pub fn close3(gpu: Vec4, rust: Vec3, relative: f32) -> bool {
    close(gpu.x, rust.x, relative)
        && close(gpu.y, rust.y, relative)
        && close(gpu.z, rust.z, relative)
}

/// The test's adapter, or the end of the test (after `skipped: no GPU adapter`).
macro_rules! gpu_or_skip {
    () => {
        match context() {
            Some(context) => context,
            None => return Ok(()),
        }
    };
}
