//! Depth-stack files: `<name>.exr` (single part, scan lines, ZIP16, one f32 channel per layer
//! and quantity: `layerNNN.Z`, `layerNNN.dzdu`, `layerNNN.dzdv`, row-major, y = row) plus the
//! JSON sidecar `<name>.json` (= [`StackMeta`]). Layout: docs/stacks.md.

use super::{check_size, sidecar_path, validate, DepthStack, StackMeta};
use crate::artefact::{input, Limit, OutDir};
use anyhow::{anyhow, bail, Context, Result};
use exr::prelude::*;
use std::path::{Path, PathBuf};

/// Channel name of `quantity` ("Z", "dzdu" or "dzdv") of layer `l`: `layer000.Z` etc.
pub fn channel_name(l: usize, quantity: &str) -> String {
    format!("layer{l:03}.{quantity}")
}

/// Writes `stack` to `path` (the `.exr`) and its sidecar (`.json` next to it), replacing
/// existing files. The stack is validated first; f32 values are stored losslessly (ZIP16),
/// +inf included. Commands write through [`write_to`] instead.
pub fn write(path: &Path, stack: &DepthStack) -> Result<()> {
    let stem = path
        .file_stem()
        .with_context(|| format!("{}: no file name", path.display()))?
        .to_string_lossy()
        .into_owned();
    let (dir, _) = OutDir::for_file(path, true)?;
    write_to(&dir, &stem, stack).map(|_| ())
}

/// The two file names of stack `stem` in an output folder: `<stem>.exr`, `<stem>.json`.
pub fn file_names(stem: &str) -> [String; 2] {
    [format!("{stem}.exr"), format!("{stem}.json")]
}

/// Writes `stack` as `<stem>.exr` + `<stem>.json` into `out` (the output writer: confined,
/// atomic, refused if they exist unless forced). Returns the path of the `.exr`.
pub fn write_to(out: &OutDir, stem: &str, stack: &DepthStack) -> Result<PathBuf> {
    let [exr_name, json_name] = file_names(stem);
    let path = out.path(&exr_name)?;
    validate(stack).with_context(|| format!("refusing to write {}", path.display()))?;
    let m = &stack.meta;
    let mut list: SmallVec<[AnyChannel<FlatSamples>; 4]> = SmallVec::new();
    for l in 0..m.layers {
        for (q, ch) in [
            ("Z", &stack.depth),
            ("dzdu", &stack.dzdu),
            ("dzdv", &stack.dzdv),
        ] {
            let name = Text::new_or_none(channel_name(l, q))
                .ok_or_else(|| anyhow!("channel name for layer {l} not representable"))?;
            list.push(AnyChannel::new(name, FlatSamples::F32(ch[l].clone())));
        }
    }
    let encoding = Encoding {
        compression: Compression::ZIP16,
        blocks: Blocks::ScanLines,
        line_order: LineOrder::Increasing,
    };
    let layer = Layer::new(
        (m.width, m.height),
        LayerAttributes::default(),
        encoding,
        AnyChannels::sort(list),
    );
    let image = Image::from_layer(layer);
    out.write_with(&exr_name, |f| {
        let mut w = std::io::BufWriter::new(f);
        image
            .write()
            .to_buffered(&mut w)
            .map_err(|e| anyhow!("encoding OpenEXR: {e}"))?;
        Ok(std::io::Write::flush(&mut w)?)
    })?;
    out.write_json(&json_name, m)?;
    Ok(path)
}

/// Reads and validates a depth stack: `path` is the `.exr`, the sidecar is `path` with `.json`.
/// Every error names the file (and layer / texel where relevant).
pub fn read(path: &Path) -> Result<DepthStack> {
    read_inner(path).with_context(|| format!("{}", path.display()))
}

fn read_inner(path: &Path) -> Result<DepthStack> {
    if is_deep_file(path)? {
        return Ok(super::deep::read_deep_stack(path, false)?.0);
    }
    let side = sidecar_path(path);
    if std::fs::symlink_metadata(&side).is_err() {
        bail!("missing sidecar {}", side.display());
    }
    let text = input::read_text(&side, Limit::SIDECAR).context("reading sidecar")?;
    let meta: StackMeta = serde_json::from_str(&text)
        .with_context(|| format!("malformed sidecar {}", side.display()))?;
    input::open_regular(path)?;
    check_size(&meta).with_context(|| format!("sidecar {}", side.display()))?;
    check_header(path, &meta)?;

    let image = exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_file(path)
        .map_err(|e| anyhow!("not a readable OpenEXR file: {e}"))?;
    if image.layer_data.len() != 1 {
        bail!(
            "expected a single-part EXR, found {} parts",
            image.layer_data.len()
        );
    }
    let layer = image
        .layer_data
        .into_iter()
        .next()
        .context("EXR has no part")?;
    let (w, h) = (layer.size.width(), layer.size.height());
    if (w, h) != (meta.width, meta.height) {
        bail!(
            "EXR is {w}x{h} but the sidecar says {}x{}",
            meta.width,
            meta.height
        );
    }
    let mut depth: Vec<Option<Vec<f32>>> = vec![None; meta.layers];
    let mut dzdu = depth.clone();
    let mut dzdv = depth.clone();
    for ch in layer.channel_data.list {
        let name = ch.name.to_string();
        let (l, q) = layer_channel(&name, meta.layers)?;
        let values = match ch.sample_data {
            FlatSamples::F32(v) => v,
            FlatSamples::F16(_) => bail!("channel '{name}' is half (f16); 32-bit float required"),
            FlatSamples::U32(_) => bail!("channel '{name}' is uint; 32-bit float required"),
        };
        if values.len() != w * h {
            bail!(
                "channel '{name}' has {} values, expected {w}x{h}",
                values.len()
            );
        }
        let slot = match q {
            Quantity::Z => &mut depth[l],
            Quantity::Dzdu => &mut dzdu[l],
            Quantity::Dzdv => &mut dzdv[l],
        };
        *slot = Some(values);
    }
    let take = |v: Vec<Option<Vec<f32>>>, q: &str| -> Result<Vec<Vec<f32>>> {
        v.into_iter()
            .enumerate()
            .map(|(l, c)| {
                c.ok_or_else(|| {
                    anyhow!(
                        "channel '{}' missing (sidecar says {} layers)",
                        channel_name(l, q),
                        meta.layers
                    )
                })
            })
            .collect()
    };
    let stack = DepthStack {
        depth: take(depth, "Z")?,
        dzdu: take(dzdu, "dzdu")?,
        dzdv: take(dzdv, "dzdv")?,
        meta,
    };
    validate(&stack)?;
    Ok(stack)
}

