//! Deep OpenEXR images (single-part deep scan line, compression NONE, RLE or ZIPS), decoded
//! against the OpenEXR file layout ("OpenEXR File Layout", Deep Data): magic 76 2f 31 01, a
//! version word with the deep bit (0x800), a header of attributes, a table of chunk offsets, and
//! per scan line a chunk `y: i32, packed table size: u64, packed data size: u64, unpacked data
//! size: u64, pixel offset table, sample data`. The pixel offset table holds, per pixel, the
//! cumulative sample count of the line (i32); the sample data holds, per channel in header
//! order (alphabetical), every sample of the line left to right. RLE and ZIPS undo the
//! compressor (RLE runs, or zlib), then the byte predictor (t[i] += t[i−1] − 128) and the
//! split into two halves interleaved; a block whose packed size equals its unpacked size is
//! stored raw. Every offset, size and count is checked before use, and allocations are bounded
//! by the file's length, so a corrupt file is a one-line error.

use crate::artefact::{input, Limit};
use anyhow::{anyhow, bail, Context, Result};

pub use super::MAX_SIDE;
/// Largest number of samples in one pixel.
pub const MAX_SAMPLES_PER_PIXEL: usize = 1 << 16;

/// A channel's pixel type.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PixelType {
    /// 32-bit unsigned integer.
    Uint,
    /// 16-bit float.
    Half,
    /// 32-bit float.
    Float,
}

impl PixelType {
    fn size(self) -> usize {
        match self {
            PixelType::Half => 2,
            _ => 4,
        }
    }
}

/// The compressions OpenEXR allows for deep data that are read here.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DeepCompression {
    /// Uncompressed.
    None,
    /// Run-length encoded.
    Rle,
    /// zlib, one scan line per block.
    Zips,
}

/// A decoded deep image: per pixel (row-major, y = scan line from the top of the data window)
/// its samples; `values[c]` holds channel c's samples of all pixels in pixel order.
#[derive(Clone, Debug)]
pub struct DeepImage {
    /// Data-window width in pixels.
    pub width: usize,
    /// Data-window height in pixels.
    pub height: usize,
    /// Compression the file used.
    pub compression: DeepCompression,
    /// Channel names and types in file order.
    pub channels: Vec<(String, PixelType)>,
    /// Sample count of each pixel.
    pub counts: Vec<u32>,
    /// Start of each pixel's samples in `values[c]` (prefix sums of `counts`, one extra).
    pub starts: Vec<usize>,
    /// `values[c][starts[p] + k]`: channel c of sample k of pixel p.
    pub values: Vec<Vec<f32>>,
    /// How many of the pixel offset tables and sample blocks were stored compressed.
    pub compressed_blocks: usize,
}

impl DeepImage {
    /// The index of channel `name`, if present.
    pub fn channel(&self, name: &str) -> Option<usize> {
        self.channels.iter().position(|(n, _)| n == name)
    }
}

const MAGIC: [u8; 4] = [0x76, 0x2f, 0x31, 0x01];
const DEEP_BIT: u32 = 0x800;
const TILED_BIT: u32 = 0x200;
const MULTIPART_BIT: u32 = 0x1000;

/// Whether `bytes` start like an OpenEXR file with deep data (version bit 11), read from the
/// first 8 bytes only.
pub fn is_deep_exr(bytes: &[u8]) -> bool {
    bytes.len() >= 8
        && bytes[..4] == MAGIC
        && u32::from_le_bytes([bytes[4], bytes[5], bytes[6], bytes[7]]) & DEEP_BIT != 0
}

struct Cur<'a> {
    b: &'a [u8],
    pos: usize,
}

