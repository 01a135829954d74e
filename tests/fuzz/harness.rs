//! A fuzzing harness on stable Rust for every input parser of momentlab: OBJ, PLY, STL, glTF,
//! glb, the EXR depth stack (with its sidecar), the deep EXR, the scene JSON, basis catalogs,
//! basis formulas, and the `lp` and `shadow` JSON batches.
//!
//! Inputs per parser: a seed corpus (the committed fixtures where there are some, and small
//! valid files built here), structured generation (random but well-formed files of the format,
//! with random counts, types and values), and a seeded byte mutator over both (bit flips,
//! random and "interesting" bytes and numbers, insertions, deletions, duplications, splices,
//! truncation). Each input is parsed once and checked for
//!
//! * no panic (`catch_unwind`; an `Err` is the expected answer to bad input),
//! * no hang (a watchdog stops the run when one input takes longer than the time limit),
//! * no allocation beyond the input bound: the peak of live heap bytes allocated by the parsing
//!   thread during one input stays ≤ [`ALLOC_BASE`] + [`ALLOC_PER_BYTE`] × input length
//!   (a counting global allocator; allocations of helper threads are not counted).
//!
//! Shared by the CI test (`tests/fuzz/main.rs`, a short budget) and the offline run
//! (`cargo run --release --example fuzz -- --inputs N`), which writes `reports/fuzz/fuzz.json`.

#![allow(dead_code)]

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::panic::AssertUnwindSafe;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// Allowed peak heap of one parse: this many bytes …
pub const ALLOC_BASE: usize = 64 << 20;
/// … plus this many per input byte.
pub const ALLOC_PER_BYTE: usize = 256;

// ---- counting allocator ------------------------------------------------------------------------

thread_local! {
    static COUNTING: Cell<bool> = const { Cell::new(false) };
    static LIVE: Cell<isize> = const { Cell::new(0) };
    static PEAK: Cell<isize> = const { Cell::new(0) };
}

/// The system allocator, counting the live bytes of the thread that asked for counting.
pub struct Counting;

fn count(delta: isize) {
    let _ = COUNTING.try_with(|c| {
        if c.get() {
            let _ = LIVE.try_with(|l| {
                let v = l.get() + delta;
                l.set(v);
                let _ = PEAK.try_with(|p| {
                    if v > p.get() {
                        p.set(v)
                    }
                });
            });
        }
    });
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        count(l.size() as isize);
        System.alloc(l)
    }
    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        count(-(l.size() as isize));
        System.dealloc(p, l)
    }
    unsafe fn alloc_zeroed(&self, l: Layout) -> *mut u8 {
        count(l.size() as isize);
        System.alloc_zeroed(l)
    }
    unsafe fn realloc(&self, p: *mut u8, l: Layout, n: usize) -> *mut u8 {
        count(n as isize - l.size() as isize);
        System.realloc(p, l, n)
    }
}

/// Run `f` with this thread's allocations counted; returns its result and the peak live bytes.
fn counted<T>(f: impl FnOnce() -> T) -> (T, usize) {
    LIVE.with(|l| l.set(0));
    PEAK.with(|p| p.set(0));
    COUNTING.with(|c| c.set(true));
    let r = f();
    COUNTING.with(|c| c.set(false));
    (r, PEAK.with(|p| p.get()).max(0) as usize)
}

// ---- parsers -----------------------------------------------------------------------------------

/// Every fuzzed parser, by name.
pub const PARSERS: [&str; 12] = [
    "obj", "ply", "stl", "gltf", "glb", "exr", "deep-exr", "scene", "catalog", "formula", "lp",
    "shadow",
];

/// A small OBJ that the glTF buffer reader and the scene's mesh reader hand out.
const SMALL_OBJ: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";

