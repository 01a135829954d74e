//! The Markdown report of a sweep and the files it links (`search_m<m>.md`, `fig4_m<m>.svg`,
//! `distributions.svg`, `fig3.svg`, `eliminated_m<m>.csv`): what the race resolved, every
//! elimination's evidence, the winner against the paper's bases and the closed forms, the
//! ranking, the tied set and the top 20. The numbers come from `crate::search::reference`; every file goes through
//! `artefact::OutDir`.

use super::sweep_charts::{fig4_data, plot_fig3, plot_fig4, plot_side_by_side};
use crate::artefact::OutDir;
use crate::search::race::{normal_quantile, Correction};
use crate::search::reference::{
    errors_of, fig3_panels, pick_kernels, rank_of, summarize, Reference, Summary,
};
use crate::search::results::{
    ranking, read_json, read_rows, Row, COMPLETE_FILE, CONFIG_FILE, PARTIAL_FILE,
};
use crate::search::tieset::{status, tie_set, winner_of, TieSet};
use crate::search::{Dataset, RaceSummary, SweepConfig, SweepOptions, SweepSummary};
use anyhow::{bail, Result};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Options of [`write`].
#[derive(Clone, Debug)]
pub struct ReportOptions {
    /// Solver and chunk size for the Fig. 3 curves.
    pub solver: String,
    /// Fragments per solver instance (warm-start chain) of the Fig. 3 curves.
    pub chunk: usize,
    /// Results directories of other sweeps (e.g. m = 2 and 3) for the side-by-side plot.
    pub compare: Vec<PathBuf>,
    /// Depths at which the Fig. 3 curves are solved.
    pub fig3_points: usize,
    /// How the results are named in the text (e.g. their directory).
    pub results_label: String,
    /// The race's own account (`complete.json` of an unsharded racing run).
    pub race: Option<RaceSummary>,
    /// Confidence of the race (intervals in the text are stated at this level).
    pub confidence: f64,
    /// What a partial merge lacks (`partial.json`): the report says "partial" and names it.
    pub partial: Option<crate::search::merge::Partial>,
}

impl Default for ReportOptions {
    fn default() -> Self {
        ReportOptions {
            solver: "fast".into(),
            chunk: 4096,
            compare: Vec::new(),
            fig3_points: 96,
            results_label: String::new(),
            race: None,
            confidence: 0.99,
            partial: None,
        }
    }
}

impl ReportOptions {
    /// The options of the report of sweep `opts` whose rows are in `results`: its solver, chunk
    /// and confidence, and the race's own account (`complete.json` of an unsharded racing
    /// run); no comparison sweeps, Fig. 3 at 96 depths.
    pub fn of(opts: &SweepOptions, results: &Path) -> ReportOptions {
        ReportOptions {
            solver: opts.solver.clone(),
            chunk: opts.chunk,
            results_label: results.display().to_string(),
            race: read_json::<SweepSummary>(&results.join(COMPLETE_FILE))
                .ok()
                .and_then(|s| s.race),
            confidence: opts.confidence,
            partial: read_json(&results.join(PARTIAL_FILE)).ok(),
            ..ReportOptions::default()
        }
    }
}

/// The files [`write`] may write for a sweep of m-function candidates (to check them before
/// any work).
pub fn files(m: usize) -> [String; 5] {
    [
        format!("search_m{m}.md"),
        format!("fig4_m{m}.svg"),
        format!("eliminated_m{m}.csv"),
        "distributions.svg".into(),
        "fig3.svg".into(),
    ]
}

