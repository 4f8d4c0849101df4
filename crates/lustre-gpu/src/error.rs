//! Errors of the GPU renderer.

/// What can go wrong on the GPU side.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// No adapter at all: no GPU and no software rasterizer (install lavapipe:
    /// `apt-get install mesa-vulkan-drivers libvulkan1`).
    #[error(
        "no GPU adapter found ({0}); install a Vulkan driver, e.g. lavapipe: \
         apt-get install mesa-vulkan-drivers libvulkan1"
    )]
    NoAdapter(String),
    /// The adapter refused to create a device.
    #[error("the adapter {adapter} could not create a device: {message}")]
    Device {
        /// Adapter name.
        adapter: String,
        /// wgpu's message.
        message: String,
    },
    /// A parameter outside what the renderer accepts (names the parameter).
    #[error("invalid {parameter}: {message}")]
    Invalid {
        /// Which input.
        parameter: String,
        /// What is wrong with it.
        message: String,
    },
    /// A validation or out-of-memory error reported by wgpu while rendering.
    #[error("wgpu reported an error during {stage}: {message}")]
    Wgpu {
        /// What was being done.
        stage: &'static str,
        /// wgpu's message.
        message: String,
    },
}

/// Result with [`GpuError`].
pub type Result<T> = std::result::Result<T, GpuError>;

/// Shorthand for an [`GpuError::Invalid`].
pub(crate) fn invalid(parameter: impl Into<String>, message: impl Into<String>) -> GpuError {
    GpuError::Invalid {
        parameter: parameter.into(),
        message: message.into(),
    }
}

/// A [`GpuError::Wgpu`] for `stage`.
pub(crate) fn wgpu_error(stage: &'static str, e: impl std::fmt::Display) -> GpuError {
    GpuError::Wgpu {
        stage,
        message: e.to_string(),
    }
}

/// A validation scope around some GPU work ([`push_scope`], closed by [`scope_result`]).
///
/// Natively the scope is popped and its answer awaited, so the work's first validation error
/// comes back as a [`GpuError::Wgpu`] naming the stage. In a browser (wasm32) WebGPU answers a
/// pop only after control returns to the page's event loop, which a frame cannot wait for:
/// there no scope is pushed, and an error reaches the device's uncaptured-error handler (the
/// page reports it on its console and on screen).
#[derive(Debug)]
pub(crate) struct Scope(#[cfg(not(target_arch = "wasm32"))] wgpu::ErrorScopeGuard);

/// Opens a validation scope on `ctx`'s device.
pub(crate) fn push_scope(ctx: &crate::context::GpuContext) -> Scope {
    #[cfg(not(target_arch = "wasm32"))]
    {
        Scope(ctx.device.push_error_scope(wgpu::ErrorFilter::Validation))
    }
    #[cfg(target_arch = "wasm32")]
    {
        let _ = ctx;
        Scope()
    }
}

/// Closes a validation scope: the first error wgpu reported in it, as a [`GpuError::Wgpu`]
/// (always `Ok` in a browser: see [`Scope`]).
pub(crate) fn scope_result(scope: Scope, stage: &'static str) -> Result<()> {
    #[cfg(not(target_arch = "wasm32"))]
    {
        match pollster::block_on(scope.0.pop()) {
            Some(e) => Err(wgpu_error(stage, e)),
            None => Ok(()),
        }
    }
    #[cfg(target_arch = "wasm32")]
    {
        let _ = (scope, stage);
        Ok(())
    }
}