impl<'a> Cur<'a> {
    fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8]> {
        if self.b.len() - self.pos < n {
            bail!(
                "truncated file: {what} needs {n} bytes at offset {}, only {} left",
                self.pos,
                self.b.len() - self.pos
            );
        }
        let s = &self.b[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }
    fn u32(&mut self, what: &str) -> Result<u32> {
        let s = self.take(4, what)?;
        Ok(u32::from_le_bytes([s[0], s[1], s[2], s[3]]))
    }
    fn i32(&mut self, what: &str) -> Result<i32> {
        Ok(self.u32(what)? as i32)
    }
    fn u64(&mut self, what: &str) -> Result<u64> {
        let s = self.take(8, what)?;
        Ok(u64::from_le_bytes(s.try_into().expect("8 bytes")))
    }
    fn cstr(&mut self, what: &str) -> Result<&'a str> {
        let rest = &self.b[self.pos..];
        let n = match rest.iter().take(256).position(|&c| c == 0) {
            Some(n) => n,
            None if rest.len() < 256 => bail!(
                "truncated file: {what} at offset {} runs past the end",
                self.pos
            ),
            None => bail!("{what} at offset {} is longer than 255 bytes", self.pos),
        };
        let s = std::str::from_utf8(&rest[..n])
            .map_err(|_| anyhow!("{what} at offset {} is not text", self.pos))?;
        self.pos += n + 1;
        Ok(s)
    }
}

struct Header {
    channels: Vec<(String, PixelType)>,
    compression: DeepCompression,
    window: [i32; 4],
    kind: String,
}

fn read_header(c: &mut Cur) -> Result<Header> {
    let mut channels = None;
    let mut compression = None;
    let mut window = None;
    let mut kind = None;
    loop {
        let name = c.cstr("attribute name")?;
        if name.is_empty() {
            break;
        }
        let ty = c.cstr("attribute type")?;
        let size = c.i32("attribute size")?;
        if size < 0 {
            bail!("attribute '{name}' has negative size {size}");
        }
        let v = c.take(size as usize, &format!("attribute '{name}'"))?;
        match name {
            "channels" => {
                if ty != "chlist" {
                    bail!("attribute 'channels' has type '{ty}', expected chlist");
                }
                let mut cc = Cur { b: v, pos: 0 };
                let mut list = Vec::new();
                loop {
                    let n = cc.cstr("channel name")?;
                    if n.is_empty() {
                        break;
                    }
                    let pt = match cc.i32("channel pixel type")? {
                        0 => PixelType::Uint,
                        1 => PixelType::Half,
                        2 => PixelType::Float,
                        t => bail!("channel '{n}' has unknown pixel type {t}"),
                    };
                    cc.take(4, "channel flags")?;
                    let xs = cc.i32("channel x sampling")?;
                    let ys = cc.i32("channel y sampling")?;
                    if (xs, ys) != (1, 1) {
                        bail!("channel '{n}' is subsampled ({xs}x{ys}); deep channels must not be");
                    }
                    list.push((n.to_string(), pt));
                }
                channels = Some(list);
            }
            "compression" => {
                if v.len() != 1 {
                    bail!("attribute 'compression' has size {}", v.len());
                }
                compression = Some(match v[0] {
                    0 => DeepCompression::None,
                    1 => DeepCompression::Rle,
                    2 => DeepCompression::Zips,
                    3 => bail!(
                        "deep compression ZIP (16 scan lines per block) is not read; write the deep image with ZIPS, RLE or no compression"
                    ),
                    k => bail!("compression {k} is not allowed for deep data (only NONE, RLE, ZIPS, ZIP)"),
                });
            }
            "dataWindow" => {
                if v.len() != 16 {
                    bail!("attribute 'dataWindow' has size {}", v.len());
                }
                let mut cc = Cur { b: v, pos: 0 };
                let mut w = [0i32; 4];
                for x in &mut w {
                    *x = cc.i32("dataWindow")?;
                }
                window = Some(w);
            }
            "type" => {
                kind = Some(
                    String::from_utf8_lossy(v)
                        .trim_end_matches('\0')
                        .to_string(),
                );
            }
            _ => {}
        }
    }
    Ok(Header {
        channels: channels.ok_or_else(|| anyhow!("header has no 'channels' attribute"))?,
        compression: compression.ok_or_else(|| anyhow!("header has no 'compression'"))?,
        window: window.ok_or_else(|| anyhow!("header has no 'dataWindow'"))?,
        kind: kind.ok_or_else(|| anyhow!("header has no 'type' attribute"))?,
    })
}