/// Parse `input` with parser `name` (files for the EXR readers go to `scratch`). `Err` is fine.
fn parse(name: &str, input: &[u8], scratch: &Path) {
    let reader = |p: &str| -> anyhow::Result<Vec<u8>> {
        match p {
            "m.bin" => Ok(vec![0u8; 64]),
            _ => anyhow::bail!("no file {p}"),
        }
    };
    let text = || String::from_utf8_lossy(input).into_owned();
    match name {
        "obj" | "ply" | "stl" | "gltf" | "glb" => {
            let _ = momentlab::render::mesh::load_mesh(&format!("m.{name}"), input, &reader);
        }
        "exr" => {
            // The first byte chooses what is fuzzed: the .exr (sidecar valid) or the sidecar.
            let (exr, side) = match input.split_first() {
                Some((k, rest)) if k % 2 == 1 => (seed_exr().0.clone(), rest.to_vec()),
                Some((_, rest)) => (rest.to_vec(), seed_exr().1.clone()),
                None => (Vec::new(), Vec::new()),
            };
            let p = scratch.join("v.exr");
            std::fs::write(&p, exr).unwrap();
            std::fs::write(scratch.join("v.json"), side).unwrap();
            let _ = momentlab::stack::read(&p);
        }
        "deep-exr" => {
            if let Ok(img) = momentlab::stack::deep::read_deep(input) {
                let p = scratch.join("d.exr");
                std::fs::write(&p, input).unwrap();
                std::fs::write(scratch.join("d.json"), r#"{"light_dir": [0.2, -1, 0.1]}"#).unwrap();
                let _ = momentlab::stack::deep::read_deep_stack(&p, true);
                drop(img);
            }
        }
        "scene" => {
            let mesh = |p: &str| -> anyhow::Result<Vec<u8>> {
                if p.ends_with(".obj") {
                    Ok(SMALL_OBJ.as_bytes().to_vec())
                } else {
                    anyhow::bail!("no file {p}")
                }
            };
            let _ = momentlab::render::Scene::from_json(&text(), &mesh);
        }
        "catalog" => {
            let _ = momentlab::basis::Catalog::from_json(&text());
        }
        "formula" => {
            let _ = momentlab::basis::Function::parse(&text());
        }
        "lp" => {
            let _ = momentlab::batch::lp::solve_batch(&text(), catalog(), false);
        }
        "shadow" => {
            let _ = momentlab::batch::shadow::evaluate_batch(&text(), "fuzz");
        }
        _ => panic!("unknown parser {name}"),
    }
}

fn catalog() -> &'static momentlab::basis::Catalog {
    static C: std::sync::OnceLock<momentlab::basis::Catalog> = std::sync::OnceLock::new();
    C.get_or_init(momentlab::basis::Catalog::embedded)
}

/// A valid 6×5 depth stack (.exr bytes, sidecar bytes), rendered once.
fn seed_exr() -> &'static (Vec<u8>, Vec<u8>) {
    static S: std::sync::OnceLock<(Vec<u8>, Vec<u8>)> = std::sync::OnceLock::new();
    S.get_or_init(|| {
        let scene = momentlab::render::Scene::from_json(
            r#"{"name":"s","lights":[{"dir":[0.2,-1,0.1]}],"objects":[{"type":"plane","size":[4,4]},{"type":"box","size":[1,1,1],"transform":{"translate":[0,0.6,0]}}]}"#,
            &|p: &str| anyhow::bail!("no file {p}"),
        )
        .unwrap();
        let stack = momentlab::render::render_view(&scene, 0, 6);
        let dir = std::env::temp_dir().join(format!("momentlab-fuzz-seed-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        momentlab::stack::write(&dir.join("v.exr"), &stack).unwrap();
        let r = (
            std::fs::read(dir.join("v.exr")).unwrap(),
            std::fs::read(dir.join("v.json")).unwrap(),
        );
        let _ = std::fs::remove_dir_all(&dir);
        r
    })
}

// ---- seeds and structured generation -----------------------------------------------------------

/// The repository root (fixtures are read from there).
fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn cube() -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    let v = (0..8)
        .map(|i| [(i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32])
        .collect();
    let f = vec![
        [0, 2, 1],
        [1, 2, 3],
        [4, 5, 6],
        [5, 7, 6],
        [0, 1, 4],
        [1, 5, 4],
        [2, 6, 3],
        [3, 6, 7],
        [0, 4, 2],
        [2, 4, 6],
        [1, 3, 5],
        [3, 7, 5],
    ];
    (v, f)
}

fn gen_obj(r: &mut ChaCha8Rng, v: &[[f32; 3]], f: &[[u32; 3]]) -> Vec<u8> {
    let mut s = String::from("# fuzz\no cube\n");
    for p in v {
        s += &format!("v {} {} {}\n", p[0], p[1], p[2]);
    }
    if r.gen_bool(0.3) {
        s += "vt 0 0\nvn 0 0 1\n";
    }
    for t in f {
        match r.gen_range(0..4) {
            0 => s += &format!("f {}/1 {}/1 {}/1\n", t[0] + 1, t[1] + 1, t[2] + 1),
            1 => s += &format!("f {} {} {}\n", t[0] as i64 - v.len() as i64, -1, -2),
            _ => s += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1),
        }
    }
    s.into_bytes()
}

