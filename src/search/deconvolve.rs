//! How many candidates the full-size racing test would eliminate, estimated from the plan's
//! proxy race, which sees every block at 1/s of its size (pure functions, no IO).
//!
//! **Model.** Candidate c's standardised margin on the proxy's block is u_c = (d̄_c − h_c)/se_c:
//! d̄ its mean paired difference to the stage reference, se its standard error on the proxy's
//! fragments and h the full block's threshold. u_c ~ N(ν_c, 1) with ν_c = (g_c − h_c)/se_c for
//! the true gap g_c. On the full block the standard error is se_c/√s, so the run eliminates c
//! with probability Φ(√s·ν_c). Deciding on u_c itself (u_c > 0) eliminates with probability
//! Φ(ν_c): too often below the threshold and too rarely above it, which biases the proxy's
//! survivor counts wherever many candidates lie close to the threshold.
//!
//! **Estimate.** The ν_c of a stage are drawn from an unknown distribution G, estimated by
//! nonparametric maximum likelihood (Kiefer & Wolfowitz 1956; EM on a grid of ν, as in
//! Koenker & Mizera 2014) from all u_c of the stage; each candidate's elimination probability is
//! its posterior mean of Φ(√s·ν) under G. Their sum estimates the run's count.

use super::race::normal_cdf;

/// Margins beyond ±`DECIDED` are decided without the fit (their likelihood at |ν| ≤ 1, where
/// Φ(√s·ν) is not already 0 or 1, is below 1e-17 of that at ν = u).
const DECIDED: f64 = 10.0;
/// The fit uses the margins in ±`FIT` and a grid of ν over ±(`FIT` + 4) in steps of `STEP`.
const FIT: f64 = 12.0;
const STEP: f64 = 0.1;
/// Margins are binned to `BIN` (the likelihood varies by under 2 % within a bin).
const BIN: f64 = 0.02;
/// EM's iterations: fewer leave G smoother than the data say (at 100, near-ties 0.7 below the
/// threshold are over-counted by 10 %; at 1 000 by 3 %, with a spread of 1–2 % over samples).
const EM_ITERATIONS: usize = 1000;

/// Per-candidate probability that the full-size test (s times the proxy's fragments) eliminates
/// it, from the proxy's standardised margins `u` (see the module docs; ±∞ and NaN are decided:
/// +∞ eliminated, otherwise kept). `share` = s ≥ 1.
pub fn elimination_probabilities(u: &[f64], share: f64) -> Vec<f64> {
    let root = share.max(1.0).sqrt();
    let grid: Vec<f64> = {
        let k = ((FIT + 4.0) / STEP).round() as i64;
        (-k..=k).map(|i| i as f64 * STEP).collect()
    };
    // Binned margins in the fit window: (centre, count).
    let mut bins: std::collections::BTreeMap<i64, f64> = Default::default();
    for &x in u {
        if x.is_finite() && x.abs() <= FIT {
            *bins.entry((x / BIN).round() as i64).or_default() += 1.0;
        }
    }
    let centres: Vec<f64> = bins.keys().map(|&b| b as f64 * BIN).collect();
    let counts: Vec<f64> = bins.values().copied().collect();
    let weights = npmle(&centres, &counts, &grid);
    let tail: Vec<f64> = grid.iter().map(|&v| normal_cdf(root * v)).collect();
    u.iter()
        .map(|&x| {
            if x.is_nan() || x < -DECIDED {
                0.0
            } else if x > DECIDED {
                1.0
            } else {
                posterior_mean(x, &grid, &weights, &tail)
            }
        })
        .collect()
}

