//! glTF 2.0 meshes (`.gltf` JSON with data-URI or external buffers, `.glb` binary): the default
//! scene (else the first), every node's mesh placed by the node's world matrix
//! M_world = M_parent · M_local, M_local = T · R · S (or the node's matrix, column-major), in
//! f64; every primitive of mode TRIANGLES (indexed or not). Other modes, sparse or quantized
//! position accessors are one-line errors. The document is parsed and validated by the `gltf`
//! crate; accessor data is read here with every offset, stride and count checked.

use crate::render::scene::Tri;
use anyhow::{anyhow, bail, Context, Result};
use base64::Engine;
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Mode;

type M4 = [[f64; 4]; 4]; // row-major: m[row][col]

const IDENTITY: M4 = [
    [1.0, 0.0, 0.0, 0.0],
    [0.0, 1.0, 0.0, 0.0],
    [0.0, 0.0, 1.0, 0.0],
    [0.0, 0.0, 0.0, 1.0],
];

fn mul(a: &M4, b: &M4) -> M4 {
    std::array::from_fn(|i| std::array::from_fn(|j| (0..4).map(|k| a[i][k] * b[k][j]).sum()))
}

/// The node's local matrix: its `matrix` (column-major in the file) or T · R(q) · S.
fn local_matrix(t: gltf::scene::Transform) -> Result<M4> {
    Ok(match t {
        gltf::scene::Transform::Matrix { matrix } => {
            std::array::from_fn(|i| std::array::from_fn(|j| matrix[j][i] as f64))
        }
        gltf::scene::Transform::Decomposed {
            translation,
            rotation,
            scale,
        } => {
            let q = rotation.map(|c| c as f64);
            let n = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
            if !(n.is_finite() && n > 0.0) {
                bail!("a node's rotation quaternion {rotation:?} is zero or not finite");
            }
            let [x, y, z, w] = q.map(|c| c / n);
            let r = [
                [
                    1.0 - 2.0 * (y * y + z * z),
                    2.0 * (x * y - z * w),
                    2.0 * (x * z + y * w),
                ],
                [
                    2.0 * (x * y + z * w),
                    1.0 - 2.0 * (x * x + z * z),
                    2.0 * (y * z - x * w),
                ],
                [
                    2.0 * (x * z - y * w),
                    2.0 * (y * z + x * w),
                    1.0 - 2.0 * (x * x + y * y),
                ],
            ];
            let s = scale.map(|c| c as f64);
            let mut m = IDENTITY;
            for i in 0..3 {
                for j in 0..3 {
                    m[i][j] = r[i][j] * s[j];
                }
                m[i][3] = translation[i] as f64;
            }
            m
        }
    })
}

/// The bytes of an accessor's elements: (data, stride, count) with every range checked.
fn accessor_bytes<'b>(
    acc: &gltf::Accessor,
    buffers: &'b [Vec<u8>],
    what: &str,
) -> Result<(&'b [u8], usize, usize)> {
    if acc.sparse().is_some() {
        bail!("{what}: sparse accessors are not supported");
    }
    let view = acc
        .view()
        .ok_or_else(|| anyhow!("{what}: accessor has no buffer view"))?;
    let data = &buffers[view.buffer().index()];
    let elem = acc.size();
    let stride = view.stride().unwrap_or(elem);
    let count = acc.count();
    if stride < elem {
        bail!("{what}: byte stride {stride} smaller than the element size {elem}");
    }
    let vend = view
        .offset()
        .checked_add(view.length())
        .filter(|&e| e <= data.len())
        .ok_or_else(|| {
            anyhow!(
                "{what}: buffer view {} runs past the end of its buffer ({} bytes)",
                view.index(),
                data.len()
            )
        })?;
    let vdata = &data[view.offset()..vend];
    if count == 0 {
        return Ok((&vdata[..0], stride, 0));
    }
    let end = (count - 1)
        .checked_mul(stride)
        .and_then(|x| x.checked_add(elem))
        .and_then(|x| x.checked_add(acc.offset()))
        .filter(|&e| e <= vdata.len())
        .ok_or_else(|| {
            anyhow!(
                "{what}: accessor {} ({count} elements) runs past the end of its buffer view",
                acc.index()
            )
        })?;
    Ok((&vdata[acc.offset()..end], stride, count))
}

