//! The proxy race's estimates refined on fresh fragments, before the run is simulated on them
//! (`search --plan`, [`super::plan::proxy_race`], [`super::forecast`]).
//!
//! Every gap ĝ_c of the proxy is paired with one candidate, its winner w, on the proxy's small
//! blocks: the noise of w's own mean there is shared by every gap (a common shift), and the
//! per-fragment spreads σ_c share the blocks' few outlying fragments. Independent noise would
//! average out over the candidates; the shared part does not, and the race's cost is most
//! sensitive to exactly these gaps (how far the field is from the best). So the plan scores a
//! few candidates and w once more on a fresh block of F fragments the proxy never saw (the next
//! F of the race's fragment order):
//!
//! * the [`CLOSEST`] candidates with the smallest ĝ_c (those that decide the later stages) take
//!   their gap and spread on the fresh block;
//! * [`DRAWN`] others, evenly spaced in the order of ĝ_c, fit the calibration of the rest:
//!   g = a + b·ĝ by least squares (selection on ĝ does not bias a regression on ĝ), and the
//!   spreads σ × ρ with ρ the median ratio of fresh to proxy spread.

use super::forecast::Estimate;
use super::Scorer;
use anyhow::Result;
use std::time::Instant;

/// Candidates nearest the proxy's winner scored on the fresh block.
pub const CLOSEST: usize = 128;
/// Candidates drawn evenly over the rest to fit the calibration.
pub const DRAWN: usize = 128;

/// What the refinement did (printed by the plan).
#[derive(Clone, Debug, PartialEq)]
pub struct Refinement {
    /// Fresh fragments scored.
    pub fragments: usize,
    /// Candidates that took their fresh gap and spread.
    pub closest: usize,
    /// Candidates that fitted the calibration.
    pub drawn: usize,
    /// g = a + b·ĝ for the rest: (a, b).
    pub line: (f64, f64),
    /// ρ: the rest's spreads are multiplied by it.
    pub spread: f64,
    /// LP solves and wall seconds of the refinement.
    pub lp_solves: u64,
    /// Wall seconds (all threads).
    pub seconds: f64,
}

/// The refined estimates of `est` (sorted by index; `winner` has gap 0), scoring the chosen
/// candidates and the winner on `fresh` (sorted fragment ids) with `cols(index)` their
/// functions. None when there are fewer than `min_fresh` fresh fragments (the plan: one
/// stage-0 block) or nothing to refine.
pub fn refine(
    scorer: &Scorer,
    est: &[Estimate],
    winner: u64,
    fresh: &[u32],
    min_fresh: usize,
    cols: &dyn Fn(u64) -> Result<Vec<usize>>,
) -> Result<Option<(Vec<Estimate>, Refinement)>> {
    if fresh.is_empty() || fresh.len() < min_fresh {
        return Ok(None);
    }
    let (closest, drawn) = choose(est, winner, CLOSEST, DRAWN);
    if closest.is_empty() {
        return Ok(None);
    }
    let chosen: Vec<usize> = closest.iter().chain(&drawn).copied().collect();
    let mut cands = chosen
        .iter()
        .map(|&k| cols(est[k].index))
        .collect::<Result<Vec<_>>>()?;
    cands.push(cols(winner)?);
    let t0 = Instant::now();
    let errs = scorer.errors_many(&cands, fresh, &|_| {})?;
    let seconds = t0.elapsed().as_secs_f64();
    let (last, own) = errs.split_last().expect("the winner was scored");
    let fresh_stats: Vec<(f64, f64)> = own
        .iter()
        .map(|e| paired(&e.errors, &last.errors))
        .collect();
    let pairs: Vec<(f64, f64)> = drawn
        .iter()
        .zip(&fresh_stats[closest.len()..])
        .map(|(&k, f)| (est[k].gap, f.0))
        .collect();
    let line = fit(&pairs);
    let mut ratios: Vec<f64> = drawn
        .iter()
        .zip(&fresh_stats[closest.len()..])
        .filter(|(&k, _)| est[k].sd > 0.0)
        .map(|(&k, f)| f.1 / est[k].sd)
        .collect();
    ratios.sort_by(f64::total_cmp);
    let spread = ratios.get(ratios.len() / 2).copied().unwrap_or(1.0);
    let fit = Fit {
        line,
        spread,
        fragments: fresh.len(),
    };
    let out = combine(est, winner, &closest, &fresh_stats, &fit);
    Ok(Some((
        out,
        Refinement {
            fragments: fresh.len(),
            closest: closest.len(),
            drawn: drawn.len(),
            line,
            spread,
            lp_solves: (cands.len() * fresh.len()) as u64,
            seconds,
        },
    )))
}

/// What the fresh block says about the rest: the line a + b·ĝ, the spread ratio ρ, and its
/// fragments F.
struct Fit {
    line: (f64, f64),
    spread: f64,
    fragments: usize,
}

/// The refined estimates (module docs): the `closest` (positions in `est`) pooled with their
/// fresh (gap, spread) `fresh`, every other candidate moved by its share w_c = F/(n_c + F)
/// towards the fit, the winner unchanged.
fn combine(
    est: &[Estimate],
    winner: u64,
    closest: &[usize],
    fresh: &[(f64, f64)],
    fit: &Fit,
) -> Vec<Estimate> {
    let f = fit.fragments as f64;
    let share = |e: &Estimate| f / (e.fragments as f64 + f);
    let (a, b) = fit.line;
    let mut out: Vec<Estimate> = est
        .iter()
        .map(|e| {
            if e.index == winner {
                return *e;
            }
            let w = share(e);
            Estimate {
                gap: e.gap + w * (a + b * e.gap - e.gap),
                sd: e.sd * (1.0 + w * (fit.spread - 1.0)),
                ..*e
            }
        })
        .collect();
    for (&k, &(gap, sd)) in closest.iter().zip(fresh) {
        let (e, w) = (&est[k], share(&est[k]));
        out[k].gap = (1.0 - w) * e.gap + w * gap;
        out[k].sd = ((1.0 - w) * e.sd * e.sd + w * sd * sd).sqrt();
        out[k].fragments = e.fragments + fit.fragments as u64;
    }
    out
}