/// Whether `path` is a deep OpenEXR image (from its first 8 bytes).
pub fn is_deep_file(path: &Path) -> Result<bool> {
    use std::io::Read;
    let mut head = Vec::with_capacity(8);
    let (f, _) = input::open_regular(path)?;
    f.take(8)
        .read_to_end(&mut head)
        .with_context(|| format!("reading {}", path.display()))?;
    Ok(super::deep::is_deep_exr(&head))
}

/// From the EXR header alone (before decoding pixels): a single part of the sidecar's size,
/// stored with a lossless compression (docs/stacks.md: depths must survive bit-exactly).
fn check_header(path: &Path, meta: &StackMeta) -> Result<()> {
    let md = exr::meta::MetaData::read_from_file(path, false)
        .map_err(|e| anyhow!("not a readable OpenEXR file: {e}"))?;
    if md.headers.len() != 1 {
        bail!(
            "expected a single-part EXR, found {} parts",
            md.headers.len()
        );
    }
    let h = &md.headers[0];
    if h.compression.may_loose_data() {
        bail!(
            "EXR compression {:?} is lossy; depth stacks need a lossless one (ZIP, ZIPS, PIZ, RLE or none)",
            h.compression
        );
    }
    // Channel names and layers (the pixels of a channel are only decoded when it is expected),
    // one channel per layer and quantity: `layer0.Z` and `layer000.Z` together are refused.
    let mut seen: std::collections::HashMap<(usize, &'static str), String> = Default::default();
    for ch in &h.channels.list {
        let name = ch.name.to_string();
        let (l, q) = layer_channel(&name, meta.layers)?;
        if let Some(other) = seen.insert((l, q.name()), name.clone()) {
            bail!(
                "channels '{other}' and '{name}' are both layer {l}'s {}: one channel per \
                 layer and quantity",
                q.name()
            );
        }
    }
    let (w, hh) = (h.layer_size.width(), h.layer_size.height());
    if (w, hh) != (meta.width, meta.height) {
        bail!(
            "EXR is {w}x{hh} but the sidecar says {}x{}",
            meta.width,
            meta.height
        );
    }
    Ok(())
}

enum Quantity {
    Z,
    Dzdu,
    Dzdv,
}

impl Quantity {
    fn name(&self) -> &'static str {
        match self {
            Quantity::Z => "Z",
            Quantity::Dzdu => "dzdu",
            Quantity::Dzdv => "dzdv",
        }
    }
}

/// The layer and quantity of channel `name`, checked against the sidecar's layer count.
fn layer_channel(name: &str, layers: usize) -> Result<(usize, Quantity)> {
    let (l, q) = parse_channel(name).ok_or_else(|| {
        anyhow!("unexpected channel '{name}' (expected layerNNN.Z / .dzdu / .dzdv)")
    })?;
    if l >= layers {
        bail!("channel '{name}' is beyond the sidecar's layer count {layers}");
    }
    Ok((l, q))
}

fn parse_channel(name: &str) -> Option<(usize, Quantity)> {
    let rest = name.strip_prefix("layer")?;
    let (num, q) = rest.split_once('.')?;
    if num.is_empty() || !num.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    let l = num.parse().ok()?;
    let q = match q {
        "Z" => Quantity::Z,
        "dzdu" => Quantity::Dzdu,
        "dzdv" => Quantity::Dzdv,
        _ => return None,
    };
    Some((l, q))
}

/// The `.exr` entries of `dir` other than folders, sorted by file name (a link or device named
/// `.exr` is listed, so that reading it says what it is rather than skipping it).
pub fn exr_files(dir: &Path) -> Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    for entry in std::fs::read_dir(dir).with_context(|| format!("reading {}", dir.display()))? {
        let p = entry?.path();
        if !p.is_dir() && p.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr")) {
            files.push(p);
        }
    }
    files.sort_by(|a, b| a.file_name().cmp(&b.file_name()));
    Ok(files)
}

/// Reads every `.exr` depth stack in `dir` (sorted by file name). Errors if there is none.
pub fn load_dir(dir: &Path) -> Result<Vec<DepthStack>> {
    let files = exr_files(dir)?;
    if files.is_empty() {
        bail!("no .exr depth stacks in {}", dir.display());
    }
    files.iter().map(|p| read(p)).collect()
}