/// Write the report of a sweep into `out`: `fig4_m<m>.svg` (histogram with `refs` marked),
/// `distributions.svg` (this sweep and `opts.compare` side by side), `fig3.svg`,
/// `eliminated_m<m>.csv` (racing runs: every elimination with its evidence) and `search_m<m>.md`
/// (ranking text, evidence, top-20 table).
/// Returns the numbers the text states.
pub fn write(
    out: &OutDir,
    rows: &[Row],
    data: &Dataset,
    refs: &[Reference],
    opts: &ReportOptions,
) -> Result<Summary> {
    let summary = summarize(rows, refs);
    let Some(best) = &summary.best else {
        bail!("no scored candidates to report");
    };
    let m = best.functions.len();
    let errs = errors_of(rows);
    let ties = tie_set(rows);
    out.write_text(
        &format!("fig4_m{m}.svg"),
        &plot_fig4(&format!("Candidate errors, m = {m}"), rows, refs)?,
    )?;
    if let Some(csv) = eliminated_list(rows, &ties) {
        out.write_text(&format!("eliminated_m{m}.csv"), &csv)?;
    }
    let mut sets = vec![(format!("m = {m}"), errs.clone())];
    for d in &opts.compare {
        let r = read_rows(d)?;
        let cfg: SweepConfig = read_json(&d.join(CONFIG_FILE))?;
        if cfg.m != m {
            sets.push((format!("m = {}", cfg.m), errors_of(&r)));
        }
    }
    sets.sort_by(|a, b| a.0.cmp(&b.0));
    out.write_text("distributions.svg", &plot_side_by_side(&sets)?)?;
    let kernels = pick_kernels(data, 3);
    let panels = fig3_panels(data, &kernels, opts.fig3_points, &opts.solver)?;
    out.write_text("fig3.svg", &plot_fig3(&panels)?)?;
    let sampled = data.sampled_fraction();
    let mut md = format!(
        "# Candidate sweep, m = {m}\n\nWritten by {}.\n\nResults: `{}`. {} fragments, {} non-trivial; the sweep's dataset \
         holds {} of the non-trivial ones ({:.2} %, stratified by view and layer), trivial fragments \
         (G = 0 for every candidate) are counted exactly.\n\n![Fig. 4 analogue](fig4_m{m}.svg)\n\n{}\n\
         ## What the race resolved\n\n{}\n## Eliminations and their evidence\n\n{}\n## The winner, the paper's bases and the closed forms\n\n{}\n\
         ## Ranking\n\n{}\n## Tied for first\n\n{}\n## Top 20\n\nCandidates scored on every fragment of the sample are ranked first; below them, \
         unranked (–), the lowest estimates of candidates that left the race on fewer fragments.\n\n{}\n\
         ![error distributions](distributions.svg)\n\n![Fig. 3 analogue](fig3.svg)\n",
        crate::report::provenance::Provenance::current().line(),
        opts.results_label,
        data.total_count(),
        data.nontrivial_population(),
        data.fragments().len(),
        sampled * 100.0,
        fig4_text(rows),
        resolution_text(&ties, &summary, opts),
        evidence_text(rows, &ties, opts, 40),
        reference_table(&summary, rows, opts.confidence),
        ranking_text(rows, refs),
        tie_table(&ties, opts.confidence, 50),
        top_table(rows, 20)
    );
    if let Some(p) = &opts.partial {
        let head = md.find("\n\n").map_or(md.len(), |i| i + 2);
        md.insert_str(
            head,
            &format!(
                "**Partial results** (`merge --allow-partial`, no `complete.json`): {}. The \
                 ranking below covers only the candidates present.\n\n",
                p.line().trim_start_matches("partial: ")
            ),
        );
    }
    md.push_str(
        "\nReference values: LP candidates (label \"(LP)\") are scored on every fragment of the \
         sweep's dataset with the same grid and solver as the candidates; closed forms (label \
         \"(closed form)\") are `momentlab evaluate` values (metrics::evaluate, same bias) on every \
         fragment of the stacks. Errors and standard errors estimate the mean |G − PCF| over all \
         fragments of the stacks.\n",
    );
    out.write_text(&format!("search_m{m}.md"), &md)?;
    Ok(summary)
}

/// Markdown table of the `count` best candidates: the candidates scored on every fragment
/// first, ranked by error; then, unranked ("–"), the lowest estimates of candidates that left
/// the race on fewer fragments (an estimate on a sample is not a rank among finished scores).
pub fn top_table(rows: &[Row], count: usize) -> String {
    let by_index: std::collections::HashMap<u64, &Row> =
        rows.iter().map(|r| (r.index, r)).collect();
    let mut s = String::from("| rank | index | functions | error (%) | ± s.e. (%) | fragments | race |\n|---:|---:|---|---:|---:|---:|---|\n");
    let (full, partial): (Vec<Row>, Vec<Row>) = ranking(rows).into_iter().partition(|r| r.full);
    let mut rank = 0;
    for r in full.iter().chain(&partial).take(count) {
        let own = r
            .duplicate_of
            .and_then(|d| by_index.get(&d))
            .map_or(r, |x| *x);
        let shown = if r.full {
            rank += 1;
            rank.to_string()
        } else {
            "–".to_string()
        };
        let _ = writeln!(
            s,
            "| {} | {} | {} | {:.4} | {:.4} | {} | {}{} |",
            shown,
            r.index,
            r.functions.join(", "),
            r.error.unwrap() * 100.0,
            r.stderr.unwrap_or(0.0) * 100.0,
            own.fragments,
            status(own),
            if r.duplicate_of.is_some() {
                " (duplicate span)"
            } else {
                ""
            }
        );
    }
    s
}

