//! The shadow-map pipeline on the GPU, for one setting's shader module and one depth map:
//! encode (render), filter along x and along y (render, each output stored in the storage
//! format), lookup of every fragment (compute). The passes are described by data
//! ([`super::passes`]); this file creates the resources, records the passes with a timestamp
//! pair each where the adapter has timestamp queries, and reads the results back.

use super::device::Gpu;
use super::passes;
use super::readback;
use crate::quantize::study::Storage;
use crate::shader::Module;
use anyhow::{bail, Result};
use wgpu::util::DeviceExt;

/// The texture format a storage format is rendered into (RGBA; m channels over ⌈m/4⌉ of them).
pub fn texture_format(storage: Storage) -> Result<wgpu::TextureFormat> {
    Ok(match storage {
        Storage::Float32 => wgpu::TextureFormat::Rgba32Float,
        Storage::Unorm(16) => wgpu::TextureFormat::Rgba16Unorm,
        Storage::Half => wgpu::TextureFormat::Rgba16Float,
        other => bail!("no GPU texture format for storage {other:?}"),
    })
}

/// What the pipeline runs: the module (with `tunedEncode` and `tunedShadow`), its storage and
/// the 1-D filter weights. `wgsl`, when given, is the shader text run instead of the module's
/// own printing (an export file as shipped); the module then only gives the channel count.
pub struct Program<'a> {
    /// The shader module with `tunedEncode` and `tunedShadow`.
    pub module: &'a Module,
    /// WGSL text run instead of the module's own printing.
    pub wgsl: Option<&'a str>,
    /// Storage format of the moment maps.
    pub storage: Storage,
    /// 1-D filter weights (the separable kernel).
    pub weights: &'a [f32],
}

/// The receivers to look up: texel index and z_f (already biased) per fragment.
#[derive(Clone, Debug, Default)]
pub struct Receivers {
    /// Texel index y·width + x of each receiver.
    pub texel: Vec<u32>,
    /// Biased fragment depth z_f of each receiver.
    pub zf: Vec<f32>,
}

/// Seconds per pass from timestamp queries (None where the adapter has none).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PassTimes {
    /// Encode pass, seconds.
    pub encode: f64,
    /// Filter passes, seconds.
    pub filter: f64,
    /// Lookup pass, seconds.
    pub lookup: f64,
}

/// What one run gives: the filtered, stored map (m values per texel, texel-major), G per
/// receiver, and the pass times.
pub struct Output {
    /// The encoded, stored map before filtering: m values per texel, texel-major.
    pub encoded: Vec<f32>,
    /// The filtered, stored map: m values per texel, texel-major.
    pub filtered: Vec<f32>,
    /// G per receiver.
    pub shadow: Vec<f32>,
    /// Pass times (None without timestamp queries).
    pub times: Option<PassTimes>,
}

/// The program's functions as WGSL, and its channel count m.
fn functions(p: &Program) -> Result<(String, usize)> {
    let Some(enc) = p.module.func("tunedEncode") else {
        bail!("shader module has no tunedEncode");
    };
    if p.module.func("tunedShadow").is_none() {
        bail!("shader module has no tunedShadow");
    }
    let text = match p.wgsl {
        Some(t) => t.to_string(),
        None => crate::shader::wgsl(p.module)?,
    };
    Ok((text, enc.n_outputs()))
}

fn target(gpu: &Gpu, (w, h): (u32, u32), format: wgpu::TextureFormat) -> wgpu::Texture {
    gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("moments"),
        size: wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    })
}

fn bind(
    gpu: &Gpu,
    layout: &wgpu::BindGroupLayout,
    res: &[wgpu::BindingResource],
) -> wgpu::BindGroup {
    let entries: Vec<wgpu::BindGroupEntry> = res
        .iter()
        .enumerate()
        .map(|(i, r)| wgpu::BindGroupEntry {
            binding: i as u32,
            resource: r.clone(),
        })
        .collect();
    gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout,
        entries: &entries,
    })
}