/// Undoes RLE: a signed count byte n < 0 copies −n literal bytes, n ≥ 0 repeats the next byte
/// n + 1 times. The output must be exactly `out_len` bytes.
fn unrle(src: &[u8], out_len: usize) -> Result<Vec<u8>> {
    let mut out = Vec::with_capacity(out_len);
    let mut i = 0;
    while i < src.len() {
        let n = src[i] as i8;
        i += 1;
        if n < 0 {
            let k = -(n as i32) as usize;
            if src.len() - i < k || out.len() + k > out_len {
                bail!("corrupt RLE data");
            }
            out.extend_from_slice(&src[i..i + k]);
            i += k;
        } else {
            let k = n as usize + 1;
            if i >= src.len() || out.len() + k > out_len {
                bail!("corrupt RLE data");
            }
            out.resize(out.len() + k, src[i]);
            i += 1;
        }
    }
    if out.len() != out_len {
        bail!(
            "RLE data unpacks to {} bytes, expected {out_len}",
            out.len()
        );
    }
    Ok(out)
}

/// Undoes the predictor (t[i] = t[i−1] + t[i] − 128) and the interleave (first half of the
/// bytes to even positions, second half to odd ones) that RLE and ZIP apply before packing.
fn unpredict(mut t: Vec<u8>) -> Vec<u8> {
    for i in 1..t.len() {
        t[i] = t[i - 1].wrapping_add(t[i]).wrapping_sub(128);
    }
    let n = t.len();
    let half = n.div_ceil(2);
    let mut out = Vec::with_capacity(n);
    for i in 0..half {
        out.push(t[i]);
        if half + i < n {
            out.push(t[half + i]);
        }
    }
    out
}

fn unpack(comp: DeepCompression, src: &[u8], out_len: usize) -> Result<(Vec<u8>, bool)> {
    if src.len() == out_len || comp == DeepCompression::None {
        if src.len() != out_len {
            bail!(
                "uncompressed block has {} bytes, expected {out_len}",
                src.len()
            );
        }
        return Ok((src.to_vec(), false));
    }
    let raw = match comp {
        DeepCompression::Rle => unrle(src, out_len)?,
        DeepCompression::Zips => {
            let v = miniz_oxide::inflate::decompress_to_vec_zlib_with_limit(src, out_len)
                .map_err(|e| anyhow!("corrupt zlib data ({:?})", e.status))?;
            if v.len() != out_len {
                bail!("zlib data unpacks to {} bytes, expected {out_len}", v.len());
            }
            v
        }
        DeepCompression::None => unreachable!("handled above"),
    };
    Ok((unpredict(raw), true))
}

/// Sample counts and channel values of one scan line: (counts per pixel, values per channel).
type Line = (Vec<u32>, Vec<Vec<f32>>);

