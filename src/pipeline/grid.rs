//! Step 3: LP grid refinement — b_MSM with Algorithm 1 on grids of n points, per scene; the
//! chosen n is the first whose error differs from the next finer grid by less than
//! tolerance / 10. Artefacts: `grid_refinement.json`, `grid_refinement.svg`.

use super::techniques::evaluate;
use super::Plan;
use crate::artefact::{read_json, write_json};
use crate::report::chart;
use crate::report::recommend::per_scene;
use crate::stack::DepthStack;
use crate::technique::lp_candidate::LpCandidate;
use anyhow::Result;
use std::path::Path;

/// Per grid size n, the per-scene errors (scene, mean |G − PCF|).
pub type Refinement = Vec<(usize, Vec<(String, f64)>)>;

/// The refinement, read back from `file` or computed on every `2·lp_stride`-th fragment.
pub fn refine(stacks: &[DepthStack], plan: &Plan, file: &Path) -> Result<Refinement> {
    if let Ok(r) = read_json(file) {
        return Ok(r);
    }
    let mut r = Vec::new();
    for &n in &plan.grid_sizes {
        let basis = crate::basis::Catalog::embedded().basis(&[
            "z".to_string(),
            "z^2".into(),
            "z^3".into(),
            "z^4".into(),
        ])?;
        let t = LpCandidate::new(basis, crate::Grid::uniform(n)?, "fast")?;
        let rep = evaluate(stacks, &t, &format!("b_MSM, n = {n}"), plan.lp_stride * 2)?;
        let sc: Vec<(String, f64)> = per_scene(&rep)
            .into_iter()
            .map(|(a, e, _)| (a, e))
            .collect();
        r.push((n, sc));
    }
    write_json(file, &r)?;
    Ok(r)
}

/// Per scene (in the order of the coarsest grid), the first n whose error differs from the
/// next finer grid by less than `tolerance` (the finest n when none does).
pub fn choose(refinement: &Refinement, tolerance: f64) -> Vec<(String, usize)> {
    let Some((_, first)) = refinement.first() else {
        return Vec::new();
    };
    first
        .iter()
        .map(|(scene, _)| {
            let errs = series_of(refinement, scene);
            let pick = errs
                .windows(2)
                .find(|w| (w[1].1 - w[0].1).abs() < tolerance)
                .map(|w| w[0].0 as usize)
                .unwrap_or_else(|| errs.last().map_or(0, |x| x.0 as usize));
            (scene.clone(), pick)
        })
        .collect()
}

/// (n, error) of one scene over the grid sizes.
fn series_of(refinement: &Refinement, scene: &str) -> Vec<(f64, f64)> {
    refinement
        .iter()
        .filter_map(|(n, sc)| sc.iter().find(|x| x.0 == scene).map(|x| (*n as f64, x.1)))
        .collect()
}

/// The error-against-n chart, one line per scene.
pub fn chart(refinement: &Refinement, chosen: &[(String, usize)], file: &Path) -> Result<()> {
    let series: Vec<(String, Vec<(f64, f64)>)> = chosen
        .iter()
        .map(|(scene, _)| (scene.clone(), series_of(refinement, scene)))
        .collect();
    chart::lines_svg(
        file,
        "LP b_MSM error against grid size n",
        "grid points n (log scale)",
        "mean |G − PCF|",
        &series,
        true,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn first_settled_grid_per_scene() {
        let r: Refinement = vec![
            (64, vec![("a".into(), 0.30), ("b".into(), 0.20)]),
            (128, vec![("a".into(), 0.25), ("b".into(), 0.2001)]),
            (256, vec![("a".into(), 0.2499), ("b".into(), 0.2001)]),
        ];
        assert_eq!(
            choose(&r, 0.001),
            vec![("a".to_string(), 128), ("b".to_string(), 64)]
        );
        // Never settles: the finest grid.
        assert_eq!(choose(&r, 1e-9)[0], ("a".to_string(), 256));
        assert!(choose(&Vec::new(), 0.1).is_empty());
    }
}
