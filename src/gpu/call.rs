//! Any function of a shader [`Module`] run on the GPU, one invocation per input row: the
//! module's WGSL ([`crate::shader::wgsl`]) with a generated compute entry point [`MAIN`] that
//! reads the invocation's flattened f32 inputs, calls the function and writes its flattened
//! outputs — the layout of [`Func::eval`]: inputs are the parameters in order (an array or a
//! vector as its components), outputs are the return value first, then the `out` parameters
//! in order (passed as `&` of `var` locals).
//!
//! Invocation i reads `input[i·n_in .. (i+1)·n_in]` and writes `output[i·n_out ..]`; the
//! number of invocations is the output buffer's length over n_out. Workgroups of
//! [`GROUP`] invocations are dispatched in rows of at most [`ROW`] workgroups (a 2-D dispatch
//! for large n), and the rows are split into chunks that fit the device's storage-buffer
//! binding limit.

use super::device::Gpu;
use super::readback;
use crate::shader::{Func, Module, Shape};
use anyhow::{anyhow, bail, Result};
use std::fmt::Write;
use wgpu::util::DeviceExt;

/// Invocations per workgroup.
pub const GROUP: u32 = 64;
/// Workgroups per row of the 2-D dispatch (WebGPU allows 65 535 per dimension).
pub const ROW: u32 = 32_768;
/// Name of the generated entry point.
pub const MAIN: &str = "main";

fn type_of(shape: Shape) -> String {
    match shape {
        Shape::Scalar => "f32".into(),
        Shape::Array(n) => format!("array<f32, {n}>"),
        Shape::Vector(n) => format!("vec{n}<f32>"),
    }
}

/// The components of a value of `shape` held in `name`, as WGSL expressions.
fn components(name: &str, shape: Shape) -> Vec<String> {
    match shape {
        Shape::Scalar => vec![name.to_string()],
        Shape::Array(n) => (0..n).map(|c| format!("{name}[{c}]")).collect(),
        Shape::Vector(n) => (0..n)
            .map(|c| format!("{name}.{}", ["x", "y", "z", "w"][c]))
            .collect(),
    }
}

/// The WGSL compute shader that calls `name` of `module` once per invocation: the module's
/// WGSL, two storage buffers (`call_in`, binding 0, read; `call_out`, binding 1, read-write)
/// and the entry point [`MAIN`]. An error when there is no such function, or when a function
/// of the module has a name the entry point uses (`main`, `call_…`).
pub fn shader(module: &Module, name: &str) -> Result<String> {
    let f: &Func = module
        .func(name)
        .ok_or_else(|| anyhow!("GPU call: the module has no function '{name}'"))?;
    if let Some(bad) = module
        .funcs
        .iter()
        .find(|g| g.name == MAIN || g.name.starts_with("call_"))
    {
        bail!(
            "GPU call: function name '{}' is reserved for the generated entry point",
            bad.name
        );
    }
    let (n_in, n_out) = (f.n_inputs(), f.n_outputs());
    let mut s = crate::shader::wgsl(module)?;
    let _ = write!(
        s,
        "\n// generated entry point: one call of {name} per invocation\n\
         @group(0) @binding(0) var<storage, read> call_in: array<f32>;\n\
         @group(0) @binding(1) var<storage, read_write> call_out: array<f32>;\n\n\
         @compute @workgroup_size({GROUP})\n\
         fn {MAIN}(@builtin(global_invocation_id) call_id: vec3<u32>) {{\n    \
         let call_i = call_id.y * {}u + call_id.x;\n    \
         if (call_i >= arrayLength(&call_out) / {n_out}u) {{\n        return;\n    }}\n    \
         let call_a = call_i * {}u;\n",
        ROW * GROUP,
        n_in.max(1)
    );
    // n_in = 0: call_in is still read (a one-value dummy), so that the binding exists
    if n_in == 0 {
        s.push_str("    let call_unused = call_in[0];\n");
    }
    let mut args = Vec::new();
    let mut k = 0usize;
    for (p, param) in f.inputs().iter().enumerate() {
        let comps: Vec<String> = (0..param.shape.len())
            .map(|c| format!("call_in[call_a + {}u]", k + c))
            .collect();
        k += param.shape.len();
        let value = match param.shape {
            Shape::Scalar => comps[0].clone(),
            sh => format!("{}({})", type_of(sh), comps.join(", ")),
        };
        let _ = writeln!(s, "    let call_p{p}: {} = {value};", type_of(param.shape));
        args.push(format!("call_p{p}"));
    }
    for (o, param) in f.outputs().iter().enumerate() {
        let _ = writeln!(s, "    var call_o{o}: {};", type_of(param.shape));
        args.push(format!("&call_o{o}"));
    }
    let call = format!("{name}({})", args.join(", "));
    let mut outs = Vec::new();
    match f.return_shape() {
        Some(shape) => {
            let _ = writeln!(s, "    let call_r: {} = {call};", type_of(shape));
            outs.extend(components("call_r", shape));
        }
        None => {
            let _ = writeln!(s, "    {call};");
        }
    }
    for (o, param) in f.outputs().iter().enumerate() {
        outs.extend(components(&format!("call_o{o}"), param.shape));
    }
    let _ = writeln!(s, "    let call_b = call_i * {n_out}u;");
    for (j, e) in outs.iter().enumerate() {
        let _ = writeln!(s, "    call_out[call_b + {j}u] = {e};");
    }
    s.push_str("}\n");
    Ok(s)
}

