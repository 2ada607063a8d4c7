//! Refusing jobs that cannot fit in memory before they start: the bytes a job needs, from the
//! method's measured model (its registry row's `memory`: bytes per pixel with and without
//! layers, bytes per texel of the textures its parameters size) or the bytes per pixel measured
//! for a comparison (`docs/performance.md`), against the memory the system says is available
//! (`MemAvailable` of `/proc/meminfo`, or less with `REFRACT_MEMORY_LIMIT_MIB`; no check
//! where neither says).

use refract_scene::{BackendId, MethodParams};

/// Measured peak resident bytes per pixel (`/usr/bin/time -f %M`, 1024² vs 2048², release):
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

/// The environment variable that caps the memory a run may plan for, in MiB (1 to 2^30, i.e.
/// up to 1 PiB): a run on a shared machine, or a test that must see a refusal on any machine.
pub const LIMIT_VARIABLE: &str = "REFRACT_MEMORY_LIMIT_MIB";

/// `MemAvailable` in bytes, when the system says.
fn mem_available() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// The bytes a run may plan for: `MemAvailable`, capped by [`LIMIT_VARIABLE`] when set.
fn available() -> crate::Result<Option<u64>> {
    let limit = match std::env::var(LIMIT_VARIABLE) {
        Ok(text) => {
            let mib = text
                .trim()
                .parse::<u64>()
                .ok()
                .filter(|m| (1..=1 << 30).contains(m));
            let mib = mib.ok_or_else(|| {
                crate::LabError::invalid(format!(
                    "{LIMIT_VARIABLE}={text}: expected MiB from 1 to {}",
                    1u64 << 30
                ))
            })?;
            Some(mib << 20)
        }
        Err(_) => None,
    };
    Ok(match (mem_available(), limit) {
        (Some(system), Some(limit)) => Some(system.min(limit)),
        (system, limit) => system.or(limit),
    })
}

fn gib(bytes: u64) -> f64 {
    bytes as f64 / f64::from(1u32 << 30)
}

/// The bytes a frame of `method` at `width × height` needs (with its AOV layers when
/// `layers`): its row's memory model, plus the GPU's share when it runs there (its per-pixel
/// targets and its own copy of the textures; host memory on lavapipe).
pub fn method_estimate(
    method: &MethodParams,
    width: u32,
    height: u32,
    layers: bool,
    backends: &[BackendId],
) -> u64 {
    let model = method.id().info().memory;
    let frame = model.bytes(method, width, height, layers);
    let gpu = if backends.contains(&BackendId::Gpu) {
        u64::from(width) * u64::from(height) * GPU_BYTES_PER_PIXEL
            + model.texture_bytes(method, width, height)
    } else {
        0
    };
    BASE_BYTES + frame + gpu
}

/// Fails, with the estimate and the limit, when a frame of `method` would not fit
/// ([`method_estimate`]).
pub fn check_method(
    what: &str,
    method: &MethodParams,
    width: u32,
    height: u32,
    layers: bool,
    backends: &[BackendId],
) -> crate::Result<()> {
    let needed = method_estimate(method, width, height, layers, backends);
    if let Some(limit) = available()? {
        crate::ensure!(
            needed <= limit,
            "{what} of {} ({}) at {width}x{height} needs about {:.1} GiB (measured for this method \
             and its parameters{}), but {:.1} GiB are available; choose a smaller --res or smaller \
             textures",
            method.id(),
            method.describe(),
            gib(needed),
            if backends.contains(&BackendId::Gpu) {
                ", with the GPU's share"
            } else {
                ""
            },
            gib(limit)
        );
    }
    Ok(())
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
    if let Some(limit) = available()? {
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
    use refract_scene::MethodId;

    /// The estimate follows the method and its parameters (issue 34, item 5: it assumed 182
    /// bytes a pixel for every method; `iterative-seeded` with `guard=100` needs about 640, so
    /// its 8192² EXR, about 40 GiB, was accepted on a 24 GiB machine).
    #[test]
    fn estimates_follow_the_method_and_its_parameters() {
        let gib_of = |m: &MethodParams, r: u32, layers| {
            gib(method_estimate(m, r, r, layers, &[BackendId::Cpu]))
        };
        let wyman = MethodParams::defaults(MethodId::Wyman);
        let mut seeded = MethodParams::defaults(MethodId::IterativeSeeded);
        let narrow = gib_of(&seeded, 8192, true);
        seeded.set("guard", "100", "test").expect("guard");
        let wide = gib_of(&seeded, 8192, true);
        // wyman: its buffers and layers, and the objects' pass from the eye (an upper bound).
        assert!((12.0..16.0).contains(&gib_of(&wyman, 8192, true)), "wyman");
        assert!((18.0..23.0).contains(&narrow), "seeded: {narrow}");
        assert!((38.0..44.0).contains(&wide), "seeded, guard 100: {wide}");
        // Textures sized by parameters, whatever the frame: 6 x 8 distance-map layers of 2048².
        let mut maps = MethodParams::defaults(MethodId::DistanceMap);
        maps.set("res", "2048", "test").expect("res");
        maps.set("layers", "8", "test").expect("layers");
        assert!(gib_of(&maps, 16, false) > 2.0);
    }

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
        let wyman = MethodParams::defaults(MethodId::Wyman);
        let huge = method_estimate(&wyman, 16384, 16384, true, &[BackendId::Cpu]);
        assert!(gib(huge) > 40.0);
    }
}
