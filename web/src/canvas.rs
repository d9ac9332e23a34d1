//! The page's canvas as a wgpu surface: WebGPU where the browser has it, WebGL2 otherwise.

use runtime::render::{GpuContext, GpuError};
use web_sys::HtmlCanvasElement;

/// Which of the browser's APIs draws.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WebBackend {
    WebGpu,
    WebGl2,
}

impl WebBackend {
    pub fn name(self) -> &'static str {
        match self {
            WebBackend::WebGpu => "WebGPU",
            WebBackend::WebGl2 => "WebGL2",
        }
    }

    fn backends(self) -> wgpu::Backends {
        match self {
            WebBackend::WebGpu => wgpu::Backends::BROWSER_WEBGPU,
            WebBackend::WebGl2 => wgpu::Backends::GL,
        }
    }
}

/// The device, the canvas's surface configured for it, and the backend that drew.
pub struct CanvasGpu {
    pub gpu: GpuContext,
    pub surface: wgpu::Surface<'static>,
    pub config: wgpu::SurfaceConfiguration,
    pub backend: WebBackend,
}

/// Opens `canvas` with `wanted` (or WebGPU and then WebGL2 when `None`). Each failure is kept,
/// so that a browser with neither says why of both.
pub async fn open(
    canvas: &HtmlCanvasElement,
    wanted: Option<WebBackend>,
) -> Result<CanvasGpu, String> {
    let tries = match wanted {
        Some(b) => vec![b],
        None => vec![WebBackend::WebGpu, WebBackend::WebGl2],
    };
    let mut reasons = Vec::new();
    for backend in tries {
        match open_with(canvas, backend).await {
            Ok(opened) => return Ok(opened),
            // The native message's advice (install a driver) means nothing in a browser.
            Err(GpuError::NoAdapter { .. }) => {
                reasons.push(format!("{}: the browser offers no adapter", backend.name()))
            }
            Err(e) => reasons.push(format!("{}: {e}", backend.name())),
        }
    }
    Err(format!(
        "this browser cannot draw the scene ({})",
        reasons.join("; ")
    ))
}

async fn open_with(canvas: &HtmlCanvasElement, backend: WebBackend) -> Result<CanvasGpu, GpuError> {
    if backend == WebBackend::WebGpu && !has_webgpu() {
        return Err(GpuError::Surface("navigator.gpu is missing".into()));
    }
    let mut descriptor = wgpu::InstanceDescriptor::new_without_display_handle();
    descriptor.backends = backend.backends();
    let instance = wgpu::Instance::new(descriptor);
    let target = wgpu::SurfaceTarget::Canvas(canvas.clone());
    let (gpu, surface) =
        GpuContext::for_surface_of(instance, backend.backends(), backend.name(), target).await?;
    let capabilities = surface.get_capabilities(&gpu.adapter);
    let format = capabilities
        .formats
        .iter()
        .copied()
        .find(|f| !f.is_srgb())
        .or(capabilities.formats.first().copied())
        .ok_or_else(|| GpuError::Surface("the canvas offers no format".into()))?;
    let config = wgpu::SurfaceConfiguration {
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
        format,
        color_space: wgpu::SurfaceColorSpace::Auto,
        width: canvas.width().max(1),
        height: canvas.height().max(1),
        present_mode: wgpu::PresentMode::Fifo,
        desired_maximum_frame_latency: 2,
        alpha_mode: capabilities
            .alpha_modes
            .first()
            .copied()
            .unwrap_or(wgpu::CompositeAlphaMode::Auto),
        view_formats: vec![],
    };
    surface.configure(&gpu.device, &config);
    Ok(CanvasGpu {
        gpu,
        surface,
        config,
        backend,
    })
}

/// Whether the browser offers WebGPU at all (`navigator.gpu`); wgpu's own request would
/// otherwise fail with a less plain message.
fn has_webgpu() -> bool {
    web_sys::window()
        .map(|w| {
            let gpu = js_sys::Reflect::get(&w.navigator(), &"gpu".into());
            gpu.is_ok_and(|g| !g.is_undefined() && !g.is_null())
        })
        .unwrap_or(false)
}
