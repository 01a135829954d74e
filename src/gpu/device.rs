//! One headless wgpu device on whatever backend the machine has (Vulkan, Metal, DX12), and the
//! report of its adapter. Without an adapter — no GPU, no driver, or no Vulkan loader —
//! [`Gpu::new`] fails with one line saying so.

use anyhow::{anyhow, bail, Result};
use serde::{Deserialize, Serialize};

/// What the adapter is: the fields a figure needs to name the machine it was measured on.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Adapter {
    /// Adapter name, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)" or "NVIDIA H100 80GB HBM3".
    pub name: String,
    /// Driver name and version information.
    pub driver: String,
    /// Graphics API: "vulkan", "metal", "dx12", "gl".
    pub backend: String,
    /// wgpu's device type: "cpu", "integrated-gpu", "discrete-gpu", "virtual-gpu", "other".
    pub device_type: String,
    /// True for a software rasterizer (lavapipe, WARP, SwiftShader): its timings are CPU
    /// timings and are never mixed with hardware figures.
    pub software: bool,
}

impl Adapter {
    fn of(info: &wgpu::AdapterInfo) -> Adapter {
        let device_type = match info.device_type {
            wgpu::DeviceType::Cpu => "cpu",
            wgpu::DeviceType::IntegratedGpu => "integrated-gpu",
            wgpu::DeviceType::DiscreteGpu => "discrete-gpu",
            wgpu::DeviceType::VirtualGpu => "virtual-gpu",
            wgpu::DeviceType::Other => "other",
        };
        let backend = match info.backend {
            wgpu::Backend::Vulkan => "vulkan",
            wgpu::Backend::Metal => "metal",
            wgpu::Backend::Dx12 => "dx12",
            wgpu::Backend::Gl => "gl",
            wgpu::Backend::BrowserWebGpu => "webgpu",
            _ => "other",
        };
        Adapter {
            name: info.name.clone(),
            driver: format!("{} {}", info.driver, info.driver_info)
                .trim()
                .to_string(),
            backend: backend.into(),
            device_type: device_type.into(),
            software: info.device_type == wgpu::DeviceType::Cpu,
        }
    }

    /// "llvmpipe (LLVM 15.0.6, 256 bits), vulkan, software".
    pub fn label(&self) -> String {
        format!(
            "{}, {}, {}",
            self.name,
            self.backend,
            if self.software {
                "software"
            } else {
                "hardware"
            }
        )
    }

    /// A file-name stem for the adapter's artefacts: lower-case letters, digits and '-'.
    pub fn file_stem(&self) -> String {
        let mut s = String::new();
        for c in self.name.chars() {
            if c.is_ascii_alphanumeric() {
                s.push(c.to_ascii_lowercase());
            } else if !s.ends_with('-') {
                s.push('-');
            }
        }
        let s = s.trim_matches('-');
        let s = if s.is_empty() { "adapter" } else { s };
        s.chars().take(60).collect()
    }
}

/// A device and its queue, with the features the shadow-map pipeline uses.
pub struct Gpu {
    /// The wgpu device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// What the adapter is.
    pub adapter: Adapter,
    /// Timestamp queries inside passes are available (per-pass times in `gpu bench`).
    pub timestamps: bool,
    /// Nanoseconds per timestamp tick.
    pub timestamp_period: f64,
}

/// The features the pipeline needs: 16-bit UNORM textures, rendered to with the adapter's own
/// format capabilities (WebGPU's core list has no renderable RGBA16Unorm).
const REQUIRED: wgpu::Features = wgpu::Features::TEXTURE_FORMAT_16BIT_NORM
    .union(wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES);

