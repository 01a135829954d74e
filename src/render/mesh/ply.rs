//! PLY meshes (ASCII 1.0, binary_little_endian 1.0, binary_big_endian 1.0): the `vertex`
//! element's x, y, z properties and the `face` element's list property `vertex_indices` (or
//! `vertex_index`); polygons are fan-triangulated, other elements and properties skipped. Every
//! count is checked against the bytes left before anything is allocated.

use super::fan;
use crate::render::scene::Tri;
use anyhow::{anyhow, bail, Context, Result};

#[derive(Clone, Copy, Debug, PartialEq)]
enum Ty {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Ty {
    fn parse(s: &str) -> Option<Ty> {
        Some(match s {
            "char" | "int8" => Ty::I8,
            "uchar" | "uint8" => Ty::U8,
            "short" | "int16" => Ty::I16,
            "ushort" | "uint16" => Ty::U16,
            "int" | "int32" => Ty::I32,
            "uint" | "uint32" => Ty::U32,
            "float" | "float32" => Ty::F32,
            "double" | "float64" => Ty::F64,
            _ => return None,
        })
    }
    fn size(self) -> usize {
        match self {
            Ty::I8 | Ty::U8 => 1,
            Ty::I16 | Ty::U16 => 2,
            Ty::I32 | Ty::U32 | Ty::F32 => 4,
            Ty::F64 => 8,
        }
    }
    fn is_int(self) -> bool {
        !matches!(self, Ty::F32 | Ty::F64)
    }
}

#[derive(Debug)]
enum Prop {
    Scalar(String, Ty),
    /// name, count type, item type
    List(String, Ty, Ty),
}

#[derive(Debug)]
struct Element {
    name: String,
    count: usize,
    props: Vec<Prop>,
}

#[derive(Clone, Copy, PartialEq)]
enum Enc {
    Ascii,
    Le,
    Be,
}

/// A cursor over the body: binary values or ASCII tokens.
struct Body<'a> {
    b: &'a [u8],
    pos: usize,
    enc: Enc,
}

