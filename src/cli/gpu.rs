//! `momentlab gpu check` and `momentlab gpu bench`: the shadow-map pipeline and the emitted
//! shader code run by the machine's GPU driver (src/gpu).

use super::common::{resolution, stacks_or_default, usize_in};
use anyhow::{bail, Context, Result};
use clap::Subcommand;
use momentlab::artefact::{read_text, Limit};
use momentlab::gpu::{bench, study, Gpu};
use momentlab::tune::space::{parse_list, Setting, StorageKind, TechniqueKind};
use std::path::{Path, PathBuf};

#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(subcommand)]
    pub what: What,
}

#[derive(Subcommand, Debug)]
pub enum What {
    /// Every technique × storage (or a tune export) on the GPU against the CPU model of the
    /// same pipeline, fragment by fragment; exit 1 naming the first that disagrees.
    Check(CheckArgs),
    /// Time per pass (encode, filter, lookup) against shadow-map size, filter size and output
    /// resolution: the paper's Figure 7 analogue, written as <out>/<adapter>.json and .svg.
    Bench(BenchArgs),
}

fn odd_taps(s: &str) -> std::result::Result<usize, String> {
    match s.trim().parse::<usize>() {
        Ok(t) if t % 2 == 1 && t <= 31 => Ok(t),
        _ => Err(format!("filter taps must be odd and at most 31, got '{s}'")),
    }
}

#[derive(clap::Args, Debug)]
pub struct BenchArgs {
    /// Shadow-map sizes (texels per edge, comma list) of the size axis.
    #[arg(long, value_delimiter = ',', default_value = "512,1024,2048,4096", value_parser = usize_in(1, 16384))]
    pub sizes: Vec<usize>,
    /// Filter taps per axis (odd, comma list) of the filter axis.
    #[arg(long, value_delimiter = ',', default_value = "3,9,15", value_parser = odd_taps)]
    pub filters: Vec<usize>,
    /// Output resolutions (pixels per edge = lookups per edge, comma list) of the output axis.
    #[arg(long, value_delimiter = ',', default_value = "128,256,512", value_parser = usize_in(1, 16384))]
    pub outputs: Vec<usize>,
    /// The base point the axes vary around: size, taps, output.
    #[arg(long, value_delimiter = ',', default_value = "512,9,256", value_parser = usize_in(1, 16384))]
    pub base: Vec<usize>,
    /// Timed runs per point (after one warm-up; 1..=100).
    #[arg(long, default_value_t = 3, value_parser = usize_in(1, 100))]
    pub repeats: usize,
    /// Timed runs per point whose shadow map's edge is at least --large-from (1..=100).
    #[arg(long, default_value_t = 2, value_parser = usize_in(1, 100))]
    pub repeats_large: usize,
    /// The edge (texels) from which a point counts as large.
    #[arg(long, default_value_t = 2048, value_parser = usize_in(1, 16384))]
    pub large_from: usize,
    /// Techniques (repeatable, comma lists).
    #[arg(
        long,
        default_value = "vsm,esm,evsm,hamburger4,hausdorff4,hamburger6,tmsm"
    )]
    pub technique: Vec<String>,
    /// Storages (repeatable, comma lists).
    #[arg(long, default_value = "f32,unorm16-theta,unorm16,f16")]
    pub storage: Vec<String>,
    /// Output folder: <out>/<adapter>.json and <out>/<adapter>_{size,filter,output}.svg.
    #[arg(long, default_value = "results/gpu")]
    pub out: PathBuf,
    /// Replace existing files.
    #[arg(long)]
    pub force: bool,
}

#[derive(clap::Args, Debug)]
pub struct CheckArgs {
    /// Depth stacks (default: render the embedded scenes, said so on stderr).
    #[arg(long)]
    pub stacks: Option<PathBuf>,
    /// Resolution when rendering the embedded scenes (16..=4096).
    #[arg(long, default_value_t = 64, value_parser = resolution())]
    pub resolution: usize,
    /// Techniques (repeatable, comma lists): vsm, esm, evsm, hamburger4, hausdorff4, hamburger6, tmsm.
    #[arg(
        long,
        default_value = "vsm,esm,evsm,hamburger4,hausdorff4,hamburger6,tmsm"
    )]
    pub technique: Vec<String>,
    /// Storages (repeatable, comma lists): f32, unorm16-theta, unorm16, f16.
    #[arg(long, default_value = "f32,unorm16-theta,unorm16,f16")]
    pub storage: Vec<String>,
    /// Check these tune exports instead (folders with setting.json and shadow.wgsl, as
    /// written by `momentlab tune`); the shipped shader text is what runs. Repeatable.
    #[arg(long)]
    pub export: Vec<PathBuf>,
    /// Receivers per view at most (a regular subsample of the fragments; 1..=10000000).
    #[arg(long, default_value_t = 4_000, value_parser = usize_in(1, 10_000_000))]
    pub receivers: usize,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: Args) -> Result<()> {
    match args.what {
        What::Check(a) => check(a),
        What::Bench(a) => bench_cmd(a),
    }
}

/// setting.json of a tune export: the setting and the shader files.
#[derive(serde::Deserialize)]
struct ExportFile {
    setting: Setting,
}