/// A render pipeline drawing the full-screen triangle of `wgsl` into `k` targets of `format`.
fn render_pipeline(
    gpu: &Gpu,
    label: &str,
    wgsl: &str,
    k: usize,
    format: wgpu::TextureFormat,
) -> Result<wgpu::RenderPipeline> {
    let module = gpu.module(label, wgsl)?;
    let targets: Vec<Option<wgpu::ColorTargetState>> =
        (0..k).map(|_| Some(format.into())).collect();
    gpu.scoped(&format!("{label} pipeline"), || {
        gpu.device
            .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: None,
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("vs"),
                    compilation_options: Default::default(),
                    buffers: &[],
                },
                primitive: Default::default(),
                depth_stencil: None,
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some("fs"),
                    compilation_options: Default::default(),
                    targets: &targets,
                }),
                multiview_mask: None,
                cache: None,
            })
    })
}

/// Record one full-screen draw into `targets`, with a timestamp pair `2q, 2q + 1`.
fn draw(
    enc: &mut wgpu::CommandEncoder,
    pipeline: &wgpu::RenderPipeline,
    group: &wgpu::BindGroup,
    targets: &[wgpu::TextureView],
    ts: Option<(&wgpu::QuerySet, u32)>,
) {
    let attachments: Vec<Option<wgpu::RenderPassColorAttachment>> = targets
        .iter()
        .map(|view| {
            Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                    store: wgpu::StoreOp::Store,
                },
            })
        })
        .collect();
    let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: None,
        color_attachments: &attachments,
        depth_stencil_attachment: None,
        timestamp_writes: ts.map(|(set, q)| wgpu::RenderPassTimestampWrites {
            query_set: set,
            beginning_of_pass_write_index: Some(2 * q),
            end_of_pass_write_index: Some(2 * q + 1),
        }),
        occlusion_query_set: None,
        multiview_mask: None,
    });
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, group, &[]);
    pass.draw(0..3, 0..1);
}

/// The compiled passes of one program, reusable over runs (the bench repeats them).
pub struct Compiled {
    m: usize,
    k: usize,
    format: wgpu::TextureFormat,
    encode: wgpu::RenderPipeline,
    filter_x: wgpu::RenderPipeline,
    filter_y: wgpu::RenderPipeline,
    lookup: wgpu::ComputePipeline,
}

