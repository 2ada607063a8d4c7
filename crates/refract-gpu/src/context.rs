//! Finding an adapter and a device, headless, with clear errors.

use std::fmt;
use std::sync::{Arc, Mutex};

/// Why the GPU backend could not run.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// No adapter exists (no GPU and no software Vulkan such as lavapipe).
    #[error(
        "no GPU adapter found (install a Vulkan driver, e.g. Debian's mesa-vulkan-drivers for lavapipe{0})"
    )]
    NoAdapter(String),
    /// The device could not be created.
    #[error("cannot create a device on {adapter}: {message}")]
    Device {
        /// Adapter name.
        adapter: String,
        /// What wgpu said.
        message: String,
    },
    /// A resolution the adapter cannot hold.
    #[error("resolution {width}x{height} exceeds what {adapter} supports ({limit})")]
    ResolutionTooLarge {
        /// Requested width.
        width: u32,
        /// Requested height.
        height: u32,
        /// Adapter name.
        adapter: String,
        /// Which limit.
        limit: String,
    },
    /// A scene whose buffer is larger than the adapter binds (issue 54 #5: a raw wgpu
    /// validation error above about 1.68M triangles on lavapipe).
    #[error(
        "the scene's {count} {what} need {bytes} bytes in one GPU buffer; {adapter} binds at most {limit} bytes in a storage buffer (about {max} {what}): trace it on the CPU (`--reference-backend cpu`, the default)"
    )]
    SceneTooLarge {
        /// What the buffer holds (`triangles`, `BVH nodes`).
        what: &'static str,
        /// How many.
        count: usize,
        /// Their bytes.
        bytes: u64,
        /// The adapter's limit in bytes.
        limit: u64,
        /// How many fit.
        max: u64,
        /// Adapter name.
        adapter: String,
    },
    /// The device could not allocate a resource.
    #[error("the GPU is out of memory")]
    OutOfMemory,
    /// A wgpu validation or device error while rendering.
    #[error("GPU error: {0}")]
    Wgpu(String),
    /// Reading results back failed (device lost, mapping failed).
    #[error("reading back from the GPU failed: {0}")]
    Readback(String),
    /// Invalid parameters.
    #[error(transparent)]
    Ior(#[from] refract_core::kernel::InvalidIor),
    /// `REFRACT_RAY_QUERY` is not one of its values, or ray queries are forced on an adapter
    /// without them.
    #[error("ray queries: {0}")]
    RayQuery(String),
}

impl GpuContext {
    /// Refuses a storage buffer of `count` elements of `T` that the device cannot bind
    /// (`max_storage_buffer_binding_size`, `max_buffer_size`), with a clear error naming the
    /// count and the limit.
    pub fn check_storage<T>(&self, what: &'static str, count: usize) -> Result<(), GpuError> {
        let element = std::mem::size_of::<T>().max(1) as u64;
        let limits = self.device.limits();
        let limit = limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size);
        let bytes = count as u64 * element;
        if bytes <= limit {
            return Ok(());
        }
        Err(GpuError::SceneTooLarge {
            what,
            count,
            bytes,
            limit,
            max: limit / element,
            adapter: self.info.name.clone(),
        })
    }
}

/// Whether the reference traverses its scene with the adapter's hardware ray queries
/// (`EXPERIMENTAL_RAY_QUERY`) or the WGSL BVH traversal; from `REFRACT_RAY_QUERY`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum RayQueryPolicy {
    /// Ray queries where the adapter offers them, the WGSL traversal elsewhere (unset or `auto`).
    #[default]
    Auto,
    /// Ray queries; an adapter without them is an error (`on`).
    On,
    /// The WGSL traversal even where ray queries exist (`off`).
    Off,
}

/// The process's policy when a program chose one ([`RayQueryPolicy::choose`], e.g. the CLI's
/// `--ray-query`); it takes precedence over `REFRACT_RAY_QUERY`.
static CHOSEN_POLICY: std::sync::OnceLock<RayQueryPolicy> = std::sync::OnceLock::new();

