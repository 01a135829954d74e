//! Step 9: the report (`index.html` + `report.md`) from the artefacts of the other steps; the
//! sub-reports (sweep, θ, quantization, stability) are included from their folders.

use super::progress::pct;
use super::theta::ThetaRow;
use super::{Config, Plan};
use crate::report::document::Document;
use crate::report::pareto::{self, Entry};
use crate::report::recommend::{Measured, Recommendation};
use crate::stack::DepthStack;
use anyhow::Result;
use std::path::{Path, PathBuf};

fn s(x: impl ToString) -> String {
    x.to_string()
}

/// Everything the report shows.
pub struct ReportInputs<'a> {
    pub plan: &'a Plan,
    pub config: &'a Config,
    pub stacks: &'a [DepthStack],
    pub all: &'a [Measured],
    pub entries: &'a [Entry],
    pub recs: &'a [Recommendation],
    pub chosen_grid: &'a [(String, usize)],
    pub refinement: &'a [(usize, Vec<(String, f64)>)],
    pub theta_rows: &'a [ThetaRow],
    pub search_notes: &'a [String],
    pub search_report: &'a Path,
    pub out: &'a Path,
    pub pictures: &'a [(String, String)],
    pub seconds: f64,
}

/// Copy the markdown of a sub-report in as preformatted text and its SVG figures as figures.
fn include_folder(doc: &mut Document, dir: &Path, out: &Path) -> Result<()> {
    let Ok(rd) = std::fs::read_dir(dir) else {
        return Ok(());
    };
    let mut files: Vec<PathBuf> = rd.filter_map(|e| e.ok().map(|e| e.path())).collect();
    files.sort();
    let rel = |p: &Path| {
        p.strip_prefix(out)
            .map(|r| r.to_string_lossy().replace('\\', "/"))
            .unwrap_or_else(|_| p.display().to_string())
    };
    for f in &files {
        match f.extension().and_then(|e| e.to_str()) {
            // Sub-reports' own image links are relative to their folder: the figures are
            // added below as figures of this report, so drop those lines from the text.
            Some("md") => doc.code(
                std::fs::read_to_string(f)?
                    .lines()
                    .filter(|l| !l.trim_start().starts_with("!["))
                    .collect::<Vec<_>>()
                    .join("\n")
                    .trim()
                    .to_string(),
            ),
            Some("svg") | Some("png") => doc.figure(
                rel(f),
                f.file_name()
                    .map(|n| n.to_string_lossy().to_string())
                    .unwrap_or_default(),
            ),
            _ => {}
        }
    }
    Ok(())
}