/// Two-sided interval d ± z_{1−α/2}·se at `confidence`, in percentage points.
fn interval(d: f64, se: f64, confidence: f64) -> (f64, f64) {
    let z = normal_quantile(1.0 - (1.0 - confidence) / 2.0);
    ((d - z * se) * 100.0, (d + z * se) * 100.0)
}

/// The catalog names of the paper's bases (to find their rows among the candidates).
const PAPER_CANDIDATES: [(&str, &[&str]); 3] = [
    ("b_MSM (LP)", &["z", "z^2", "z^3", "z^4"]),
    (
        "b_TMSM (LP)",
        &["sin(2πz)", "cos(2πz)", "sin(4πz)", "cos(4πz)"],
    ),
    ("VSM (LP)", &["z", "z^2"]),
];

/// The race status of a reference that is also a catalog candidate (b_MSM, b_TMSM, VSM).
fn candidate_status(label: &str, rows: &[Row]) -> Option<String> {
    let names = PAPER_CANDIDATES.iter().find(|p| p.0 == label)?.1;
    let mut want: Vec<&str> = names.to_vec();
    want.sort_unstable();
    let r = rows.iter().find(|r| {
        let mut f: Vec<&str> = r.functions.iter().map(|x| x.as_str()).collect();
        f.sort_unstable();
        f == want
    })?;
    let rep = r
        .duplicate_of
        .and_then(|d| rows.iter().find(|x| x.index == d))
        .unwrap_or(r);
    Some(format!("candidate {}: {}", r.index, status(rep)))
}

/// The winner, the references and the closed forms with their difference to the winner and
/// its interval at `confidence`.
pub fn reference_table(summary: &Summary, rows: &[Row], confidence: f64) -> String {
    let Some(best) = &summary.best else {
        return String::new();
    };
    let c = confidence * 100.0;
    let mut s = format!(
        "| | m | error (%) ± s.e. | Δ to the winner (pp) | {c:.0} % interval of Δ (pp) | pairing | verdict | in the race |\n|---|---:|---:|---:|---|---|---|---|\n| winner ({}) | {} | {:.4} ± {:.4} | 0 | | | | tied for first |\n",
        best.functions.join(", "),
        best.functions.len(),
        best.error * 100.0,
        best.stderr * 100.0
    );
    for r in summary.references.iter().filter(|r| r.label != "PCF") {
        let Some((d, se)) = r.diff else { continue };
        let (lo, hi) = interval(d, se, confidence);
        let verdict = if lo > 0.0 {
            "worse than the winner"
        } else if hi < 0.0 {
            "better than the winner"
        } else {
            "not significantly different"
        };
        let _ = writeln!(
            s,
            "| {} | {} | {:.4} ± {:.4} | {:+.4} | [{:+.4}, {:+.4}] | {} | {} | {} |",
            r.label,
            r.m,
            r.error * 100.0,
            r.stderr * 100.0,
            d * 100.0,
            lo,
            hi,
            if r.paired {
                "paired, every fragment"
            } else if r.closed_form {
                "unpaired (closed form exact on all fragments of the stacks)"
            } else {
                "unpaired"
            },
            verdict,
            candidate_status(&r.label, rows).unwrap_or_else(|| "not a catalog candidate".into())
        );
    }
    s.push_str(&format!(
        "\nIntervals are two-sided at {c:.0} % for each line separately (normal approximation). \
         Paired differences use one scoring pass of the winner and the reference on every fragment \
         of the sweep's sample; closed forms are exact population values, so their interval is \
         the winner's own.\n"
    ));
    s
}