impl RayQueryPolicy {
    /// Sets the policy of every device this process opens from now on (once; a second choice
    /// is ignored and returns `false`).
    pub fn choose(self) -> bool {
        CHOSEN_POLICY.set(self).is_ok()
    }

    /// The policy chosen by the program ([`Self::choose`]), else the one `REFRACT_RAY_QUERY`
    /// names: `auto` (or unset), `on`, `off`.
    pub fn current() -> Result<Self, GpuError> {
        match CHOSEN_POLICY.get() {
            Some(policy) => Ok(*policy),
            None => Self::from_env(),
        }
    }

    /// The policy `REFRACT_RAY_QUERY` names: `auto` (or unset), `on`, `off`.
    pub fn from_env() -> Result<Self, GpuError> {
        match std::env::var("REFRACT_RAY_QUERY").as_deref() {
            Err(_) | Ok("auto") => Ok(Self::Auto),
            Ok("on") => Ok(Self::On),
            Ok("off") => Ok(Self::Off),
            Ok(other) => Err(GpuError::RayQuery(format!(
                "REFRACT_RAY_QUERY=`{other}`: expected auto, on or off"
            ))),
        }
    }
}

/// A device and its queue, plus what the adapter can do. A clone is another handle onto the
/// same device and queue (wgpu's handles are reference-counted; error scopes are per thread),
/// for work on another thread such as the viewer's background reference.
#[derive(Clone)]
pub struct GpuContext {
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// The adapter's description.
    pub info: wgpu::AdapterInfo,
    /// Whether GPU timestamps are available (TIMESTAMP_QUERY).
    pub timestamps: bool,
    /// Whether the device has hardware ray queries enabled (`EXPERIMENTAL_RAY_QUERY`, by
    /// [`RayQueryPolicy`]): the reference then traverses its scene with them.
    pub ray_queries: bool,
    /// Why the reference cannot run here: [`RayQueryPolicy::On`] on an adapter without ray
    /// queries. Only the reference traces rays, so only it refuses; every other method runs.
    pub ray_query_refusal: Option<String>,
    /// The first error no scope caught (wgpu's default handler panics; ours keeps it for the
    /// next [`GpuContext::checked`] or [`GpuContext::wait`] to return).
    uncaught: Arc<Mutex<Option<String>>>,
}

impl fmt::Debug for GpuContext {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("GpuContext")
            .field("adapter", &self.info.name)
            .field("backend", &self.info.backend)
            .finish()
    }
}

/// An adapter wgpu can see and what the reference can use of it.
#[derive(Clone, Debug)]
pub struct AdapterSummary {
    /// Name, backend, device type, driver.
    pub info: wgpu::AdapterInfo,
    /// Whether it offers hardware ray queries (`EXPERIMENTAL_RAY_QUERY`).
    pub ray_queries: bool,
}

/// Every adapter wgpu can see (honouring `WGPU_BACKEND`), for `refract info`.
pub fn list_adapters() -> Vec<AdapterSummary> {
    let instance =
        wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
    pollster::block_on(instance.enumerate_adapters(wgpu::Backends::all()))
        .iter()
        .map(|adapter| AdapterSummary {
            info: adapter.get_info(),
            ray_queries: adapter
                .features()
                .contains(wgpu::Features::EXPERIMENTAL_RAY_QUERY),
        })
        .collect()
}

impl GpuContext {
    /// Opens the first adapter, honouring `WGPU_BACKEND` (which backends to try) and
    /// `WGPU_ADAPTER_NAME` (a substring of the adapter name), and creates a device with the
    /// adapter's own limits and TIMESTAMP_QUERY when available.
    pub fn new() -> Result<Self, GpuError> {
        pollster::block_on(Self::new_async())
    }