impl Body<'_> {
    fn left(&self) -> usize {
        self.b.len() - self.pos
    }
    fn token(&mut self) -> Result<&str> {
        while self.pos < self.b.len() && self.b[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        let s = self.pos;
        while self.pos < self.b.len() && !self.b[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        if s == self.pos {
            bail!("unexpected end of data");
        }
        std::str::from_utf8(&self.b[s..self.pos]).map_err(|_| anyhow!("non-ASCII value"))
    }
    fn value(&mut self, ty: Ty) -> Result<f64> {
        if self.enc == Enc::Ascii {
            let t = self.token()?;
            // A `float` property is an f32 in every encoding: its text is rounded to f32 as
            // declared (once, from the text), so ASCII and binary give the same mesh.
            let v: f64 = if ty == Ty::F32 {
                t.parse::<f32>().map(f64::from)
            } else {
                t.parse()
            }
            .map_err(|_| anyhow!("bad number '{t}'"))?;
            if ty.is_int() && v.fract() != 0.0 {
                bail!("'{t}' is not an integer");
            }
            return Ok(v);
        }
        let n = ty.size();
        if self.left() < n {
            bail!("unexpected end of data");
        }
        let mut a = [0u8; 8];
        a[..n].copy_from_slice(&self.b[self.pos..self.pos + n]);
        self.pos += n;
        if self.enc == Enc::Be {
            a[..n].reverse();
        }
        Ok(match ty {
            Ty::I8 => a[0] as i8 as f64,
            Ty::U8 => a[0] as f64,
            Ty::I16 => i16::from_le_bytes([a[0], a[1]]) as f64,
            Ty::U16 => u16::from_le_bytes([a[0], a[1]]) as f64,
            Ty::I32 => i32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
            Ty::U32 => u32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
            Ty::F32 => f32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
            Ty::F64 => f64::from_le_bytes(a),
        })
    }
    /// The smallest number of bytes one record of `e` takes (ASCII: one byte per value).
    fn min_record(&self, e: &Element) -> usize {
        e.props
            .iter()
            .map(|p| match (p, self.enc) {
                (_, Enc::Ascii) => 2,
                (Prop::Scalar(_, t), _) => t.size(),
                (Prop::List(_, c, _), _) => c.size(),
            })
            .sum::<usize>()
            .max(1)
    }
}

fn parse_header(b: &[u8]) -> Result<(Enc, Vec<Element>, usize)> {
    let end = b
        .windows(10)
        .position(|w| w == b"end_header")
        .ok_or_else(|| anyhow!("PLY header has no 'end_header'"))?;
    let mut body = end + 10;
    if b.get(body) == Some(&b'\r') {
        body += 1;
    }
    if b.get(body) != Some(&b'\n') {
        bail!("PLY: 'end_header' is not followed by a line break");
    }
    body += 1;
    let head = std::str::from_utf8(&b[..end]).map_err(|_| anyhow!("PLY header is not text"))?;
    let mut enc = None;
    let mut elems: Vec<Element> = Vec::new();
    for (i, line) in head.lines().enumerate() {
        let w: Vec<&str> = line.split_ascii_whitespace().collect();
        let ln = i + 1;
        match w.first().copied() {
            None | Some("comment") | Some("obj_info") => {}
            Some("ply") if i == 0 => {}
            Some("format") => {
                if w.len() != 3 || w[2] != "1.0" {
                    bail!("PLY header line {ln}: unsupported format line '{line}'");
                }
                enc = Some(match w[1] {
                    "ascii" => Enc::Ascii,
                    "binary_little_endian" => Enc::Le,
                    "binary_big_endian" => Enc::Be,
                    f => bail!("PLY header line {ln}: unknown format '{f}'"),
                });
            }
            Some("element") => {
                if w.len() != 3 {
                    bail!("PLY header line {ln}: expected 'element NAME COUNT'");
                }
                let count = w[2]
                    .parse()
                    .map_err(|_| anyhow!("PLY header line {ln}: bad element count '{}'", w[2]))?;
                elems.push(Element {
                    name: w[1].to_string(),
                    count,
                    props: Vec::new(),
                });
            }
            Some("property") => {
                let e = elems
                    .last_mut()
                    .ok_or_else(|| anyhow!("PLY header line {ln}: property before any element"))?;
                let ty = |s: &str| {
                    Ty::parse(s).ok_or_else(|| anyhow!("PLY header line {ln}: unknown type '{s}'"))
                };
                if w.get(1) == Some(&"list") {
                    if w.len() != 5 {
                        bail!("PLY header line {ln}: expected 'property list CTYPE ITYPE NAME'");
                    }
                    let c = ty(w[2])?;
                    if !c.is_int() {
                        bail!("PLY header line {ln}: list count type must be an integer type");
                    }
                    e.props.push(Prop::List(w[4].to_string(), c, ty(w[3])?));
                } else {
                    if w.len() != 3 {
                        bail!("PLY header line {ln}: expected 'property TYPE NAME'");
                    }
                    e.props.push(Prop::Scalar(w[2].to_string(), ty(w[1])?));
                }
            }
            Some(k) => bail!("PLY header line {ln}: unexpected '{k}'"),
        }
    }
    let enc = enc.ok_or_else(|| anyhow!("PLY header has no 'format' line"))?;
    Ok((enc, elems, body))
}

/// Triangles of a PLY file.
pub fn load_ply_bytes(b: &[u8]) -> Result<Vec<Tri>> {
    let (enc, elems, start) = parse_header(b)?;
    let mut body = Body { b, pos: start, enc };
    let vi = elems
        .iter()
        .position(|e| e.name == "vertex")
        .ok_or_else(|| anyhow!("PLY has no 'vertex' element"))?;
    let xyz: Vec<usize> = ["x", "y", "z"]
        .iter()
        .map(|n| {
            elems[vi]
                .props
                .iter()
                .position(|p| matches!(p, Prop::Scalar(m, _) if m == n))
                .ok_or_else(|| anyhow!("PLY vertex element has no scalar property '{n}'"))
        })
        .collect::<Result<_>>()?;
    let mut verts: Vec<[f64; 3]> = Vec::new();
    let mut tris = Vec::new();
    let mut faces_seen = false;
    for e in &elems {
        // every record takes at least min_record bytes: the count must fit in what is left
        if e.count > body.left() / body.min_record(e) {
            bail!(
                "PLY element '{}' declares {} records but only {} bytes are left",
                e.name,
                e.count,
                body.left()
            );
        }
        let is_vertex = e.name == "vertex";
        let face_prop = (e.name == "face").then(|| {
            e.props.iter().position(
                |p| matches!(p, Prop::List(n, _, _) if n == "vertex_indices" || n == "vertex_index"),
            )
        });
        if is_vertex {
            verts.reserve(e.count);
        }
        let mut idx = Vec::new();
        for r in 0..e.count {
            let mut v = [0.0; 3];
            let ctx = || format!("PLY element '{}' record {r}", e.name);
            for (k, p) in e.props.iter().enumerate() {
                match p {
                    Prop::Scalar(_, t) => {
                        let x = body.value(*t).with_context(ctx)?;
                        if is_vertex {
                            if let Some(c) = xyz.iter().position(|&j| j == k) {
                                v[c] = x;
                            }
                        }
                    }
                    Prop::List(_, ct, it) => {
                        let n = body.value(*ct).with_context(ctx)?;
                        if !(0.0..=1e9).contains(&n) {
                            bail!("{}: list length {n} out of range", ctx());
                        }
                        let n = n as usize;
                        let min = if enc == Enc::Ascii { 2 } else { it.size() };
                        if n > body.left() / min {
                            bail!(
                                "{}: list of {n} values runs past the end of the file",
                                ctx()
                            );
                        }
                        let wanted = face_prop == Some(Some(k));
                        if wanted {
                            idx.clear();
                        }
                        for _ in 0..n {
                            let x = body.value(*it).with_context(ctx)?;
                            if wanted {
                                if !(x >= 0.0 && x <= usize::MAX as f64) {
                                    bail!("{}: negative vertex index {x}", ctx());
                                }
                                idx.push(x as usize);
                            }
                        }
                        if wanted {
                            fan(&verts, &idx, &ctx, &mut tris)?;
                        }
                    }
                }
            }
            if is_vertex {
                verts.push(v);
            }
        }
        if e.name == "face" {
            faces_seen = true;
            if face_prop == Some(None) {
                bail!("PLY face element has no list property 'vertex_indices'");
            }
        }
    }
    if !faces_seen {
        bail!("PLY has no 'face' element (a point cloud has no triangles)");
    }
    Ok(tris)
}
