//! Mesh files: one mesh written as OBJ, glTF (.gltf with an embedded and with an external
//! buffer, .glb), PLY (ASCII, binary little and big endian) and STL (ASCII, binary) loads to
//! the same triangles and renders bit-identical depth stacks; glTF node transforms are applied;
//! unsupported, misnamed and corrupt files are one-line errors (never a panic).

use base64::Engine;
use momentlab::render::mesh::load_mesh;
use momentlab::render::{render_view, Scene};
use std::collections::HashMap;

type V = [f32; 3];

/// The test mesh: an L-shaped block (two boxes) and a tilted quad over it, on coordinates
/// exact in f32, as indexed triangles.
fn mesh() -> (Vec<V>, Vec<[u32; 3]>) {
    let mut v: Vec<V> = Vec::new();
    let mut f: Vec<[u32; 3]> = Vec::new();
    let mut block = |lo: V, hi: V| {
        let b = v.len() as u32;
        for i in 0..8 {
            v.push([
                if i & 1 == 0 { lo[0] } else { hi[0] },
                if i & 2 == 0 { lo[1] } else { hi[1] },
                if i & 4 == 0 { lo[2] } else { hi[2] },
            ]);
        }
        for q in [
            [0, 2, 6, 4],
            [1, 5, 7, 3],
            [0, 4, 5, 1],
            [2, 3, 7, 6],
            [0, 1, 3, 2],
            [4, 6, 7, 5],
        ] {
            f.push([b + q[0], b + q[1], b + q[2]]);
            f.push([b + q[0], b + q[2], b + q[3]]);
        }
    };
    block([-1.0, 0.0, -1.0], [1.0, 0.5, 1.0]);
    block([-1.0, 0.5, -1.0], [-0.25, 1.75, 0.5]);
    let b = v.len() as u32;
    v.extend([
        [-1.5, 2.0, -1.5],
        [1.5, 2.5, -1.5],
        [1.5, 3.0, 1.25],
        [-1.5, 2.5, 1.25],
    ]);
    f.push([b, b + 1, b + 2]);
    f.push([b, b + 2, b + 3]);
    (v, f)
}

