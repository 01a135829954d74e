//! Compile check for emitted shader modules (shared by the test binaries that emit shaders).
//!
//! [`compile_check`] wraps a module's text exactly as printed (no define injected) in small
//! shaders that call every function, and compiles each:
//! * GLSL 3.30 fragment (OpenGL SPIR-V, `-G`), GLSL 4.50 fragment and compute, GLSL ES 3.10
//!   fragment and compute (Vulkan SPIR-V, `-V`), each validated by spirv-val;
//! * GLSL ES 3.00 fragment (WebGL 2; glslang's front end only, SPIR-V needs ES ≥ 3.10);
//! * HLSL pixel and compute (glslang's HLSL front end, `-D -e main`, SM 5 entry points);
//! * WGSL: parsed and validated by naga (wgpu's front end), a compute and a fragment entry
//!   point, out parameters passed as `&local`.
//!
//! Any error or warning is a failure. [`tools_present`] decides whether the glslang part runs:
//! without glslangValidator it skips loudly, unless MOMENTLAB_REQUIRE_GLSLANG is set (then it
//! fails); the WGSL part always runs.
#![allow(dead_code)]

use momentlab::shader::{self, Module, Shape};
use std::process::Command;

/// True if glslangValidator and spirv-val run. If they do not: panics when
/// MOMENTLAB_REQUIRE_GLSLANG is set, otherwise prints why the check is skipped and returns false.
pub fn tools_present(test: &str) -> bool {
    let ok = |bin: &str| {
        Command::new(bin)
            .arg("--version")
            .output()
            .map(|o| o.status.success())
            .unwrap_or(false)
    };
    let present = ok("glslangValidator") && ok("spirv-val");
    if !present {
        if std::env::var_os("MOMENTLAB_REQUIRE_GLSLANG").is_some() {
            panic!(
                "{test}: glslangValidator/spirv-val not found but MOMENTLAB_REQUIRE_GLSLANG is set"
            );
        }
        eprintln!(
            "SKIPPED {test}: glslangValidator/spirv-val not installed (apt install glslang-tools \
             spirv-tools); set MOMENTLAB_REQUIRE_GLSLANG=1 to make this a failure"
        );
    }
    present
}

/// Statements that call every function of `m` with inputs derived from the float `src` and add
/// every output component to the float `acc` (GLSL or HLSL).
fn calls(m: &Module, lang: shader::Lang) -> String {
    let vec = |n: usize| match lang {
        shader::Lang::Glsl => format!("vec{n}"),
        shader::Lang::Hlsl => format!("float{n}"),
    };
    let decl = |name: &str, shape: Shape, init: bool| -> String {
        match shape {
            Shape::Scalar => {
                if init {
                    format!("float {name} = src;")
                } else {
                    format!("float {name};")
                }
            }
            Shape::Array(n) => {
                let mut s = format!("float {name}[{n}];");
                if init {
                    for c in 0..n {
                        s += &format!(" {name}[{c}] = src * {}.0 + 0.125;", c + 1);
                    }
                }
                s
            }
            Shape::Vector(n) => {
                if init {
                    format!("{} {name} = {}(src);", vec(n), vec(n))
                } else {
                    format!("{} {name};", vec(n))
                }
            }
        }
    };
    let sum = |name: &str, shape: Shape| -> String {
        match shape {
            Shape::Scalar => format!("acc += {name};"),
            Shape::Array(n) => (0..n).map(|c| format!("acc += {name}[{c}];")).collect(),
            Shape::Vector(n) => (0..n)
                .map(|c| format!("acc += {name}.{};", ["x", "y", "z", "w"][c]))
                .collect(),
        }
    };
    let mut s = String::new();
    for (k, f) in m.funcs.iter().enumerate() {
        let mut args = Vec::new();
        for (i, p) in f.inputs().iter().enumerate() {
            let n = format!("a{k}_{i}");
            s += &format!("    {}\n", decl(&n, p.shape, true));
            args.push(n);
        }
        let outs: Vec<(String, Shape)> = f
            .outputs()
            .iter()
            .enumerate()
            .map(|(i, p)| (format!("o{k}_{i}"), p.shape))
            .collect();
        for (n, sh) in &outs {
            s += &format!("    {}\n", decl(n, *sh, false));
            args.push(n.clone());
        }
        let call = format!("{}({})", f.name, args.join(", "));
        match f.return_shape() {
            Some(sh) => {
                let n = format!("r{k}");
                let ty = match sh {
                    Shape::Vector(d) => vec(d),
                    _ => "float".into(),
                };
                s += &format!("    {ty} {n} = {call};\n    {}\n", sum(&n, sh));
            }
            None => s += &format!("    {call};\n"),
        }
        for (n, sh) in &outs {
            s += &format!("    {}\n", sum(n, *sh));
        }
    }
    s
}

