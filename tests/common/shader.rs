//! Compile check for emitted shader modules (shared by the test binaries that emit shaders).
//!
//! [`compile_check`] wraps a module's GLSL and HLSL text in small shaders that call every
//! function — GLSL 450 fragment and compute, GLSL ES 310 (highp, fragment), HLSL pixel and
//! compute (glslang's HLSL front end, `-D -e main`) — compiles each with glslangValidator to
//! SPIR-V and validates it with spirv-val. Any error or warning is a failure.
//! [`tools_present`] decides whether to run: without glslangValidator it skips loudly, unless
//! MOMENTLAB_REQUIRE_GLSLANG is set (then it fails).
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
/// every output component to the float `acc`.
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

/// The wrapper shaders: (label, file extension, glslangValidator arguments, source).
type Wrapper = (String, &'static str, Vec<&'static str>, String);

fn wrappers(m: &Module) -> Result<Vec<Wrapper>, String> {
    let g = shader::glsl(m).map_err(|e| e.to_string())?;
    let h = shader::hlsl(m).map_err(|e| e.to_string())?;
    let gc = calls(m, shader::Lang::Glsl);
    let hc = calls(m, shader::Lang::Hlsl);
    Ok(vec![
        (
            "GLSL 450 fragment".into(),
            "frag",
            vec![],
            format!(
                "#version 450\nlayout(location = 0) in float v_in;\nlayout(location = 0) out vec4 o_color;\n{g}\nvoid main()\n{{\n    float src = v_in;\n    float acc = 0.0;\n{gc}    o_color = vec4(acc);\n}}\n"
            ),
        ),
        (
            "GLSL 450 compute".into(),
            "comp",
            vec![],
            format!(
                "#version 450\nlayout(local_size_x = 64) in;\nlayout(std430, binding = 0) buffer Data {{ float data[]; }};\n{g}\nvoid main()\n{{\n    uint i = gl_GlobalInvocationID.x;\n    float src = data[i];\n    float acc = 0.0;\n{gc}    data[i] = acc;\n}}\n"
            ),
        ),
        (
            "GLSL ES 310 fragment (highp)".into(),
            "frag",
            vec![],
            format!(
                "#version 310 es\nprecision highp float;\n#define MOMENTLAB_PRECISE\nlayout(location = 0) in highp float v_in;\nlayout(location = 0) out highp vec4 o_color;\n{g}\nvoid main()\n{{\n    float src = v_in;\n    float acc = 0.0;\n{gc}    o_color = vec4(acc);\n}}\n"
            ),
        ),
        (
            "HLSL pixel".into(),
            "frag",
            vec!["-D", "-e", "main"],
            format!(
                "{h}\nfloat4 main(float v_in : TEXCOORD0) : SV_Target\n{{\n    float src = v_in;\n    float acc = 0.0;\n{hc}    return float4(acc, acc, acc, acc);\n}}\n"
            ),
        ),
        (
            "HLSL compute".into(),
            "comp",
            vec!["-D", "-e", "main"],
            format!(
                "RWStructuredBuffer<float> data : register(u0);\n{h}\n[numthreads(64, 1, 1)]\nvoid main(uint3 id : SV_DispatchThreadID)\n{{\n    float src = data[id.x];\n    float acc = 0.0;\n{hc}    data[id.x] = acc;\n}}\n"
            ),
        ),
    ])
}

/// Compile every function of `m` in all wrappers and validate the SPIR-V. `label` names the
/// temporary files and the error messages. Err lists every wrapper that failed with the
/// compiler's output and the wrapper source.
pub fn compile_check(label: &str, m: &Module) -> Result<(), String> {
    let dir = super::tmp(&format!("shader-{label}"));
    let mut errors = Vec::new();
    for (i, (what, ext, args, src)) in wrappers(m)?.into_iter().enumerate() {
        let file = dir.join(format!("w{i}.{ext}"));
        let spv = dir.join(format!("w{i}.spv"));
        std::fs::write(&file, &src).map_err(|e| e.to_string())?;
        let out = Command::new("glslangValidator")
            .args(&args)
            .arg("-V")
            .arg("-o")
            .arg(&spv)
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