fn obj(v: &[V], f: &[[u32; 3]]) -> Vec<u8> {
    let mut s = String::from("# test mesh\n");
    for p in v {
        s += &format!("v {} {} {}\n", p[0], p[1], p[2]);
    }
    for t in f {
        s += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    s.into_bytes()
}

#[derive(Clone, Copy)]
enum Ply {
    Ascii,
    Le,
    Be,
}

/// PLY with an extra vertex property (colour) and an extra element (edges) to be skipped.
fn ply(v: &[V], f: &[[u32; 3]], enc: Ply) -> Vec<u8> {
    let fmt = match enc {
        Ply::Ascii => "ascii",
        Ply::Le => "binary_little_endian",
        Ply::Be => "binary_big_endian",
    };
    let mut out = format!(
        "ply\nformat {fmt} 1.0\ncomment made by the test\nelement vertex {}\nproperty float x\n\
         property float y\nproperty float z\nproperty uchar red\nelement face {}\n\
         property list uchar int vertex_indices\nelement edge 1\nproperty int vertex1\n\
         property int vertex2\nend_header\n",
        v.len(),
        f.len()
    )
    .into_bytes();
    let put32 = |o: &mut Vec<u8>, b: [u8; 4]| match enc {
        Ply::Be => o.extend(b.iter().rev()),
        _ => o.extend(b),
    };
    for p in v {
        match enc {
            Ply::Ascii => out.extend(format!("{} {} {} 200\n", p[0], p[1], p[2]).bytes()),
            _ => {
                for c in p {
                    put32(&mut out, c.to_le_bytes());
                }
                out.push(200);
            }
        }
    }
    for t in f {
        match enc {
            Ply::Ascii => out.extend(format!("3 {} {} {}\n", t[0], t[1], t[2]).bytes()),
            _ => {
                out.push(3);
                for i in t {
                    put32(&mut out, (*i as i32).to_le_bytes());
                }
            }
        }
    }
    match enc {
        Ply::Ascii => out.extend(b"0 1\n"),
        _ => {
            put32(&mut out, 0i32.to_le_bytes());
            put32(&mut out, 1i32.to_le_bytes());
        }
    }
    out
}

fn stl_ascii(v: &[V], f: &[[u32; 3]]) -> Vec<u8> {
    let mut s = String::from("solid test\n");
    for t in f {
        s += "  facet normal 0 0 0\n    outer loop\n";
        for i in t {
            let p = v[*i as usize];
            s += &format!("      vertex {:e} {:e} {:e}\n", p[0], p[1], p[2]);
        }
        s += "    endloop\n  endfacet\n";
    }
    s += "endsolid test\n";
    s.into_bytes()
}

fn stl_binary(v: &[V], f: &[[u32; 3]]) -> Vec<u8> {
    let mut out = vec![b' '; 80];
    out[..5].copy_from_slice(b"solid"); // a binary header may start with "solid" too
    out.extend((f.len() as u32).to_le_bytes());
    for t in f {
        out.extend([0u8; 12]);
        for i in t {
            for c in v[*i as usize] {
                out.extend(c.to_le_bytes());
            }
        }
        out.extend([0u8; 2]);
    }
    out
}

/// Buffer bytes (positions f32 then u32 indices) and the glTF JSON for them; `uri` None = GLB.
fn gltf_json(v: &[V], f: &[[u32; 3]], uri: Option<&str>) -> (String, Vec<u8>) {
    let mut bin = Vec::new();
    for p in v {
        for c in p {
            bin.extend(c.to_le_bytes());
        }
    }
    let pos_len = bin.len();
    for t in f {
        for i in t {
            bin.extend(i.to_le_bytes());
        }
    }
    let (mut lo, mut hi) = ([f32::MAX; 3], [f32::MIN; 3]);
    for p in v {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let buffer = match uri {
        Some(u) => format!(r#"{{"byteLength":{},"uri":"{u}"}}"#, bin.len()),
        None => format!(r#"{{"byteLength":{}}}"#, bin.len()),
    };
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
        "nodes":[{{"mesh":0}}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1,"mode":4}}]}}],
        "buffers":[{buffer}],
        "bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":{pos_len}}},
                       {{"buffer":0,"byteOffset":{pos_len},"byteLength":{}}}],
        "accessors":[{{"bufferView":0,"componentType":5126,"count":{},"type":"VEC3",
                       "min":[{},{},{}],"max":[{},{},{}]}},
                     {{"bufferView":1,"componentType":5125,"count":{},"type":"SCALAR"}}]}}"#,
        bin.len() - pos_len,
        v.len(),
        lo[0],
        lo[1],
        lo[2],
        hi[0],
        hi[1],
        hi[2],
        f.len() * 3
    );
    (json, bin)
}

fn glb(json: &str, bin: &[u8]) -> Vec<u8> {
    let mut j = json.as_bytes().to_vec();
    while !j.len().is_multiple_of(4) {
        j.push(b' ');
    }
    let mut b = bin.to_vec();
    while !b.len().is_multiple_of(4) {
        b.push(0);
    }
    let total = 12 + 8 + j.len() + 8 + b.len();
    let mut out = Vec::new();
    out.extend(b"glTF");
    out.extend(2u32.to_le_bytes());
    out.extend((total as u32).to_le_bytes());
    out.extend((j.len() as u32).to_le_bytes());
    out.extend(0x4E4F534Au32.to_le_bytes());
    out.extend(j);
    out.extend((b.len() as u32).to_le_bytes());
    out.extend(0x004E4942u32.to_le_bytes());
    out.extend(b);
    out
}

