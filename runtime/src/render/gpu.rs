//! Choosing an adapter and opening a device, headless or for a window.

use std::fmt;

foundation::named_enum! {
    /// Which graphics API to use.
    #[derive(Default)]
    pub enum Backend ("graphics backend") {
        /// Vulkan if any adapter offers it, else OpenGL.
        #[default]
        Auto = "auto",
        Vulkan = "vulkan",
        Gl = "gl",
    }
}

impl Backend {
    pub fn backends(self) -> wgpu::Backends {
        match self {
            Backend::Auto => wgpu::Backends::VULKAN | wgpu::Backends::GL,
            Backend::Vulkan => wgpu::Backends::VULKAN,
            Backend::Gl => wgpu::Backends::GL,
        }
    }

    #[cfg_attr(target_arch = "wasm32", allow(dead_code))]
    fn description(self) -> &'static str {
        match self {
            Backend::Auto => "Vulkan or OpenGL",
            Backend::Vulkan => "Vulkan",
            Backend::Gl => "OpenGL",
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    #[error(
        "no {backend} graphics adapter found{}. On a machine without a GPU install a software \
         driver: for Vulkan `apt-get install mesa-vulkan-drivers libvulkan1` (lavapipe), for \
         OpenGL `apt-get install libegl1 libgl1-mesa-dri` (llvmpipe); then retry with another \
         backend or this one",
        if *for_window { " that can draw into the window" } else { "" }
    )]
    NoAdapter {
        backend: &'static str,
        for_window: bool,
    },
    #[error("cannot draw into the window: {0}")]
    Surface(String),
    #[error("the adapter {adapter} could not open a device: {message}")]
    Device { adapter: String, message: String },
}

/// An open device and what it runs on.
pub struct GpuContext {
    pub instance: wgpu::Instance,
    pub adapter: wgpu::Adapter,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
}

/// Adapter name, type and backend, for logs and benchmarks.
pub struct AdapterDescription(pub wgpu::AdapterInfo);

impl fmt::Display for AdapterDescription {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let i = &self.0;
        write!(f, "{} ({:?}, {:?}", i.name, i.device_type, i.backend)?;
        if !i.driver.is_empty() {
            write!(f, ", {} {}", i.driver, i.driver_info)?;
        }
        write!(f, ")")
    }
}

#[cfg(not(target_arch = "wasm32"))]
fn preference(info: &wgpu::AdapterInfo) -> u8 {
    let device = match info.device_type {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Cpu => 3,
        wgpu::DeviceType::Other => 4,
    };
    // Prefer Vulkan to GL on the same kind of device.
    device * 2 + u8::from(info.backend != wgpu::Backend::Vulkan)
}

impl GpuContext {
    /// Opens the best adapter of `backend` without a window.
    #[cfg(not(target_arch = "wasm32"))]
    pub fn headless(backend: Backend) -> Result<Self, GpuError> {
        let instance = Self::instance(
            backend,
            wgpu::InstanceDescriptor::new_without_display_handle(),
        );
        let adapter =
            pollster::block_on(Self::best_adapter(&instance, backend.backends(), |_| true)).ok_or(
                GpuError::NoAdapter {
                    backend: backend.description(),
                    for_window: false,
                },
            )?;
        pollster::block_on(Self::open(instance, adapter))
    }

    /// Opens the best adapter of `backend` that can present to `target` (a window), with the
    /// surface for it.
    #[cfg(not(target_arch = "wasm32"))]
    pub fn for_surface(
        backend: Backend,
        descriptor: wgpu::InstanceDescriptor,
        target: impl Into<wgpu::SurfaceTarget<'static>>,
    ) -> Result<(Self, wgpu::Surface<'static>), GpuError> {
        let instance = Self::instance(backend, descriptor);
        pollster::block_on(Self::for_surface_of(
            instance,
            backend.backends(),
            backend.description(),
            target,
        ))
    }