    async fn new_async() -> Result<Self, GpuError> {
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let adapter = match std::env::var("WGPU_ADAPTER_NAME") {
            Ok(wanted) => {
                let wanted = wanted.to_lowercase();
                let adapters = instance.enumerate_adapters(wgpu::Backends::all()).await;
                adapters
                    .into_iter()
                    .find(|a| a.get_info().name.to_lowercase().contains(&wanted))
                    .ok_or_else(|| {
                        GpuError::NoAdapter(format!("; none matches WGPU_ADAPTER_NAME={wanted}"))
                    })?
            }
            Err(_) => instance
                .request_adapter(&wgpu::RequestAdapterOptions {
                    power_preference: wgpu::PowerPreference::HighPerformance,
                    ..Default::default()
                })
                .await
                .map_err(|err| GpuError::NoAdapter(format!("; {err}")))?,
        };
        Self::from_adapter_async(&adapter).await
    }

    /// A context on `adapter` (e.g. one compatible with a window's surface): a device with the
    /// adapter's own limits and TIMESTAMP_QUERY when available.
    pub fn from_adapter(adapter: &wgpu::Adapter) -> Result<Self, GpuError> {
        pollster::block_on(Self::from_adapter_async(adapter))
    }

    async fn from_adapter_async(adapter: &wgpu::Adapter) -> Result<Self, GpuError> {
        let info = adapter.get_info();
        let timestamps = adapter.features().contains(wgpu::Features::TIMESTAMP_QUERY);
        let has_ray_queries = adapter
            .features()
            .contains(wgpu::Features::EXPERIMENTAL_RAY_QUERY);
        let (ray_queries, ray_query_refusal) = match RayQueryPolicy::current()? {
            RayQueryPolicy::Auto => (has_ray_queries, None),
            RayQueryPolicy::Off => (false, None),
            RayQueryPolicy::On if has_ray_queries => (true, None),
            RayQueryPolicy::On => (
                false,
                Some(format!(
                    "ray queries forced on (--ray-query on or REFRACT_RAY_QUERY=on), but {} ({}) has no ray queries (lavapipe has them from Mesa 24.1; docs/reference.md)",
                    info.name, info.driver_info
                )),
            ),
        };
        let mut required_features = wgpu::Features::empty();
        if timestamps {
            required_features |= wgpu::Features::TIMESTAMP_QUERY;
        }
        let experimental_features = if ray_queries {
            required_features |= wgpu::Features::EXPERIMENTAL_RAY_QUERY;
            experimental_ray_queries()
        } else {
            wgpu::ExperimentalFeatures::disabled()
        };
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("refract"),
                required_features,
                required_limits: adapter.limits(),
                experimental_features,
                memory_hints: wgpu::MemoryHints::Performance,
                trace: wgpu::Trace::Off,
            })
            .await
            .map_err(|err| GpuError::Device {
                adapter: info.name.clone(),
                message: err.to_string(),
            })?;
        let uncaught = Arc::new(Mutex::new(None));
        let keep = Arc::clone(&uncaught);
        device.on_uncaptured_error(Arc::new(move |err: wgpu::Error| {
            if let Ok(mut slot) = keep.lock() {
                slot.get_or_insert_with(|| err.to_string());
            }
        }));
        Ok(Self {
            device,
            queue,
            info,
            timestamps,
            ray_queries,
            ray_query_refusal,
            uncaught,
        })
    }

    /// Opens a context for a test: `None` (after printing `skipped: no GPU adapter`) when there
    /// is none, unless `REFRACT_REQUIRE_GPU=1`, where a missing adapter panics.
    pub fn for_tests() -> Option<Self> {
        match Self::new() {
            Ok(context) => Some(context),
            Err(err) => {
                let required = std::env::var("REFRACT_REQUIRE_GPU").is_ok_and(|v| v == "1");
                assert!(!required, "REFRACT_REQUIRE_GPU=1 but: {err}");
                println!("skipped: no GPU adapter ({err})");
                None
            }
        }
    }

    /// Waits for all submitted work; an error no scope caught since is returned here.
    pub fn wait(&self) -> Result<(), GpuError> {
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map(|_| ())
            .map_err(|err| GpuError::Readback(err.to_string()))?;
        self.take_uncaught()
    }

    fn take_uncaught(&self) -> Result<(), GpuError> {
        let error = match self.uncaught.lock() {
            Ok(mut slot) => slot.take(),
            Err(poisoned) => poisoned.into_inner().take(),
        };
        error.map_or(Ok(()), |message| Err(GpuError::Wgpu(message)))
    }

    /// Copies a `MAP_READ` buffer's content out.
    pub fn read_buffer(&self, buffer: &wgpu::Buffer) -> Result<Vec<u8>, GpuError> {
        let slice = buffer.slice(..);
        let (sender, receiver) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |result| {
            let _ = sender.send(result);
        });
        self.wait()?;
        receiver
            .recv()
            .map_err(|err| GpuError::Readback(err.to_string()))?
            .map_err(|err| GpuError::Readback(err.to_string()))?;
        let data = slice
            .get_mapped_range()
            .map_err(|err| GpuError::Readback(err.to_string()))?
            .to_vec();
        buffer.unmap();
        Ok(data)
    }

    /// Runs `work` inside validation, out-of-memory and internal error scopes and reports the
    /// first error (an allocation the device cannot make is [`GpuError::OutOfMemory`], never a
    /// panic).
    pub fn checked<T>(&self, work: impl FnOnce() -> T) -> Result<T, GpuError> {
        let validation = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let memory = self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let internal = self.device.push_error_scope(wgpu::ErrorFilter::Internal);
        let value = work();
        let internal = pollster::block_on(internal.pop());
        let memory = pollster::block_on(memory.pop());
        let validation = pollster::block_on(validation.pop());
        if memory.is_some() {
            return Err(GpuError::OutOfMemory);
        }
        if let Some(err) = validation.or(internal) {
            return Err(GpuError::Wgpu(err.to_string()));
        }
        self.take_uncaught()?;
        Ok(value)
    }
}