fn read_positions(acc: &gltf::Accessor, buffers: &[Vec<u8>], what: &str) -> Result<Vec<[f64; 3]>> {
    if acc.dimensions() != Dimensions::Vec3 || acc.data_type() != DataType::F32 {
        bail!(
            "{what}: POSITION must be VEC3 of FLOAT, found {:?} of {:?}",
            acc.dimensions(),
            acc.data_type()
        );
    }
    let (d, stride, n) = accessor_bytes(acc, buffers, what)?;
    Ok((0..n)
        .map(|i| {
            let f = |c: usize| {
                let o = i * stride + 4 * c;
                f32::from_le_bytes([d[o], d[o + 1], d[o + 2], d[o + 3]]) as f64
            };
            [f(0), f(1), f(2)]
        })
        .collect())
}

fn read_indices(acc: &gltf::Accessor, buffers: &[Vec<u8>], what: &str) -> Result<Vec<usize>> {
    if acc.dimensions() != Dimensions::Scalar {
        bail!("{what}: indices must be SCALAR");
    }
    let (d, stride, n) = accessor_bytes(acc, buffers, what)?;
    let at = |i: usize| i * stride;
    Ok(match acc.data_type() {
        DataType::U8 => (0..n).map(|i| d[at(i)] as usize).collect(),
        DataType::U16 => (0..n)
            .map(|i| u16::from_le_bytes([d[at(i)], d[at(i) + 1]]) as usize)
            .collect(),
        DataType::U32 => (0..n)
            .map(|i| {
                let o = at(i);
                u32::from_le_bytes([d[o], d[o + 1], d[o + 2], d[o + 3]]) as usize
            })
            .collect(),
        t => bail!("{what}: index type {t:?} (need unsigned byte, short or int)"),
    })
}

/// The data of every buffer: the GLB's binary chunk or a base64 data URI or an external file;
/// at most [`Limit::MESH`](crate::artefact::Limit::MESH) in all (one file named by many buffers
/// counts each time).
fn load_buffers(g: &gltf::Gltf, resolve: &dyn Fn(&str) -> Result<Vec<u8>>) -> Result<Vec<Vec<u8>>> {
    let limit = crate::artefact::Limit::MESH;
    let mut total = 0u64;
    g.document
        .buffers()
        .map(|b| {
            let i = b.index();
            let data = match b.source() {
                gltf::buffer::Source::Bin => g.blob.clone().ok_or_else(|| {
                    anyhow!("glTF buffer {i} refers to a missing GLB binary chunk")
                })?,
                gltf::buffer::Source::Uri(uri) => {
                    if let Some(rest) = uri.strip_prefix("data:") {
                        let (_, b64) = rest
                            .split_once(";base64,")
                            .ok_or_else(|| anyhow!("glTF buffer {i}: data URI is not base64"))?;
                        base64::engine::general_purpose::STANDARD
                            .decode(b64)
                            .map_err(|e| anyhow!("glTF buffer {i}: bad base64 data ({e})"))?
                    } else if uri.contains("://") {
                        bail!(
                            "glTF buffer {i}: remote URI '{}' is not read; download it next to \
                             the .gltf",
                            uri.escape_debug()
                        );
                    } else {
                        resolve(uri).with_context(|| {
                            format!("glTF buffer {i} ('{}')", uri.escape_debug())
                        })?
                    }
                }
            };
            total += data.len() as u64;
            if total > limit.bytes {
                bail!("glTF buffer {i}: the buffers hold more than {limit} in all");
            }
            if data.len() < b.length() {
                bail!(
                    "glTF buffer {i}: {} bytes, but the file declares byteLength {}",
                    data.len(),
                    b.length()
                );
            }
            Ok(data)
        })
        .collect()
}

/// Largest node depth followed (guards against cyclic node graphs).
const MAX_DEPTH: usize = 256;

