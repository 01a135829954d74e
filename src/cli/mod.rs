//! The command-line layer: parses arguments, reads and writes files, shows progress bars, and
//! calls the library. No numerics here. One file per subcommand.

pub mod bench;
pub mod bench_lp;
pub mod bench_shadow;
pub mod candidates;
pub mod common;
pub mod evaluate;
pub mod gpu;
pub mod import;
pub mod lp;
pub mod merge;
pub mod plan;
pub mod quantize;
pub mod render;
pub mod reproduce;
pub mod search;
pub mod shadow;
pub mod stability;
pub mod theta;
pub mod threads;
pub mod tune;

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};

/// The flags every command spells the same way (shown by `momentlab --help`).
pub const VOCABULARY_HELP: &str = "\
One vocabulary across the commands (older spellings are still accepted):
  --out DIR         the output folder; by default under results/ (nothing tracked). reproduce
                    and search keep bulky data (stacks, sweep rows) apart in --results DIR
  --force           overwrite existing outputs (reproduce: recompute every step)
  --technique T     repeatable, comma lists: vsm, esm, evsm, csm, hamburger4, hausdorff4,
                    hamburger6, hamburgerM (even M, Algorithm 2, e.g. hamburger8), tmsm,
                    lp:f1,f2,… (an LP candidate; its commas stay inside it)
  --m M             number of moments (basis functions)
  --inputs N        number of inputs of a measurement; --repeats N its timed passes
  --resolution R    shadow-map resolution of rendered stacks, 16..=4096
  --stacks DIR      depth stacks to read (default: render the embedded scenes)
  --json            machine-readable output on stdout";

/// momentlab: moment shadow mapping research pipeline.
#[derive(Parser, Debug)]
#[command(
    name = "momentlab",
    version,
    about,
    long_about = None,
    after_long_help = VOCABULARY_HELP,
    after_help = "Threads: RAYON_NUM_THREADS, else SLURM_CPUS_PER_TASK, else all CPUs; a request \
                  above the CPUs available is clamped to them (noted on stderr after success).\n\
                  Outputs: commands never replace an existing file without --force; a results \
                  folder takes one writer at a time. Inputs: regular files only, each kind with \
                  a size limit (docs/files.md)."
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Solve Algorithm 1 (the discretized moment problem) for a JSON batch.
    Lp(lp::Args),
    /// Count, list and index candidates (m-subsets of the basis catalog).
    Candidates(candidates::Args),
    /// Render depth stacks of the scenes with the reference ray caster.
    Render(render::Args),
    /// Validate and import depth stacks written by another renderer.
    Import(import::Args),
    /// Error of a technique against PCF over all fragments of the depth stacks.
    Evaluate(evaluate::Args),
    /// Closed-form shadow techniques for a JSON batch of (moments, z_f).
    Shadow(shadow::Args),
    /// Stress-test every technique where it fails; writes results/stability/ (or --out).
    Stability(stability::Args),
    /// Benchmarks (LP solvers, closed-form techniques).
    Bench(bench::Args),
    /// Optimal affine quantization transform θ for a basis.
    Theta(theta::Args),
    /// Quantized moment shadow maps on the depth stacks: error against bias α per bit depth.
    Quantize(quantize::Args),
    /// The candidate sweep: rank every m-subset of the catalog.
    Search(search::Args),
    /// Merge sharded search results.
    Merge(merge::Args),
    /// Search technique × storage × biases per scene: the cheapest setting within a tolerance
    /// and the noise bound (`recommend` is another name for it).
    #[command(alias = "recommend")]
    Tune(tune::Args),
    /// Reproduce the whole study on the default data and write the report.
    Reproduce(reproduce::Args),
    /// The pipeline and shader code on this machine's GPU: `gpu check`, `gpu bench`.
    Gpu(gpu::Args),
}

