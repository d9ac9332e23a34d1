//! Choosing an adapter and opening a device, headless or for a window.

use std::fmt;

/// Which graphics API to use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Backend {
    /// Vulkan if any adapter offers it, else OpenGL.
    #[default]
    Auto,
    Vulkan,
    Gl,
}

impl std::str::FromStr for Backend {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "auto" => Ok(Backend::Auto),
            "vulkan" => Ok(Backend::Vulkan),
            "gl" => Ok(Backend::Gl),
            _ => Err(format!("unknown backend {s:?} (auto, vulkan, gl)")),
        }
    }
}

impl Backend {
    fn backends(self) -> wgpu::Backends {
        match self {
            Backend::Auto => wgpu::Backends::VULKAN | wgpu::Backends::GL,
            Backend::Vulkan => wgpu::Backends::VULKAN,
            Backend::Gl => wgpu::Backends::GL,
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    #[error(
        "no {backend} graphics adapter found. On a machine without a GPU install a software \
         driver: for Vulkan `apt-get install mesa-vulkan-drivers libvulkan1` (lavapipe), for \
         OpenGL `apt-get install libegl1 libgl1-mesa-dri` (llvmpipe); then retry, or pass \
         --backend to pick one"
    )]
    NoAdapter { backend: String },
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
    pub fn headless(backend: Backend) -> Result<Self, GpuError> {
        let mut descriptor = wgpu::InstanceDescriptor::new_without_display_handle();
        descriptor.backends = backend.backends();
        let instance = wgpu::Instance::new(descriptor);
        let adapters = pollster::block_on(instance.enumerate_adapters(backend.backends()));
        let adapter = adapters
            .into_iter()
            .min_by_key(|a| preference(&a.get_info()))
            .ok_or_else(|| GpuError::NoAdapter {
                backend: match backend {
                    Backend::Auto => "Vulkan or OpenGL".into(),
                    Backend::Vulkan => "Vulkan".into(),
                    Backend::Gl => "OpenGL".into(),
                },
            })?;
        Self::open(instance, adapter)
    }

    /// Opens a device on `adapter`, asking for the adapter's own limits (large scenes need
    /// big storage buffers).
    pub fn open(instance: wgpu::Instance, adapter: wgpu::Adapter) -> Result<Self, GpuError> {
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("hprt"),
            required_features: wgpu::Features::empty(),
            required_limits: adapter.limits(),
            ..Default::default()
        }))
        .map_err(|e| GpuError::Device {
            adapter: adapter.get_info().name,
            message: e.to_string(),
        })?;
        // Errors outside the renderer's error scopes are reported, not turned into a panic.
        device.on_uncaptured_error(std::sync::Arc::new(|error: wgpu::Error| {
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
