//! The x86-64 instructions a build was compiled to use, checked against the CPU it runs on.
//!
//! The workspace builds for `x86-64-v3` without FMA (`.cargo/config.toml`): AVX2 makes each
//! eight-lane operation of the kernels ([`refract_core::lanes`]) one instruction instead of two
//! SSE halves, 7–16 % of a CPU frame (docs/performance.md, "Building for older CPUs"); FMA is
//! left out because glam fuses some of its operations when it is on (`Vec3A::cross`), which
//! moves the last bits of a few results, and Rust never fuses our own `a·b + c`: without it an
//! `x86-64-v3` build computes the same bits as an `x86-64-v2` one. Such a binary stops with an
//! illegal instruction on a CPU older than the level (Intel before Haswell, 2013; AMD before
//! Excavator, 2015). The `refract` binary calls [`exit_if_unsupported`] first and the Python
//! module [`check_instruction_set`], so that such a CPU gets a message that says how to rebuild
//! instead.
//!
//! The check is itself compiled for the build's level, so it is written to need nothing of it:
//! integer masks, static strings, no formatting. `qemu-x86_64 -cpu Nehalem target/release/refract`
//! (Debian `qemu-user`) runs a build on a CPU without AVX; docs/performance.md says what it
//! printed.

/// The extensions this module knows: those of the x86-64 levels v2 and v3, and FMA (which the
/// workspace's build leaves out), named as `-C target-feature` names them.
pub const EXTENSIONS: [&str; 15] = [
    "sse3",
    "ssse3",
    "sse4.1",
    "sse4.2",
    "popcnt",
    "cmpxchg16b",
    "avx",
    "avx2",
    "bmi1",
    "bmi2",
    "f16c",
    "lzcnt",
    "movbe",
    "xsave",
    "fma",
];

/// Bit `i` set: this build was compiled to use [`EXTENSIONS`]`[i]` (`cfg!(target_feature)`).
pub const fn compiled_mask() -> u32 {
    let compiled = [
        cfg!(target_feature = "sse3"),
        cfg!(target_feature = "ssse3"),
        cfg!(target_feature = "sse4.1"),
        cfg!(target_feature = "sse4.2"),
        cfg!(target_feature = "popcnt"),
        cfg!(target_feature = "cmpxchg16b"),
        cfg!(target_feature = "avx"),
        cfg!(target_feature = "avx2"),
        cfg!(target_feature = "bmi1"),
        cfg!(target_feature = "bmi2"),
        cfg!(target_feature = "f16c"),
        cfg!(target_feature = "lzcnt"),
        cfg!(target_feature = "movbe"),
        cfg!(target_feature = "xsave"),
        cfg!(target_feature = "fma"),
    ];
    let mut mask = 0;
    let mut i = 0;
    while i < compiled.len() {
        if compiled[i] {
            mask |= 1 << i;
        }
        i += 1;
    }
    mask
}

/// Bit `i` set: this CPU has [`EXTENSIONS`]`[i]`, asked with `cpuid` (raw-cpuid); all bits
/// on other architectures, where none is compiled in.
///
/// Not `is_x86_feature_detected!`: it answers `true` without asking for every extension the
/// build was compiled with, which is the question here.
pub fn detected_mask() -> u32 {
    #[cfg(target_arch = "x86_64")]
    {
        let cpu = raw_cpuid::CpuId::new();
        let basic = cpu.get_feature_info();
        let extended = cpu.get_extended_feature_info();
        let has = |f: fn(&raw_cpuid::FeatureInfo) -> bool| basic.as_ref().is_some_and(f);
        let has_extended =
            |f: fn(&raw_cpuid::ExtendedFeatures) -> bool| extended.as_ref().is_some_and(f);
        // AVX state is usable only where the OS saves it (OSXSAVE).
        let avx = has(|f| f.has_avx() && f.has_oxsave());
        let lzcnt = cpu
            .get_extended_processor_and_feature_identifiers()
            .is_some_and(|f| f.has_lzcnt());
        let detected = [
            has(|f| f.has_sse3()),
            has(|f| f.has_ssse3()),
            has(|f| f.has_sse41()),
            has(|f| f.has_sse42()),
            has(|f| f.has_popcnt()),
            has(|f| f.has_cmpxchg16b()),
            avx,
            avx && has_extended(|f| f.has_avx2()),
            has_extended(|f| f.has_bmi1()),
            has_extended(|f| f.has_bmi2()),
            avx && has(|f| f.has_f16c()),
            lzcnt,
            has(|f| f.has_movbe()),
            has(|f| f.has_xsave()),
            avx && has(|f| f.has_fma()),
        ];
        let mut mask = 0;
        for (i, detected) in detected.into_iter().enumerate() {
            mask |= u32::from(detected) << i;
        }
        mask
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        u32::MAX
    }
}

/// Bit `i` set: [`EXTENSIONS`]`[i]` is compiled in and the CPU lacks it.
pub fn missing_mask() -> u32 {
    compiled_mask() & !detected_mask()
}