    /// Opens the best adapter among `backends` of `instance` that can present to `target` (a
    /// window or a page's canvas), with the surface for it. `description` names the backends
    /// in the error.
    pub async fn for_surface_of(
        instance: wgpu::Instance,
        backends: wgpu::Backends,
        description: &'static str,
        target: impl Into<wgpu::SurfaceTarget<'static>>,
    ) -> Result<(Self, wgpu::Surface<'static>), GpuError> {
        let surface = instance
            .create_surface(target)
            .map_err(|e| GpuError::Surface(e.to_string()))?;
        #[cfg(not(target_arch = "wasm32"))]
        let adapter =
            Self::best_adapter(&instance, backends, |a| a.is_surface_supported(&surface)).await;
        // A browser lists no adapters (WebGL2 has one only for the canvas): it picks one.
        #[cfg(target_arch = "wasm32")]
        let adapter = {
            let _ = backends;
            let options = wgpu::RequestAdapterOptions {
                compatible_surface: Some(&surface),
                ..Default::default()
            };
            instance.request_adapter(&options).await.ok()
        };
        let adapter = adapter.ok_or(GpuError::NoAdapter {
            backend: description,
            for_window: true,
        })?;
        Ok((Self::open(instance, adapter).await?, surface))
    }

    #[cfg(not(target_arch = "wasm32"))]
    fn instance(backend: Backend, mut descriptor: wgpu::InstanceDescriptor) -> wgpu::Instance {
        descriptor.backends = backend.backends();
        wgpu::Instance::new(descriptor)
    }

    /// The adapter policy, one for windows and headless work: a real GPU before a software
    /// one, Vulkan before OpenGL on the same kind of device.
    #[cfg(not(target_arch = "wasm32"))]
    async fn best_adapter(
        instance: &wgpu::Instance,
        backends: wgpu::Backends,
        usable: impl Fn(&wgpu::Adapter) -> bool,
    ) -> Option<wgpu::Adapter> {
        instance
            .enumerate_adapters(backends)
            .await
            .into_iter()
            .filter(|a| usable(a))
            .min_by_key(|a| preference(&a.get_info()))
    }

    /// Opens a device on `adapter`, asking for the adapter's own limits (large scenes need
    /// big storage buffers).
    async fn open(instance: wgpu::Instance, adapter: wgpu::Adapter) -> Result<Self, GpuError> {
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("hprt"),
                required_features: wgpu::Features::empty(),
                required_limits: required_limits(&adapter),
                ..Default::default()
            })
            .await
            .map_err(|e| GpuError::Device {
                adapter: adapter.get_info().name,
                message: e.to_string(),
            })?;
        // Errors outside the renderer's error scopes are reported, not turned into a panic.
        device.on_uncaptured_error(std::sync::Arc::new(|error: wgpu::Error| {
            note_uncaptured(&error);
            log::error!("graphics driver: {error}");
        }));
        Ok(Self {
            instance,
            adapter,
            device,
            queue,
        })
    }

    pub fn description(&self) -> AdapterDescription {
        AdapterDescription(self.adapter.get_info())
    }

    /// Blocks until the GPU has finished all submitted work.
    pub fn wait(&self) {
        // Only fails if the device is lost, which the next call reports anyway.
        let _ = self.device.poll(wgpu::PollType::wait_indefinitely());
    }
}

/// The adapter's own limits (large scenes need big storage buffers). With
/// `HPRT_GPU_LIMITS=webgl2`, a browser's WebGL2 limits instead (no compute, no storage
/// buffers; the adapter's texture sizes), so that the paths a WebGL2 page takes run natively
/// and are tested there (CONVENTIONS.md, "The web viewer").
fn required_limits(adapter: &wgpu::Adapter) -> wgpu::Limits {
    #[cfg(not(target_arch = "wasm32"))]
    if std::env::var("HPRT_GPU_LIMITS").as_deref() == Ok("webgl2") {
        log::warn!("HPRT_GPU_LIMITS=webgl2: the device takes a browser's WebGL2 limits");
        return wgpu::Limits::downlevel_webgl2_defaults().using_resolution(adapter.limits());
    }
    adapter.limits()
}

/// Whether the driver ran out of memory outside an error scope in this process.
static RAN_OUT_OF_MEMORY: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Notes an error no scope caught (the device's uncaptured-error handler calls this).
fn note_uncaptured(error: &wgpu::Error) {
    if matches!(error, wgpu::Error::OutOfMemory { .. }) {
        RAN_OUT_OF_MEMORY.store(true, std::sync::atomic::Ordering::Relaxed);
    }
}

/// Whether memory ran out earlier where no error scope caught it: what fails later is then
/// reported as running out of memory, its cause.
#[cfg_attr(target_arch = "wasm32", allow(dead_code))]
pub(super) fn ran_out_of_memory() -> bool {
    RAN_OUT_OF_MEMORY.load(std::sync::atomic::Ordering::Relaxed)
}