/// Entry point of the binary: parse, run, and map the outcome to an exit code — 0 on success
/// (and when stdout is closed early, e.g. `| head`), 2 for a usage error, 1 for any other
/// error; every error is one line on stderr.
pub fn main() -> i32 {
    quiet_broken_pipe();
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => return usage_error(&e),
    };
    let result = threads::init_from_env().and_then(|note| dispatch(cli).map(|()| note));
    let result = result.and_then(|note| {
        use std::io::Write;
        std::io::stdout().flush().context("writing stdout")?;
        Ok(note)
    });
    match result {
        Ok(note) => {
            if let Some(n) = note {
                note_line(&n);
            }
            0
        }
        Err(e) if is_broken_pipe(&e) => 0,
        Err(e) => {
            // One line, naming what went wrong and where (the error chain joined by ": "),
            // and the last one: progress output ends before it.
            momentlab::progress::silence();
            note_line(&format!("error: {}", one_line(&format!("{e:#}"))));
            1
        }
    }
}

/// A line on stderr; a stderr that cannot be written (full device) is not a second error.
fn note_line(s: &str) {
    use std::io::Write;
    let _ = writeln!(std::io::stderr().lock(), "{s}");
}

fn dispatch(cli: Cli) -> Result<()> {
    // Long commands stop cleanly on SIGINT/SIGTERM (exit 130, one line; momentlab::artefact::interrupt).
    let long = match &cli.command {
        Command::Theta(_) => Some(("theta", true)),
        Command::Stability(_) => Some(("stability", true)),
        // Its checkpoint lives in --out.
        Command::Evaluate(a) => Some(("evaluate", a.out.is_some())),
        // Its checkpoint lives in --out.
        Command::Tune(a) => Some(("tune", a.out.is_some())),
        Command::Quantize(a) => Some(("quantize", a.merge.is_none())),
        Command::Search(_) => Some(("search", true)),
        Command::Reproduce(_) => Some(("reproduce", true)),
        _ => None,
    };
    if let Some((name, resumes)) = long {
        momentlab::artefact::interrupt::install(name, resumes);
    }
    match cli.command {
        Command::Lp(a) => lp::run(a),
        Command::Candidates(a) => candidates::run(a),
        Command::Render(a) => render::run(a),
        Command::Import(a) => import::run(a),
        Command::Evaluate(a) => evaluate::run(a),
        Command::Shadow(a) => shadow::run(a),
        Command::Stability(a) => stability::run(a),
        Command::Bench(a) => bench::run(a),
        Command::Theta(a) => theta::run(a),
        Command::Quantize(a) => quantize::run(a),
        Command::Search(a) => search::run(a),
        Command::Merge(a) => merge::run(a),
        Command::Tune(a) => tune::run(a),
        Command::Reproduce(a) => reproduce::run(a),
        Command::Gpu(a) => gpu::run(a),
    }
}

/// Help and version go to stdout (exit 0); a usage error becomes one line on stderr (exit 2).
fn usage_error(e: &clap::Error) -> i32 {
    use clap::error::ErrorKind;
    match e.kind() {
        ErrorKind::DisplayHelp | ErrorKind::DisplayVersion => {
            let _ = e.print();
            0
        }
        _ => {
            // clap's message: "error: …" (possibly continued on indented lines), a blank
            // line, then tips and usage. Keep the message, on one line.
            let text = e.to_string();
            let msg: Vec<&str> = text
                .lines()
                .take_while(|l| !l.trim().is_empty() && !l.starts_with("Usage:"))
                .map(str::trim)
                .collect();
            note_line(&one_line(&msg.join(" ")));
            2
        }
    }
}

/// Collapse line breaks so that every error is exactly one line.
fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