/// The tied set: each survivor's paired difference to the winner pooled over the blocks, with
/// its interval (standard errors exact on blocks whose reference is the winner, else bounded
/// by Cauchy–Schwarz, so the intervals are conservative).
pub fn tie_table(t: &TieSet, confidence: f64, limit: usize) -> String {
    if !t.raced {
        return "Not a racing run: no tie set (every candidate was scored on every fragment).\n"
            .into();
    }
    let c = confidence * 100.0;
    let mut s = format!(
        "{} candidates are statistically tied for first{}.\n\n| # | index | functions | error (%) | Δ to the winner (pp) | {c:.0} % interval (pp) | fragments | unsettled LPs |\n|---:|---:|---|---:|---:|---|---:|---:|\n",
        t.tied.len(),
        if t.tied_duplicates > 0 {
            format!(" (plus {} duplicate spans of them)", t.tied_duplicates)
        } else {
            String::new()
        }
    );
    for (k, r) in t.tied.iter().take(limit).enumerate() {
        let (d, se) = (r.diff.unwrap_or(0.0), r.diff_se.unwrap_or(0.0));
        let (lo, hi) = interval(d, se, confidence);
        let _ = writeln!(
            s,
            "| {} | {} | {} | {:.4} | {:+.4} | [{:+.4}, {:+.4}] | {} | {} |",
            k + 1,
            r.index,
            r.functions.join(", "),
            r.error.unwrap_or(f64::NAN) * 100.0,
            d * 100.0,
            lo,
            hi,
            r.fragments,
            r.lp_failures
        );
    }
    if t.tied.len() > limit {
        let _ = writeln!(
            s,
            "\n… and {} more (`tied: true` in results.jsonl).",
            t.tied.len() - limit
        );
    }
    s
}

/// The sentence under Fig. 4: what it is drawn from.
pub fn fig4_text(rows: &[Row]) -> String {
    let d = fig4_data(rows);
    let n: usize = d.classes.iter().map(Vec::len).sum();
    format!(
        "Fig. 4 is drawn from one common sample: each of the {n} candidates is scored on the same \
         {} fragments (racing stage 0's block; in an exhaustive run, every fragment), with a \
         median standard error of {:.4} percentage points per candidate (the differences between \
         candidates, paired on the same fragments, are more precise). The black outline is the \
         race's deeper estimate of the {} candidates scored on more fragments; red: tied for \
         first; grey: unresolved; the lines mark the paper's bases (b_MSM, b_TMSM), VSM, ESM and \
         the closed forms.\n",
        d.fragments,
        d.median_se * 100.0,
        d.deeper.len()
    )
}