const PLY_TYPES: [(&str, usize); 8] = [
    ("char", 1),
    ("uchar", 1),
    ("short", 2),
    ("ushort", 2),
    ("int", 4),
    ("uint", 4),
    ("float", 4),
    ("double", 8),
];

fn gen_ply(r: &mut ChaCha8Rng, v: &[[f32; 3]], f: &[[u32; 3]]) -> Vec<u8> {
    let enc = ["ascii", "binary_little_endian", "binary_big_endian"][r.gen_range(0..3)];
    let (vt, vs) = PLY_TYPES[if r.gen_bool(0.5) {
        6
    } else {
        r.gen_range(0..8)
    }];
    let (it, is) = PLY_TYPES[[4usize, 5, 1, 3][r.gen_range(0..4)]];
    let extra = r.gen_bool(0.3);
    let mut out = format!(
        "ply\nformat {enc} 1.0\ncomment fuzz\nelement vertex {}\nproperty {vt} x\nproperty {vt} y\n\
         property {vt} z\n{}element face {}\nproperty list uchar {it} vertex_indices\nend_header\n",
        v.len(),
        if extra { "property uchar red\n" } else { "" },
        f.len()
    )
    .into_bytes();
    let put = |o: &mut Vec<u8>, x: f64, ty: &str, size: usize| {
        let mut b: Vec<u8> = match ty {
            "float" => (x as f32).to_le_bytes().to_vec(),
            "double" => x.to_le_bytes().to_vec(),
            _ => (x as i64).to_le_bytes()[..size].to_vec(),
        };
        if enc == "binary_big_endian" {
            b.reverse();
        }
        o.extend(b);
    };
    for p in v {
        if enc == "ascii" {
            out.extend(
                format!(
                    "{} {} {}{}\n",
                    p[0],
                    p[1],
                    p[2],
                    if extra { " 7" } else { "" }
                )
                .bytes(),
            );
        } else {
            for c in p {
                put(&mut out, *c as f64, vt, vs);
            }
            if extra {
                out.push(7);
            }
        }
    }
    for t in f {
        if enc == "ascii" {
            out.extend(format!("3 {} {} {}\n", t[0], t[1], t[2]).bytes());
        } else {
            out.push(3);
            for i in t {
                put(&mut out, *i as f64, it, is);
            }
        }
    }
    out
}

fn gen_stl(r: &mut ChaCha8Rng, v: &[[f32; 3]], f: &[[u32; 3]]) -> Vec<u8> {
    if r.gen_bool(0.5) {
        let mut s = String::from("solid fuzz\n");
        for t in f {
            s += "facet normal 0 0 1\nouter loop\n";
            for i in t {
                let p = v[*i as usize % v.len()];
                s += &format!("vertex {} {} {}\n", p[0], p[1], p[2]);
            }
            s += "endloop\nendfacet\n";
        }
        (s + "endsolid fuzz\n").into_bytes()
    } else {
        let mut out = vec![b' '; 80];
        out.extend((f.len() as u32).to_le_bytes());
        for t in f {
            out.extend([0u8; 12]);
            for i in t {
                for c in v[*i as usize % v.len()] {
                    out.extend(c.to_le_bytes());
                }
            }
            out.extend([0u8; 2]);
        }
        out
    }
}