/// Decodes chunk `i` at byte `off` of `b`: (its line in the data window, the line, how many of
/// its two blocks were compressed). `lines` are those decoded so far (a line twice is refused).
fn read_chunk(
    b: &[u8],
    h: &Header,
    i: usize,
    off: usize,
    lines: &[Option<Line>],
) -> Result<(usize, Line, usize)> {
    let [x0, y0, x1, _] = h.window;
    let (w, hgt) = ((x1 as i64 - x0 as i64 + 1) as usize, lines.len());
    let psize: usize = h.channels.iter().map(|(_, t)| t.size()).sum();
    let mut k = Cur { b, pos: off };
    let ctx = || format!("chunk {i} at offset {off}");
    let y = k.i32("scan line y").with_context(ctx)?;
    let line = y as i64 - y0 as i64;
    if !(0..hgt as i64).contains(&line) {
        bail!("{}: scan line y = {y} outside the data window", ctx());
    }
    let line = line as usize;
    if lines[line].is_some() {
        bail!("{}: scan line y = {y} stored twice", ctx());
    }
    let tsize = k.u64("packed table size").with_context(ctx)?;
    let dsize = k.u64("packed sample size").with_context(ctx)?;
    let usize_ = k.u64("unpacked sample size").with_context(ctx)?;
    let left = (b.len() - k.pos) as u64;
    if tsize > left || dsize > left - tsize {
        bail!(
            "{}: packed sizes {tsize} + {dsize} run past the end of the file ({left} bytes left)",
            ctx()
        );
    }
    let tbytes = k.take(tsize as usize, "pixel offset table")?;
    let dbytes = k.take(dsize as usize, "sample data")?;
    let (table, zt) = unpack(h.compression, tbytes, 4 * w)
        .with_context(|| format!("{}: pixel offset table", ctx()))?;
    let mut prev = 0i64;
    let mut row = vec![0u32; w];
    for (x, cnt) in row.iter_mut().enumerate() {
        let v = i32::from_le_bytes(table[4 * x..4 * x + 4].try_into().expect("4 bytes")) as i64;
        let n = v - prev;
        if n < 0 {
            bail!(
                "{}: pixel offset table decreases at x = {} ({prev} then {v})",
                ctx(),
                x as i64 + x0 as i64
            );
        }
        if n as usize > MAX_SAMPLES_PER_PIXEL {
            bail!(
                "{}: pixel x = {} has {n} samples (more than {MAX_SAMPLES_PER_PIXEL})",
                ctx(),
                x as i64 + x0 as i64
            );
        }
        *cnt = n as u32;
        prev = v;
    }
    let total = prev as u64;
    let want = total * psize as u64;
    if usize_ != want {
        bail!(
            "{}: unpacked sample size {usize_} disagrees with {total} samples × {psize} bytes",
            ctx()
        );
    }
    // an unpacked size larger than any packing of this chunk's bytes could give is corrupt
    // (zlib expands at most ~1032:1, RLE 64:1): bounds the allocation by the file's length
    if want > (dsize + 64).saturating_mul(1100) {
        bail!(
            "{}: {want} unpacked bytes from {dsize} packed is impossible",
            ctx()
        );
    }
    let (data, zd) = unpack(h.compression, dbytes, want as usize)
        .with_context(|| format!("{}: sample data", ctx()))?;
    let chans = decode_channels(&h.channels, &data, total as usize);
    Ok((line, (row, chans), zt as usize + zd as usize))
}

/// The values of each channel (as f32) from a line's unpacked sample data of `n` samples.
fn decode_channels(channels: &[(String, PixelType)], data: &[u8], n: usize) -> Vec<Vec<f32>> {
    let mut chans = Vec::with_capacity(channels.len());
    let mut p = 0;
    for (_, t) in channels {
        let bytes = &data[p..p + n * t.size()];
        p += n * t.size();
        chans.push(match t {
            PixelType::Float => bytes
                .chunks_exact(4)
                .map(|q| f32::from_le_bytes([q[0], q[1], q[2], q[3]]))
                .collect(),
            PixelType::Uint => bytes
                .chunks_exact(4)
                .map(|q| u32::from_le_bytes([q[0], q[1], q[2], q[3]]) as f32)
                .collect(),
            PixelType::Half => bytes
                .chunks_exact(2)
                .map(|q| exr::prelude::f16::from_bits(u16::from_le_bytes([q[0], q[1]])).to_f32())
                .collect(),
        });
    }
    chans
}