/// As [`calls`], in WGSL: `var` locals for the out parameters, passed as `&local`.
fn wgsl_calls(m: &Module) -> String {
    let ty = |shape: Shape| match shape {
        Shape::Scalar => "f32".to_string(),
        Shape::Array(n) => format!("array<f32, {n}>"),
        Shape::Vector(n) => format!("vec{n}<f32>"),
    };
    let sum = |name: &str, shape: Shape| -> String {
        match shape {
            Shape::Scalar => format!("acc += {name};"),
            Shape::Array(n) => (0..n).map(|c| format!(" acc += {name}[{c}];")).collect(),
            Shape::Vector(n) => (0..n)
                .map(|c| format!(" acc += {name}.{};", ["x", "y", "z", "w"][c]))
                .collect(),
        }
    };
    let mut s = String::new();
    for (k, f) in m.funcs.iter().enumerate() {
        let mut args = Vec::new();
        for (i, p) in f.inputs().iter().enumerate() {
            let n = format!("a{k}_{i}");
            s += &match p.shape {
                Shape::Scalar => format!("    let {n}: f32 = src;\n"),
                Shape::Vector(d) => format!("    let {n}: vec{d}<f32> = vec{d}<f32>(src);\n"),
                Shape::Array(d) => {
                    let mut t = format!("    var {n}: array<f32, {d}>;");
                    for c in 0..d {
                        t += &format!(" {n}[{c}] = src * {}.0 + 0.125;", c + 1);
                    }
                    t + "\n"
                }
            };
            args.push(n);
        }
        let outs: Vec<(String, Shape)> = f
            .outputs()
            .iter()
            .enumerate()
            .map(|(i, p)| (format!("o{k}_{i}"), p.shape))
            .collect();
        for (n, sh) in &outs {
            s += &format!("    var {n}: {};\n", ty(*sh));
            args.push(format!("&{n}"));
        }
        let call = format!("{}({})", f.name, args.join(", "));
        match f.return_shape() {
            Some(sh) => {
                let n = format!("r{k}");
                s += &format!("    let {n}: {} = {call};\n    {}\n", ty(sh), sum(&n, sh));
            }
            None => s += &format!("    {call};\n"),
        }
        for (n, sh) in &outs {
            s += &format!("    {}\n", sum(n, *sh));
        }
    }
    s
}

/// The WGSL wrapper of `m`: the module's text, a compute entry point `main` over a storage
/// buffer and a fragment entry point `fragment_main`, each calling every function.
pub fn wgsl_wrapper(m: &Module) -> Result<String, String> {
    let w = shader::wgsl(m).map_err(|e| e.to_string())?;
    let c = wgsl_calls(m);
    Ok(format!(
        "@group(0) @binding(0) var<storage, read_write> data: array<f32>;\n{w}\n\
         @compute @workgroup_size(64)\nfn main(@builtin(global_invocation_id) id: vec3<u32>)\n{{\n    \
         let src: f32 = data[id.x];\n    var acc: f32 = 0.0;\n{c}    data[id.x] = acc;\n}}\n\n\
         @fragment\nfn fragment_main(@location(0) v_in: f32) -> @location(0) vec4<f32>\n{{\n    \
         let src: f32 = v_in;\n    var acc: f32 = 0.0;\n{c}    return vec4<f32>(acc);\n}}\n"
    ))
}