/// `println!` panics when stdout cannot be written (Rust ignores SIGPIPE): a closed pipe ends
/// quietly with exit 0, like a classic Unix filter; any other write error on stdout (a full
/// device, `> /dev/full`) is an ordinary one-line error with exit 1, and one on stderr ends with
/// exit 1 (there is nowhere to say it). Other panics keep the default report.
fn quiet_broken_pipe() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let msg = info
            .payload()
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| info.payload().downcast_ref::<&str>().copied())
            .unwrap_or("");
        if msg.contains("Broken pipe") || msg.contains("os error 32") {
            std::process::exit(0);
        }
        if let Some(why) = msg.strip_prefix("failed printing to stdout: ") {
            note_line(&format!("error: writing stdout: {}", one_line(why)));
            std::process::exit(1);
        }
        if msg.starts_with("failed printing to stderr") {
            std::process::exit(1);
        }
        default(info);
    }));
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    fn walk(cmd: &clap::Command, path: &str, missing: &mut Vec<String>) {
        for a in cmd.get_arguments() {
            let id = a.get_id().as_str();
            if id == "help" || id == "version" {
                continue;
            }
            let help = a.get_help().map(|h| h.to_string()).unwrap_or_default();
            if help.trim().is_empty() {
                missing.push(format!("{path} {id}"));
            }
        }
        for sc in cmd.get_subcommands() {
            if sc
                .get_about()
                .is_none_or(|h| h.to_string().trim().is_empty())
            {
                missing.push(format!("{path} {} (about)", sc.get_name()));
            }
            walk(sc, &format!("{path} {}", sc.get_name()), missing);
        }
    }

    #[test]
    fn every_argument_and_subcommand_has_help() {
        let mut missing = Vec::new();
        walk(&Cli::command(), "momentlab", &mut missing);
        assert!(missing.is_empty(), "no help text: {missing:?}");
        Cli::command().debug_assert();
    }

    /// Every argument of every (sub)command, with the command path.
    fn all_args(
        cmd: &clap::Command,
        path: &str,
        out: &mut Vec<(String, clap::Arg, clap::Command)>,
    ) {
        for a in cmd.get_arguments() {
            out.push((path.to_string(), a.clone(), cmd.clone()));
        }
        for sc in cmd.get_subcommands() {
            all_args(sc, &format!("{path} {}", sc.get_name()), out);
        }
    }

    /// One command-line vocabulary: older or competing spellings exist only as hidden aliases,
    /// every output folder is --out (the only second folder is --results, next to an --out),
    /// --technique is repeatable wherever it exists, every --resolution has the same range, and
    /// every default output folder is under results/.
    #[test]
    fn one_vocabulary_across_commands() {
        const RETIRED: &[&str] = &[
            "reports",
            "report",
            "output",
            "output-dir",
            "pictures",
            "overwrite",
            "fresh",
            "reps",
            "techniques",
            "problems",
            "reference-problems",
            "speed-inputs",
            "samples",
            "moments",
        ];
        let mut args = Vec::new();
        all_args(&Cli::command(), "momentlab", &mut args);
        let mut bad = Vec::new();
        let mut resolutions = 0;
        for (path, a, cmd) in &args {
            let Some(long) = a.get_long() else { continue };
            let visible: Vec<&str> = a.get_visible_aliases().unwrap_or_default();
            for name in std::iter::once(long).chain(visible.iter().copied()) {
                if RETIRED.contains(&name) {
                    bad.push(format!("{path}: visible --{name}"));
                }
            }
            match long {
                "technique" if !matches!(a.get_action(), clap::ArgAction::Append) => {
                    bad.push(format!("{path}: --technique is not repeatable"));
                }
                "results" if cmd.get_arguments().all(|b| b.get_long() != Some("out")) => {
                    bad.push(format!("{path}: --results without --out"));
                }
                "resolution" => {
                    resolutions += 1;
                    let c = cmd.clone().mut_args(|x| x.required(false));
                    let ok = |v: &str| {
                        c.clone()
                            .try_get_matches_from(["x", "--resolution", v])
                            .is_ok()
                    };
                    if ok("15") || !ok("16") || !ok("4096") || ok("4097") {
                        bad.push(format!("{path}: --resolution range is not 16..=4096"));
                    }
                }
                _ => {}
            }
            if matches!(long, "out" | "results") {
                for d in a.get_default_values() {
                    if !d.to_string_lossy().starts_with("results") {
                        bad.push(format!(
                            "{path}: --{long} defaults to {d:?}, not under results/"
                        ));
                    }
                }
            }
        }
        assert!(resolutions >= 7, "{resolutions} --resolution flags found");
        // Every command that writes files names its folder --out.
        for path in [
            "render",
            "import",
            "evaluate",
            "stability",
            "theta",
            "quantize",
            "merge",
            "search",
            "reproduce",
        ] {
            let has_out = args
                .iter()
                .any(|(p, a, _)| p == &format!("momentlab {path}") && a.get_long() == Some("out"));
            if !has_out {
                bad.push(format!("momentlab {path}: no --out"));
            }
        }
        assert!(bad.is_empty(), "{bad:#?}");
    }

    /// The retired spellings still parse, as the flags that replaced them.
    #[test]
    fn old_spellings_still_work() {
        let parse = |v: &[&str]| Cli::try_parse_from(v).unwrap_or_else(|e| panic!("{v:?}: {e}"));
        match parse(&["momentlab", "reproduce", "--reports", "r", "--fresh"]).command {
            Command::Reproduce(a) => assert!(a.out == std::path::Path::new("r") && a.force),
            _ => unreachable!(),
        }
        match parse(&["momentlab", "search", "--report", "r"]).command {
            Command::Search(a) => {
                assert_eq!(a.opts.out.as_deref(), Some(std::path::Path::new("r")))
            }
            _ => unreachable!(),
        }
        match parse(&[
            "momentlab",
            "recommend",
            "--techniques",
            "vsm,esm",
            "--fragments",
            "7",
        ])
        .command
        {
            Command::Tune(a) => assert!(a.technique == ["vsm,esm"] && a.fragments == 7),
            _ => unreachable!(),
        }
        match parse(&["momentlab", "theta", "--moments", "4"]).command {
            Command::Theta(a) => assert_eq!(a.m, Some(4)),
            _ => unreachable!(),
        }
        match parse(&[
            "momentlab",
            "bench",
            "shadow",
            "--reps",
            "2",
            "--technique",
            "vsm,tmsm",
        ])
        .command
        {
            Command::Bench(bench::Args {
                what: bench::What::Shadow(a),
            }) => assert!(a.repeats == 2 && a.technique == ["vsm,tmsm"]),
            _ => unreachable!(),
        }
        match parse(&["momentlab", "bench", "lp", "--problems", "5"]).command {
            Command::Bench(bench::Args {
                what: bench::What::Lp(a),
            }) => assert_eq!(a.inputs, 5),
            _ => unreachable!(),
        }
        match parse(&["momentlab", "import", "x.exr", "--out", "o", "--overwrite"]).command {
            Command::Import(a) => assert!(a.force),
            _ => unreachable!(),
        }
        match parse(&[
            "momentlab",
            "evaluate",
            "--technique",
            "vsm",
            "--pictures",
            "p",
        ])
        .command
        {
            Command::Evaluate(a) => assert_eq!(a.out.as_deref(), Some(std::path::Path::new("p"))),
            _ => unreachable!(),
        }
        match parse(&[
            "momentlab",
            "stability",
            "--samples",
            "9",
            "--techniques",
            "vsm",
        ])
        .command
        {
            Command::Stability(a) => assert!(a.inputs == 9 && a.technique == ["vsm"]),
            _ => unreachable!(),
        }
        match parse(&["momentlab", "quantize", "--techniques", "4msm"]).command {
            Command::Quantize(a) => assert_eq!(a.technique, ["4msm"]),
            _ => unreachable!(),
        }
    }

    /// The example of a schema help text: (input JSON, output line).
    fn help_example(help: &str) -> (String, String) {
        let ex = &help[help.find("Example:").expect("an example")..];
        let input = &ex[ex.find("echo '").expect("echo") + 6..ex.find("' | momentlab").unwrap()];
        let output = ex.lines().last().unwrap().trim();
        (input.to_string(), output.to_string())
    }

    /// `lp --help` and `shadow --help` show the JSON schema, and their examples print what the
    /// help text says they print.
    #[test]
    fn schema_help_examples_are_true() {
        for name in ["lp", "shadow"] {
            let mut cmd = Cli::command();
            let help = cmd
                .find_subcommand_mut(name)
                .unwrap()
                .render_long_help()
                .to_string();
            assert!(
                help.contains("Input (JSON object") && help.contains("Output"),
                "{name}"
            );
            assert!(help.contains("Example:"), "{name}");
        }
        let (input, output) = help_example(lp::SCHEMA_HELP);
        let got = momentlab::batch::lp::solve_batch(
            &input,
            &momentlab::basis::Catalog::embedded(),
            false,
        )
        .unwrap();
        assert_eq!(got, output);
        let (input, output) = help_example(shadow::SCHEMA_HELP);
        let got = momentlab::batch::shadow::evaluate_batch(&input, "example").unwrap();
        assert_eq!(serde_json::to_string(&got).unwrap(), output);
    }

    #[test]
    fn errors_are_one_line() {
        assert_eq!(one_line("a\n  b\tc"), "a b c");
    }
}
