//! Step 3: LP grid refinement — b_MSM with Algorithm 1 on grids of n points, per scene. The
//! choice is a convergence test ([`choose`]): the smallest n whose error is within the tolerance
//! of the finest grid evaluated. Artefacts: `grid_refinement.json` ([`GridChoice`]: tolerance,
//! every n's per-scene errors, the chosen n per scene) and `grid_refinement.svg`.

use super::techniques::evaluate;
use super::Plan;
use crate::artefact::{read_json, write_json};
use crate::metrics::Subject;
use crate::report::chart;
use crate::report::recommend::per_scene;
use crate::stack::DepthStack;
use crate::technique::lp_candidate::LpCandidate;
use anyhow::Result;
use std::collections::BTreeMap;
use std::path::Path;

/// Per grid size n, the per-scene errors (scene, mean |G − PCF|).
pub type Refinement = Vec<(usize, Vec<(String, f64)>)>;

/// `grid_refinement.json`: `{"tolerance": t, "grids": [[n, [[scene, error], …]], …],
/// "chosen": {scene: n}}`.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct GridChoice {
    /// Allowed |e(n) − e(n_max)| of a chosen grid size.
    pub tolerance: f64,
    /// Mean error per scene for each grid size n.
    pub grids: Refinement,
    /// The chosen grid size n per scene.
    pub chosen: BTreeMap<String, usize>,
}

/// The refinement for `plan.grid_sizes` on every `2·lp_stride`-th fragment, written to `file`
/// (with the choice for `tolerance`) after every grid size. Grid sizes already in `file` (an
/// earlier run) are read back, only missing ones computed.
pub fn refine(
    stacks: &[DepthStack],
    plan: &Plan,
    file: &Path,
    tolerance: f64,
) -> Result<Refinement> {
    let done: Refinement = read_json::<GridChoice>(file)
        .map(|c| c.grids)
        .unwrap_or_default();
    let mut r = Vec::new();
    for &n in &plan.grid_sizes {
        if let Some(row) = done.iter().find(|x| x.0 == n) {
            r.push(row.clone());
            continue;
        }
        let basis = crate::basis::Catalog::embedded().basis(&[
            "z".to_string(),
            "z^2".into(),
            "z^3".into(),
            "z^4".into(),
        ])?;
        let t = LpCandidate::new(basis, crate::Grid::uniform(n)?, crate::lp::SolverKind::Fast)?;
        let label = format!("b_MSM, n = {n}");
        let rep = evaluate(
            stacks,
            &[Subject::Technique(&t)],
            &[&label],
            plan.lp_stride * 2,
        )?
        .remove(0);
        let sc: Vec<(String, f64)> = per_scene(&rep)
            .into_iter()
            .map(|(a, e, _)| (a, e))
            .collect();
        r.push((n, sc));
        write_json(
            file,
            &GridChoice {
                tolerance,
                grids: r.clone(),
                chosen: choose(&r, tolerance).into_iter().collect(),
            },
        )?;
    }
    Ok(r)
}

/// Convergence test per scene (in the order of the coarsest grid): the smallest n whose error
/// e(n) satisfies |e(n) − e(n_max)| ≤ `tolerance`, with n_max the finest grid evaluated for that
/// scene. Comparing with the finest grid (not with the next one) does not stop on a plateau:
/// two neighbouring grids can agree while a finer one is still much better. NaN errors never
/// qualify.
pub fn choose(refinement: &Refinement, tolerance: f64) -> Vec<(String, usize)> {
    let Some((_, first)) = refinement.iter().min_by_key(|x| x.0) else {
        return Vec::new();
    };
    first
        .iter()
        .map(|(scene, _)| {
            let mut errs = series_of(refinement, scene);
            errs.sort_by(|a, b| a.0.total_cmp(&b.0));
            let finest = errs.last().map_or(f64::NAN, |x| x.1);
            let pick = errs
                .iter()
                .find(|(_, e)| (e - finest).abs() <= tolerance)
                .or(errs.last())
                .map_or(0, |x| x.0 as usize);
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
        .map(|(scene, _)| {
            let pts = series_of(refinement, scene);
            (
                scene.clone(),
                pts.iter().map(|&(n, e)| (n, 100.0 * e)).collect(),
            )
        })
        .collect();
    let svg = chart::lines_svg(
        "LP b_MSM error against grid size n",
        "grid points n (log scale)",
        "mean |G − PCF| (%)",
        &series,
        true,
    )?;
    crate::artefact::write_text(file, &svg)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn r() -> Refinement {
        vec![
            (
                64,
                vec![("a".into(), 0.30), ("b".into(), 0.20), ("c".into(), 0.04)],
            ),
            (
                128,
                vec![("a".into(), 0.25), ("b".into(), 0.2001), ("c".into(), 0.06)],
            ),
            (
                256,
                vec![
                    ("a".into(), 0.2499),
                    ("b".into(), 0.2001),
                    ("c".into(), 0.0505),
                ],
            ),
            (
                512,
                vec![
                    ("a".into(), 0.2000),
                    ("b".into(), 0.2002),
                    ("c".into(), 0.0501),
                ],
            ),
        ]
    }

    #[test]
    fn smallest_grid_within_tolerance_of_the_finest() {
        // a: 128 → 256 is a plateau (Δ 1e-4) but 512 is 0.05 better: the plateau is not chosen.
        // b: flat from the start. c: non-monotone (up at 128); 256 is within 1e-3 of 512.
        assert_eq!(
            choose(&r(), 0.001),
            vec![
                ("a".to_string(), 512),
                ("b".to_string(), 64),
                ("c".to_string(), 256)
            ]
        );
        // c with a tolerance below 256's distance (4e-4): the finest grid.
        assert_eq!(choose(&r(), 0.0003)[2], ("c".to_string(), 512));
        // Never within a tiny tolerance except at the finest grid itself.
        assert_eq!(choose(&r(), 0.0)[0], ("a".to_string(), 512));
        assert!(choose(&Vec::new(), 0.1).is_empty());
    }

    #[test]
    fn chosen_error_is_within_tolerance_of_finest_on_random_refinements() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        for _ in 0..1000 {
            let sizes = [64, 128, 256, 512, 1024, 2048, 4096];
            let k = rng.gen_range(1..=sizes.len());
            let rf: Refinement = sizes[..k]
                .iter()
                .map(|&n| (n, vec![("s".to_string(), rng.gen_range(0.0..0.05))]))
                .collect();
            let t = rng.gen_range(0.0..0.02);
            let (_, n) = choose(&rf, t).pop().unwrap();
            let err = |n: usize| rf.iter().find(|x| x.0 == n).unwrap().1[0].1;
            let finest = err(sizes[k - 1]);
            assert!((err(n) - finest).abs() <= t);
            // No smaller n qualifies.
            for &m in sizes[..k].iter().filter(|&&m| m < n) {
                assert!((err(m) - finest).abs() > t);
            }
        }
    }

    #[test]
    fn json_shape() {
        let c = GridChoice {
            tolerance: 0.001,
            grids: r(),
            chosen: choose(&r(), 0.001).into_iter().collect(),
        };
        let v: serde_json::Value = serde_json::to_value(&c).unwrap();
        assert_eq!(v["tolerance"], 0.001);
        assert_eq!(v["grids"][0][0], 64);
        assert_eq!(v["grids"][0][1][0][0], "a");
        assert_eq!(v["chosen"]["a"], 512);
    }
}