/// Decodes a single-part deep scan line OpenEXR file.
pub fn read_deep(b: &[u8]) -> Result<DeepImage> {
    if b.len() < 8 || b[..4] != MAGIC {
        bail!("not an OpenEXR file (bad magic number)");
    }
    let mut c = Cur { b, pos: 4 };
    let version = c.u32("version")?;
    if version & 0xff != 2 {
        bail!("OpenEXR version {} is not 2", version & 0xff);
    }
    if version & MULTIPART_BIT != 0 {
        bail!("multi-part deep files are not read; write a single-part deep scan line image");
    }
    if version & DEEP_BIT == 0 {
        bail!("not a deep OpenEXR image");
    }
    if version & TILED_BIT != 0 {
        bail!("tiled deep images (deeptile) are not read; write deep scan lines");
    }
    let h = read_header(&mut c)?;
    if h.kind != "deepscanline" {
        bail!(
            "part type '{}' is not read; write a deep scan line image (deepscanline)",
            h.kind
        );
    }
    let [x0, y0, x1, y1] = h.window;
    let (w, hgt) = (x1 as i64 - x0 as i64 + 1, y1 as i64 - y0 as i64 + 1);
    if w < 1 || hgt < 1 || w > MAX_SIDE as i64 || hgt > MAX_SIDE as i64 {
        bail!("data window {w}x{hgt} outside 1..={MAX_SIDE} per side");
    }
    let (w, hgt) = (w as usize, hgt as usize);
    if h.channels.is_empty() {
        bail!("deep image has no channels");
    }
    // the offset table: one u64 per scan line (one line per chunk for NONE, RLE, ZIPS)
    let mut offsets = Vec::with_capacity(hgt);
    for i in 0..hgt {
        offsets.push(c.u64(&format!("chunk offset {i}"))?);
    }
    // per line (in any chunk order): its sample counts and channel values; allocated as lines
    // are decoded, so memory follows the data present, not the header's claims
    let mut lines: Vec<Option<Line>> = vec![None; hgt];
    let mut compressed_blocks = 0;
    for (i, &off) in offsets.iter().enumerate() {
        if off < c.pos as u64 || off >= b.len() as u64 {
            bail!(
                "chunk offset {i} ({off}) points outside the file ({} bytes)",
                b.len()
            );
        }
        let (line, decoded, compressed) = read_chunk(b, &h, i, off as usize, &lines)?;
        compressed_blocks += compressed;
        lines[line] = Some(decoded);
    }
    if let Some(i) = lines.iter().position(Option::is_none) {
        bail!("scan line {} has no chunk", i as i64 + y0 as i64);
    }
    let mut counts = Vec::with_capacity(w * hgt);
    let mut values: Vec<Vec<f32>> = vec![Vec::new(); h.channels.len()];
    for (row, chans) in lines.into_iter().flatten() {
        counts.extend(row);
        for (v, lc) in values.iter_mut().zip(chans) {
            v.extend(lc);
        }
    }
    let mut starts = Vec::with_capacity(w * hgt + 1);
    let mut s = 0usize;
    for &n in &counts {
        starts.push(s);
        s += n as usize;
    }
    starts.push(s);
    Ok(DeepImage {
        width: w,
        height: hgt,
        compression: h.compression,
        channels: h.channels,
        counts,
        starts,
        values,
        compressed_blocks,
    })
}

