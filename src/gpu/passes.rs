//! The WGSL of the shadow-map passes, generated from data: the channel count m (one RGBA
//! texture per four channels), the 1-D filter weights and the setting's shader module (its
//! `tunedEncode` and `tunedShadow` printed by [`crate::shader::wgsl`]).
//!
//! * encode (render pass, fragment per texel): s = tunedEncode(z0), written to the targets;
//! * filter (render pass, fragment per texel): Σ_i w_i·s(p + i·axis), edges clamped, taps in
//!   order, each written as acc = acc + w_i·s_i (a driver may fuse it);
//! * lookup (compute, one invocation per fragment): the texel's filtered channels at its
//!   centre and G = tunedShadow(s, z_f).

use std::fmt::Write;

/// Number of RGBA textures holding `m` channels.
pub fn textures_for(m: usize) -> usize {
    m.div_ceil(4)
}

/// The full-screen triangle every render pass draws (three vertices, no buffers).
const VERTEX: &str = "@vertex\nfn vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {\n    let x = f32(i32(i & 1u) * 4 - 1);\n    let y = f32(i32(i & 2u) * 2 - 1);\n    return vec4<f32>(x, y, 0.0, 1.0);\n}\n";

fn out_struct(k: usize) -> String {
    let mut s = String::from("struct Targets {\n");
    for j in 0..k {
        let _ = writeln!(s, "    @location({j}) t{j}: vec4<f32>,");
    }
    s.push_str("}\n");
    s
}

/// `array<f32, m>` components packed into `k` vec4s ("vec4<f32>(s[0], s[1], s[2], s[3])", …),
/// padding with 0.
fn pack(m: usize, k: usize, src: &str) -> Vec<String> {
    (0..k)
        .map(|j| {
            let c: Vec<String> = (0..4)
                .map(|i| {
                    let ch = 4 * j + i;
                    if ch < m {
                        format!("{src}[{ch}]")
                    } else {
                        "0.0".into()
                    }
                })
                .collect();
            format!("vec4<f32>({})", c.join(", "))
        })
        .collect()
}

/// The encode pass: `functions` holds `tunedEncode(depth: f32, stored: ptr<function, array<f32, m>>)`.
pub fn encode(functions: &str, m: usize) -> String {
    let k = textures_for(m);
    let outs = pack(m, k, "s");
    format!(
        "{functions}\n@group(0) @binding(0) var depth_map: texture_2d<f32>;\n{}{VERTEX}\n@fragment\nfn fs(@builtin(position) p: vec4<f32>) -> Targets {{\n    let z = textureLoad(depth_map, vec2<i32>(p.xy), 0).x;\n    var s: array<f32, {m}>;\n    tunedEncode(z, &s);\n    return Targets({});\n}}\n",
        out_struct(k),
        outs.join(", ")
    )
}

/// One filter pass over `k` textures along x (`vertical` false) or y with the 1-D `weights`.
pub fn filter(k: usize, weights: &[f32], vertical: bool) -> String {
    let r = (weights.len() / 2) as i64;
    let mut s = String::new();
    for j in 0..k {
        let _ = writeln!(s, "@group(0) @binding({j}) var src{j}: texture_2d<f32>;");
    }
    s.push_str(&out_struct(k));
    s.push_str(VERTEX);
    s.push_str("\n@fragment\nfn fs(@builtin(position) p: vec4<f32>) -> Targets {\n");
    s.push_str("    let c = vec2<i32>(p.xy);\n    let hi = vec2<i32>(textureDimensions(src0)) - vec2<i32>(1, 1);\n");
    for j in 0..k {
        let _ = writeln!(s, "    var a{j} = vec4<f32>(0.0, 0.0, 0.0, 0.0);");
    }
    for (i, &w) in weights.iter().enumerate() {
        let d = i as i64 - r;
        let off = if vertical {
            format!("vec2<i32>(0, {d})")
        } else {
            format!("vec2<i32>({d}, 0)")
        };
        let _ = writeln!(s, "    let q{i} = clamp(c + {off}, vec2<i32>(0, 0), hi);");
        for j in 0..k {
            let _ = writeln!(
                s,
                "    a{j} = a{j} + {} * textureLoad(src{j}, q{i}, 0);",
                crate::shader::wgsl::literal(w)
            );
        }
    }
    let outs: Vec<String> = (0..k).map(|j| format!("a{j}")).collect();
    let _ = writeln!(s, "    return Targets({});\n}}", outs.join(", "));
    s
}

/// Invocations per workgroup of the lookup, and workgroups per row of its 2-D dispatch.
pub const LOOKUP_GROUP: u32 = 64;
/// Largest workgroups per row of the lookup's 2-D dispatch.
pub const LOOKUP_ROW: u32 = 32768;

/// The lookup pass: `functions` holds `tunedShadow(stored: array<f32, m>, fragmentDepth: f32) -> f32`.
/// Bindings: the k filtered maps, the fragments (texel index, z_f) and G out.
pub fn lookup(functions: &str, m: usize) -> String {
    let k = textures_for(m);
    let mut s = format!("{functions}\n");
    for j in 0..k {
        let _ = writeln!(s, "@group(0) @binding({j}) var map{j}: texture_2d<f32>;");
    }
    let _ = writeln!(
        s,
        "struct Frag {{\n    texel: u32,\n    zf: f32,\n}}\n@group(0) @binding({k}) var<storage, read> frags: array<Frag>;\n@group(0) @binding({}) var<storage, read_write> shadow: array<f32>;",
        k + 1
    );
    let _ = writeln!(
        s,
        "@compute @workgroup_size({LOOKUP_GROUP})\nfn main(@builtin(global_invocation_id) id: vec3<u32>) {{\n    let i = id.y * {} + id.x;\n    if (i >= arrayLength(&frags)) {{\n        return;\n    }}\n    let f = frags[i];\n    let w = textureDimensions(map0).x;\n    let q = vec2<i32>(i32(f.texel % w), i32(f.texel / w));",
        LOOKUP_GROUP * LOOKUP_ROW
    );
    for j in 0..k {
        let _ = writeln!(s, "    let v{j} = textureLoad(map{j}, q, 0);");
    }
    let comps: Vec<String> = (0..m)
        .map(|c| format!("v{}.{}", c / 4, ["x", "y", "z", "w"][c % 4]))
        .collect();
    let _ = writeln!(
        s,
        "    let s = array<f32, {m}>({});\n    shadow[i] = tunedShadow(s, f.zf);\n}}",
        comps.join(", ")
    );
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::device::naga_check;

    const FUNCS: &str = "fn tunedEncode(depth: f32, stored: ptr<function, array<f32, 6>>) {\n    for (var i = 0; i < 6; i++) { (*stored)[i] = depth; }\n}\nfn tunedShadow(stored: array<f32, 6>, fragmentDepth: f32) -> f32 {\n    return select(0.0, 1.0, stored[0] < fragmentDepth);\n}\n";

    #[test]
    fn every_pass_validates_with_naga() {
        for m in [1, 2, 4, 6, 8] {
            let f = FUNCS
                .replace("6", &m.to_string())
                .replace("i < 6", &format!("i < {m}"));
            naga_check(&encode(&f, m)).unwrap_or_else(|e| panic!("encode m = {m}: {e}"));
            naga_check(&lookup(&f, m)).unwrap_or_else(|e| panic!("lookup m = {m}: {e}"));
            let w = [0.25f32, 0.5, 0.25];
            for v in [false, true] {
                naga_check(&filter(textures_for(m), &w, v))
                    .unwrap_or_else(|e| panic!("filter m = {m}: {e}"));
            }
        }
    }
}
