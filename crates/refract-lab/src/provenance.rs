//! Where and how a measurement was made, read from the system and the build, never typed: the
//! commit of the checkout a command runs in, the date, the compiler and build settings, the CPU,
//! the load average. `refract claims` opens `docs/claims.md` with it and `refract bench --table
//! all` heads its tables with it.

use std::fmt::Write as _;
use std::time::SystemTime;

/// The commit of the checkout the command runs in (`git rev-parse --short=12 HEAD`), with
/// `(uncommitted changes)` when tracked files differ from it; a sentence saying so where git or
/// the checkout is missing.
pub fn checkout_commit() -> String {
    let git = |args: &[&str]| {
        std::process::Command::new("git")
            .args(args)
            .output()
            .ok()
            .filter(|out| out.status.success())
            .map(|out| String::from_utf8_lossy(&out.stdout).trim().to_owned())
    };
    match git(&["rev-parse", "--short=12", "HEAD"]) {
        Some(hash) => {
            let changed = git(&["status", "--porcelain", "--untracked-files=no"])
                .is_some_and(|status| !status.is_empty());
            if changed {
                format!("{hash} (uncommitted changes)")
            } else {
                hash
            }
        }
        None => "unknown (not run in a git checkout)".to_owned(),
    }
}

/// The compiler that built this crate (`rustc --version` at build time).
pub fn rustc() -> &'static str {
    env!("REFRACT_BUILD_RUSTC")
}

/// The build's profile, optimisation level, debug assertions, target and `RUSTFLAGS`.
pub fn build() -> &'static str {
    env!("REFRACT_BUILD_PROFILE")
}

/// The 1-, 5- and 15-minute load averages (`/proc/loadavg`), `None` where the system has none.
pub fn load_average() -> Option<String> {
    let text = std::fs::read_to_string("/proc/loadavg").ok()?;
    let fields: Vec<&str> = text.split_whitespace().take(3).collect();
    (fields.len() == 3).then(|| fields.join(" / "))
}

/// What made a frame, as its files carry it (EXR header attributes, PNG text chunks:
/// `refract_eval::FrameFiles::write_exr_described`): the scene, the method, its parameters,
/// the backend (`cpu`, `gpu`, `trace`), the device (the GPU adapter, else this machine's CPU),
/// the resolution, this build's version and the checkout's commit.
pub fn frame_description(
    scene: &str,
    method: &refract_scene::MethodParams,
    backend: &str,
    device: Option<&str>,
    size: (u32, u32),
) -> Vec<(&'static str, String)> {
    let made_by = (method.id().name(), method.describe());
    file_description(scene, (made_by.0, &made_by.1), backend, device, size)
}

/// [`frame_description`] of a frame from anything, named by `(method, params)` (an engine's
/// own frame: its label and no parameters).
pub fn file_description(
    scene: &str,
    (method, params): (&str, &str),
    backend: &str,
    device: Option<&str>,
    (width, height): (u32, u32),
) -> Vec<(&'static str, String)> {
    vec![
        ("refract.scene", scene.to_owned()),
        ("refract.method", method.to_owned()),
        ("refract.params", params.to_owned()),
        ("refract.backend", backend.to_owned()),
        (
            "refract.device",
            device.map_or_else(crate::timing::cpu_description, str::to_owned),
        ),
        ("refract.resolution", format!("{width}x{height}")),
        ("refract.version", env!("CARGO_PKG_VERSION").to_owned()),
        ("refract.commit", checkout_commit()),
    ]
}

/// The date now, UTC, RFC 3339 to the second.
pub fn now() -> String {
    humantime::format_rfc3339_seconds(SystemTime::now()).to_string()
}

/// A run's provenance: taken at its start ([`Self::start`]) and finished at its end
/// ([`Self::finish`]).
#[derive(Clone, Debug)]
pub struct Provenance {
    /// When the run started (UTC).
    pub started: String,
    /// [`checkout_commit`] at the start.
    pub commit: String,
    /// [`crate::timing::cpu_description`].
    pub cpu: String,
    /// The GPU adapter the run used, if any.
    pub gpu: Option<String>,
    /// [`load_average`] at the start and at the end.
    pub load: (Option<String>, Option<String>),
    /// Seconds the run took.
    pub seconds: f64,
    start: std::time::Instant,
}

impl Provenance {
    /// The provenance of a run starting now.
    pub fn start() -> Self {
        Self {
            started: now(),
            commit: checkout_commit(),
            cpu: crate::timing::cpu_description(),
            gpu: None,
            load: (load_average(), None),
            seconds: 0.0,
            start: std::time::Instant::now(),
        }
    }

    /// Records the end of the run.
    pub fn finish(&mut self) {
        self.load.1 = load_average();
        self.seconds = self.start.elapsed().as_secs_f64();
    }

    /// The block as Markdown list items.
    pub fn markdown(&self) -> String {
        let mut md = String::new();
        let _ = writeln!(md, "- commit: {}", self.commit);
        let _ = writeln!(md, "- date: {} (UTC), {:.0} s", self.started, self.seconds);
        let _ = writeln!(md, "- compiler: {}", rustc());
        let _ = writeln!(md, "- build: {}", build());
        let _ = writeln!(md, "- CPU: {}", self.cpu);
        let _ = writeln!(md, "- GPU: {}", self.gpu.as_deref().unwrap_or("none used"));
        let load = |l: &Option<String>| l.clone().unwrap_or_else(|| "unknown".to_owned());
        let _ = writeln!(
            md,
            "- load average (1 / 5 / 15 min): {} at the start, {} at the end",
            load(&self.load.0),
            load(&self.load.1)
        );
        md
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The commit is the checkout's own: run by `cargo test` inside the repository, it is what
    /// git says HEAD is (or says that there is no checkout, when git does).
    #[test]
    fn the_commit_is_the_checkouts() {
        let head = std::process::Command::new("git")
            .args(["rev-parse", "--short=12", "HEAD"])
            .output()
            .ok()
            .filter(|out| out.status.success())
            .map(|out| String::from_utf8_lossy(&out.stdout).trim().to_owned());
        let commit = checkout_commit();
        match head {
            Some(hash) => assert!(commit.starts_with(&hash), "{commit} vs {hash}"),
            None => assert!(commit.starts_with("unknown"), "{commit}"),
        }
    }

    /// The block names every field, from the build and the system.
    #[test]
    fn the_block_is_measured() {
        let mut p = Provenance::start();
        p.finish();
        let md = p.markdown();
        assert!(md.contains(&format!("- commit: {}", p.commit)), "{md}");
        assert!(rustc().starts_with("rustc "), "{}", rustc());
        assert!(
            build().contains("opt-level") && build().contains("target "),
            "{}",
            build()
        );
        for field in [
            "- date: ",
            "- compiler: rustc ",
            "- build: profile ",
            "- CPU: ",
            "- GPU: ",
            "- load average",
        ] {
            assert!(md.contains(field), "{field}: {md}");
        }
    }
}