/// What the race resolved, with its budget and whether it bound.
pub fn resolution_text(t: &TieSet, _summary: &Summary, opts: &ReportOptions) -> String {
    if !t.raced {
        return "Exhaustive run: every candidate on every fragment of the sample, no racing. \
                Differences between candidates are exact on the sample; ± s.e. is the \
                uncertainty of an absolute error against the full stacks.\n"
            .into();
    }
    let c = opts.confidence * 100.0;
    let mut s = String::new();
    if let Some(r) = &opts.race {
        let _ = writeln!(
            s,
            "A candidate leaves the race only by evidence: when it is worse than the stage's \
             reference with confidence; there is no cap. Budget: the sweep's sample of {} \
             non-trivial fragments (`--max-fragments`){}. Tests: {} bound, {}, {}. Stage 0's block is the common sample: one \
             look, every candidate scored on all of it; a later block is tested on its prefixes of \
             1/8, 1/4 and 1/2 that hold at least `--early-look` fragments, the survivors of \
             each look on the next, then on the whole block.\n",
            r.fragment_budget,
            if r.lp_budget_bound {
                " and an LP budget (`--lp-budget`), which ended the race"
            } else {
                ""
            },
            r.bound.name(),
            if r.paired {
                "paired differences to the stage reference"
            } else {
                "independent intervals"
            },
            correction_text(r.correction, c, r.looks)
        );
        s.push_str("| stage | candidates | fragments | reference | z | eliminated by evidence |\n|---:|---:|---:|---:|---:|---:|\n");
        for (k, st) in r.stages.iter().enumerate() {
            let _ = writeln!(
                s,
                "| {k} | {} | {} | {} | {:.2} | {} |",
                st.candidates,
                st.fragments,
                st.reference,
                st.z,
                if st.early_eliminated > 0 {
                    format!(
                        "{} ({} at an early look)",
                        st.confidence_eliminated, st.early_eliminated
                    )
                } else {
                    st.confidence_eliminated.to_string()
                }
            );
        }
        let end = if r.lp_budget_bound {
            format!(
                "**Unresolved**: the LP budget ended the race with {} candidates left; none of them \
                 was eliminated or completed, and the best candidate is among them at {c:.0} %.",
                r.unresolved
            )
        } else if r.resolved {
            "**Resolved**: one candidate was left before the fragment budget was reached (the \
             budget did not bind)."
                .to_string()
        } else {
            format!(
                "**The fragment budget bound**: {} candidates are still statistically tied for \
                 first; the {} fragments of the sample do not separate them at {c:.0} %.",
                r.tied, r.fragment_budget
            )
        };
        let _ = writeln!(
            s,
            "\nThe race used {} of the {} fragments (pilot block {}){}. {end}\n",
            r.fragments_used,
            r.fragment_budget,
            r.pilot_fragments,
            if r.lp_budget_bound {
                ""
            } else {
                ", then completed the survivors on the fragments they had not seen"
            }
        );
    } else {
        let _ = writeln!(
            s,
            "Merged shards (or a run without its `complete.json`): the tied set below is the union \
             of the shards' tied sets, each relative to its own shard's winner.\n"
        );
    }
    let together = match opts.race.as_ref().map(|r| (r.correction, r.looks)) {
        Some((Correction::All, _)) => format!(
            "all these statements hold together with probability ≥ {c:.0} % (normal \
             approximation of block means)"
        ),
        Some((Correction::Best, looks)) => format!(
            "each at its test's level, 1 − (1 − {c:.0} %)/{looks} (normal approximation of block \
             means), not all together: what holds at {c:.0} % is the next line"
        ),
        None => "each at its shard's per-test level".to_string(),
    };
    let _ = writeln!(
        s,
        "- {} candidates were **eliminated by evidence**: each is worse than its stage reference, \
         {together}. No candidate left without evidence.",
        t.confidence
    );
    let (n, what) = if t.unresolved.is_empty() {
        (t.tied.len(), "tied for first")
    } else {
        (t.unresolved.len(), "left unresolved by the LP budget")
    };
    let _ = writeln!(
        s,
        "- **Certified**: with probability ≥ {c:.0} %, the best candidate (smallest mean error over \
         the sample's fragments) is one of the {n} candidates {what}.\n\
         - **Not resolved**: the order within that set; the absolute errors against the full \
         stacks carry the ± s.e. of the sample (the same for every candidate, since all see the \
         same fragments)."
    );
    s
}

/// What the race's confidence `c` (percent) covers, with its split over `looks` planned looks.
fn correction_text(correction: Correction, c: f64, looks: u64) -> String {
    match correction {
        Correction::Best => format!(
            "confidence {c:.0} % that the best candidate survives (`--correction {}`: it takes \
             one test per look, so the Bonferroni split is over the {looks} looks of the stages \
             only; an elimination of another candidate is evidence at the per-test level, not \
             jointly with the others)",
            correction.name()
        ),
        Correction::All => format!(
            "confidence {c:.0} % for all eliminations together (`--correction {}`: Bonferroni \
             over the {looks} looks of the stages, the candidates of each stage and the shards)",
            correction.name()
        ),
    }
}