/// glTF JSON and its binary buffer (positions f32, then u32 or u16 indices).
fn gen_gltf(r: &mut ChaCha8Rng, v: &[[f32; 3]], f: &[[u32; 3]]) -> (String, Vec<u8>) {
    let mut bin = Vec::new();
    for p in v {
        for c in p {
            bin.extend(c.to_le_bytes());
        }
    }
    let pos_len = bin.len();
    let short = r.gen_bool(0.5);
    for t in f {
        for i in t {
            if short {
                bin.extend((*i as u16).to_le_bytes());
            } else {
                bin.extend(i.to_le_bytes());
            }
        }
    }
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let b64 = {
        use base64::Engine;
        base64::engine::general_purpose::STANDARD.encode(&bin)
    };
    let uri = match r.gen_range(0..3) {
        0 => format!(r#","uri":"data:application/octet-stream;base64,{b64}""#),
        1 => r#","uri":"m.bin""#.to_string(),
        _ => String::new(),
    };
    let node = if r.gen_bool(0.5) {
        r#"{"mesh":0,"translation":[1,2,3],"scale":[2,2,2]}"#
    } else {
        r#"{"mesh":0,"matrix":[1,0,0,0,0,1,0,0,0,0,1,0,0,0,0,1]}"#
    };
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{node}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1,"mode":4}}]}}],
"buffers":[{{"byteLength":{}{uri}}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":{pos_len}}},{{"buffer":0,"byteOffset":{pos_len},"byteLength":{}}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":{},"type":"VEC3","min":[0,0,0],"max":[1,1,1]}},
{{"bufferView":1,"componentType":{},"count":{},"type":"SCALAR"}}]}}"#,
        bin.len(),
        f.len() * 3 * if short { 2 } else { 4 },
        v.len(),
        if short { 5123 } else { 5125 },
        f.len() * 3
    );
    (json, bin)
}

