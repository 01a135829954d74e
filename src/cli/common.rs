//! Mechanisms shared by every subcommand: FILE arguments where `-` is stdin, the depth stacks
//! of `--stacks` (or the rendered default dataset, said so on stderr), technique lists that
//! keep `lp:` specs whole, value parsers that check a flag's documented range before any work,
//! and the limits that bound memory before anything is allocated.

use anyhow::{Context, Result};
use momentlab::stack::DepthStack;
use std::path::Path;

/// Largest shadow-map resolution accepted by any command (12 views × layers × res² fragments).
pub const MAX_RESOLUTION: u64 = 4096;
/// Smallest shadow-map resolution accepted by any command (a view wider than the 9×9 filter).
pub const MIN_RESOLUTION: u64 = 16;
/// Largest LP grid size n accepted by any command (the tables hold n·m values per solver).
pub const MAX_GRID: u64 = momentlab::grid::MAX_POINTS as u64;
/// Largest number of random inputs of a speed measurement or stress test.
pub const MAX_INPUTS: u64 = 10_000_000;

/// Text of a FILE argument: `None` or `-` reads stdin. Returns (text, name for errors). The
/// bounded reader of [`momentlab::artefact::input`] with the batch limit (regular files only).
pub fn read_input(file: Option<&Path>) -> Result<(String, String)> {
    momentlab::artefact::read_input(file, momentlab::artefact::Limit::BATCH)
}

/// The depth stacks of `--stacks DIR`, or — when it is missing — the embedded default dataset
/// rendered at `resolution` (announced on stderr, with how to use one's own stacks). Stacks
/// without any fragment are an error, never a 0 % result.
pub fn stacks_or_default(
    dir: Option<&Path>,
    resolution: usize,
    cmd: &str,
) -> Result<Vec<DepthStack>> {
    let stacks = match dir {
        Some(d) => {
            momentlab::stack::load_dir(d).with_context(|| format!("--stacks {}", d.display()))?
        }
        None => {
            eprintln!(
                "{cmd}: no --stacks given: rendering the embedded default dataset at {resolution}×{resolution} \
                 (pass --stacks DIR for your own depth stacks)"
            );
            momentlab::render::default_dataset(resolution)?
        }
    };
    require_fragments(&stacks, dir)?;
    Ok(stacks)
}

/// Error when the stacks hold no fragment (every texel of every view empty), naming the folder.
pub fn require_fragments(stacks: &[DepthStack], dir: Option<&Path>) -> Result<()> {
    momentlab::metrics::require_fragments(stacks).with_context(|| {
        dir.map_or("the rendered stacks".to_string(), |d| {
            d.display().to_string()
        })
    })
}

/// A comma-separated technique list where `lp:` specs keep their commas: after an `lp:` item,
/// items that are not technique names belong to its basis (`lp:z,z^2,vsm` = `lp:z,z^2` and
/// `vsm`). Commas inside parentheses never split. Empty items are dropped.
pub fn split_techniques(list: &str) -> Vec<String> {
    let known = |s: &str| {
        momentlab::technique::registry::is_closed_form_name(s)
            || matches!(s, "pcf" | "cdf")
            || s.starts_with("lp:")
    };
    let mut out: Vec<String> = Vec::new();
    for item in momentlab::basis::split_list(list) {
        if item.is_empty() {
            continue;
        }
        match out.last_mut() {
            Some(last) if last.starts_with("lp:") && !known(&item) => {
                last.push(',');
                last.push_str(&item);
            }
            _ => out.push(item),
        }
    }
    out
}

/// Every technique named by repeated `--technique` values, each a comma list
/// ([`split_techniques`]), in order, without duplicates.
pub fn technique_list(values: &[String]) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for v in values {
        for t in split_techniques(v) {
            if !out.contains(&t) {
                out.push(t);
            }
        }
    }
    out
}

/// The `--resolution` of every command: MIN_RESOLUTION..=MAX_RESOLUTION.
pub fn resolution() -> clap::builder::RangedU64ValueParser<usize> {
    usize_in(MIN_RESOLUTION, MAX_RESOLUTION)
}

/// An integer flag in lo..=hi (value parser; clap names the range in its error).
pub fn usize_in(lo: u64, hi: u64) -> clap::builder::RangedU64ValueParser<usize> {
    clap::builder::RangedU64ValueParser::<usize>::new().range(lo..=hi)
}

fn number(s: &str) -> Result<f64, String> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("'{s}' is not a number"))?;
    if !v.is_finite() {
        return Err(format!("{s} is not finite"));
    }
    Ok(v)
}

/// A finite number ≥ 0 (value parser).
pub fn non_negative(s: &str) -> Result<f64, String> {
    let v = number(s)?;
    if v < 0.0 {
        return Err(format!("{v} is negative; need a finite number ≥ 0"));
    }
    Ok(v)
}

/// A number in (0, 1] (value parser).
pub fn fraction(s: &str) -> Result<f64, String> {
    let v = number(s)?;
    if !(v > 0.0 && v <= 1.0) {
        return Err(format!("{v} is not in (0, 1]"));
    }
    Ok(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lp_specs_keep_their_commas() {
        assert_eq!(split_techniques("lp:z,z^2"), vec!["lp:z,z^2"]);
        assert_eq!(
            split_techniques("vsm, lp:z,z^2,exp(2z), hamburger4,lp:sin(2πz),cos(2πz)"),
            vec![
                "vsm",
                "lp:z,z^2,exp(2z)",
                "hamburger4",
                "lp:sin(2πz),cos(2πz)"
            ]
        );
        assert_eq!(split_techniques("vsm,,esm,"), vec!["vsm", "esm"]);
        assert!(split_techniques("").is_empty());
        assert_eq!(
            technique_list(&["vsm,lp:z,z^2".into(), "esm".into(), "vsm".into()]),
            vec!["vsm", "lp:z,z^2", "esm"]
        );
    }

    #[test]
    fn value_parsers_check_ranges() {
        assert_eq!(non_negative("0"), Ok(0.0));
        assert!(non_negative("-1").is_err());
        assert!(non_negative("nan").is_err());
        assert!(fraction("1.5").is_err());
        assert_eq!(fraction("1"), Ok(1.0));
        assert!(non_negative("inf").is_err());
        assert!(non_negative("x").is_err());
    }
}