/// Every elimination's evidence: per stage and look, how many left and the smallest lower
/// bound; then the `limit` eliminated candidates with the lowest estimates, each with its
/// look, reference, paired difference and the one-sided interval that removed it.
pub fn evidence_text(rows: &[Row], t: &TieSet, opts: &ReportOptions, limit: usize) -> String {
    if !t.raced {
        return "Exhaustive run: no eliminations.\n".into();
    }
    let m = t.winner.as_ref().map_or(0, |w| w.functions.len());
    let mut el: Vec<&Row> = rows.iter().filter(|r| r.eliminated.is_some()).collect();
    if el.is_empty() {
        return "No candidate was eliminated.\n".into();
    }
    let c = opts.confidence * 100.0;
    let mut s = format!(
        "Each eliminated candidate carries the stage and look that removed it, its stage \
         reference, the paired difference Δ = error − error(reference) on the fragments of that \
         stage's looks so far with its standard error, and the one-sided interval [lower, ∞) of \
         Δ at the stage's per-test level (its Bonferroni share of {c:.0} %) whose lower end was \
         above 0. All {} are listed in `eliminated_m{m}.csv` (and in the results' rows: `stage`, \
         `look`, `versus`, `diff`, `diff_se`, `diff_lower`).\n\n\
         | stage | look | eliminated | smallest lower bound (pp) | median lower bound (pp) |\n|---:|---:|---:|---:|---:|\n",
        el.len()
    );
    let mut groups: std::collections::BTreeMap<(usize, usize), Vec<f64>> = Default::default();
    for r in &el {
        groups
            .entry((r.stage, r.look.unwrap_or(0)))
            .or_default()
            .push(r.diff_lower.unwrap_or(f64::NAN));
    }
    for ((k, j), mut v) in groups {
        v.sort_by(f64::total_cmp);
        let _ = writeln!(
            s,
            "| {k} | {} | {} | {:+.4} | {:+.4} |",
            j + 1,
            v.len(),
            v[0] * 100.0,
            v[v.len() / 2] * 100.0
        );
    }
    el.sort_by(|a, b| {
        a.error
            .unwrap_or(f64::INFINITY)
            .total_cmp(&b.error.unwrap_or(f64::INFINITY))
            .then(a.index.cmp(&b.index))
    });
    let _ = writeln!(
        s,
        "\nThe {} eliminated candidates with the lowest estimates:\n\n\
         | index | functions | error (%) ± s.e. | fragments | stage | look | reference | Δ (pp) ± s.e. | interval of Δ (pp) |\n\
         |---:|---|---:|---:|---:|---:|---:|---:|---|",
        limit.min(el.len())
    );
    for r in el.iter().take(limit) {
        let _ = writeln!(
            s,
            "| {} | {} | {:.4} ± {:.4} | {} | {} | {} | {} | {:+.4} ± {:.4} | [{:+.4}, ∞) |",
            r.index,
            r.functions.join(", "),
            r.error.unwrap_or(f64::NAN) * 100.0,
            r.stderr.unwrap_or(0.0) * 100.0,
            r.fragments,
            r.stage,
            r.look.unwrap_or(0) + 1,
            r.versus.map_or("–".into(), |v| v.to_string()),
            r.diff.unwrap_or(f64::NAN) * 100.0,
            r.diff_se.unwrap_or(f64::NAN) * 100.0,
            r.diff_lower.unwrap_or(f64::NAN) * 100.0
        );
    }
    s
}

/// Every candidate eliminated by evidence (CSV: index, functions, error, stderr, fragments,
/// stage, look, versus, diff, diff_se, diff_lower, common_error, common_stderr), by index;
/// None for a run without racing.
fn eliminated_list(rows: &[Row], t: &TieSet) -> Option<String> {
    if !t.raced {
        return None;
    }
    let mut s = String::from(
        "index,functions,error,stderr,fragments,stage,look,versus,diff,diff_se,diff_lower,common_error,common_stderr\n",
    );
    let mut el: Vec<&Row> = rows.iter().filter(|r| r.eliminated.is_some()).collect();
    el.sort_by_key(|r| r.index);
    for r in el {
        let o = |x: Option<f64>| x.map_or(String::new(), |v| format!("{v:.8}"));
        let _ = writeln!(
            s,
            "{},\"{}\",{},{},{},{},{},{},{},{},{},{},{}",
            r.index,
            r.functions.join(", "),
            o(r.error),
            o(r.stderr),
            r.fragments,
            r.stage,
            r.look.unwrap_or(0) + 1,
            r.versus.map_or(String::new(), |v| v.to_string()),
            o(r.diff),
            o(r.diff_se),
            o(r.diff_lower),
            o(r.common_error),
            o(r.common_stderr)
        );
    }
    Some(s)
}