fn export_setting(dir: &Path) -> Result<(Setting, String)> {
    let sj = dir.join("setting.json");
    let text = read_text(&sj, Limit::BATCH)?;
    let e: ExportFile = serde_json::from_str(&text)
        .with_context(|| format!("{}: not a tune export", sj.display()))?;
    let wgsl = read_text(&dir.join("shadow.wgsl"), Limit::BATCH)?;
    Ok((e.setting, wgsl))
}

/// The settings of `--technique` × `--storage` (an error names a bad item or an empty space).
fn settings(technique: &[String], storage: &[String]) -> Result<Vec<Setting>> {
    let (technique, storage) = (technique.join(","), storage.join(","));
    let techniques = parse_list(
        "--technique",
        &technique,
        TechniqueKind::parse,
        &TechniqueKind::ALL.map(|t| t.name()),
    )?;
    let storages = parse_list(
        "--storage",
        &storage,
        StorageKind::parse,
        &StorageKind::ALL.map(|s| s.name()),
    )?;
    let v: Vec<Setting> = study::settings()
        .into_iter()
        .filter(|s| {
            techniques.contains(&s.family.technique) && storages.contains(&s.family.storage)
        })
        .collect();
    if v.is_empty() {
        bail!("--technique/--storage: no technique uses any of the storages asked for");
    }
    Ok(v)
}

fn bench_cmd(args: BenchArgs) -> Result<()> {
    let settings = settings(&args.technique, &args.storage)?;
    if args.base.len() != 3 || args.base[1].is_multiple_of(2) {
        bail!(
            "--base: expected size,taps,output with odd taps, got {:?}",
            args.base
        );
    }
    let plan = bench::Plan {
        sizes: args.sizes.clone(),
        filters: args.filters.clone(),
        outputs: args.outputs.clone(),
        base: (args.base[0], args.base[1], args.base[2]),
        repeats: args.repeats,
        repeats_large: args.repeats_large,
        large_from: args.large_from,
    };
    let out = momentlab::artefact::OutDir::new(&args.out, args.force).context("--out")?;
    let gpu = Gpu::new()?;
    let stem = gpu.adapter.file_stem();
    let files: Vec<String> = std::iter::once(format!("{stem}.json"))
        .chain(["size", "filter", "output"].map(|a| format!("{stem}_{a}.svg")))
        .collect();
    out.reserve(&files)?;
    eprintln!("gpu bench: {}", gpu.adapter.label());
    let src = momentlab::render::default_dataset(128)?;
    let view = src
        .iter()
        .max_by_key(|s| s.fragment_count())
        .expect("the default dataset has views");
    let bar = momentlab::progress::Bar::new(
        "gpu bench",
        (settings.len() * (plan.sizes.len() + plan.filters.len() + plan.outputs.len())) as u64,
    );
    let report = bench::run(&gpu, &plan, &settings, view, |_| bar.inc(1))?;
    bar.finish();
    out.write_json(&files[0], &report)?;
    for (axis, svg) in momentlab::report::gpu::gpu_charts(&report)? {
        out.write_text(&format!("{stem}_{axis}.svg"), &svg)?;
    }
    println!(
        "gpu bench: {} points in {:.0} s on {} → {}",
        report.points.len(),
        report.seconds,
        gpu.adapter.label(),
        args.out.join(&files[0]).display()
    );
    Ok(())
}

fn check(args: CheckArgs) -> Result<()> {
    // the settings first: a bad list or export is an error before any GPU or rendering work
    let runs: Vec<(Setting, Option<String>)> = if args.export.is_empty() {
        settings(&args.technique, &args.storage)?
            .into_iter()
            .map(|s| (s, None))
            .collect()
    } else {
        args.export
            .iter()
            .map(|d| export_setting(d).map(|(s, w)| (s, Some(w))))
            .collect::<Result<_>>()?
    };
    let gpu = Gpu::new()?;
    eprintln!("gpu check: {}", gpu.adapter.label());
    let stacks = stacks_or_default(args.stacks.as_deref(), args.resolution, "gpu check")?;
    let mut verdicts = Vec::new();
    for (s, wgsl) in &runs {
        for stack in &stacks {
            let v = study::check_setting(&gpu, s, wgsl.as_deref(), stack, args.receivers)?;
            if !args.json {
                println!(
                    "{:<4} {}: encode ≤ {:.1} {}, map ≤ {:.1} steps, G ≤ {:.1e} from the model on its own map ({:.3} % beyond tolerance); whole model: mean {:.1e}, {:.3} % above 1/255",
                    if v.passed { "ok" } else { "FAIL" },
                    v.label,
                    v.encode_steps,
                    if v.encode_bound > 1.0 { "ulp" } else { "codes" },
                    v.map_steps,
                    v.g_max,
                    100.0 * v.g_outliers,
                    v.pipeline_mean,
                    100.0 * v.pipeline_above_8bit
                );
            }
            verdicts.push(v);
        }
    }
    if args.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&serde_json::json!({
                "adapter": gpu.adapter,
                "verdicts": verdicts,
            }))?
        );
    }
    if let Some(f) = verdicts.iter().find_map(|v| v.failure()) {
        let n = verdicts.iter().filter(|v| !v.passed).count();
        bail!("gpu check: {n} of {} disagree; first: {f}", verdicts.len());
    }
    Ok(())
}
