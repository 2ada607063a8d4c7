//! Records how this crate was built, for the provenance of what it measures
//! (`refract_lab::provenance`): the compiler's version, the profile, the target and the flags.

fn main() {
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".to_owned());
    let version = std::process::Command::new(&rustc)
        .arg("--version")
        .output()
        .ok()
        .filter(|out| out.status.success())
        .map(|out| String::from_utf8_lossy(&out.stdout).trim().to_owned())
        .unwrap_or_else(|| "unknown".to_owned());
    println!("cargo:rustc-env=REFRACT_BUILD_RUSTC={version}");
    let var = |name: &str| std::env::var(name).unwrap_or_default();
    // CARGO_ENCODED_RUSTFLAGS separates the flags with 0x1f.
    let flags = var("CARGO_ENCODED_RUSTFLAGS").replace('\u{1f}', " ");
    println!(
        "cargo:rustc-env=REFRACT_BUILD_PROFILE=profile {}, opt-level {}, debug assertions {}, target {}{}",
        var("PROFILE"),
        var("OPT_LEVEL"),
        if std::env::var("CARGO_CFG_DEBUG_ASSERTIONS").is_ok() {
            "on"
        } else {
            "off"
        },
        var("TARGET"),
        if flags.trim().is_empty() {
            String::new()
        } else {
            format!(", RUSTFLAGS `{}`", flags.trim())
        }
    );
    println!("cargo:rerun-if-env-changed=CARGO_ENCODED_RUSTFLAGS");
    println!("cargo:rerun-if-changed=build.rs");
}
