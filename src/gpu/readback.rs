//! Reading results back from the GPU, in one place: buffers and RGBA textures of the three
//! storage formats, as f32 values.

use super::device::Gpu;
use anyhow::{anyhow, Result};

/// Bytes of one RGBA texel of `format`.
pub fn texel_bytes(format: wgpu::TextureFormat) -> u32 {
    match format {
        wgpu::TextureFormat::Rgba32Float => 16,
        _ => 8,
    }
}

/// Map a MAP_READ buffer, copy its bytes out and unmap it.
pub fn read_buffer(gpu: &Gpu, buffer: &wgpu::Buffer) -> Result<Vec<u8>> {
    let slice = buffer.slice(..);
    let (tx, rx) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    gpu.wait()?;
    rx.recv()
        .map_err(|e| anyhow!("GPU readback: {e}"))?
        .map_err(|e| anyhow!("GPU readback: {e}"))?;
    let bytes = slice
        .get_mapped_range()
        .map_err(|e| anyhow!("GPU readback: {e}"))?
        .to_vec();
    buffer.unmap();
    Ok(bytes)
}

/// A buffer the size of `size` bytes that copies land in and the CPU maps.
pub fn staging(gpu: &Gpu, size: u64) -> wgpu::Buffer {
    gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// The RGBA texels of a `width × height` texture as f32, row-major, 4 values per texel
/// (UNORM k/65535 and binary16 converted exactly).
pub fn read_texture(gpu: &Gpu, texture: &wgpu::Texture) -> Result<Vec<f32>> {
    let (w, h) = (texture.width(), texture.height());
    let format = texture.format();
    let tb = texel_bytes(format);
    let row =
        (w * tb).div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let buffer = staging(gpu, row as u64 * h as u64);
    let mut enc = gpu.device.create_command_encoder(&Default::default());
    enc.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo {
            texture,
            mip_level: 0,
            origin: wgpu::Origin3d::ZERO,
            aspect: wgpu::TextureAspect::All,
        },
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(row),
                rows_per_image: Some(h),
            },
        },
        wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
    );
    gpu.queue.submit([enc.finish()]);
    let bytes = read_buffer(gpu, &buffer)?;
    let mut out = Vec::with_capacity((w * h * 4) as usize);
    for y in 0..h as usize {
        let r = &bytes[y * row as usize..][..(w * tb) as usize];
        match format {
            wgpu::TextureFormat::Rgba32Float => out.extend(
                r.chunks_exact(4)
                    .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])),
            ),
            wgpu::TextureFormat::Rgba16Unorm => out.extend(
                r.chunks_exact(2)
                    .map(|c| (u16::from_le_bytes([c[0], c[1]]) as f64 / 65535.0) as f32),
            ),
            _ => out.extend(
                r.chunks_exact(2)
                    .map(|c| half::f16::from_bits(u16::from_le_bytes([c[0], c[1]])).to_f32()),
            ),
        }
    }
    Ok(out)
}