/// The sidecar of a deep image (`<name>.json`): only `light_dir` is required. `near`/`far`
/// (the Z of depth 0 and 1) default to the image's Z range widened by 1 % of it on each side
/// (as the renderer fits them); `scene` defaults to the file stem, `view` to "light0". Fields
/// of a stack sidecar (`width`, `height`, `layers`) may be present: width and height must
/// agree with the image, layers is recomputed.
#[derive(serde::Deserialize, Clone, Debug, Default)]
#[serde(deny_unknown_fields)]
pub struct DeepSidecar {
    /// Scene name of the stack (default: the file stem).
    pub scene: Option<String>,
    /// View name of the stack (default "light0").
    pub view: Option<String>,
    /// Direction the light travels (world space).
    pub light_dir: [f64; 3],
    /// Z of depth 0 (default: from the image's Z range).
    pub near: Option<f64>,
    /// Z of depth 1 (default: from the image's Z range).
    pub far: Option<f64>,
    /// Must equal the image width when given.
    pub width: Option<usize>,
    /// Must equal the image height when given.
    pub height: Option<usize>,
    /// Accepted and ignored: the layer count is recomputed from the samples.
    #[allow(dead_code)]
    pub layers: Option<usize>,
    /// See [`super::StackMeta::u_axis`].
    #[serde(default)]
    pub u_axis: [f64; 3],
    /// See [`super::StackMeta::v_axis`].
    #[serde(default)]
    pub v_axis: [f64; 3],
    /// See [`super::StackMeta::uv_origin`].
    #[serde(default)]
    pub uv_origin: [f64; 2],
    /// See [`super::StackMeta::texel_size`].
    #[serde(default)]
    pub texel_size: f64,
}

/// What the conversion met besides opaque surface samples.
#[derive(Clone, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct DeepStats {
    /// Samples in the file.
    pub samples: usize,
    /// Samples dropped because their alpha is 0 (they hide nothing).
    pub transparent: usize,
    /// Samples with 0 < alpha < 1 (kept as opaque surfaces).
    pub partial_alpha: usize,
    /// Samples with ZBack > Z (volumes; their front Z is the surface).
    pub volumetric: usize,
    /// Samples merged into the one in front (closer than the tolerance in depth).
    pub merged: usize,
}

/// Converts a deep image to a depth stack. Per pixel, the samples (Z, ZBack and A if present)
/// become opaque surfaces at depth z = (Z − near)/(far − near): samples with A = 0 are dropped,
/// a sample's ZBack must not be less than its Z, the samples must be sorted by Z (unless `sort`,
/// which sorts them), and samples closer than [`super::DEDUP_EPS`] in z to the kept one
/// in front of them are merged into it. Slopes per texel step ([`neighbour_slopes`]).
pub fn deep_to_stack(
    img: &DeepImage,
    side: &DeepSidecar,
    stem: &str,
    sort: bool,
) -> Result<(super::DepthStack, DeepStats)> {
    let (w, h) = (img.width, img.height);
    if side.width.is_some_and(|x| x != w) || side.height.is_some_and(|x| x != h) {
        bail!(
            "the sidecar says {}x{} but the deep image is {w}x{h}",
            side.width.unwrap_or(w),
            side.height.unwrap_or(h)
        );
    }
    let zc = img
        .channel("Z")
        .ok_or_else(|| anyhow!("deep image has no Z channel (channels: {})", names(img)))?;
    let mut stats = DeepStats {
        samples: img.values[zc].len(),
        ..Default::default()
    };
    let (zs, lo, hi) = pixel_samples(img, zc, sort, &mut stats)?;
    let (near, far) = match (side.near, side.far) {
        (Some(n), Some(f)) => (n, f),
        (None, None) => {
            if !lo.is_finite() {
                bail!("deep image has no opaque samples; give near and far in the sidecar");
            }
            let r = if hi > lo { hi - lo } else { lo.abs().max(1.0) };
            (lo - super::MARGIN * r, hi + super::MARGIN * r)
        }
        _ => bail!("the sidecar gives only one of near and far"),
    };
    if !(near.is_finite() && far.is_finite() && near < far) {
        bail!("near/far planes invalid: near={near} far={far}");
    }
    let layers_of = merged_depths(&zs, w, near, far, &mut stats)?;
    let layers = layers_of.iter().map(Vec::len).max().unwrap_or(0).max(1);
    let meta = super::StackMeta {
        scene: side.scene.clone().unwrap_or_else(|| stem.to_string()),
        view: side.view.clone().unwrap_or_else(|| "light0".into()),
        light_dir: side.light_dir,
        near,
        far,
        width: w,
        height: h,
        layers,
        u_axis: side.u_axis,
        v_axis: side.v_axis,
        uv_origin: side.uv_origin,
        texel_size: side.texel_size,
    };
    super::check_size(&meta)?;
    let n = w * h;
    let mut depth = vec![vec![f32::INFINITY; n]; layers];
    for (t, v) in layers_of.iter().enumerate() {
        for (l, &d) in v.iter().enumerate() {
            depth[l][t] = d;
        }
    }
    let (dzdu, dzdv) = neighbour_slopes(&depth, w, h);
    let st = super::DepthStack {
        meta,
        depth,
        dzdu,
        dzdv,
    };
    super::validate(&st)?;
    Ok((st, stats))
}