impl Gpu {
    /// The first adapter wgpu finds (a hardware one before a software one), or one line naming
    /// why there is none. `MOMENTLAB_GPU_ADAPTER` picks an adapter whose name contains it;
    /// `MOMENTLAB_GPU_ADAPTER=none` asks for none (the GPU step of `reproduce` is then skipped
    /// on any machine, and wgpu is not touched).
    pub fn new() -> Result<Gpu> {
        let want = std::env::var("MOMENTLAB_GPU_ADAPTER").ok();
        if want.as_deref() == Some("none") {
            bail!("no GPU adapter: MOMENTLAB_GPU_ADAPTER=none asks for none");
        }
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
        desc.backends = wgpu::Backends::PRIMARY;
        let instance = wgpu::Instance::new(desc);
        let mut adapters = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::PRIMARY));
        if adapters.is_empty() {
            bail!(
                "no GPU adapter: wgpu found no Vulkan, Metal or DX12 device (on Linux without a \
                 GPU, `apt-get install mesa-vulkan-drivers libvulkan1` gives lavapipe)"
            );
        }
        // hardware first, then software; stable otherwise
        adapters.sort_by_key(|a| a.get_info().device_type == wgpu::DeviceType::Cpu);
        let names: Vec<String> = adapters.iter().map(|a| a.get_info().name).collect();
        let adapter = match &want {
            Some(w) => adapters
                .into_iter()
                .find(|a| a.get_info().name.contains(w.as_str()))
                .ok_or_else(|| {
                    anyhow!(
                        "MOMENTLAB_GPU_ADAPTER='{w}' matches none of the adapters: {}",
                        names.join("; ")
                    )
                })?,
            None => adapters.into_iter().next().expect("non-empty"),
        };
        let info = adapter.get_info();
        let features = adapter.features();
        let renderable = adapter
            .get_texture_format_features(wgpu::TextureFormat::Rgba16Unorm)
            .allowed_usages
            .contains(wgpu::TextureUsages::RENDER_ATTACHMENT);
        if !features.contains(REQUIRED) || !renderable {
            bail!(
                "GPU adapter '{}' cannot render to 16-bit UNORM textures (RGBA16Unorm)",
                info.name
            );
        }
        let ts = wgpu::Features::TIMESTAMP_QUERY;
        let timestamps = features.contains(ts);
        let required_features = REQUIRED
            | if timestamps {
                ts
            } else {
                wgpu::Features::empty()
            };
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("momentlab"),
            required_features,
            required_limits: adapter.limits(),
            ..Default::default()
        }))
        .map_err(|e| anyhow!("GPU adapter '{}': no device: {e}", info.name))?;
        let timestamp_period = queue.get_timestamp_period() as f64;
        // errors outside a scope (there should be none: every call is scoped) are printed, not
        // turned into a panic inside wgpu
        device.on_uncaptured_error(std::sync::Arc::new(|e: wgpu::Error| {
            eprintln!(
                "momentlab: uncaptured GPU error: {}",
                one_line(&e.to_string())
            );
        }));
        Ok(Gpu {
            device,
            queue,
            adapter: Adapter::of(&info),
            timestamps,
            timestamp_period,
        })
    }

    /// Wait until the queue has finished everything submitted.
    pub fn wait(&self) -> Result<()> {
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map(|_| ())
            .map_err(|e| anyhow!("GPU '{}': {e}", self.adapter.name))
    }

    /// Run `f` with the device's validation and out-of-memory errors captured: an error
    /// becomes one line naming `what`, never a panic.
    pub fn scoped<T>(&self, what: &str, f: impl FnOnce() -> T) -> Result<T> {
        let oom = self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let val = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let out = f();
        let v = pollster::block_on(val.pop());
        let o = pollster::block_on(oom.pop());
        match v.or(o) {
            Some(e) => bail!(
                "GPU '{}', {what}: {}",
                self.adapter.name,
                one_line(&e.to_string())
            ),
            None => Ok(out),
        }
    }

    /// A shader module from WGSL text; a validation error becomes one line naming `label`.
    pub fn module(&self, label: &str, wgsl: &str) -> Result<wgpu::ShaderModule> {
        // naga's own diagnostics first: they name the line
        naga_check(wgsl).map_err(|e| anyhow!("shader '{label}': {e}"))?;
        self.scoped(&format!("shader '{label}'"), || {
            self.device
                .create_shader_module(wgpu::ShaderModuleDescriptor {
                    label: Some(label),
                    source: wgpu::ShaderSource::Wgsl(wgsl.into()),
                })
        })
    }
}

/// A multi-line error report on one line.
fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// Parse and validate WGSL with naga (wgpu's translator); the first error as one line.
pub fn naga_check(wgsl: &str) -> Result<()> {
    let module = wgpu::naga::front::wgsl::parse_str(wgsl)
        .map_err(|e| anyhow!("{}", e.emit_to_string(wgsl).lines().next().unwrap_or("")))?;
    let mut v = wgpu::naga::valid::Validator::new(
        wgpu::naga::valid::ValidationFlags::all(),
        wgpu::naga::valid::Capabilities::all(),
    );
    v.validate(&module)
        .map_err(|e| anyhow!("{}", e.emit_to_string(wgsl).trim().replace('\n', " ")))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn file_stems_are_plain() {
        let a = Adapter {
            name: "llvmpipe (LLVM 15.0.6, 256 bits)".into(),
            driver: String::new(),
            backend: "vulkan".into(),
            device_type: "cpu".into(),
            software: true,
        };
        assert_eq!(a.file_stem(), "llvmpipe-llvm-15-0-6-256-bits");
        assert_eq!(
            a.label(),
            "llvmpipe (LLVM 15.0.6, 256 bits), vulkan, software"
        );
    }

    #[test]
    fn naga_names_the_error() {
        assert!(naga_check("fn f() -> f32 { return 1.0; }").is_ok());
        let e = naga_check("fn f() -> f32 { return x; }")
            .unwrap_err()
            .to_string();
        assert!(e.contains('x') && !e.contains('\n'), "{e}");
    }
}
