//! STL meshes. Binary: an 80-byte header, a u32 (little endian) triangle count n, then n records
//! of 50 bytes (normal, three vertices as 3 × f32 LE, a u16 attribute); the file length must be
//! exactly 84 + 50·n. ASCII: `solid … facet normal … outer loop vertex x y z (×3) endloop
//! endfacet … endsolid`. Normals are ignored (the renderer uses the geometric normal).

use crate::render::scene::Tri;
use anyhow::{anyhow, bail, Result};

/// A binary STL: at least 84 bytes and exactly 84 + 50·n long for the stored count n.
pub(super) fn is_binary_stl(b: &[u8]) -> bool {
    if b.len() < 84 {
        return false;
    }
    let n = u32::from_le_bytes([b[80], b[81], b[82], b[83]]) as u64;
    84 + 50 * n == b.len() as u64
}

/// Triangles of an STL file (binary if its length matches its triangle count, else ASCII).
pub fn load_stl_bytes(b: &[u8]) -> Result<Vec<Tri>> {
    if is_binary_stl(b) {
        let n = (b.len() - 84) / 50;
        super::check_triangles(&|| "binary STL".to_string(), 0, n)?;
        let mut out = Vec::with_capacity(n);
        for rec in b[84..].chunks_exact(50) {
            let f = |k: usize| f32::from_le_bytes([rec[k], rec[k + 1], rec[k + 2], rec[k + 3]]);
            let v =
                |i: usize| -> [f64; 3] { std::array::from_fn(|c| f(12 + 12 * i + 4 * c) as f64) };
            out.push([v(0), v(1), v(2)]);
        }
        return Ok(out);
    }
    let start = b.iter().position(|c| !c.is_ascii_whitespace()).unwrap_or(0);
    // binary content (a binary header may start with "solid" too) whose length is wrong
    let binary = !b[start..].starts_with(b"solid") || std::str::from_utf8(b).is_err();
    if binary {
        if b.len() >= 84 {
            let n = u32::from_le_bytes([b[80], b[81], b[82], b[83]]);
            bail!(
                "binary STL: the header says {n} triangles ({} bytes) but the file has {} bytes",
                84 + 50 * n as u64,
                b.len()
            );
        }
        bail!("STL: neither binary (shorter than 84 bytes) nor ASCII (no 'solid')");
    }
    let text = std::str::from_utf8(b).map_err(|e| anyhow!("ASCII STL: not text ({e})"))?;
    let mut out = Vec::new();
    let mut loop_verts: Vec<[f64; 3]> = Vec::new();
    let mut in_loop = false;
    let mut toks = text.split_ascii_whitespace();
    let mut facet = 0usize;
    while let Some(t) = toks.next() {
        match t {
            "outer" => {
                if in_loop {
                    bail!("ASCII STL facet {facet}: 'outer loop' inside a loop");
                }
                in_loop = true;
                loop_verts.clear();
            }
            "vertex" => {
                if !in_loop {
                    bail!("ASCII STL facet {facet}: 'vertex' outside 'outer loop'");
                }
                let mut v = [0.0; 3];
                for c in &mut v {
                    let s = toks
                        .next()
                        .ok_or_else(|| anyhow!("ASCII STL facet {facet}: truncated vertex"))?;
                    // STL coordinates are f32 (as in the binary records): rounded once,
                    // from the text.
                    *c = s.parse::<f32>().map(f64::from).map_err(|_| {
                        anyhow!("ASCII STL facet {facet}: bad vertex coordinate '{s}'")
                    })?;
                }
                loop_verts.push(v);
            }
            "endloop" => {
                if !in_loop || loop_verts.len() != 3 {
                    bail!(
                        "ASCII STL facet {facet}: a loop has {} vertices (need 3)",
                        loop_verts.len()
                    );
                }
                out.push([loop_verts[0], loop_verts[1], loop_verts[2]]);
                in_loop = false;
                facet += 1;
            }
            _ => {}
        }
    }
    if in_loop {
        bail!("ASCII STL: truncated (facet {facet} has no 'endloop')");
    }
    Ok(out)
}