/// Every format of the test mesh, by file path (as a scene file would name them).
fn files() -> HashMap<String, Vec<u8>> {
    let (v, f) = mesh();
    let mut m = HashMap::new();
    m.insert("m.obj".into(), obj(&v, &f));
    m.insert("m_ascii.ply".into(), ply(&v, &f, Ply::Ascii));
    m.insert("m_le.ply".into(), ply(&v, &f, Ply::Le));
    m.insert("m_be.ply".into(), ply(&v, &f, Ply::Be));
    m.insert("m_ascii.stl".into(), stl_ascii(&v, &f));
    m.insert("m_bin.stl".into(), stl_binary(&v, &f));
    let (json, bin) = gltf_json(&v, &f, None);
    m.insert("m.glb".into(), glb(&json, &bin));
    let b64 = base64::engine::general_purpose::STANDARD.encode(&bin);
    let uri = format!("data:application/octet-stream;base64,{b64}");
    m.insert(
        "m_embedded.gltf".into(),
        gltf_json(&v, &f, Some(&uri)).0.into_bytes(),
    );
    // external buffer next to the .gltf, in a sub-folder of the scene
    m.insert(
        "sub/m_external.gltf".into(),
        gltf_json(&v, &f, Some("m.bin")).0.into_bytes(),
    );
    m.insert("sub/m.bin".into(), bin);
    m
}

fn reader(files: &HashMap<String, Vec<u8>>) -> impl Fn(&str) -> anyhow::Result<Vec<u8>> + '_ {
    move |p: &str| {
        files
            .get(p)
            .cloned()
            .ok_or_else(|| anyhow::anyhow!("no file {p}"))
    }
}

const FORMATS: [&str; 9] = [
    "m.obj",
    "m_ascii.ply",
    "m_le.ply",
    "m_be.ply",
    "m_ascii.stl",
    "m_bin.stl",
    "m.glb",
    "m_embedded.gltf",
    "sub/m_external.gltf",
];

#[test]
fn every_format_loads_the_same_triangles() {
    let fs = files();
    let (v, f) = mesh();
    let want: Vec<[[f64; 3]; 3]> = f
        .iter()
        .map(|t| t.map(|i| v[i as usize].map(|c| c as f64)))
        .collect();
    for name in FORMATS {
        let tris =
            load_mesh(name, &fs[name], &reader(&fs)).unwrap_or_else(|e| panic!("{name}: {e:#}"));
        assert_eq!(tris, want, "{name}");
    }
}

#[test]
fn every_format_renders_identical_stacks() {
    let fs = files();
    let scene = |name: &str| {
        let text = format!(
            r#"{{"name":"m","lights":[{{"azimuth_deg":30,"elevation_deg":50}},{{"dir":[0.2,-1,0.1]}}],
            "objects":[{{"type":"plane","size":[6,6]}},
                       {{"type":"mesh","path":"{name}","transform":{{"translate":[0.1,0.25,0]}}}}]}}"#
        );
        Scene::from_json(&text, &reader(&fs)).unwrap_or_else(|e| panic!("{name}: {e:#}"))
    };
    let reference = scene("m.obj");
    let want: Vec<_> = (0..2).map(|i| render_view(&reference, i, 40)).collect();
    // the mesh casts something: more than one layer somewhere
    assert!(want.iter().all(|s| s.meta.layers >= 3));
    for name in &FORMATS[1..] {
        let s = scene(name);
        for (i, w) in want.iter().enumerate() {
            assert_eq!(&render_view(&s, i, 40), w, "{name} view {i}");
        }
    }
}

/// Rotates v by the unit quaternion q = (x, y, z, w): v + 2w(q×v) + 2 q×(q×v).
fn quat_rotate(q: [f64; 4], v: [f64; 3]) -> [f64; 3] {
    let c = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let u = [q[0], q[1], q[2]];
    let t = c(u, v);
    let tt = c(u, t);
    std::array::from_fn(|k| v[k] + 2.0 * q[3] * t[k] + 2.0 * tt[k])
}

