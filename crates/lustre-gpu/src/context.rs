//! The headless wgpu device.

use crate::error::{GpuError, Result};

/// A headless wgpu device and queue on any adapter (a real GPU or lavapipe).
#[derive(Clone, Debug)]
pub struct GpuContext {
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// What the adapter says about itself (name, backend, device type).
    pub info: wgpu::AdapterInfo,
    /// Whether Rgba32Float textures can be filtered (`FLOAT32_FILTERABLE`); without it the
    /// environment is uploaded as Rgba16Float.
    pub float32_filterable: bool,
    /// The instance and the adapter the device came from, kept while it lives: Chromium loses
    /// a device ("A valid external Instance reference no longer exists") once they are
    /// collected.
    origin: Option<(wgpu::Instance, wgpu::Adapter)>,
}

impl GpuContext {
    /// Opens the first adapter wgpu offers (backends from `WGPU_BACKEND`, default all), without a
    /// window. Fails with [`GpuError::NoAdapter`] when there is none.
    pub fn new() -> Result<Self> {
        pollster::block_on(Self::new_async())
    }

    /// [`GpuContext::new`] without blocking: what a browser (wasm32, WebGPU) calls, where
    /// nothing may block the page.
    pub async fn new_async() -> Result<Self> {
        #[allow(unused_mut)]
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
        // In a browser, WebGPU only: the passes are compute shaders, which WebGL lacks.
        #[cfg(target_arch = "wasm32")]
        {
            desc.backends = wgpu::Backends::BROWSER_WEBGPU;
        }
        let instance = wgpu::Instance::new(desc);
        let adapter = instance
            .request_adapter(&wgpu::RequestAdapterOptions {
                power_preference: wgpu::PowerPreference::HighPerformance,
                force_fallback_adapter: false,
                compatible_surface: None,
                apply_limit_buckets: false,
            })
            .await
            .map_err(|e| GpuError::NoAdapter(e.to_string()))?;
        let mut ctx = Self::from_adapter(&adapter).await?;
        ctx.origin = Some((instance, adapter));
        Ok(ctx)
    }

    /// A device on `adapter` (one that must also draw to a window or a canvas is asked for with
    /// its surface; keep its instance alive as long as the device), with the adapter's own limits, `FLOAT32_FILTERABLE` and `TIMESTAMP_QUERY`
    /// where it has them.
    pub async fn from_adapter(adapter: &wgpu::Adapter) -> Result<Self> {
        let info = adapter.get_info();
        let float32_filterable = adapter
            .features()
            .contains(wgpu::Features::FLOAT32_FILTERABLE);
        let mut required_features = if float32_filterable {
            wgpu::Features::FLOAT32_FILTERABLE
        } else {
            wgpu::Features::empty()
        };
        // GPU timestamps for `GpuTimer`, where the adapter has them.
        if adapter.features().contains(wgpu::Features::TIMESTAMP_QUERY) {
            required_features |= wgpu::Features::TIMESTAMP_QUERY;
        }
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("lustre-gpu"),
                required_features,
                required_limits: adapter.limits(),
                experimental_features: wgpu::ExperimentalFeatures::disabled(),
                memory_hints: wgpu::MemoryHints::Performance,
                trace: wgpu::Trace::Off,
            })
            .await
            .map_err(|e| GpuError::Device {
                adapter: info.name.clone(),
                message: e.to_string(),
            })?;
        Ok(GpuContext {
            device,
            queue,
            info,
            float32_filterable,
            origin: None,
        })
    }

    /// "name (backend, device type)", for logs and reports.
    pub fn describe(&self) -> String {
        format!(
            "{} ({:?}, {:?})",
            self.info.name, self.info.backend, self.info.device_type
        )
    }

    /// Whether the adapter is a software rasterizer on the CPU (lavapipe, llvmpipe, WARP).
    pub fn is_software(&self) -> bool {
        self.info.device_type == wgpu::DeviceType::Cpu
    }

    /// Waits until the GPU has finished everything submitted so far.
    pub fn wait(&self) -> Result<()> {
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map(|_| ())
            .map_err(|e| GpuError::Wgpu {
                stage: "waiting for the queue",
                message: e.to_string(),
            })
    }
}