impl Compiled {
    /// Validate (naga) and compile the four passes of `p`.
    pub fn new(gpu: &Gpu, p: &Program) -> Result<Compiled> {
        let (funcs, m) = functions(p)?;
        let k = passes::textures_for(m);
        let format = texture_format(p.storage)?;
        let encode = render_pipeline(gpu, "encode", &passes::encode(&funcs, m), k, format)?;
        let filter_x = render_pipeline(
            gpu,
            "filter x",
            &passes::filter(k, p.weights, false),
            k,
            format,
        )?;
        let filter_y = render_pipeline(
            gpu,
            "filter y",
            &passes::filter(k, p.weights, true),
            k,
            format,
        )?;
        let module = gpu.module("lookup", &passes::lookup(&funcs, m))?;
        let lookup = gpu.scoped("lookup pipeline", || {
            gpu.device
                .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                    label: Some("lookup"),
                    layout: None,
                    module: &module,
                    entry_point: Some("main"),
                    compilation_options: Default::default(),
                    cache: None,
                })
        })?;
        Ok(Compiled {
            m,
            k,
            format,
            encode,
            filter_x,
            filter_y,
            lookup,
        })
    }

    /// Channels per texel.
    pub fn channels(&self) -> usize {
        self.m
    }

    /// Run the pipeline on a `width × height` depth map (row-major, the front layer) and look
    /// up `receivers`; `read_map` also reads the encoded and the filtered maps back. A device error is one line.
    pub fn run(
        &self,
        gpu: &Gpu,
        depth: &[f32],
        size: (usize, usize),
        receivers: &Receivers,
        read_map: bool,
    ) -> Result<Output> {
        gpu.scoped("shadow-map pipeline", || {
            self.run_unscoped(gpu, depth, size, receivers, read_map)
        })?
    }

    fn run_unscoped(
        &self,
        gpu: &Gpu,
        depth: &[f32],
        (width, height): (usize, usize),
        receivers: &Receivers,
        read_map: bool,
    ) -> Result<Output> {
        check_inputs(gpu, depth, (width, height), receivers)?;
        let size = (width as u32, height as u32);
        let dev = &gpu.device;
        let depth_tex = depth_texture(gpu, depth, size);
        let maps: Vec<Vec<wgpu::Texture>> = (0..3)
            .map(|_| {
                (0..self.k)
                    .map(|_| target(gpu, size, self.format))
                    .collect()
            })
            .collect();
        let views: Vec<Vec<wgpu::TextureView>> = maps
            .iter()
            .map(|m| {
                m.iter()
                    .map(|t| t.create_view(&Default::default()))
                    .collect()
            })
            .collect();
        fn res(v: &[wgpu::TextureView]) -> Vec<wgpu::BindingResource<'_>> {
            v.iter().map(wgpu::BindingResource::TextureView).collect()
        }
        let dview = depth_tex.create_view(&Default::default());
        let g_enc = bind(
            gpu,
            &self.encode.get_bind_group_layout(0),
            &[wgpu::BindingResource::TextureView(&dview)],
        );
        let g_fx = bind(
            gpu,
            &self.filter_x.get_bind_group_layout(0),
            &res(&views[0]),
        );
        let g_fy = bind(
            gpu,
            &self.filter_y.get_bind_group_layout(0),
            &res(&views[1]),
        );
        let n = receivers.texel.len().max(1);
        let (frags, out) = fragment_buffers(gpu, receivers);
        let mut lr = res(&views[2]);
        lr.push(frags.as_entire_binding());
        lr.push(out.as_entire_binding());
        let g_look = bind(gpu, &self.lookup.get_bind_group_layout(0), &lr);
        let queries = gpu.timestamps.then(|| {
            dev.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("pass times"),
                ty: wgpu::QueryType::Timestamp,
                count: 8,
            })
        });
        let ts = |q: u32| queries.as_ref().map(|s| (s, q));
        let mut enc = dev.create_command_encoder(&Default::default());
        draw(&mut enc, &self.encode, &g_enc, &views[0], ts(0));
        draw(&mut enc, &self.filter_x, &g_fx, &views[1], ts(1));
        draw(&mut enc, &self.filter_y, &g_fy, &views[2], ts(2));
        self.lookup_pass(&mut enc, &g_look, queries.as_ref(), n);
        let shadow_rb = readback::staging(gpu, 4 * n as u64);
        enc.copy_buffer_to_buffer(&out, 0, &shadow_rb, 0, 4 * n as u64);
        let ts_rb = queries.as_ref().map(|set| {
            let resolve = dev.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamps"),
                size: 64,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            enc.resolve_query_set(set, 0..8, &resolve, 0);
            let rb = readback::staging(gpu, 64);
            enc.copy_buffer_to_buffer(&resolve, 0, &rb, 0, 64);
            rb
        });
        gpu.queue.submit([enc.finish()]);
        let bytes = readback::read_buffer(gpu, &shadow_rb)?;
        let mut shadow: Vec<f32> = bytemuck::pod_collect_to_vec(&bytes);
        shadow.truncate(receivers.texel.len());
        let times = match ts_rb {
            Some(rb) => Some(read_times(gpu, &rb)?),
            None => None,
        };
        let (encoded, filtered) = if read_map {
            (
                self.read_map(gpu, &maps[0], width * height)?,
                self.read_map(gpu, &maps[2], width * height)?,
            )
        } else {
            (Vec::new(), Vec::new())
        };
        Ok(Output {
            encoded,
            filtered,
            shadow,
            times,
        })
    }

    /// The lookup pass: one invocation per receiver, dispatched in rows of
    /// [`passes::LOOKUP_ROW`] groups, timed into queries 6 and 7 when `queries` is given.
    fn lookup_pass(
        &self,
        enc: &mut wgpu::CommandEncoder,
        g_look: &wgpu::BindGroup,
        queries: Option<&wgpu::QuerySet>,
        n: usize,
    ) {
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("lookup"),
            timestamp_writes: queries.map(|set| wgpu::ComputePassTimestampWrites {
                query_set: set,
                beginning_of_pass_write_index: Some(6),
                end_of_pass_write_index: Some(7),
            }),
        });
        pass.set_pipeline(&self.lookup);
        pass.set_bind_group(0, g_look, &[]);
        let groups = (n as u32).div_ceil(passes::LOOKUP_GROUP);
        let (x, y) = if groups <= passes::LOOKUP_ROW {
            (groups, 1)
        } else {
            (passes::LOOKUP_ROW, groups.div_ceil(passes::LOOKUP_ROW))
        };
        pass.dispatch_workgroups(x, y, 1);
    }

    /// A map read back: `texels` texels of [`Self::channels`] channels each, from the RGBA
    /// targets `maps`.
    fn read_map(&self, gpu: &Gpu, maps: &[wgpu::Texture], texels: usize) -> Result<Vec<f32>> {
        let per: Vec<Vec<f32>> = maps
            .iter()
            .map(|t| readback::read_texture(gpu, t))
            .collect::<Result<_>>()?;
        let mut f = Vec::with_capacity(texels * self.m);
        for t in 0..texels {
            for c in 0..self.m {
                f.push(per[c / 4][4 * t + c % 4]);
            }
        }
        Ok(f)
    }
}

