//! `momentlab render`: ray-cast depth stacks of the scenes (embedded default dataset unless
//! `--scenes FOLDER|FILE`) and write one `<scene>_<view>.exr` + `.json` per view.

use super::common::resolution;
use anyhow::{bail, Context, Result};
use momentlab::artefact::OutDir;
use momentlab::progress::Bar;
use momentlab::render::scene::{LightDesc, UpAxis};
use momentlab::render::{self, Scene};
use momentlab::stack;
use std::path::PathBuf;
use std::time::Instant;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// A folder of scene JSON files, one scene file, or a mesh file (.gltf, .glb, .obj,
    /// .ply, .stl) rendered directly (default: the embedded dataset).
    #[arg(long)]
    pub scenes: Option<PathBuf>,
    /// A light for a mesh file given to --scenes: AZ,EL (degrees; where it comes from) or
    /// X,Y,Z (direction of travel); repeat for several views. Replaces the sidecar's lights.
    #[arg(long = "light", allow_hyphen_values = true)]
    pub lights: Vec<LightDesc>,
    /// Up axis of a mesh file given to --scenes (y or z; z-up meshes are turned −90° about X).
    #[arg(long)]
    pub up_axis: Option<UpAxis>,
    /// Output folder for the depth stacks (existing files there are refused unless --force).
    #[arg(long, default_value = "results/stacks/default")]
    pub out: PathBuf,
    /// Replace files that already exist in --out.
    #[arg(long)]
    pub force: bool,
    /// Shadow-map resolution (square; 16..=4096).
    #[arg(long, default_value_t = 512, value_parser = resolution())]
    pub resolution: usize,
    /// Render only the scene with this name.
    #[arg(long)]
    pub only: Option<String>,
    /// Also write `<scene>_<view>.preview.png`: front depth (near = bright) | layer count
    /// (viridis), the colours of every picture (docs/evaluation.md).
    #[arg(long)]
    pub preview: bool,
    /// Print one JSON object per run (views, files, fragments, layers) instead of the table.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: Args) -> Result<()> {
    let mut scenes: Vec<Scene> = match &args.scenes {
        Some(p) => render::load_scenes(p, &args.lights, args.up_axis)?,
        None => render::embedded_scenes()?,
    };
    if let Some(only) = &args.only {
        let names: Vec<String> = scenes.iter().map(|s| s.name.clone()).collect();
        scenes.retain(|s| &s.name == only);
        if scenes.is_empty() {
            bail!("--only {only}: no such scene (have: {})", names.join(", "));
        }
    }
    // Every file name before any rendering: two views with one name, or files already in
    // --out (without --force), are refused here.
    let out = OutDir::new(&args.out, args.force)?;
    let mut names = Vec::new();
    for s in &scenes {
        for light in &s.lights {
            let stem = format!("{}_{}", s.name, light.name);
            names.extend(stack::file_names(&stem));
            if args.preview {
                names.push(format!("{stem}.preview.png"));
            }
        }
    }
    out.reserve(&names).context("render")?;
    let views: usize = scenes.iter().map(|s| s.lights.len()).sum();
    let bar = Bar::new("render rows", (views * args.resolution) as u64);
    let start = Instant::now();
    let mut lines = Vec::new();
    let mut rows = Vec::new();
    let (mut total_frags, mut max_layers) = (0usize, 0usize);
    // Stacks written so far: a view that cannot be a stack (too many layers) fails the run
    // before its files are written, and the files of the views before it are removed, so the
    // run leaves no partial dataset behind.
    let mut written: Vec<String> = Vec::new();
    for s in &scenes {
        for (i, light) in s.lights.iter().enumerate() {
            bar.set_label(&format!("render rows ({}/{})", s.name, light.name));
            let t0 = Instant::now();
            let st = match render::render_view_with(s, i, args.resolution, &|k| bar.inc(k)) {
                Ok(st) => st,
                Err(e) => {
                    for n in &written {
                        out.remove(n)?;
                    }
                    return Err(e.context("render"));
                }
            };
            written.extend(stack::file_names(&st.file_stem()));
            if args.preview {
                written.push(format!("{}.preview.png", st.file_stem()));
            }
            let dt = t0.elapsed().as_secs_f64();
            let path = stack::write_to(&out, &st.file_stem(), &st)?;
            if args.preview {
                momentlab::report::pictures::write_png_to(
                    &out,
                    &format!("{}.preview.png", st.file_stem()),
                    &momentlab::report::pictures::preview_picture(&st),
                )?;
            }
            let frags = st.fragment_count();
            rows.push(serde_json::json!({
                "scene": s.name, "view": light.name, "file": path,
                "fragments": frags, "layers": st.meta.layers, "seconds": dt,
            }));
            let covered = (0..st.texel_count())
                .filter(|&t| st.depth[0][t].is_finite())
                .count();
            total_frags += frags;
            max_layers = max_layers.max(st.meta.layers);
            lines.push(format!(
                "{:>8} {:>7} {:>8} tris {:>10} fragments  {:>5.2} per covered texel  {:>3} layers  {:>6.2} s",
                s.name,
                light.name,
                s.triangles.len(),
                frags,
                frags as f64 / covered.max(1) as f64,
                st.meta.layers,
                dt
            ));
        }
    }
    bar.finish();
    if args.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&serde_json::json!({
                "resolution": args.resolution, "out": args.out, "views": rows,
                "fragments": total_frags, "max_layers": max_layers,
                "seconds": start.elapsed().as_secs_f64(),
            }))?
        );
        return Ok(());
    }
    for l in &lines {
        println!("{l}");
    }
    println!(
        "rendered {views} views at {r}x{r} in {:.2} s: {total_frags} fragments, at most {max_layers} layers -> {}",
        start.elapsed().as_secs_f64(),
        args.out.display(),
        r = args.resolution
    );
    Ok(())
}
