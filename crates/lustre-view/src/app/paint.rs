//! Painting a window frame: egui's textures updated and its shapes drawn into the surface and,
//! for a screenshot, into a texture that is read back from the GPU as RGBA8.

use super::window::Gfx;
use lustre_gpu::record_texture_readback;
use std::sync::mpsc::channel;

/// Draws egui into the surface (and, for a screenshot, into a texture read back as RGBA8).
/// `Ok(None)`: the surface was not ready (timeout, occluded, outdated: reconfigured).
#[allow(clippy::type_complexity)]
pub(super) fn paint(
    g: &mut Gfx,
    jobs: &[egui::ClippedPrimitive],
    mut delta: egui::TexturesDelta,
    ppp: f32,
    capture: bool,
) -> Result<Option<(u32, u32, Vec<u8>)>, String> {
    // Textures are updated whether or not the surface draws this time; freed after painting.
    for (id, ds) in delta.set.drain() {
        for d in &ds {
            g.renderer.update_texture(&g.device, &g.queue, id, d);
        }
    }
    let free: Vec<egui::TextureId> = delta.free.drain().collect();
    let r = paint_surface(g, jobs, ppp, capture);
    for id in &free {
        g.renderer.free_texture(id);
    }
    r
}

/// [`paint`] once the textures are up to date.
fn paint_surface(
    g: &mut Gfx,
    jobs: &[egui::ClippedPrimitive],
    ppp: f32,
    capture: bool,
) -> Result<Option<(u32, u32, Vec<u8>)>, String> {
    let size = g.window.inner_size();
    if size.width == 0 || size.height == 0 {
        return Ok(None);
    }
    if (size.width, size.height) != (g.config.width, g.config.height) {
        g.config.width = size.width;
        g.config.height = size.height;
        g.surface.configure(&g.device, &g.config);
    }
    let frame = match g.surface.get_current_texture() {
        wgpu::CurrentSurfaceTexture::Success(t) | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
        wgpu::CurrentSurfaceTexture::Timeout | wgpu::CurrentSurfaceTexture::Occluded => {
            return Ok(None)
        }
        wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
            g.surface.configure(&g.device, &g.config);
            return Ok(None);
        }
        wgpu::CurrentSurfaceTexture::Validation => {
            return Err("the window's surface failed validation".into())
        }
    };
    let screen = egui_wgpu::ScreenDescriptor {
        size_in_pixels: [g.config.width, g.config.height],
        pixels_per_point: ppp,
    };
    let mut enc = g
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("egui"),
        });
    let extra = g
        .renderer
        .update_buffers(&g.device, &g.queue, &mut enc, jobs, &screen);
    let view = frame
        .texture
        .create_view(&wgpu::TextureViewDescriptor::default());
    let target = capture.then(|| {
        g.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("screenshot"),
            size: wgpu::Extent3d {
                width: g.config.width,
                height: g.config.height,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: g.config.format,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        })
    });
    let target_view = target
        .as_ref()
        .map(|t| t.create_view(&wgpu::TextureViewDescriptor::default()));
    for v in std::iter::once(&view).chain(target_view.as_ref()) {
        let pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("egui"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: v,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        let mut pass = pass.forget_lifetime();
        g.renderer.render(&mut pass, jobs, &screen);
    }
    let (w, h) = (g.config.width, g.config.height);
    let readback = target
        .as_ref()
        .map(|t| record_texture_readback(&g.device, &mut enc, t, (w, h), 4, "screenshot readback"));
    g.queue
        .submit(extra.into_iter().chain(std::iter::once(enc.finish())));
    g.queue.present(frame);
    let Some((buffer, padded)) = readback else {
        return Ok(Some((0, 0, vec![])));
    };
    let bgra = matches!(
        g.config.format,
        wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb
    );
    let rgba = read_back(g, &buffer, (w, h), padded, bgra)?;
    Ok(Some((w, h, rgba)))
}

/// Waits for the GPU and maps `buffer`, the screenshot's `w`×`h` pixels in rows of `padded`
/// bytes, as RGBA8 ([`opaque_rgba`]).
fn read_back(
    g: &Gfx,
    buffer: &wgpu::Buffer,
    (w, h): (u32, u32),
    padded: u32,
    bgra: bool,
) -> Result<Vec<u8>, String> {
    let slice = buffer.slice(..);
    let (tx, rx) = channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    g.device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| format!("waiting for the screenshot: {e}"))?;
    rx.recv()
        .map_err(|e| e.to_string())?
        .map_err(|e| format!("mapping the screenshot: {e}"))?;
    let data = slice.get_mapped_range().map_err(|e| e.to_string())?;
    Ok(opaque_rgba(&data, (w, h), padded, bgra))
}

/// `w`×`h` pixels of 4 bytes (BGRA when `bgra`, else RGBA) in rows of `padded` bytes (the
/// copy's row alignment), as tightly packed RGBA8 with an opaque alpha.
fn opaque_rgba(data: &[u8], (w, h): (u32, u32), padded: u32, bgra: bool) -> Vec<u8> {
    let row = 4 * w;
    let mut rgba = Vec::with_capacity((row * h) as usize);
    for y in 0..h as usize {
        let line = &data[y * padded as usize..y * padded as usize + row as usize];
        for px in line.chunks_exact(4) {
            if bgra {
                rgba.extend_from_slice(&[px[2], px[1], px[0], 255]);
            } else {
                rgba.extend_from_slice(&[px[0], px[1], px[2], 255]);
            }
        }
    }
    rgba
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn read_back_rows_lose_their_padding_and_come_out_rgba_and_opaque() {
        // 2×2 pixels in rows of 12 bytes: 8 of pixels, 4 of padding (0xEE).
        let mut data = vec![];
        for y in 0..2u8 {
            for x in 0..2u8 {
                data.extend_from_slice(&[10 * y + x, 100, 200, 7]);
            }
            data.extend_from_slice(&[0xEE; 4]);
        }
        let rgba = opaque_rgba(&data, (2, 2), 12, false);
        assert_eq!(
            rgba,
            [0, 100, 200, 255, 1, 100, 200, 255, 10, 100, 200, 255, 11, 100, 200, 255]
        );
        let bgra = opaque_rgba(&data, (2, 2), 12, true);
        assert_eq!(
            bgra,
            [200, 100, 0, 255, 200, 100, 1, 255, 200, 100, 10, 255, 200, 100, 11, 255]
        );
    }
}