/// One-line errors for inputs the pipeline cannot take: a depth map of the wrong length,
/// receivers outside it, a map larger than the adapter's textures.
fn check_inputs(
    gpu: &Gpu,
    depth: &[f32],
    (width, height): (usize, usize),
    receivers: &Receivers,
) -> Result<()> {
    if depth.len() != width * height || width == 0 || height == 0 {
        bail!(
            "GPU pipeline: {} depths for a {width}×{height} map",
            depth.len()
        );
    }
    if receivers.texel.len() != receivers.zf.len()
        || receivers.texel.iter().any(|&t| t as usize >= depth.len())
    {
        bail!("GPU pipeline: receivers do not fit the {width}×{height} map");
    }
    let max = gpu.device.limits().max_texture_dimension_2d as usize;
    if width > max || height > max {
        bail!("GPU pipeline: a {width}×{height} map exceeds the adapter's {max}² textures");
    }
    Ok(())
}

/// The front-layer depth map as an R32Float texture.
fn depth_texture(gpu: &Gpu, depth: &[f32], size: (u32, u32)) -> wgpu::Texture {
    gpu.device.create_texture_with_data(
        &gpu.queue,
        &wgpu::TextureDescriptor {
            label: Some("depth"),
            size: wgpu::Extent3d {
                width: size.0,
                height: size.1,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::R32Float,
            usage: wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        },
        wgpu::util::TextureDataOrder::LayerMajor,
        bytemuck::cast_slice(depth),
    )
}

/// The receivers as a storage buffer of (texel, z_f) pairs, and the shadow output buffer (one
/// f32 each; one dummy entry when there are none).
fn fragment_buffers(gpu: &Gpu, receivers: &Receivers) -> (wgpu::Buffer, wgpu::Buffer) {
    let n = receivers.texel.len().max(1);
    let mut frag_bytes = Vec::with_capacity(8 * n);
    for (t, z) in receivers.texel.iter().zip(&receivers.zf) {
        frag_bytes.extend_from_slice(&t.to_le_bytes());
        frag_bytes.extend_from_slice(&z.to_le_bytes());
    }
    if receivers.texel.is_empty() {
        frag_bytes.extend_from_slice(&[0u8; 8]);
    }
    let frags = gpu
        .device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("fragments"),
            contents: &frag_bytes,
            usage: wgpu::BufferUsages::STORAGE,
        });
    let out = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("shadow"),
        size: 4 * n as u64,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    (frags, out)
}

/// The pass times from the resolved timestamp queries (pairs 0–3: encode, filter x, filter y,
/// lookup), in seconds.
fn read_times(gpu: &Gpu, rb: &wgpu::Buffer) -> Result<PassTimes> {
    let t: Vec<u64> = bytemuck::pod_collect_to_vec(&readback::read_buffer(gpu, rb)?);
    let s = |q: usize| t[2 * q + 1].saturating_sub(t[2 * q]) as f64 * gpu.timestamp_period * 1e-9;
    Ok(PassTimes {
        encode: s(0),
        filter: s(1) + s(2),
        lookup: s(3),
    })
}