/// Weights of G on `grid` maximising Σ_b count_b · ln Σ_i w_i φ(x_b − ν_i) (EM from uniform).
fn npmle(x: &[f64], count: &[f64], grid: &[f64]) -> Vec<f64> {
    let k = grid.len();
    let mut w = vec![1.0 / k as f64; k];
    let total: f64 = count.iter().sum();
    if total == 0.0 {
        return w;
    }
    let like: Vec<Vec<f64>> = x
        .iter()
        .map(|&xb| grid.iter().map(|&v| density(xb - v)).collect())
        .collect();
    let mut next = vec![0.0; k];
    for _ in 0..EM_ITERATIONS {
        next.iter_mut().for_each(|v| *v = 0.0);
        for (row, &c) in like.iter().zip(count) {
            let mix: f64 = row.iter().zip(&w).map(|(l, w)| l * w).sum();
            if mix > 0.0 {
                let f = c / (mix * total);
                for ((n, l), w) in next.iter_mut().zip(row).zip(&w) {
                    *n += f * l * w;
                }
            }
        }
        std::mem::swap(&mut w, &mut next);
    }
    w
}

/// E[t(ν) | x] under the prior `weights` on `grid`, t = `tail` on the grid.
fn posterior_mean(x: f64, grid: &[f64], weights: &[f64], tail: &[f64]) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for ((&v, &w), &t) in grid.iter().zip(weights).zip(tail) {
        let p = w * density(x - v);
        num += p * t;
        den += p;
    }
    if den > 0.0 {
        num / den
    } else {
        // Outside the prior's support: the margin itself decides.
        normal_cdf(x)
    }
}

/// Standard normal density.
fn density(x: f64) -> f64 {
    (-0.5 * x * x).exp() / (2.0 * std::f64::consts::PI).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::search::race::normal_quantile;
    use rand::{Rng, SeedableRng};

    /// Proxy margins of a population of true margins ν at share s; returns (the run's expected
    /// count Σ Φ(√s ν), the estimate, the proxy's own count of u > 0).
    fn counts(nu: &[f64], share: f64, seed: u64) -> (f64, f64, f64) {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let u: Vec<f64> = nu
            .iter()
            .map(|&v| v + normal_quantile(rng.gen_range(1e-12..1.0)))
            .collect();
        let truth = nu.iter().map(|&v| normal_cdf(share.sqrt() * v)).sum();
        let est = elimination_probabilities(&u, share).iter().sum();
        let hard = u.iter().filter(|&&x| x > 0.0).count() as f64;
        (truth, est, hard)
    }

    #[test]
    fn near_ties_below_the_threshold_are_not_over_eliminated() {
        // 3 000 candidates just below the threshold (ν = −0.7) and 1 000 far above it
        // (eliminated for sure), as at m = 4's later stages. The run eliminates about
        // 1 000 + 3 000·Φ(−0.7·√8) ≈ 1 072; the proxy's own test about 1 000 + 3 000·Φ(−0.7)
        // ≈ 1 726.
        let nu: Vec<f64> = (0..4000)
            .map(|i| if i < 3000 { -0.7 } else { 6.0 })
            .collect();
        for seed in 0..5 {
            let (truth, est, hard) = counts(&nu, 8.0, seed);
            assert!((est - truth).abs() < 0.08 * truth, "{est} vs {truth}");
            assert!(hard - truth > 0.5 * truth, "{hard} vs {truth}");
        }
    }

    #[test]
    fn a_spread_population_is_counted_within_a_few_percent() {
        // True margins spread uniformly over [−6, 6]: about half are eliminated.
        let nu: Vec<f64> = (0..5000).map(|i| -6.0 + 12.0 * i as f64 / 4999.0).collect();
        for seed in 0..5 {
            let (truth, est, _) = counts(&nu, 8.0, seed);
            assert!((est - truth).abs() < 0.06 * truth, "{est} vs {truth}");
        }
    }

    #[test]
    fn decided_margins_need_no_fit() {
        let p = elimination_probabilities(&[-40.0, 40.0, f64::INFINITY, f64::NAN], 8.0);
        assert_eq!(p, vec![0.0, 1.0, 1.0, 0.0]);
    }

    #[test]
    fn one_candidate_at_the_threshold_is_a_coin_toss() {
        // A single margin 0: G puts its mass near 0, and Φ(√s·0) = 1/2.
        let p = elimination_probabilities(&[0.0], 8.0);
        assert!((p[0] - 0.5).abs() < 0.02, "{p:?}");
    }
}