/// Positions in `est` of the `closest` candidates with the smallest gaps (the winner
/// excluded) and of `drawn` others evenly spaced over the rest in the order of their gaps.
pub fn choose(
    est: &[Estimate],
    winner: u64,
    closest: usize,
    drawn: usize,
) -> (Vec<usize>, Vec<usize>) {
    let mut by_gap: Vec<usize> = (0..est.len())
        .filter(|&k| est[k].index != winner && est[k].gap.is_finite())
        .collect();
    by_gap.sort_by(|&a, &b| {
        est[a]
            .gap
            .total_cmp(&est[b].gap)
            .then(est[a].index.cmp(&est[b].index))
    });
    let near = closest.min(by_gap.len());
    let rest = &by_gap[near..];
    let take = drawn.min(rest.len());
    let spaced = (0..take).map(|j| rest[j * rest.len() / take]).collect();
    (by_gap[..near].to_vec(), spaced)
}

/// Mean and standard deviation of the paired differences a − b.
fn paired(a: &[f64], b: &[f64]) -> (f64, f64) {
    let n = a.len().min(b.len());
    if n == 0 {
        return (0.0, 0.0);
    }
    let d = || a.iter().zip(b).map(|(x, y)| x - y);
    let mean = d().sum::<f64>() / n as f64;
    let var = if n > 1 {
        d().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1) as f64
    } else {
        0.0
    };
    (mean, var.sqrt())
}

/// Least squares y = a + b·x over `pairs` (x, y); with fewer than two distinct x, b = 1 and a
/// the mean of y − x.
pub fn fit(pairs: &[(f64, f64)]) -> (f64, f64) {
    if pairs.is_empty() {
        return (0.0, 1.0);
    }
    let n = pairs.len() as f64;
    let mx = pairs.iter().map(|p| p.0).sum::<f64>() / n;
    let my = pairs.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = pairs.iter().map(|p| (p.0 - mx) * (p.0 - mx)).sum();
    let sxy: f64 = pairs.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    if sxx <= f64::EPSILON * mx.abs().max(1.0) * n {
        return (my - mx, 1.0);
    }
    let b = sxy / sxx;
    (my - b * mx, b)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn est(index: u64, gap: f64) -> Estimate {
        Estimate {
            index,
            gap,
            sd: 1.0,
            esd: 1.0,
            fragments: 100,
        }
    }

    #[test]
    fn fit_recovers_a_line_and_falls_back_to_a_shift() {
        let pairs: Vec<(f64, f64)> = (0..10).map(|i| (i as f64, 0.5 + 2.0 * i as f64)).collect();
        let (a, b) = fit(&pairs);
        assert!(
            (a - 0.5).abs() < 1e-12 && (b - 2.0).abs() < 1e-12,
            "{a} {b}"
        );
        assert_eq!(fit(&[(1.0, 3.0), (1.0, 5.0)]), (3.0, 1.0));
        assert_eq!(fit(&[]), (0.0, 1.0));
    }

    #[test]
    fn choose_takes_the_nearest_and_spreads_the_rest() {
        // Gaps 0.9, 0.8, …, 0.0 for indices 0..10; the winner (index 9, gap 0) is left out.
        let e: Vec<Estimate> = (0..10).map(|i| est(i, (9 - i) as f64 / 10.0)).collect();
        let (near, drawn) = choose(&e, 9, 3, 2);
        assert_eq!(near, [8, 7, 6]);
        // The rest by gap: 5, 4, 3, 2, 1, 0 (six); two evenly spaced: positions 0 and 3.
        assert_eq!(drawn, [5, 2]);
        let (near, drawn) = choose(&e, 9, 20, 5);
        assert_eq!(near.len(), 9);
        assert!(drawn.is_empty());
    }

    /// With F = 300 fresh fragments: a closest candidate seen on 100 pools 3/4 fresh, another
    /// seen on 300 moves half way to the line, the winner stays.
    #[test]
    fn combine_weights_by_fragments() {
        let mut e = vec![est(0, 0.0), est(1, 0.2), est(2, 0.4)];
        e[2].fragments = 300;
        let fit = Fit {
            line: (0.1, 0.5),
            spread: 3.0,
            fragments: 300,
        };
        let out = combine(&e, 0, &[1], &[(0.6, 5.0)], &fit);
        assert_eq!(out[0], e[0]);
        assert!((out[1].gap - (0.25 * 0.2 + 0.75 * 0.6)).abs() < 1e-15);
        assert!((out[1].sd - (0.25f64 + 0.75 * 25.0).sqrt()).abs() < 1e-15);
        assert_eq!(out[1].fragments, 400);
        // Line at 0.4: 0.1 + 0.2 = 0.3; half way: 0.35. Spread 1 → 3: half way 2.
        assert!((out[2].gap - 0.35).abs() < 1e-15);
        assert!((out[2].sd - 2.0).abs() < 1e-15);
    }

    #[test]
    fn paired_differences_have_their_mean_and_spread() {
        let (m, s) = paired(&[1.0, 2.0, 3.0, 4.0], &[0.0, 0.0, 0.0, 0.0]);
        assert_eq!(m, 2.5);
        assert!((s - (5.0f64 / 3.0).sqrt()).abs() < 1e-15);
    }
}