/// Text: where the references rank and how far the best candidate is below them.
pub fn ranking_text(rows: &[Row], refs: &[Reference]) -> String {
    let errs = errors_of(rows);
    let mut s = String::new();
    let Some(top) = winner_of(rows) else {
        return "No scored candidates.\n".into();
    };
    let best = top.error.unwrap_or(f64::NAN);
    let _ = writeln!(
        s,
        "The winner of {} scored candidates is {} = ({}) with {:.4} % ± {:.4} %{}.",
        errs.len(),
        top.index,
        top.functions.join(", "),
        best * 100.0,
        top.stderr.unwrap_or(0.0) * 100.0,
        if top.full {
            ", scored on every fragment"
        } else {
            ""
        }
    );
    let lowest = &ranking(rows)[0];
    if lowest.index != top.index {
        let _ = writeln!(
            s,
            "The lowest estimate is that of {} = ({}), {:.4} % ± {:.4} % on a sample of {} fragments \
             ({}): an estimate of a candidate that left the race, not a measured improvement.",
            lowest.index,
            lowest.functions.join(", "),
            lowest.error.unwrap_or(f64::NAN) * 100.0,
            lowest.stderr.unwrap_or(0.0) * 100.0,
            lowest.fragments,
            status(lowest)
        );
    }
    s.push_str("Ranks below count every candidate's estimate, sampled ones included.\n\n");
    let m = top.functions.len();
    for r in refs.iter().filter(|r| r.label != "PCF" && r.m != m) {
        let _ = writeln!(
            s,
            "- {} (m = {}): {:.4} % ± {:.4} % (not ranked: different m).",
            r.label,
            r.m,
            r.error * 100.0,
            r.stderr * 100.0
        );
    }
    for r in refs.iter().filter(|r| r.label != "PCF" && r.m == m) {
        let _ = writeln!(
            s,
            "- {}: {:.4} % ± {:.4} %, rank {} of {} (the best candidate is {:.4} percentage points, {:.1} % relative, below it).",
            r.label,
            r.error * 100.0,
            r.stderr * 100.0,
            rank_of(&errs, r.error),
            errs.len(),
            (r.error - best) * 100.0,
            if r.error > 0.0 { (r.error - best) / r.error * 100.0 } else { 0.0 }
        );
    }
    s.push_str(
        "\nPaper (Peters & Klein 2015, Section 3.2): b_MSM 2.19 %, b_TMSM 1.93 % (the minimum over all 66045 candidates).\n",
    );
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(index: u64, e: Option<f64>, dup: Option<u64>) -> Row {
        Row {
            error: e,
            stderr: e.map(|_| 0.001),
            fragments: 10,
            degenerate: e.is_none() && dup.is_none(),
            duplicate_of: dup,
            full: true,
            ..Row::plain(index, vec![format!("f{index}")])
        }
    }

    #[test]
    fn top_table_ranks_only_candidates_scored_on_every_fragment() {
        // Candidate 7 left the race early with the lowest estimate: it is listed below the
        // finished candidates without a rank, and rank 1 goes to the best finished one.
        let mut early = row(7, Some(0.01), None);
        early.full = false;
        early.fragments = 3;
        let rows = vec![row(0, Some(0.03), None), row(1, Some(0.02), None), early];
        let t = top_table(&rows, 3);
        let body: Vec<&str> = t.lines().skip(2).collect();
        assert!(body[0].starts_with("| 1 | 1 | f1 |"), "{t}");
        assert!(body[1].starts_with("| 2 | 0 | f0 |"), "{t}");
        assert!(body[2].starts_with("| – | 7 | f7 |"), "{t}");
    }

    #[test]
    fn ranking_table_and_text() {
        let rows = vec![
            row(0, Some(0.03), None),
            row(1, Some(0.02), None),
            row(2, None, None),
            row(3, None, Some(1)),
        ];
        let r = ranking(&rows);
        assert_eq!(r.iter().map(|r| r.index).collect::<Vec<_>>(), vec![1, 3, 0]);
        assert_eq!(rank_of(&errors_of(&rows), 0.025), 3);
        assert_eq!(rank_of(&errors_of(&rows), 0.01), 1);
        let t = top_table(&rows, 2);
        assert_eq!(t.lines().count(), 4);
        assert!(t.contains("| 1 | 1 | f1 | 2.0000 |"), "{t}");
        let refs = [Reference {
            label: "b_MSM (LP)".into(),
            m: 1,
            error: 0.025,
            stderr: 0.0,
            closed_form: false,
            diff: None,
        }];
        let text = ranking_text(&rows, &refs);
        assert!(text.contains("rank 3 of 3"), "{text}");
        assert!(text.contains("0.5000 percentage points"), "{text}");
    }
}