/// The names of the extensions set in `mask`, in [`EXTENSIONS`] order.
pub fn extension_names(mask: u32) -> Vec<&'static str> {
    EXTENSIONS
        .iter()
        .enumerate()
        .filter(|(i, _)| mask & (1 << i) != 0)
        .map(|(_, name)| *name)
        .collect()
}

/// What to do on a CPU that lacks an extension the build uses (the end of
/// [`UnsupportedCpu`]'s message).
pub const REBUILD_ADVICE: &str = "it was compiled for x86-64-v3 (AVX2: Intel Haswell, AMD \
     Excavator and later; .cargo/config.toml). Rebuild for this CPU with RUSTFLAGS=\"-C \
     target-cpu=x86-64-v2\" (or \"-C target-cpu=native\"), e.g. `RUSTFLAGS=\"-C \
     target-cpu=x86-64-v2\" cargo build --release`";

/// The CPU lacks instructions this build was compiled to use.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error(
    "this build of refract uses x86-64 instructions this CPU does not have ({}); {REBUILD_ADVICE}",
    missing.join(", ")
)]
pub struct UnsupportedCpu {
    /// The instruction-set extensions compiled in and missing at run time (`"avx2"`, ...).
    pub missing: Vec<&'static str>,
}

/// Whether the CPU has every instruction-set extension this build was compiled to use.
///
/// # Errors
/// [`UnsupportedCpu`] naming the missing extensions.
pub fn check_instruction_set() -> Result<(), UnsupportedCpu> {
    match missing_mask() {
        0 => Ok(()),
        missing => Err(UnsupportedCpu {
            missing: extension_names(missing),
        }),
    }
}

/// For a binary's first line: on a CPU without an extension the build uses, writes
/// [`UnsupportedCpu`]'s message to stderr and exits with status 2; otherwise returns. Static
/// strings only (see the module's documentation).
pub fn exit_if_unsupported() {
    let missing = missing_mask();
    if missing != 0 {
        unsupported_exit(missing);
    }
}

#[cold]
#[inline(never)]
fn unsupported_exit(missing: u32) -> ! {
    use std::io::Write;
    let mut stderr = std::io::stderr().lock();
    // Errors writing to stderr cannot be reported anywhere; the exit status still says it.
    let _ = stderr.write_all(
        b"error: this build of refract uses x86-64 instructions this CPU does not have (",
    );
    let mut first = true;
    for (i, name) in EXTENSIONS.iter().enumerate() {
        if missing & (1 << i) != 0 {
            if !first {
                let _ = stderr.write_all(b", ");
            }
            let _ = stderr.write_all(name.as_bytes());
            first = false;
        }
    }
    let _ = stderr.write_all(b"); ");
    let _ = stderr.write_all(REBUILD_ADVICE.as_bytes());
    let _ = stderr.write_all(b"\n");
    std::process::exit(2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_missing_extensions_are_named_in_order() {
        let avx = 1 << 6;
        let avx2 = 1 << 7;
        assert_eq!(EXTENSIONS[6], "avx");
        assert_eq!(EXTENSIONS[7], "avx2");
        assert_eq!(extension_names(avx2 | avx), ["avx", "avx2"]);
        assert!(extension_names(0).is_empty());
        let message = UnsupportedCpu {
            missing: extension_names(avx | avx2),
        }
        .to_string();
        assert!(
            message.contains("not have (avx, avx2); it was compiled for x86-64-v3"),
            "{message}"
        );
        assert!(
            message.contains("RUSTFLAGS=\"-C target-cpu=x86-64-v2\""),
            "{message}"
        );
    }

    /// The compiled mask follows the build's flags: SSE2-only builds set nothing, and a level
    /// implies its predecessors' extensions.
    #[test]
    fn the_compiled_mask_is_the_builds_target_features() {
        let compiled = compiled_mask();
        assert_eq!(compiled & (1 << 7) != 0, cfg!(target_feature = "avx2"));
        assert_eq!(compiled & (1 << 14) != 0, cfg!(target_feature = "fma"));
        if cfg!(target_feature = "avx2") {
            let v2 = 0b11_1111;
            assert_eq!(compiled & v2, v2, "{compiled:#b}");
        }
    }

    /// The tests run, so this CPU has what the build was compiled for; and `cpuid` finds what
    /// the standard library's detection finds.
    #[test]
    fn this_cpu_runs_this_build() {
        assert_eq!(check_instruction_set(), Ok(()));
        #[cfg(target_arch = "x86_64")]
        {
            let detected = detected_mask();
            assert_eq!(detected & (1 << 3) != 0, is_x86_feature_detected!("sse4.2"));
            if !cfg!(target_feature = "avx2") {
                assert_eq!(detected & (1 << 7) != 0, is_x86_feature_detected!("avx2"));
            }
            if !cfg!(target_feature = "fma") {
                assert_eq!(detected & (1 << 14) != 0, is_x86_feature_detected!("fma"));
            }
        }
    }
}