#[test]
fn gltf_node_transforms_and_instances_are_applied() {
    // one triangle mesh with two primitives (u16 indices and non-indexed), used by two nodes:
    // node 0 (T·R·S) with child node 1 (a column-major matrix: translation (0, 1, 0) and a
    // scale of 3 along x), and node 2 at the origin.
    let tri: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]];
    let mut bin = Vec::new();
    for p in tri {
        for c in p {
            bin.extend(c.to_le_bytes());
        }
    }
    for i in [0u16, 2, 1] {
        bin.extend(i.to_le_bytes());
    }
    bin.extend([0u8; 2]);
    let (s2, c2) = (0.5f64.sqrt(), 0.5f64.sqrt()); // 90° about y: (0, sin 45°, 0, cos 45°)
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scenes":[{{"nodes":[0,2]}}],
        "nodes":[{{"translation":[1,2,3],"rotation":[0,{s2},0,{c2}],"scale":[2,2,2],"children":[1]}},
                 {{"mesh":0,"matrix":[3,0,0,0, 0,1,0,0, 0,0,1,0, 0,1,0,1]}},
                 {{"mesh":0}}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}},
                                 {{"attributes":{{"POSITION":0}}}}]}}],
        "buffers":[{{"byteLength":{}}}],
        "bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":36}},
                       {{"buffer":0,"byteOffset":36,"byteLength":6}}],
        "accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3",
                       "min":[0,0,0],"max":[1,0,1]}},
                     {{"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"}}]}}"#,
        bin.len()
    );
    let g = glb(&json, &bin);
    let tris = load_mesh("t.glb", &g, &|p| anyhow::bail!("no {p}")).unwrap();
    assert_eq!(tris.len(), 4);
    let q = [0.0, s2, 0.0, c2];
    let node1 = |p: [f64; 3]| [3.0 * p[0], p[1] + 1.0, p[2]];
    let node0 = |p: [f64; 3]| {
        let r = quat_rotate(q, p.map(|c| 2.0 * c));
        [r[0] + 1.0, r[1] + 2.0, r[2] + 3.0]
    };
    let t = tri.map(|p| p.map(|c| c as f64));
    let world = t.map(|p| node0(node1(p)));
    let close = |a: [[f64; 3]; 3], b: [[f64; 3]; 3]| {
        a.iter()
            .flatten()
            .zip(b.iter().flatten())
            .all(|(x, y)| (x - y).abs() < 1e-12)
    };
    assert!(
        close(tris[0], [world[0], world[2], world[1]]),
        "{:?}",
        tris[0]
    );
    assert!(close(tris[1], world), "{:?}", tris[1]);
    assert_eq!(tris[2], [t[0], t[2], t[1]]);
    assert_eq!(tris[3], t);
    // spot check: local (1, 0, 0) → child (3, 1, 0) → scaled (6, 2, 0) → rotated 90° about y
    // (x → −z) (0, 2, −6) → translated (1, 4, −3)
    assert!(
        close([tris[1][1]; 3], [[1.0, 4.0, -3.0]; 3]),
        "{:?}",
        tris[1][1]
    );
}

fn err(name: &str, bytes: &[u8]) -> String {
    let fs = files();
    let e = load_mesh(name, bytes, &reader(&fs))
        .err()
        .unwrap_or_else(|| panic!("{name} accepted"));
    let m = format!("{e:#}");
    assert!(!m.contains('\n'), "multi-line: {m}");
    m
}

