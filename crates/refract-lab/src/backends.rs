//! The renderers a command runs: parsing `--backends`, opening the GPU (or saying why not), and
//! checking every requested method is supported before any work starts.

use refract_cpu::CpuRenderer;
use refract_gpu::GpuRenderer;
use refract_scene::{BackendId, MethodParams, Renderer};
use refract_trace::ReferenceRenderer;

use crate::progress::{Note, Progress};

/// What to do when a renderer a command would run is missing: no GPU adapter, or no engine
/// (`crate::engines`: Node, Chromium or the npm packages).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GpuPolicy {
    /// The user asked for it: missing is an error.
    Required,
    /// A default list: run without it, with a one-line notice.
    IfAvailable,
}

/// Parses a `--backends` list (`cpu`, `gpu`).
pub fn parse_backends(names: &[String]) -> crate::Result<Vec<BackendId>> {
    names
        .iter()
        .map(|name| match name.as_str() {
            "cpu" => Ok(BackendId::Cpu),
            "gpu" => Ok(BackendId::Gpu),
            other => crate::bail!("--backends: unknown backend `{other}`; expected cpu or gpu"),
        })
        .collect()
}

/// Opens the renderers of `backends` (the reference is not one of them); the GPU adapter used,
/// or why the GPU is left out, goes to `progress`.
pub fn open(
    backends: &[BackendId],
    policy: GpuPolicy,
    progress: &dyn Progress,
) -> crate::Result<Vec<Box<dyn Renderer>>> {
    let mut renderers: Vec<Box<dyn Renderer>> = Vec::new();
    for &backend in backends {
        match backend {
            BackendId::Cpu => renderers.push(Box::new(CpuRenderer::new())),
            BackendId::Gpu => match GpuRenderer::new() {
                Ok(gpu) => {
                    let info = &gpu.context().info;
                    progress.note(Note::Info(format!(
                        "GPU: {} ({:?})",
                        info.name, info.backend
                    )));
                    renderers.push(Box::new(gpu));
                }
                Err(err) if policy == GpuPolicy::IfAvailable => {
                    progress.note(Note::Skipped(format!("{err}; running on the CPU only")));
                }
                Err(err) => return Err(err.into()),
            },
            BackendId::Trace => {
                crate::bail!("--backends: the reference always runs; expected cpu or gpu")
            }
        }
    }
    Ok(renderers)
}

/// Where a command traces its references.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum ReferenceBackend {
    /// The CPU tracer (`refract_trace`), the default.
    #[default]
    Cpu,
    /// The WGSL tracer (`refract_gpu::reference`; docs/reference.md).
    Gpu,
}

impl ReferenceBackend {
    /// The renderer that traces the references: the CPU tracer, or the GPU (no adapter is an
    /// error naming why).
    pub fn renderer(self) -> crate::Result<Box<dyn Renderer>> {
        Ok(match self {
            Self::Cpu => Box::new(ReferenceRenderer::new()),
            Self::Gpu => Box::new(GpuRenderer::new()?),
        })
    }
}

/// Fails, naming the method and backend, when a renderer does not support a method.
pub fn check_supported(
    renderers: &[Box<dyn Renderer>],
    methods: &[MethodParams],
) -> crate::Result<()> {
    for renderer in renderers {
        for method in methods {
            if !renderer.supports(method.id()) {
                return Err(refract_scene::RenderError::Unsupported {
                    backend: renderer.backend(),
                    method: method.id(),
                }
                .into());
            }
        }
    }
    Ok(())
}