/// wgpu's token for its experimental features, asked for only to enable
/// `EXPERIMENTAL_RAY_QUERY` where the adapter offers it and `REFRACT_RAY_QUERY` is not `off`.
#[allow(unsafe_code)]
fn experimental_ray_queries() -> wgpu::ExperimentalFeatures {
    // SAFETY: the token acknowledges that wgpu's experimental ray-query API may still have
    // bugs. We use it only as wgpu's own example does (one triangle BLAS, one TLAS instance,
    // `rayQueryProceed` over opaque geometry), the results are held to the WGSL traversal's by
    // crates/refract-cli/tests/ray_query.rs, and `REFRACT_RAY_QUERY=off` turns it off.
    unsafe { wgpu::ExperimentalFeatures::enabled() }
}

#[cfg(test)]
mod tests {
    use super::GpuContext;

    /// A buffer beyond what the adapter binds is refused naming the count, the limit and what
    /// to do (issue 54 #5: the GPU reference above about 1.68M triangles failed with wgpu's
    /// raw validation error); one within it passes.
    #[test]
    fn storage_beyond_the_binding_limit_is_refused_by_name() {
        let Some(context) = GpuContext::for_tests() else {
            return;
        };
        type Triangle = [u32; 16];
        assert!(context.check_storage::<Triangle>("triangles", 1000).is_ok());
        let limits = context.device.limits();
        let limit = limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size);
        let count = (limit / 64 + 1) as usize;
        let err = context
            .check_storage::<Triangle>("triangles", count)
            .expect_err("beyond the limit")
            .to_string();
        assert!(
            err.contains(&format!("{count} triangles need"))
                && err.contains(&format!("at most {limit} bytes"))
                && err.contains("--reference-backend cpu"),
            "{err}"
        );
    }
}