/// Per pixel, the Z of its kept samples (alpha > 0; checked: finite Z, ZBack ≥ Z, sorted by Z
/// unless `sort`), sorted; and the least and greatest kept Z. `zc` is the Z channel.
fn pixel_samples(
    img: &DeepImage,
    zc: usize,
    sort: bool,
    stats: &mut DeepStats,
) -> Result<(Vec<Vec<f64>>, f64, f64)> {
    let (w, h) = (img.width, img.height);
    let zb = img.channel("ZBack");
    let ac = img.channel("A");
    let at = |t: usize| (t % w, t / w);
    let mut zs: Vec<Vec<f64>> = Vec::with_capacity(w * h);
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for t in 0..w * h {
        let (x, y) = at(t);
        let mut v = Vec::with_capacity(img.counts[t] as usize);
        for s in img.starts[t]..img.starts[t + 1] {
            let z = img.values[zc][s] as f64;
            if !z.is_finite() {
                bail!(
                    "pixel (x={x}, y={y}) sample {}: Z = {z} is not finite",
                    s - img.starts[t]
                );
            }
            if let Some(b) = zb {
                let back = img.values[b][s] as f64;
                if back.is_nan() || back < z {
                    bail!(
                        "pixel (x={x}, y={y}) sample {}: ZBack = {back} is not ≥ Z = {z}",
                        s - img.starts[t]
                    );
                }
                stats.volumetric += (back > z) as usize;
            }
            if let Some(a) = ac {
                let a = img.values[a][s];
                if a.is_nan() {
                    bail!(
                        "pixel (x={x}, y={y}) sample {}: alpha is NaN",
                        s - img.starts[t]
                    );
                }
                if a == 0.0 {
                    stats.transparent += 1;
                    continue;
                }
                stats.partial_alpha += (a < 1.0) as usize;
            }
            if let Some(&p) = v.last() {
                if z < p && !sort {
                    bail!(
                        "pixel (x={x}, y={y}): samples not sorted by Z ({p} before {z}); \
                         import with --sort to sort them"
                    );
                }
            }
            v.push(z);
            lo = lo.min(z);
            hi = hi.max(z);
        }
        v.sort_by(f64::total_cmp);
        zs.push(v);
    }
    Ok((zs, lo, hi))
}

/// Per pixel, the depths z = (Z − near)/(far − near) of its samples `zs` (sorted), each within
/// [0, 1], a sample closer than [`super::DEDUP_EPS`] to the kept one in front merged into it.
fn merged_depths(
    zs: &[Vec<f64>],
    w: usize,
    near: f64,
    far: f64,
    stats: &mut DeepStats,
) -> Result<Vec<Vec<f32>>> {
    let at = |t: usize| (t % w, t / w);
    let range = far - near;
    let mut layers_of: Vec<Vec<f32>> = Vec::with_capacity(zs.len());
    for (t, v) in zs.iter().enumerate() {
        let (x, y) = at(t);
        let mut out: Vec<f32> = Vec::with_capacity(v.len());
        let mut last = f64::NEG_INFINITY;
        for &z in v {
            let d = (z - near) / range;
            if !(0.0..=1.0).contains(&d) {
                bail!(
                    "pixel (x={x}, y={y}): Z = {z} outside the sidecar's near..far = {near}..{far}"
                );
            }
            if d - last <= super::DEDUP_EPS {
                stats.merged += 1;
                continue;
            }
            last = d;
            out.push(d as f32);
        }
        layers_of.push(out);
    }
    Ok(layers_of)
}

