//! Refusing jobs that cannot fit in memory before they start: the bytes a job needs, from the
//! bytes per pixel measured for each kind of run (`docs/performance.md`), against the memory
//! the system says is available (`MemAvailable` of `/proc/meminfo`; no check where it cannot
//! be read).

use refract_scene::BackendId;

/// Measured peak resident bytes per pixel (`/usr/bin/time -f %M`, 1024² vs 2048², release):
/// `refract render` of an image-space method on the CPU to a PNG (colour-only frames).
pub const RENDER_METHOD_PNG_BYTES_PER_PIXEL: u64 = 46;
/// `refract render` of an image-space method to an EXR (colour and AOV layers).
pub const RENDER_METHOD_EXR_BYTES_PER_PIXEL: u64 = 182;
/// `refract render --method reference` to a PNG.
pub const RENDER_REFERENCE_PNG_BYTES_PER_PIXEL: u64 = 120;
/// `refract render --method reference` to an EXR.
pub const RENDER_REFERENCE_EXR_BYTES_PER_PIXEL: u64 = 234;
/// `refract compare` on the CPU (the reference, every method's frame and error maps).
pub const COMPARE_BYTES_PER_PIXEL: u64 = 330;
/// What the GPU backend adds (targets, output and readback buffers: host memory on lavapipe).
pub const GPU_BYTES_PER_PIXEL: u64 = 200;
/// Fixed overhead (binary, meshes, BVHs, pipelines).
pub const BASE_BYTES: u64 = 200 << 20;

/// The bytes a job of `pixels` needs at `per_pixel`, plus the GPU's share when it runs.
pub fn estimate(pixels: u64, per_pixel: u64, backends: &[BackendId]) -> u64 {
    let gpu = if backends.contains(&BackendId::Gpu) {
        GPU_BYTES_PER_PIXEL
    } else {
        0
    };
    BASE_BYTES + pixels * (per_pixel + gpu)
}

/// `MemAvailable` in bytes, when the system says.
fn available() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

fn gib(bytes: u64) -> f64 {
    bytes as f64 / f64::from(1u32 << 30)
}

/// Fails, with the estimate and the limit, when a job of `width × height` would not fit.
pub fn check(
    what: &str,
    width: u32,
    height: u32,
    per_pixel: u64,
    backends: &[BackendId],
) -> crate::Result<()> {
    let pixels = u64::from(width) * u64::from(height);
    let needed = estimate(pixels, per_pixel, backends);
    if let Some(limit) = available() {
        crate::ensure!(
            needed <= limit,
            "{what} at {width}x{height} needs about {:.1} GiB ({per_pixel} bytes a pixel measured{}), \
             but {:.1} GiB are available; choose a smaller --res",
            gib(needed),
            if backends.contains(&BackendId::Gpu) {
                format!(", + {GPU_BYTES_PER_PIXEL} on the GPU")
            } else {
                String::new()
            },
            gib(limit)
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn estimates_grow_with_pixels_and_the_gpu() {
        let cpu = estimate(1 << 20, COMPARE_BYTES_PER_PIXEL, &[BackendId::Cpu]);
        let both = estimate(
            1 << 20,
            COMPARE_BYTES_PER_PIXEL,
            &[BackendId::Cpu, BackendId::Gpu],
        );
        assert_eq!(cpu, BASE_BYTES + (1 << 20) * 330);
        assert_eq!(both - cpu, (1 << 20) * GPU_BYTES_PER_PIXEL);
        // 16384² of `wyman` to an EXR is about 46 GiB.
        let huge = estimate(
            16384 * 16384,
            RENDER_METHOD_EXR_BYTES_PER_PIXEL,
            &[BackendId::Cpu],
        );
        assert!(gib(huge) > 40.0);
    }
}
