//! `momentlab tune`: per scene and over all scenes, the cheapest technique × storage × bias
//! setting within `--tolerance` of the best (library: `momentlab::tune`).

use super::common::{non_negative, stacks_or_default, usize_in, MAX_INPUTS, MAX_RESOLUTION};
use anyhow::{Context, Result};
use momentlab::artefact::{Checkpoint, OutDir};
use momentlab::progress::Bar;
use momentlab::tune::space::{parse_list, StorageKind, TechniqueKind};
use momentlab::tune::units::CHECKPOINT;
use momentlab::tune::{self, table::table, Options};
use std::path::PathBuf;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Depth stacks (default: render the embedded scenes, said so on stderr).
    #[arg(long)]
    pub stacks: Option<PathBuf>,
    /// Resolution when rendering the embedded scenes (16..=4096).
    #[arg(long, default_value_t = 512, value_parser = usize_in(16, MAX_RESOLUTION))]
    pub resolution: usize,
    /// Absolute error above the best setting that is acceptable (0.002 = 0.2 points; ≥ 0).
    #[arg(long, default_value_t = 0.002, value_parser = non_negative, allow_negative_numbers = true)]
    pub tolerance: f64,
    /// Techniques to search (repeatable; comma lists).
    #[arg(
        long,
        alias = "techniques",
        default_value = "vsm,esm,evsm,hamburger4,hausdorff4,hamburger6,tmsm"
    )]
    pub technique: Vec<String>,
    /// Comma-separated storages to search (f32, unorm16-theta, unorm16, f16).
    #[arg(long, default_value = "f32,unorm16-theta,unorm16,f16")]
    pub storages: String,
    /// Largest share of fragments whose shadow is more than 1/255 (one 8-bit display step) from
    /// the same technique on exact moments, for a setting to be feasible (0.001 = 0.1 %).
    #[arg(long, default_value_t = 0.001, value_parser = non_negative, allow_negative_numbers = true)]
    pub max_noise: f64,
    /// Fragments sampled per scene (1..=10000000).
    #[arg(long, default_value_t = 8192, value_parser = usize_in(1, MAX_INPUTS))]
    pub fragments: usize,
    /// Fragments per scene of the screening pass over the whole grid (1..=10000000).
    #[arg(long, default_value_t = 1024, value_parser = usize_in(1, MAX_INPUTS))]
    pub screen: usize,
    /// Settings per scene and family re-scored on all sampled fragments (1..=100).
    #[arg(long, default_value_t = 2, value_parser = usize_in(1, 100))]
    pub keep: usize,
    /// Seed of the fragment sample.
    #[arg(long, default_value_t = 2015)]
    pub seed: u64,
    /// Write tune.json and export/<scene>/ (setting.json, shadow.glsl/.hlsl/.wgsl) into this
    /// folder.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Replace existing files in --out.
    #[arg(long)]
    pub force: bool,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// The folder of the export inside --out.
const EXPORT_DIR: &str = "export";

/// The options of `args`; a one-line error for a bad list or an empty space.
pub fn options(args: &Args) -> Result<Options> {
    let tnames: Vec<&str> = TechniqueKind::ALL.iter().map(|t| t.name()).collect();
    let snames: Vec<&str> = StorageKind::ALL.iter().map(|s| s.name()).collect();
    let opts = Options {
        techniques: parse_list(
            "--technique",
            &super::common::technique_list(&args.technique).join(","),
            TechniqueKind::parse,
            &tnames,
        )?,
        storages: parse_list("--storages", &args.storages, StorageKind::parse, &snames)?,
        tolerance: args.tolerance,
        max_noise: args.max_noise,
        cost: Some(momentlab::gpu::cost::tune_cost),
        fragments_per_scene: args.fragments,
        screen_per_scene: args.screen.min(args.fragments),
        keep: args.keep,
        seed: args.seed,
        ..Options::default()
    };
    opts.check()?;
    Ok(opts)
}

pub fn run(args: Args) -> Result<()> {
    let opts = options(&args)?;
    let out = match &args.out {
        Some(dir) => {
            // Nothing in --out is replaced without --force, but what an interrupted tuning
            // wrote there (its checkpoint then resumes, or refuses other parameters, once the
            // stacks are loaded).
            OutDir::new(dir, args.force).context("--out")?;
            let resumable = Checkpoint::exists(dir, CHECKPOINT);
            let o = OutDir::new(dir, args.force || resumable).context("--out")?;
            o.reserve(["tune.json"]).context("--out")?;
            Some(o)
        }
        None => None,
    };
    // Before rendering and tuning: every file of the export can be written (inside --out, no
    // linked folder on the way, nothing replaced without --force). The export has a folder per
    // scene: the embedded dataset's scenes are known without rendering, given stacks are read
    // first.
    let reserve_export = |scenes: &[String]| -> Result<()> {
        match &out {
            Some(o) => o
                .reserve(tune::export::file_names(EXPORT_DIR, scenes))
                .context("--out"),
            None => Ok(()),
        }
    };
    if args.stacks.is_none() {
        let mut scenes: Vec<String> = Vec::new();
        for (scene, _) in momentlab::render::default_dataset_views()? {
            if !scenes.contains(&scene) {
                scenes.push(scene);
            }
        }
        reserve_export(&scenes)?;
    }
    let stacks = stacks_or_default(args.stacks.as_deref(), args.resolution, "tune")?;
    if args.stacks.is_some() {
        reserve_export(&tune::sample::scene_names(&stacks))?;
    }
    // With --out, the checkpoint: one unit per target (scene, all) and family of the α floors,
    // per setting screened and per setting confirmed; valid for the same options and stacks
    // (by content).
    let cp = match &args.out {
        Some(dir) => {
            let params = tune::units::params(&opts, &stacks);
            let cp = Checkpoint::open(dir, CHECKPOINT, params, args.force).context("--out")?;
            cp.start()?;
            if cp.resuming() {
                eprintln!(
                    "tune: resuming the interrupted run in {}: {} units (α floors, screened and \
                     confirmed settings) done",
                    cp.dir().display(),
                    cp.done()
                );
            }
            Some(cp)
        }
        None => None,
    };
    let bar = Bar::new("tune", 0);
    let store = cp.as_ref().map(|c| c as &dyn tune::units::UnitStore);
    let t = tune::tune_with(&stacks, &opts, &bar, store)?;
    if let Some(o) = &out {
        tune::export::write(o, EXPORT_DIR, &t)?;
        // Last: a folder with tune.json holds the whole tuning.
        o.write_json("tune.json", &t)?;
    }
    if let Some(cp) = cp {
        cp.finish()?;
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&t)?);
        return Ok(());
    }
    print!("{}", table(&t));
    Ok(())
}