#[test]
fn unsupported_misnamed_and_corrupt_files_are_one_line_errors() {
    let fs = files();
    let m = err("m.fbx", b"Kaydara FBX Binary");
    assert!(
        m.contains("FBX (.fbx) is not a supported mesh format"),
        "{m}"
    );
    let m = err("m.xyz", b"1 2 3");
    assert!(m.contains(".xyz format is not a supported"), "{m}");
    let m = err("mesh", b"v 0 0 0");
    assert!(m.contains("no file extension"), "{m}");
    // misnamed: content of another format
    for (name, real, what) in [
        ("m.obj", "m_ascii.ply", "PLY"),
        ("m.obj", "m.glb", "glTF (binary .glb)"),
        ("m.ply", "m_bin.stl", "STL"),
        ("m.stl", "m_le.ply", "PLY"),
        ("m.glb", "m_embedded.gltf", "glTF (JSON)"),
        ("m.gltf", "m.glb", "glTF (binary .glb)"),
    ] {
        let m = err(name, &fs[real]);
        assert!(m.contains(&format!("its content is {what}")), "{name}: {m}");
    }
    let m = err("m.ply", &fs["m.obj"]);
    assert!(m.contains("is not a PLY file"), "{m}");
    let m = err("m.stl", &fs["m.obj"]);
    assert!(m.contains("is not a STL file"), "{m}");
    let m = err("m.obj", &[0u8, 1, 2, 3, 0, 0]);
    assert!(m.contains("not a text OBJ"), "{m}");

    // truncated binary files and absurd counts
    let le = &fs["m_le.ply"];
    let m = err("m.ply", &le[..le.len() - 7]);
    assert!(m.contains("PLY element"), "{m}");
    let absurd = String::from_utf8_lossy(&fs["m_le.ply"])
        .replacen("element vertex 20", "element vertex 4000000000", 1)
        .into_bytes();
    let m = err("m.ply", &absurd);
    assert!(m.contains("declares 4000000000 records"), "{m}");
    let m = err(
        "m.ply",
        b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nend_header\n",
    );
    assert!(m.contains("no scalar property 'y'"), "{m}");
    let m = err(
        "m.ply",
        b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n3 0 1 2\n",
    );
    assert!(m.contains("vertex index 1 out of range"), "{m}");
    let st = &fs["m_bin.stl"];
    let m = err("m.stl", &st[..st.len() - 10]);
    assert!(
        m.contains("the header says") && m.contains("but the file has"),
        "{m}"
    );
    let mut st2 = st.clone();
    st2[80..84].copy_from_slice(&u32::MAX.to_le_bytes());
    let m = err("m.stl", &st2);
    assert!(
        m.contains("the header says") && m.contains("but the file has"),
        "{m}"
    );
    let m = err(
        "m.stl",
        b"solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nendloop\nendfacet\n",
    );
    assert!(m.contains("loop has 2 vertices"), "{m}");
    let g = &fs["m.glb"];
    let m = err("m.glb", &g[..g.len() - 40]);
    assert!(m.contains("glTF"), "{m}");
    // external buffer missing; a declared buffer longer than the data
    let m = err("m.gltf", &fs["sub/m_external.gltf"]);
    assert!(
        m.contains("glTF buffer 0") && m.contains("no file m.bin"),
        "{m}"
    );
    let short = String::from_utf8_lossy(&fs["m_embedded.gltf"])
        .replacen("\"byteLength\":", "\"byteLength\":1", 1)
        .into_bytes();
    let m = err("m.gltf", &short);
    assert!(m.contains("declares byteLength"), "{m}");
    // a primitive that is not triangles
    let lines = String::from_utf8_lossy(&fs["m_embedded.gltf"])
        .replacen("\"mode\":4", "\"mode\":1", 1)
        .into_bytes();
    let m = err("m.gltf", &lines);
    assert!(
        m.contains("mode Lines is not supported (only TRIANGLES)"),
        "{m}"
    );
}

/// The test mesh moved off the f32 grid: each coordinate plus a small irrational offset, in f64.
fn mesh_f64() -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    let (v, f) = mesh();
    let v = v
        .iter()
        .enumerate()
        .map(|(i, p)| {
            std::array::from_fn(|c| p[c] as f64 + 0.01 * ((3 * i + c) as f64).sin() / 3.0)
        })
        .collect();
    (v, f)
}

/// PLY of `v` with vertex properties of type `ty` ("float" or "double"): ASCII with every f64
/// digit (17 significant), or binary little endian rounded to the declared type.
fn ply_typed(v: &[[f64; 3]], f: &[[u32; 3]], ty: &str, ascii: bool) -> Vec<u8> {
    let fmt = if ascii {
        "ascii"
    } else {
        "binary_little_endian"
    };
    let mut out = format!(
        "ply\nformat {fmt} 1.0\nelement vertex {}\nproperty {ty} x\nproperty {ty} y\n\
         property {ty} z\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
        v.len(),
        f.len()
    )
    .into_bytes();
    for p in v {
        for c in p {
            match (ascii, ty) {
                (true, _) => out.extend(format!("{c:.16e} ").bytes()),
                (false, "float") => out.extend((*c as f32).to_le_bytes()),
                (false, _) => out.extend(c.to_le_bytes()),
            }
        }
        if ascii {
            out.push(b'\n');
        }
    }
    for t in f {
        if ascii {
            out.extend(format!("3 {} {} {}\n", t[0], t[1], t[2]).bytes());
        } else {
            out.push(3);
            t.iter().for_each(|i| out.extend((*i as i32).to_le_bytes()));
        }
    }
    out
}