/// Run `name` of `module` on the GPU for every row of `inputs` (n rows of `n_inputs()` f32
/// values each, parameters in order); returns n rows of `n_outputs()` values (return value
/// first, then the `out` parameters), the layout of [`Func::eval`].
pub fn call(gpu: &Gpu, module: &Module, name: &str, inputs: &[f32]) -> Result<Vec<f32>> {
    let wgsl = shader(module, name)?;
    let f = module.func(name).expect("shader() found it");
    let (n_in, n_out) = (f.n_inputs(), f.n_outputs());
    let n = if n_in == 0 {
        bail!("GPU call: {name} takes no inputs; nothing says how many calls to make")
    } else if !inputs.len().is_multiple_of(n_in) {
        bail!(
            "GPU call: {} input values for {name} are not rows of {n_in}",
            inputs.len()
        )
    } else {
        inputs.len() / n_in
    };
    if n == 0 {
        return Ok(Vec::new());
    }
    let label = format!("call {name}");
    let shader = gpu.module(&label, &wgsl)?;
    let dev = &gpu.device;
    let storage = |read_only: bool, binding: u32| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    };
    let (pipeline, layout) = gpu.scoped(&format!("{label} pipeline"), || {
        let layout = dev.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("call"),
            entries: &[storage(true, 0), storage(false, 1)],
        });
        let pl = dev.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("call"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = dev.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(&label),
            layout: Some(&pl),
            module: &shader,
            entry_point: Some(MAIN),
            compilation_options: Default::default(),
            cache: None,
        });
        (pipeline, layout)
    })?;
    // rows per chunk: both buffers within the binding and buffer limits
    let limits = dev.limits();
    let max_bytes = limits
        .max_storage_buffer_binding_size
        .min(limits.max_buffer_size);
    let per_row = 4 * n_in.max(n_out) as u64;
    let chunk = ((max_bytes / per_row) as usize).min(
        (ROW as usize) * (GROUP as usize) * (limits.max_compute_workgroups_per_dimension as usize),
    );
    if chunk == 0 {
        bail!("GPU call: one row of {name} exceeds the device's storage-buffer limit");
    }
    let mut out = Vec::with_capacity(n * n_out);
    for start in (0..n).step_by(chunk) {
        let rows = chunk.min(n - start);
        let rows_in = &inputs[start * n_in..(start + rows) * n_in];
        let bytes_out = 4 * (rows * n_out) as u64;
        let part = gpu.scoped(&format!("{label} dispatch"), || {
            let buf_in = dev.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("call in"),
                contents: bytemuck::cast_slice(rows_in),
                usage: wgpu::BufferUsages::STORAGE,
            });
            let buf_out = dev.create_buffer(&wgpu::BufferDescriptor {
                label: Some("call out"),
                size: bytes_out,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            let group = dev.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("call"),
                layout: &layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: buf_in.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: buf_out.as_entire_binding(),
                    },
                ],
            });
            let rb = readback::staging(gpu, bytes_out);
            let mut enc = dev.create_command_encoder(&Default::default());
            {
                let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("call"),
                    timestamp_writes: None,
                });
                pass.set_pipeline(&pipeline);
                pass.set_bind_group(0, &group, &[]);
                let (x, y) = dispatch(rows);
                pass.dispatch_workgroups(x, y, 1);
            }
            enc.copy_buffer_to_buffer(&buf_out, 0, &rb, 0, bytes_out);
            gpu.queue.submit([enc.finish()]);
            rb
        })?;
        let bytes = readback::read_buffer(gpu, &part)?;
        out.extend_from_slice(&bytemuck::pod_collect_to_vec::<u8, f32>(&bytes));
    }
    Ok(out)
}