/// The report document of a run (written by the caller as index.html and report.md).
pub fn build(r: ReportInputs) -> Result<Document> {
    let mut d = Document::new("momentlab: Moment Shadow Mapping, reproduced");
    d.paragraph(format!(
        "Run '{}' ({} configuration): {} views at {}×{}, {} fragments, {:.0} s on this machine. \
         Every number below is produced by momentlab from these depth stacks, except where a \
         column or sentence says 'paper' (Peters & Klein, I3D 2015, and its supplementary).",
        r.config.run,
        r.config.preset.name(),
        r.stacks.len(),
        r.plan.resolution,
        r.plan.resolution,
        r.stacks.iter().map(|s| s.fragment_count()).sum::<usize>(),
        r.seconds
    ));

    d.heading("The paper's numbers side by side with ours");
    let find = |n: &str, p: &str| r.all.iter().find(|m| m.name == n && m.precision == p);
    let err_of = |n: &str, p: &str| find(n, p).map_or("n/a".to_string(), |m| pct(m.error));
    let mut rows = vec![
        vec![
            s("b_MSM error (LP, 4 moments)"),
            s("2.19 %"),
            err_of("lp:z,z^2,z^3,z^4", "f64"),
        ],
        vec![
            s("b_TMSM error (LP)"),
            s("1.93 %"),
            err_of("lp:sin(2πz),cos(2πz),sin(4πz),cos(4πz)", "f64"),
        ],
        vec![
            s("Hamburger 4MSM (closed form, f32)"),
            s("—"),
            err_of("hamburger4", "f32"),
        ],
        vec![s("TMSM (closed form, f32)"), s("—"), err_of("tmsm", "f32")],
        vec![
            s("candidates evaluated, time"),
            s("66045, several weeks on a cluster"),
            r.search_notes.join("; "),
        ],
    ];
    for &(m, gain, _, secs) in r.theta_rows {
        let paper = match m {
            2 => "2 bits",
            3 => "6.2 bits",
            4 => "12.2783 bits",
            6 => "30.511 bits",
            _ => "—",
        };
        rows.push(vec![
            format!("θ{m} entropy gain"),
            s(paper),
            format!("{gain:.4} bits ({secs:.1} s)"),
        ]);
    }
    d.table(&["quantity", "paper", "momentlab (this run)"], rows);

    d.heading("Techniques against PCF on the same fragments");
    let lp_grid = r.chosen_grid.iter().map(|x| x.1).max().unwrap_or(0);
    d.paragraph(format!(
        "Error = mean |G − PCF| over all fragments of all layers (9×9 Gaussian PCF, σ = 2.4 \
         texels). Closed forms see every fragment; LP candidates (Algorithm 1 on n = {lp_grid} \
         uniform grid points, the largest n the grid convergence test below chose: {}) every \
         {}-th fragment. Speed: mean nanoseconds per evaluation on one core over the filter \
         windows of fragments sampled from the same depth stacks, for closed forms and LP \
         candidates alike (momentlab's timing loop, `momentlab bench shadow --corpus stacks`).",
        r.chosen_grid
            .iter()
            .map(|(s, n)| format!("{s} {n}"))
            .collect::<Vec<_>>()
            .join(", "),
        r.plan.lp_stride
    ));
    let mut sorted: Vec<&Measured> = r.all.iter().collect();
    sorted.sort_by(|a, b| a.error.total_cmp(&b.error));
    d.table(
        &[
            "technique",
            "precision",
            "error",
            "ns / fragment",
            "bits / texel",
            "fragments",
            "trivial",
            "non-finite",
            "unsettled LPs",
        ],
        sorted
            .iter()
            .map(|m| {
                vec![
                    m.name.clone(),
                    m.precision.clone(),
                    pct(m.error),
                    format!("{:.1}", m.ns_per_fragment),
                    m.bits_per_texel.to_string(),
                    m.fragments.to_string(),
                    m.trivial.to_string(),
                    m.non_finite.to_string(),
                    m.unsettled.to_string(),
                ]
            })
            .collect(),
    );
    d.heading("Speed against accuracy");
    d.figure(
        "speed_accuracy.svg",
        "Error against PCF over nanoseconds per fragment. Every point is numbered (legend on \
         the right, ★ = Pareto front, also the red line); blue = LP candidates (Algorithm 1 on a \
         grid, references), black = closed forms; circle = f32, triangle = f64; marker size \
         grows with bits per texel.",
    );
    d.figure(
        "error_histograms.svg",
        "Distribution of |G − PCF| over fragments per technique (f32 closed forms and LP \
         candidates), log₁₀ counts per bin (four bins per decade; the first bin is [0, 1e-4)). \
         Every bin is drawn: an empty bin at a count of 0.5 (log₁₀ = −0.3) on the dashed \
         baseline; the legend is right of the plot.",
    );
    let front = pareto::pareto_front(r.entries);
    d.paragraph(format!(
        "Pareto front: {}.",
        front
            .iter()
            .map(|&i| format!("{} ({})", r.entries[i].name, r.entries[i].precision))
            .collect::<Vec<_>>()
            .join(", ")
    ));

    d.heading("No more model than a scene needs");
    d.paragraph(format!(
        "Recommendation per scene: the cheapest closed-form technique (fewest bits per texel, \
         then fewest ns per fragment) whose error is within {} of the best closed form on that \
         scene (`momentlab recommend --tolerance`). Runner-up: the most accurate cheaper \
         technique (what going faster costs in error), or the next within the tolerance.",
        pct(r.config.tolerance)
    ));
    d.table(
        &[
            "scene",
            "recommended",
            "error",
            "bits / texel",
            "ns / fragment",
            "best",
            "best error",
            "runner-up",
            "its error (ns)",
        ],
        r.recs
            .iter()
            .map(|x| {
                vec![
                    x.scene.clone(),
                    format!("{} ({})", x.name, x.precision),
                    pct(x.error),
                    x.bits_per_texel.to_string(),
                    format!("{:.1}", x.ns_per_fragment),
                    x.best_name.clone(),
                    pct(x.best_error),
                    x.runner_up.as_ref().map_or("–".into(), |u| u.0.clone()),
                    x.runner_up.as_ref().map_or("–".into(), |u| {
                        format!(
                            "{} ({:+.2} pp, {:.1} ns)",
                            pct(u.1),
                            100.0 * (u.1 - x.error),
                            u.2
                        )
                    }),
                ]
            })
            .collect(),
    );
    let grid_tol = r.config.tolerance / 10.0;
    d.paragraph(format!(
        "LP grid: b_MSM evaluated with n = {} grid points (every {}-th fragment); the chosen n \
         is the smallest whose error is within {} of the finest grid's (a convergence test: \
         neighbouring grids can agree on a plateau while a finer one is still better). \
         docs/evaluation.md explains non-monotone steps.",
        r.refinement
            .iter()
            .map(|x| x.0.to_string())
            .collect::<Vec<_>>()
            .join(", "),
        r.plan.lp_stride * 2,
        pct(grid_tol)
    ));
    let mut head = vec!["scene".to_string()];
    head.extend(r.refinement.iter().map(|x| format!("n = {}", x.0)));
    head.push("chosen n".into());
    let head: Vec<&str> = head.iter().map(|s| s.as_str()).collect();
    d.table(
        &head,
        r.chosen_grid
            .iter()
            .map(|(s, n)| {
                let mut row = vec![s.clone()];
                for (_, sc) in r.refinement {
                    row.push(
                        sc.iter()
                            .find(|x| &x.0 == s)
                            .map_or("–".into(), |x| pct(x.1)),
                    );
                }
                row.push(n.to_string());
                row
            })
            .collect(),
    );
    d.figure(
        "grid_refinement.svg",
        "LP b_MSM error per scene against the grid size n.",
    );

    d.heading("Shadow pictures (Hamburger 4MSM)");
    d.paragraph(
        "Panels, left to right: front depth, layer count, PCF shadow, technique shadow, |error| \
         heat map.",
    );
    for (f, c) in r.pictures {
        d.figure(f.clone(), c.clone());
    }

    d.heading("Candidate sweep (Fig. 3 and Fig. 4 analogues)");
    for n in r.search_notes {
        d.paragraph(n.clone());
    }
    include_folder(&mut d, r.search_report, r.out)?;

    d.heading("Quantization transforms θ (Fig. 5 analogue) and 16-bit moment shadow maps");
    include_folder(&mut d, &r.out.join("theta"), r.out)?;
    include_folder(&mut d, &r.out.join("quantize"), r.out)?;

    d.heading("Stability: where each method fails");
    include_folder(&mut d, &r.out.join("stability"), r.out)?;
    Ok(d)
}