/// ASCII STL of `v` with every f64 digit of each coordinate.
fn stl_ascii_f64(v: &[[f64; 3]], f: &[[u32; 3]]) -> Vec<u8> {
    let mut s = String::from("solid t\n");
    for t in f {
        s += "facet normal 0 0 0\nouter loop\n";
        for i in t {
            let p = v[*i as usize];
            s += &format!("vertex {:.16e} {:.16e} {:.16e}\n", p[0], p[1], p[2]);
        }
        s += "endloop\nendfacet\n";
    }
    (s + "endsolid t\n").into_bytes()
}

/// Declared precision is honoured: ASCII PLY `property float` and ASCII STL coordinates are
/// rounded to f32 like their binary encodings, so ASCII and binary files of the same mesh (off
/// the f32 grid) load the same triangles and render identical stacks; `property double` stays
/// f64 in both encodings.
#[test]
fn ascii_and_binary_ply_stl_of_one_mesh_render_identical_stacks() {
    let (v, f) = mesh_f64();
    let v32: Vec<V> = v.iter().map(|p| p.map(|c| c as f32)).collect();
    let mut fs = HashMap::new();
    fs.insert("a_float.ply".to_string(), ply_typed(&v, &f, "float", true));
    fs.insert("b_float.ply".to_string(), ply_typed(&v, &f, "float", false));
    fs.insert("a.stl".to_string(), stl_ascii_f64(&v, &f));
    fs.insert("b.stl".to_string(), stl_binary(&v32, &f));
    fs.insert(
        "a_double.ply".to_string(),
        ply_typed(&v, &f, "double", true),
    );
    fs.insert(
        "b_double.ply".to_string(),
        ply_typed(&v, &f, "double", false),
    );
    let as_f32: Vec<[[f64; 3]; 3]> = f
        .iter()
        .map(|t| t.map(|i| v32[i as usize].map(f64::from)))
        .collect();
    let as_f64: Vec<[[f64; 3]; 3]> = f.iter().map(|t| t.map(|i| v[i as usize])).collect();
    assert_ne!(
        as_f32, as_f64,
        "the mesh is on the f32 grid: the test shows nothing"
    );
    for (name, want) in [
        ("a_float.ply", &as_f32),
        ("b_float.ply", &as_f32),
        ("a.stl", &as_f32),
        ("b.stl", &as_f32),
        ("a_double.ply", &as_f64),
        ("b_double.ply", &as_f64),
    ] {
        let tris = load_mesh(name, &fs[name], &reader(&fs)).unwrap();
        assert_eq!(&tris, want, "{name}");
    }
    let stacks = |name: &str| {
        let text = format!(
            r#"{{"name":"m","lights":[{{"azimuth_deg":30,"elevation_deg":50}},{{"dir":[0.2,-1,0.1]}}],
            "objects":[{{"type":"plane","size":[6,6]}},{{"type":"mesh","path":"{name}"}}]}}"#
        );
        let s = Scene::from_json(&text, &reader(&fs)).unwrap();
        (0..2).map(|i| render_view(&s, i, 40)).collect::<Vec<_>>()
    };
    let want = stacks("b_float.ply");
    assert!(want.iter().all(|s| s.meta.layers >= 3));
    for name in ["a_float.ply", "a.stl", "b.stl"] {
        assert!(
            stacks(name) == want,
            "{name}: stacks differ from the binary PLY"
        );
    }
    assert!(stacks("a_double.ply") == stacks("b_double.ply"));
}
