//! The window: its GPU objects (surface, device, egui's renderer), the winit events (resume,
//! resize, close, redraw) and one window frame (replies taken, the panels laid out and painted,
//! the next frame requested, the script stepped); the surface's life (resized, outdated or
//! lost surfaces reconfigured, a lost device ends the run cleanly).

use super::paint::paint;
use super::{App, HISTORY};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, ControlFlow};
use winit::window::{Window, WindowId};

/// The window's GPU objects.
pub(super) struct Gfx {
    pub(super) window: Arc<Window>,
    pub(super) surface: wgpu::Surface<'static>,
    pub(super) device: wgpu::Device,
    pub(super) queue: wgpu::Queue,
    pub(super) config: wgpu::SurfaceConfiguration,
    pub(super) renderer: egui_wgpu::Renderer,
    pub(super) state: egui_winit::State,
    pub(super) lost: Arc<AtomicBool>,
    pub(super) present_modes: Vec<wgpu::PresentMode>,
}

impl App {
    /// Creates the window, its surface and egui's renderer.
    fn create_gfx(&mut self, event_loop: &ActiveEventLoop) -> Result<Gfx, String> {
        let attrs = Window::default_attributes()
            .with_title("lustre view")
            .with_inner_size(PhysicalSize::new(self.size.0, self.size.1));
        let window = Arc::new(
            event_loop
                .create_window(attrs)
                .map_err(|e| format!("no window: {e}"))?,
        );
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_with_display_handle_from_env(
                Box::new(event_loop.owned_display_handle()),
            ));
        let surface = instance.create_surface(window.clone()).map_err(|e| {
            format!(
                "no GPU adapter can draw to this window (no surface: {e}); install a Vulkan \
                     driver (mesa-vulkan-drivers gives lavapipe)"
            )
        })?;
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            force_fallback_adapter: false,
            compatible_surface: Some(&surface),
            apply_limit_buckets: false,
        }))
        .map_err(|e| format!("no GPU adapter can draw to this window ({e}); install a Vulkan driver (mesa-vulkan-drivers gives lavapipe)"))?;
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("lustre-view window"),
            required_features: wgpu::Features::empty(),
            required_limits: wgpu::Limits::downlevel_defaults().using_resolution(adapter.limits()),
            experimental_features: wgpu::ExperimentalFeatures::disabled(),
            memory_hints: wgpu::MemoryHints::Performance,
            trace: wgpu::Trace::Off,
        }))
        .map_err(|e| format!("the window's GPU device ({}): {e}", adapter.get_info().name))?;
        let caps = surface.get_capabilities(&adapter);
        let format = caps
            .formats
            .iter()
            .copied()
            .find(|f| !f.is_srgb())
            .or_else(|| caps.formats.first().copied())
            .ok_or_else(|| "the window's surface offers no format".to_string())?;
        let inner = window.inner_size();
        let config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            format,
            color_space: wgpu::SurfaceColorSpace::Auto,
            width: inner.width.max(1),
            height: inner.height.max(1),
            present_mode: wgpu::PresentMode::Fifo,
            desired_maximum_frame_latency: 2,
            alpha_mode: caps
                .alpha_modes
                .first()
                .copied()
                .unwrap_or(wgpu::CompositeAlphaMode::Auto),
            view_formats: vec![],
        };
        let lost = Arc::new(AtomicBool::new(false));
        let flag = lost.clone();
        device.set_device_lost_callback(move |_, _| flag.store(true, Ordering::SeqCst));
        let renderer = egui_wgpu::Renderer::new(
            &device,
            format,
            egui_wgpu::RendererOptions {
                // The 3D view's pixels are shown as they are (no dither noise).
                dithering: false,
                ..Default::default()
            },
        );
        let state = egui_winit::State::new(
            self.ctx.clone(),
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            Some(device.limits().max_texture_dimension_2d as usize),
        );
        let mut gfx = Gfx {
            window,
            surface,
            device,
            queue,
            config,
            renderer,
            state,
            lost,
            present_modes: caps.present_modes.clone(),
        };
        configure(&mut gfx, self.vsync);
        Ok(gfx)
    }

    /// Draws one window frame; `false` when the run must end.
    fn redraw(&mut self, event_loop: &ActiveEventLoop) {
        self.poll_replies();
        self.poll_fit();
        let now = Instant::now();
        let dt = (now - self.last_tick).as_secs_f64();
        self.last_tick = now;
        self.ui_times.push_back(dt * 1e3);
        if self.ui_times.len() > HISTORY {
            self.ui_times.pop_front();
        }
        let Some(mut gfx) = self.gfx.take() else {
            return;
        };
        if gfx.lost.load(Ordering::SeqCst) {
            self.finish(event_loop, Err("the window's GPU device was lost".into()));
            return;
        }
        let raw = gfx.state.take_egui_input(&gfx.window);
        let ctx = self.ctx.clone();
        let out = ctx.run_ui(raw, |ui| self.ui(ui, dt));
        gfx.state
            .handle_platform_output(&gfx.window, out.platform_output);
        let jobs = ctx.tessellate(out.shapes, out.pixels_per_point);
        let shot = if self.settled() || !self.unattended {
            self.screenshot.take()
        } else {
            None
        };
        let r = paint(
            &mut gfx,
            &jobs,
            out.textures_delta,
            out.pixels_per_point,
            shot.is_some(),
        );
        self.gfx = Some(gfx);
        match r {
            Ok(Some(pixels)) => {
                if let Some(path) = shot {
                    self.write_screenshot(&path, pixels);
                }
            }
            Ok(None) => {
                if let Some(path) = shot {
                    // Not drawn this time (surface outdated): try again next frame.
                    self.screenshot = Some(path);
                }
            }
            Err(e) => {
                self.finish(event_loop, Err(e));
                return;
            }
        }
        if self.frame.is_some() {
            self.frames_shown += 1;
        }
        self.request_frame();
        self.step_script();
        self.check_end(event_loop);
    }
}

/// Sets the present mode (vsync: FIFO; otherwise immediate or mailbox where offered) and
/// configures the surface.
pub(super) fn configure(g: &mut Gfx, vsync: bool) {
    g.config.present_mode = if vsync {
        wgpu::PresentMode::Fifo
    } else {
        [wgpu::PresentMode::Immediate, wgpu::PresentMode::Mailbox]
            .into_iter()
            .find(|m| g.present_modes.contains(m))
            .unwrap_or(wgpu::PresentMode::Fifo)
    };
    g.surface.configure(&g.device, &g.config);
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.gfx.is_some() {
            return;
        }
        match self.create_gfx(event_loop) {
            Ok(g) => {
                g.window.request_redraw();
                self.gfx = Some(g);
            }
            Err(e) => self.finish(event_loop, Err(e)),
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        if let Some(g) = &mut self.gfx {
            let _ = g.state.on_window_event(&g.window, &event);
        }
        match event {
            WindowEvent::CloseRequested => self.finish(event_loop, Ok(())),
            WindowEvent::Resized(s) => {
                if let Some(g) = &mut self.gfx {
                    if s.width > 0 && s.height > 0 {
                        g.config.width = s.width;
                        g.config.height = s.height;
                        g.surface.configure(&g.device, &g.config);
                    }
                }
            }
            WindowEvent::RedrawRequested => self.redraw(event_loop),
            _ => {}
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        if let Some(g) = &self.gfx {
            g.window.request_redraw();
        }
        // At most ~60 window frames a second: the render thread shares the CPU (lavapipe).
        event_loop.set_control_flow(ControlFlow::WaitUntil(
            Instant::now() + Duration::from_millis(16),
        ));
    }
}