fn glb(json: &str, bin: &[u8]) -> Vec<u8> {
    let mut j = json.as_bytes().to_vec();
    while !j.len().is_multiple_of(4) {
        j.push(b' ');
    }
    let total = 12 + 8 + j.len() + 8 + bin.len();
    let mut out = Vec::new();
    out.extend(b"glTF");
    out.extend(2u32.to_le_bytes());
    out.extend((total as u32).to_le_bytes());
    out.extend((j.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(j);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(bin);
    out
}

/// A random mesh: the cube, moved, with some vertices dropped or duplicated.
fn gen_mesh(r: &mut ChaCha8Rng) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    let (mut v, mut f) = cube();
    let s: f32 = r.gen_range(-3.0..3.0);
    for p in &mut v {
        for c in p.iter_mut() {
            *c = *c * s + r.gen_range(-0.5..0.5);
        }
    }
    f.truncate(r.gen_range(1..=f.len()));
    if r.gen_bool(0.1) {
        f.push([0, 0, 9]); // an index out of range
    }
    (v, f)
}

const NUMBERS: [&str; 16] = [
    "0",
    "-0",
    "1",
    "-1",
    "1e308",
    "1e309",
    "-1e309",
    "NaN",
    "nan",
    "inf",
    "4294967295",
    "4294967296",
    "18446744073709551616",
    "9007199254740993",
    "1e-320",
    "0.5",
];

fn num(r: &mut ChaCha8Rng) -> String {
    if r.gen_bool(0.3) {
        NUMBERS[r.gen_range(0..NUMBERS.len())].to_string()
    } else {
        format!("{}", r.gen_range(-4.0f64..4.0))
    }
}

fn gen_formula(r: &mut ChaCha8Rng, depth: usize) -> String {
    let leaf = |r: &mut ChaCha8Rng| match r.gen_range(0..4) {
        0 => "z".to_string(),
        1 => num(r),
        2 => "pi".to_string(),
        _ => format!("{}", r.gen_range(0..5)),
    };
    if depth == 0 || r.gen_bool(0.3) {
        return leaf(r);
    }
    let a = gen_formula(r, depth - 1);
    let b = gen_formula(r, depth - 1);
    match r.gen_range(0..9) {
        0 => format!("({a} + {b})"),
        1 => format!("({a} - {b})"),
        2 => format!("({a} * {b})"),
        3 => format!("({a} / {b})"),
        4 => format!("{a}^{}", r.gen_range(-3..12)),
        5 => format!(
            "{}({a})",
            ["sin", "cos", "exp", "log", "sqrt", "abs", "tan", "atan"][r.gen_range(0..8)]
        ),
        6 => format!("-{a}"),
        7 => format!("z^{}", r.gen_range(1..7)),
        _ => format!("max({a}, {b})"),
    }
}

fn gen_catalog(r: &mut ChaCha8Rng) -> String {
    let n = r.gen_range(0..6);
    let fs: Vec<String> = (0..n)
        .map(|i| {
            format!(
                r#"{{"name": "f{i}", "formula": "{}"}}"#,
                gen_formula(r, 3).replace('"', "")
            )
        })
        .collect();
    format!(r#"{{"functions": [{}]}}"#, fs.join(", "))
}

fn gen_moments(r: &mut ChaCha8Rng, m: usize) -> String {
    let v: Vec<String> = (0..m).map(|_| num(r)).collect();
    format!("[{}]", v.join(", "))
}

fn gen_lp(r: &mut ChaCha8Rng) -> String {
    let basis = ["z", "z^2", "z^3", "z^4", "sin(z)", "exp(z)"];
    let m = r.gen_range(1..5);
    let b: Vec<String> = basis[..m].iter().map(|s| format!("\"{s}\"")).collect();
    let probs: Vec<String> = (0..r.gen_range(0..4))
        .map(|_| format!(r#"{{"moments": {}, "zf": {}}}"#, gen_moments(r, m), num(r)))
        .collect();
    let grid = if r.gen_bool(0.3) {
        format!(r#", "grid": {{"n": {}}}"#, r.gen_range(0..300))
    } else {
        String::new()
    };
    format!(
        r#"{{"basis": [{}], "problems": [{}]{grid}}}"#,
        b.join(", "),
        probs.join(", ")
    )
}

fn gen_shadow(r: &mut ChaCha8Rng) -> String {
    let (t, m) = [
        ("hamburger4", 4),
        ("hausdorff4", 4),
        ("vsm", 2),
        ("esm", 1),
        ("trig4", 4),
    ][r.gen_range(0..5)];
    let probs: Vec<String> = (0..r.gen_range(0..4))
        .map(|_| {
            let k = m + r.gen_range(0..2);
            format!(r#"{{"moments": {}, "zf": {}}}"#, gen_moments(r, k), num(r))
        })
        .collect();
    format!(
        r#"{{"technique": "{t}", "problems": [{}]}}"#,
        probs.join(", ")
    )
}

fn gen_scene(r: &mut ChaCha8Rng) -> String {
    let objs = [
        r#"{"type":"plane","size":[6,6]}"#.to_string(),
        format!(r#"{{"type":"box","size":[{},{},1]}}"#, num(r), num(r)),
        format!(r#"{{"type":"sphere","radius":{}}}"#, num(r)),
        format!(
            r#"{{"type":"mesh","path":"m.obj","transform":{{"translate":[0,{},0],"scale":{}}}}}"#,
            num(r),
            num(r)
        ),
    ];
    let k = r.gen_range(0..5);
    let chosen: Vec<String> = (0..k)
        .map(|_| objs[r.gen_range(0..objs.len())].clone())
        .collect();
    format!(
        r#"{{"name":"fz","lights":[{{"azimuth_deg":{},"elevation_deg":{}}},{{"dir":[0.2,-1,{}]}}],"objects":[{}]}}"#,
        num(r),
        num(r),
        num(r),
        chosen.join(",")
    )
}

/// A structured input for `parser`.
fn generate(parser: &str, r: &mut ChaCha8Rng) -> Vec<u8> {
    match parser {
        "obj" => {
            let (v, f) = gen_mesh(r);
            gen_obj(r, &v, &f)
        }
        "ply" => {
            let (v, f) = gen_mesh(r);
            gen_ply(r, &v, &f)
        }
        "stl" => {
            let (v, f) = gen_mesh(r);
            gen_stl(r, &v, &f)
        }
        "gltf" => {
            let (v, f) = gen_mesh(r);
            gen_gltf(r, &v, &f).0.into_bytes()
        }
        "glb" => {
            let (v, f) = gen_mesh(r);
            let (j, b) = gen_gltf(r, &v, &f);
            glb(&j, &b)
        }
        "exr" => {
            let (exr, side) = seed_exr();
            if r.gen_bool(0.5) {
                [&[0u8][..], exr].concat()
            } else {
                [&[1u8][..], side].concat()
            }
        }
        "scene" => gen_scene(r).into_bytes(),
        "catalog" => gen_catalog(r).into_bytes(),
        "formula" => gen_formula(r, 4).into_bytes(),
        "lp" => gen_lp(r).into_bytes(),
        "shadow" => gen_shadow(r).into_bytes(),
        _ => Vec::new(),
    }
}

/// The seed corpus of `parser`: committed fixtures and one generated file per variant.
pub fn seeds(parser: &str) -> Vec<Vec<u8>> {
    let mut out = Vec::new();
    let mut r = ChaCha8Rng::seed_from_u64(7);
    let read = |p: &str| std::fs::read(root().join(p)).ok();
    let findings = root().join("tests/fuzz/findings").join(parser);
    if let Ok(d) = std::fs::read_dir(&findings) {
        let mut ps: Vec<_> = d.filter_map(|e| e.ok()).map(|e| e.path()).collect();
        ps.sort();
        out.extend(ps.iter().filter_map(|p| std::fs::read(p).ok()));
    }
    match parser {
        "scene" => {
            for s in ["data/scenes/city.json", "data/scenes/stairs.json", "data/scenes/thin.json"]
            {
                out.extend(read(s));
            }
        }
        "catalog" => out.extend(read("basis_functions/catalog.json")),
        "deep-exr" => {
            for s in ["deep_nan", "deep_none", "deep_rle", "deep_unsorted", "deep_zips"] {
                out.extend(read(&format!("tests/fixtures/deep/{s}.exr")));
            }
        }
        "lp" => out.push(
            br#"{"basis": ["z", "z^2"], "problems": [{"moments": [0.5, 0.3], "zf": 0.6}]}"#
                .to_vec(),
        ),
        "shadow" => out.push(
            br#"{"technique": "hamburger4", "problems": [{"moments": [0.5, 0.3, 0.2, 0.15], "zf": 0.6}]}"#
                .to_vec(),
        ),
        _ => {}
    }
    for _ in 0..8 {
        out.push(generate(parser, &mut r));
    }
    out
}

// ---- mutation ----------------------------------------------------------------------------------

const INTERESTING: [&[u8]; 14] = [
    b"\x00",
    b"\xff",
    b"\x7f",
    b"\x80",
    b"\xff\xff\xff\xff",
    b"\xff\xff\xff\x7f",
    b"\x00\x00\x00\x80",
    b"\x00\x00\x80\x7f", // f32 +inf
    b"\x00\x00\xc0\x7f", // f32 NaN
    b"4294967295",
    b"-1",
    b"1e309",
    b"nan",
    b"99999999999",
];

/// One to four random edits of `data` (splices take from `other`).
pub fn mutate(r: &mut ChaCha8Rng, data: &[u8], other: &[u8]) -> Vec<u8> {
    let mut d = data.to_vec();
    for _ in 0..r.gen_range(1..=4) {
        let n = d.len();
        match r.gen_range(0..10) {
            0 if n > 0 => {
                let i = r.gen_range(0..n);
                d[i] ^= 1 << r.gen_range(0..8);
            }
            1 if n > 0 => {
                let i = r.gen_range(0..n);
                d[i] = r.gen();
            }
            2 => {
                let i = r.gen_range(0..=n);
                let k = r.gen_range(1..8);
                let bytes: Vec<u8> = (0..k).map(|_| r.gen()).collect();
                d.splice(i..i, bytes);
            }
            3 if n > 0 => {
                let i = r.gen_range(0..n);
                let k = r.gen_range(1..=(n - i).min(64));
                d.drain(i..i + k);
            }
            4 if n > 0 => {
                let i = r.gen_range(0..n);
                let k = r.gen_range(1..=(n - i).min(256));
                let chunk = d[i..i + k].to_vec();
                let j = r.gen_range(0..=n);
                d.splice(j..j, chunk);
            }
            5 if n > 0 => {
                let v = INTERESTING[r.gen_range(0..INTERESTING.len())];
                let i = r.gen_range(0..n);
                let e = (i + v.len()).min(n);
                d.splice(i..e, v.iter().copied());
            }
            6 if n > 0 => {
                // a number in text replaced by an interesting one
                let starts: Vec<usize> = (0..n)
                    .filter(|&i| d[i].is_ascii_digit() && (i == 0 || !d[i - 1].is_ascii_digit()))
                    .collect();
                if let Some(&i) = starts.get(r.gen_range(0..starts.len().max(1))) {
                    let e = (i..n).find(|&j| !d[j].is_ascii_digit()).unwrap_or(n);
                    let v = NUMBERS[r.gen_range(0..NUMBERS.len())];
                    d.splice(i..e, v.bytes());
                }
            }
            7 if n > 0 => {
                d.truncate(r.gen_range(0..n));
            }
            8 if !other.is_empty() && n > 0 => {
                let i = r.gen_range(0..n);
                let j = r.gen_range(0..other.len());
                let k = r.gen_range(1..=(other.len() - j).min(128));
                d.splice(i..i, other[j..j + k].iter().copied());
            }
            _ if n > 0 => {
                // overwrite a 4-byte little-endian word with a random count
                let i = r.gen_range(0..n);
                let e = (i + 4).min(n);
                let w: u32 = [0, 1, 255, 65535, 1 << 20, 1 << 30, u32::MAX][r.gen_range(0..7)];
                d.splice(i..e, w.to_le_bytes());
            }
            _ => d.push(r.gen()),
        }
    }
    d.truncate(1 << 20);
    d
}

// ---- the run -----------------------------------------------------------------------------------

/// Figures of one parser's run.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct ParserRun {
    pub parser: String,
    pub inputs: u64,
    pub failures: u64,
    pub panics: u64,
    pub hangs: u64,
    pub over_allocations: u64,
    /// Slowest input, seconds.
    pub max_seconds: f64,
    /// Largest peak heap of one input, bytes.
    pub max_peak_bytes: u64,
    /// Findings written (regression fixtures to be).
    pub findings: Vec<String>,
}

/// Options of [`run_parser`].
#[derive(Clone, Debug)]
pub struct Options {
    pub inputs: u64,
    pub seed: u64,
    /// Per-input time limit.
    pub limit: Duration,
    /// Where findings are written (one file per finding).
    pub findings: PathBuf,
}

thread_local! {
    static IN_PARSE: Cell<bool> = const { Cell::new(false) };
}

/// Panics inside a parse are counted, not printed; any other panic (of the harness) is.
fn quiet_panics() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let default = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if !IN_PARSE.with(|c| c.get()) {
                default(info)
            }
        }))
    });
}

/// `parse` under `catch_unwind` with its panic message suppressed.
fn guarded(parser: &str, input: &[u8], scratch: &Path) -> std::thread::Result<()> {
    IN_PARSE.with(|c| c.set(true));
    let r = std::panic::catch_unwind(AssertUnwindSafe(|| parse(parser, input, scratch)));
    IN_PARSE.with(|c| c.set(false));
    r
}

/// Run `opts.inputs` inputs through `parser`: every 4th a structured generation, the rest
/// mutations of a seed or of an earlier generation. A hang stops the process (the watchdog
/// writes the input as a finding first).
pub fn run_parser(parser: &str, opts: &Options) -> ParserRun {
    quiet_panics();
    let scratch = std::env::temp_dir().join(format!(
        "momentlab-fuzz-{}-{parser}-{}",
        std::process::id(),
        opts.seed
    ));
    let _ = std::fs::remove_dir_all(&scratch);
    std::fs::create_dir_all(&scratch).unwrap();
    std::fs::create_dir_all(&opts.findings).unwrap();
    let seeds = seeds(parser);
    let mut r = ChaCha8Rng::seed_from_u64(opts.seed ^ fxhash(parser));
    let mut run = ParserRun {
        parser: parser.into(),
        ..Default::default()
    };
    // The watchdog: the current input and when it started.
    let current = Arc::new(Mutex::new(Vec::<u8>::new()));
    let started_ms = Arc::new(AtomicU64::new(u64::MAX));
    let done = Arc::new(AtomicBool::new(false));
    let origin = Instant::now();
    let dog = {
        let (current, started_ms, done) = (current.clone(), started_ms.clone(), done.clone());
        let (limit, findings, parser) = (opts.limit, opts.findings.clone(), parser.to_string());
        std::thread::spawn(move || {
            while !done.load(Ordering::Relaxed) {
                std::thread::sleep(Duration::from_millis(50));
                let s = started_ms.load(Ordering::Relaxed);
                if s != u64::MAX
                    && origin.elapsed().as_millis() as u64 > s + limit.as_millis() as u64 * 3
                {
                    let input = current.lock().unwrap().clone();
                    let p = findings.join(format!("{parser}-hang.bin"));
                    let _ = std::fs::write(&p, &input);
                    eprintln!(
                        "fuzz: {parser}: an input ran past 3× the limit: {}",
                        p.display()
                    );
                    std::process::exit(3);
                }
            }
        })
    };
    let mut pool: Vec<Vec<u8>> = seeds.clone();
    for k in 0..opts.inputs {
        let input = if k % 4 == 0 {
            let g = generate(parser, &mut r);
            if pool.len() < 256 {
                pool.push(g.clone());
            } else {
                let i = r.gen_range(seeds.len().min(pool.len() - 1)..pool.len());
                pool[i] = g.clone();
            }
            g
        } else {
            let a = &pool[r.gen_range(0..pool.len())];
            let b = &pool[r.gen_range(0..pool.len())];
            mutate(&mut r, a, b)
        };
        current.lock().unwrap().clone_from(&input);
        let t = Instant::now();
        started_ms.store(origin.elapsed().as_millis() as u64, Ordering::Relaxed);
        let (res, peak) = counted(|| guarded(parser, &input, &scratch));
        started_ms.store(u64::MAX, Ordering::Relaxed);
        let secs = t.elapsed().as_secs_f64();
        run.inputs += 1;
        run.max_seconds = run.max_seconds.max(secs);
        run.max_peak_bytes = run.max_peak_bytes.max(peak as u64);
        let kind = if res.is_err() {
            run.panics += 1;
            Some("panic")
        } else if secs > opts.limit.as_secs_f64() {
            run.hangs += 1;
            Some("slow")
        } else if peak > ALLOC_BASE + ALLOC_PER_BYTE * input.len() {
            run.over_allocations += 1;
            Some("alloc")
        } else {
            None
        };
        if let Some(kind) = kind {
            run.failures += 1;
            if run.findings.len() < 20 {
                let p = opts
                    .findings
                    .join(format!("{parser}-{kind}-{:016x}.bin", fxhash_bytes(&input)));
                let _ = std::fs::write(&p, &input);
                run.findings.push(p.display().to_string());
            }
        }
    }
    done.store(true, Ordering::Relaxed);
    let _ = dog.join();
    let _ = std::fs::remove_dir_all(&scratch);
    run
}

fn fxhash(s: &str) -> u64 {
    fxhash_bytes(s.as_bytes())
}

fn fxhash_bytes(b: &[u8]) -> u64 {
    b.iter().fold(0xcbf29ce484222325u64, |h, &c| {
        (h ^ c as u64).wrapping_mul(0x100000001b3)
    })
}

/// Run every seed of `parser` (committed findings first) unmutated, with the same checks.
pub fn run_seeds(parser: &str, findings: &Path) -> ParserRun {
    quiet_panics();
    let scratch = std::env::temp_dir().join(format!(
        "momentlab-fuzz-seeds-{}-{parser}",
        std::process::id()
    ));
    std::fs::create_dir_all(&scratch).unwrap();
    std::fs::create_dir_all(findings).unwrap();
    let mut run = ParserRun {
        parser: parser.into(),
        ..Default::default()
    };
    for input in seeds(parser) {
        let t = Instant::now();
        let (res, peak) = counted(|| guarded(parser, &input, &scratch));
        run.inputs += 1;
        let secs = t.elapsed().as_secs_f64();
        run.max_seconds = run.max_seconds.max(secs);
        if res.is_err() || secs > 2.0 || peak > ALLOC_BASE + ALLOC_PER_BYTE * input.len() {
            run.failures += 1;
        }
    }
    let _ = std::fs::remove_dir_all(&scratch);
    run
}