fn names(img: &DeepImage) -> String {
    img.channels
        .iter()
        .map(|(n, _)| n.as_str())
        .collect::<Vec<_>>()
        .join(", ")
}

/// Receiver-plane slopes from neighbouring texels (a deep image has no normals). For a surface
/// at depth z in texel (x, y), z(x±1) is the depth in texel (x±1, y) closest to z (any layer);
/// ∂z/∂x is the one of z(x+1) − z and z − z(x−1) of smaller magnitude (one-sided where only one
/// neighbour has a surface, 0 where neither has); ∂z/∂y likewise with (x, y±1). Exact on a plane
/// that covers the neighbours; the smaller difference keeps a silhouette edge from giving a
/// steep slope to the surface in front of it.
pub fn neighbour_slopes(depth: &[Vec<f32>], w: usize, h: usize) -> (Vec<Vec<f32>>, Vec<Vec<f32>>) {
    let layers = depth.len();
    let closest = |t: usize, z: f32| -> Option<f32> {
        let mut best: Option<f32> = None;
        for l in depth {
            let d = l[t];
            if !d.is_finite() {
                break;
            }
            if best.is_none_or(|b| (d - z).abs() < (b - z).abs()) {
                best = Some(d);
            }
        }
        best
    };
    let pick = |z: f32, before: Option<f32>, after: Option<f32>| -> f32 {
        match (before.map(|b| z - b), after.map(|a| a - z)) {
            (Some(a), Some(b)) => {
                if a.abs() <= b.abs() {
                    a
                } else {
                    b
                }
            }
            (Some(a), None) | (None, Some(a)) => a,
            (None, None) => 0.0,
        }
    };
    let mut du = vec![vec![0.0f32; w * h]; layers];
    let mut dv = vec![vec![0.0f32; w * h]; layers];
    for l in 0..layers {
        for y in 0..h {
            for x in 0..w {
                let t = y * w + x;
                let z = depth[l][t];
                if !z.is_finite() {
                    continue;
                }
                let left = (x > 0).then(|| closest(t - 1, z)).flatten();
                let right = (x + 1 < w).then(|| closest(t + 1, z)).flatten();
                let up = (y > 0).then(|| closest(t - w, z)).flatten();
                let down = (y + 1 < h).then(|| closest(t + w, z)).flatten();
                du[l][t] = pick(z, left, right);
                dv[l][t] = pick(z, up, down);
            }
        }
    }
    (du, dv)
}

/// Reads a deep OpenEXR file and its sidecar (`<name>.json`) as a depth stack.
pub fn read_deep_stack(
    path: &std::path::Path,
    sort: bool,
) -> Result<(super::DepthStack, DeepStats)> {
    let side_path = super::sidecar_path(path);
    if std::fs::symlink_metadata(&side_path).is_err() {
        bail!(
            "missing sidecar {} (a deep image needs at least {{\"light_dir\": [x, y, z]}})",
            side_path.display()
        );
    }
    let text = input::read_text(&side_path, Limit::SIDECAR).context("reading sidecar")?;
    let bytes = input::read_bytes(path, Limit::DEEP)?;
    let img = read_deep(&bytes).context("deep OpenEXR")?;
    let side: DeepSidecar = serde_json::from_str(&text)
        .with_context(|| format!("malformed sidecar {}", side_path.display()))?;
    let stem = path
        .file_stem()
        .map_or("deep".into(), |s| s.to_string_lossy().to_string());
    deep_to_stack(&img, &side, &stem, sort)
}