fn visit(
    node: gltf::Node,
    parent: &M4,
    depth: usize,
    buffers: &[Vec<u8>],
    out: &mut Vec<Tri>,
) -> Result<()> {
    if depth > MAX_DEPTH {
        bail!("glTF node graph deeper than {MAX_DEPTH} (a cycle?)");
    }
    let world = mul(
        parent,
        &local_matrix(node.transform()).with_context(|| format!("glTF node {}", node.index()))?,
    );
    if let Some(mesh) = node.mesh() {
        for prim in mesh.primitives() {
            let what = format!("glTF mesh {} primitive {}", mesh.index(), prim.index());
            if prim.mode() != Mode::Triangles {
                bail!(
                    "{what}: mode {:?} is not supported (only TRIANGLES)",
                    prim.mode()
                );
            }
            let pos = prim
                .get(&gltf::Semantic::Positions)
                .ok_or_else(|| anyhow!("{what}: no POSITION attribute"))?;
            let local = read_positions(&pos, buffers, &what)?;
            let verts: Vec<[f64; 3]> = local
                .iter()
                .map(|p| {
                    std::array::from_fn(|r| {
                        world[r][0] * p[0] + world[r][1] * p[1] + world[r][2] * p[2] + world[r][3]
                    })
                })
                .collect();
            let idx: Vec<usize> = match prim.indices() {
                Some(a) => read_indices(&a, buffers, &what)?,
                None => (0..verts.len()).collect(),
            };
            if !idx.len().is_multiple_of(3) {
                bail!("{what}: {} indices is not a multiple of 3", idx.len());
            }
            // a mesh instanced by many nodes adds its triangles once per node
            super::check_triangles(&|| what.clone(), out.len(), idx.len() / 3)?;
            for f in idx.chunks_exact(3) {
                let v = |i: usize| {
                    verts.get(i).copied().ok_or_else(|| {
                        anyhow!("{what}: index {i} out of range ({} vertices)", verts.len())
                    })
                };
                out.push([v(f[0])?, v(f[1])?, v(f[2])?]);
            }
        }
    }
    for c in node.children() {
        visit(c, &world, depth + 1, buffers, out)?;
    }
    Ok(())
}

/// Refuse a primitive whose attribute, morph target or index accessor is out of range before
/// the glTF crate validates the document (its validation indexes the POSITION accessor
/// unchecked and would panic). Anything that is not JSON is left to the crate's own errors.
fn check_accessor_indices(bytes: &[u8]) -> Result<()> {
    let Ok(g) = gltf::Gltf::from_slice_without_validation(bytes) else {
        return Ok(());
    };
    let root = g.document.as_json();
    let n = root.accessors.len();
    for (mi, m) in root.meshes.iter().enumerate() {
        for (pi, p) in m.primitives.iter().enumerate() {
            let mut refs: Vec<(String, usize)> = p
                .attributes
                .iter()
                .map(|(k, v)| (format!("attribute {k:?}"), v.value()))
                .collect();
            for t in p.targets.iter().flatten() {
                for (name, a) in [
                    ("POSITION", t.positions),
                    ("NORMAL", t.normals),
                    ("TANGENT", t.tangents),
                ] {
                    refs.extend(a.map(|a| (format!("morph target {name}"), a.value())));
                }
            }
            refs.extend(p.indices.map(|a| ("indices".to_string(), a.value())));
            if let Some((what, i)) = refs.into_iter().find(|r| r.1 >= n) {
                bail!(
                    "glTF: mesh {mi} primitive {pi}: {what} refers to accessor {i}, but the \
                     file has {n}"
                );
            }
        }
    }
    Ok(())
}

/// Triangles of a glTF 2.0 file (`.gltf` or `.glb` bytes); `resolve` reads external buffers.
pub fn load_gltf_bytes(
    bytes: &[u8],
    resolve: &dyn Fn(&str) -> Result<Vec<u8>>,
) -> Result<Vec<Tri>> {
    check_accessor_indices(bytes)?;
    let g = gltf::Gltf::from_slice(bytes).map_err(|e| anyhow!("glTF: {e}"))?;
    let buffers = load_buffers(&g, resolve)?;
    let scene = g
        .document
        .default_scene()
        .or_else(|| g.document.scenes().next())
        .ok_or_else(|| anyhow!("glTF has no scene"))?;
    let mut out = Vec::new();
    for n in scene.nodes() {
        visit(n, &IDENTITY, 0, &buffers, &mut out)?;
    }
    Ok(out)
}