/// Workgroups (x, y) covering `rows` invocations: one row of workgroups while they fit in
/// [`ROW`], otherwise rows of [`ROW`] workgroups.
pub fn dispatch(rows: usize) -> (u32, u32) {
    let groups = rows.div_ceil(GROUP as usize) as u32;
    if groups <= ROW {
        (groups, 1)
    } else {
        (ROW, groups.div_ceil(ROW))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::device::naga_check;

    fn module() -> Module {
        let mut f = Func::new("k");
        let z = f.input_scalar("z");
        let a = f.input("a", Shape::Array(3));
        let v = f.input("v", Shape::Vector(2));
        let p = f.mul(z, a[2]);
        let q = f.add(p, v[1]);
        f.output("o", Shape::Vector(3), &[p, q, a[0]]);
        f.output("s", Shape::Scalar, &[v[0]]);
        f.output("arr", Shape::Array(2), &[q, z]);
        f.ret(Shape::Vector(2), &[q, p]);
        let mut g = Func::new("void_like");
        let x = g.input("x", Shape::Array(2));
        g.output("y", Shape::Scalar, &[x[1]]);
        let mut h = Func::new("scalar_ret");
        let x = h.input_scalar("x");
        h.ret(Shape::Scalar, &[x]);
        Module {
            header: vec!["test".into()],
            funcs: vec![f, g, h],
        }
    }

    #[test]
    fn generated_entry_points_validate_in_naga() {
        let m = module();
        for name in ["k", "void_like", "scalar_ret"] {
            let s = shader(&m, name).unwrap();
            naga_check(&s).unwrap_or_else(|e| panic!("{name}: {e}\n{s}"));
        }
        let s = shader(&m, "k").unwrap();
        assert!(
            s.contains("let call_p1: array<f32, 3> = array<f32, 3>(call_in[call_a + 1u], call_in[call_a + 2u], call_in[call_a + 3u]);"),
            "{s}"
        );
        assert!(
            s.contains(
                "let call_p2: vec2<f32> = vec2<f32>(call_in[call_a + 4u], call_in[call_a + 5u]);"
            ),
            "{s}"
        );
        assert!(s.contains("let call_r: vec2<f32> = k(call_p0, call_p1, call_p2, &call_o0, &call_o1, &call_o2);"), "{s}");
        // return value first, then the out parameters in order: 2 + 3 + 1 + 2 outputs
        assert!(s.contains("call_out[call_b + 1u] = call_r.y;"), "{s}");
        assert!(s.contains("call_out[call_b + 4u] = call_o0.z;"), "{s}");
        assert!(s.contains("call_out[call_b + 5u] = call_o1;"), "{s}");
        assert!(s.contains("call_out[call_b + 7u] = call_o2[1];"), "{s}");
        assert!(s.contains("let call_b = call_i * 8u;"), "{s}");
        assert!(s.contains("let call_a = call_i * 6u;"), "{s}");
        let v = shader(&m, "void_like").unwrap();
        assert!(v.contains("    void_like(call_p0, &call_o0);"), "{v}");
    }

    #[test]
    fn unknown_and_reserved_names_are_errors() {
        let m = module();
        let e = shader(&m, "nope").unwrap_err().to_string();
        assert!(e.contains("'nope'"), "{e}");
        let mut m2 = m.clone();
        m2.funcs[2].name = "main".into();
        let e = shader(&m2, "k").unwrap_err().to_string();
        assert!(e.contains("'main'") && e.contains("reserved"), "{e}");
    }

    #[test]
    fn large_dispatches_are_two_dimensional() {
        assert_eq!(dispatch(1), (1, 1));
        assert_eq!(dispatch(64 * ROW as usize), (ROW, 1));
        assert_eq!(dispatch(64 * ROW as usize + 1), (ROW, 2));
    }
}