/// Parse and validate WGSL source with naga (every validation flag, WebGPU's default
/// capabilities); Err holds naga's diagnostic and the source.
pub fn naga_check(label: &str, src: &str) -> Result<(), String> {
    let module = naga::front::wgsl::parse_str(src).map_err(|e| {
        format!(
            "{label}: WGSL (naga parse):\n{}\n--- source ---\n{src}",
            e.emit_to_string(src)
        )
    })?;
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::default(),
    )
    .validate(&module)
    .map_err(|e| {
        format!(
            "{label}: WGSL (naga validation):\n{}\n--- source ---\n{src}",
            e.emit_to_string(src)
        )
    })?;
    Ok(())
}

/// The wrapper shaders: (label, file extension, glslangValidator arguments, source).
type Wrapper = (&'static str, &'static str, Vec<&'static str>, String);

/// A GLSL fragment wrapper for `#version {version}` (ES: highp default precision); its input is
/// `gl_FragCoord.x` (GLSL 3.30 and ES 3.00 have no locations on fragment inputs, which OpenGL
/// SPIR-V requires).
fn glsl_fragment(version: &str, es: bool, g: &str, gc: &str) -> String {
    let prec = if es { "precision highp float;\n" } else { "" };
    format!(
        "#version {version}\n{prec}layout(location = 0) out vec4 o_color;\n{g}\nvoid main()\n{{\n    float src = gl_FragCoord.x;\n    float acc = 0.0;\n{gc}    o_color = vec4(acc);\n}}\n"
    )
}

/// A GLSL compute wrapper for `#version {version}` (ES: highp default precision).
fn glsl_compute(version: &str, es: bool, g: &str, gc: &str) -> String {
    let prec = if es { "precision highp float;\n" } else { "" };
    format!(
        "#version {version}\n{prec}layout(local_size_x = 64) in;\nlayout(std430, binding = 0) buffer Data {{ float data[]; }};\n{g}\nvoid main()\n{{\n    uint i = gl_GlobalInvocationID.x;\n    float src = data[i];\n    float acc = 0.0;\n{gc}    data[i] = acc;\n}}\n"
    )
}

fn wrappers(m: &Module) -> Result<Vec<Wrapper>, String> {
    let g = shader::glsl(m).map_err(|e| e.to_string())?;
    let h = shader::hlsl(m).map_err(|e| e.to_string())?;
    let gc = calls(m, shader::Lang::Glsl);
    let hc = calls(m, shader::Lang::Hlsl);
    Ok(vec![
        (
            "GLSL 3.30 fragment",
            "frag",
            vec!["-G"],
            glsl_fragment("330", false, &g, &gc),
        ),
        (
            "GLSL 4.50 fragment",
            "frag",
            vec!["-V"],
            glsl_fragment("450", false, &g, &gc),
        ),
        (
            "GLSL 4.50 compute",
            "comp",
            vec!["-V"],
            glsl_compute("450", false, &g, &gc),
        ),
        (
            "GLSL ES 3.00 fragment",
            "frag",
            vec![],
            glsl_fragment("300 es", true, &g, &gc),
        ),
        (
            "GLSL ES 3.10 fragment",
            "frag",
            vec!["-V"],
            glsl_fragment("310 es", true, &g, &gc),
        ),
        (
            "GLSL ES 3.10 compute",
            "comp",
            vec!["-V"],
            glsl_compute("310 es", true, &g, &gc),
        ),
        (
            "HLSL pixel",
            "frag",
            vec!["-D", "-e", "main", "-V"],
            format!(
                "{h}\nfloat4 main(float v_in : TEXCOORD0) : SV_Target\n{{\n    float src = v_in;\n    float acc = 0.0;\n{hc}    return float4(acc, acc, acc, acc);\n}}\n"
            ),
        ),
        (
            "HLSL compute",
            "comp",
            vec!["-D", "-e", "main", "-V"],
            format!(
                "RWStructuredBuffer<float> data : register(u0);\n{h}\n[numthreads(64, 1, 1)]\nvoid main(uint3 id : SV_DispatchThreadID)\n{{\n    float src = data[id.x];\n    float acc = 0.0;\n{hc}    data[id.x] = acc;\n}}\n"
            ),
        ),
    ])
}

/// The GLSL wrappers' versions and whether `MOMENTLAB_PRECISE` is `precise` there, for
/// checking the version guard by preprocessing: (`#version` line, ES, precise).
pub const GLSL_VERSIONS: [(&str, bool, bool); 6] = [
    ("330", false, false),
    ("400", false, true),
    ("450", false, true),
    ("300 es", true, false),
    ("310 es", true, false),
    ("320 es", true, true),
];

/// The module's GLSL in a fragment wrapper of `version`, preprocessed by glslangValidator
/// (`-E`).
pub fn glsl_preprocessed(label: &str, m: &Module, version: &str, es: bool) -> String {
    let dir = super::tmp(&format!("shader-pp-{label}"));
    let g = shader::glsl(m).unwrap();
    let file = dir.join("w.frag");
    std::fs::write(
        &file,
        glsl_fragment(version, es, &g, &calls(m, shader::Lang::Glsl)),
    )
    .unwrap();
    let out = Command::new("glslangValidator")
        .arg("-E")
        .arg(&file)
        .output()
        .unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    assert!(
        out.status.success(),
        "{label} {version}: glslangValidator -E failed"
    );
    String::from_utf8_lossy(&out.stdout).to_string()
}

/// Check every function of `m` in all wrappers: WGSL through naga always, the GLSL and HLSL
/// wrappers through glslangValidator (and their SPIR-V through spirv-val) when `glslang` is
/// true (see [`tools_present`]). `label` names the temporary files and the error messages.
/// Err lists every wrapper that failed with the compiler's output and the wrapper source.
pub fn check(label: &str, m: &Module, glslang: bool) -> Result<(), String> {
    let mut errors = Vec::new();
    if let Err(e) = wgsl_wrapper(m).and_then(|src| naga_check(label, &src)) {
        errors.push(e);
    }
    if glslang {
        if let Err(e) = glslang_check(label, m) {
            errors.push(e);
        }
    }
    if errors.is_empty() {
        Ok(())
    } else {
        Err(errors.join("\n\n"))
    }
}

/// [`check`] with glslang (callers check [`tools_present`] first).
pub fn compile_check(label: &str, m: &Module) -> Result<(), String> {
    check(label, m, true)
}

/// The glslang part of [`check`].
fn glslang_check(label: &str, m: &Module) -> Result<(), String> {
    let dir = super::tmp(&format!("shader-{label}"));
    let mut errors = Vec::new();
    for (i, (what, ext, args, src)) in wrappers(m)?.into_iter().enumerate() {
        let file = dir.join(format!("w{i}.{ext}"));
        let spv = dir.join(format!("w{i}.spv"));
        std::fs::write(&file, &src).map_err(|e| e.to_string())?;
        let mut cmd = Command::new("glslangValidator");
        cmd.args(&args);
        let codegen = !args.is_empty() && args.iter().any(|a| *a == "-V" || *a == "-G");
        if codegen {
            cmd.arg("-o").arg(&spv);
        }
        let out = cmd
            .arg(&file)
            .output()
            .map_err(|e| format!("running glslangValidator: {e}"))?;
        let text = String::from_utf8_lossy(&out.stdout).to_string()
            + &String::from_utf8_lossy(&out.stderr);
        let noisy = text.to_ascii_uppercase().contains("WARNING")
            || text.to_ascii_uppercase().contains("ERROR");
        if !out.status.success() || noisy {
            errors.push(format!(
                "{label}: {what}: glslangValidator:\n{text}\n--- source ---\n{src}"
            ));
            continue;
        }
        if !codegen {
            continue;
        }
        let val = Command::new("spirv-val")
            .arg(&spv)
            .output()
            .map_err(|e| format!("running spirv-val: {e}"))?;
        let vt = String::from_utf8_lossy(&val.stdout).to_string()
            + &String::from_utf8_lossy(&val.stderr);
        if !val.status.success() || !vt.trim().is_empty() {
            errors.push(format!("{label}: {what}: spirv-val:\n{vt}"));
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    if errors.is_empty() {
        Ok(())
    } else {
        Err(errors.join("\n\n"))
    }
}
