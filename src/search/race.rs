//! Racing statistics (pure functions, no IO): when a candidate is worse than the stage reference
//! with a stated confidence, how α is split over looks (and candidates), the block plan, and
//! paired differences pooled over blocks.
//!
//! **Test.** On stage k's block (fresh fragments, disjoint from the blocks that chose the
//! reference R_k) candidate c is eliminated *by confidence* when the lower confidence bound of
//! μ_c − μ_R at level 1 − δ is above 0: d̄ − h(d, δ) > 0 with d = e_c − e_R per fragment
//! (paired), h the one-sided half-width ([`half_width`]). R_k is a real candidate, so then c is
//! not the best.
//!
//! **Correction** ([`Correction`], [`stage_delta`]). With `best` (the default), δ = α / L for L
//! planned looks: the best candidate c* takes one test per look, each against a reference fixed
//! before the look's fragments are seen, with μ_{c*} − μ_R ≤ 0; so it is eliminated with
//! probability ≤ Σ δ = α, and it is among the survivors (the *certified set*) with probability
//! ≥ 1 − α, however many candidates there are and in whichever shard it is. With `all`,
//! δ = α / (L · |C_k| · S) for |C_k| candidates of the stage and S shards (Bonferroni over looks,
//! candidates and shards): with probability ≥ 1 − α no candidate anywhere is eliminated while
//! it is at least as good as its stage reference. No candidate leaves for any other reason:
//! there is no cap. A budget (`lp_budget` of the sweep) can only end the race early, leaving
//! its survivors *unresolved*.

/// Count, Σx and Σx² of a sample.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Moments {
    /// Sample size n.
    pub n: u64,
    /// Σx
    pub sum: f64,
    /// Σx²
    pub sumsq: f64,
}

impl Moments {
    /// The sums (n, Σx, Σx²).
    pub fn new(n: u64, sum: f64, sumsq: f64) -> Moments {
        Moments { n, sum, sumsq }
    }
    /// The sums of `xs`.
    pub fn of(xs: &[f64]) -> Moments {
        let mut m = Moments::default();
        for &x in xs {
            m.push(x);
        }
        m
    }
    /// Adds x to the sample.
    pub fn push(&mut self, x: f64) {
        self.n += 1;
        self.sum += x;
        self.sumsq += x * x;
    }
    /// Merges the sums of `o`.
    pub fn add(&mut self, o: &Moments) {
        self.n += o.n;
        self.sum += o.sum;
        self.sumsq += o.sumsq;
    }
    /// x̄ (0 for an empty sample).
    pub fn mean(&self) -> f64 {
        if self.n == 0 {
            0.0
        } else {
            self.sum / self.n as f64
        }
    }
    /// Sample variance s² = (Σx² − (Σx)²/n)/(n − 1) (∞ for n < 2).
    pub fn var(&self) -> f64 {
        if self.n < 2 {
            return f64::INFINITY;
        }
        let n = self.n as f64;
        ((self.sumsq - self.sum * self.sum / n) / (n - 1.0)).max(0.0)
    }
    /// Standard error s/√n of the mean.
    pub fn se(&self) -> f64 {
        (self.var() / self.n as f64).sqrt()
    }
}

/// The one-sided confidence bound used by the test.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Bound {
    /// Normal approximation of the mean (CLT): h = z_{1−δ} · s/√n.
    Normal,
    /// Empirical Bernstein (Maurer & Pontil 2009, Thm. 4) for values in a range of width R:
    /// h = √(2 s² ln(2/δ) / n) + 7 R ln(2/δ) / (3 (n − 1)); valid for any distribution.
    Bernstein,
}

impl Bound {
    /// The bound named "normal" or "bernstein".
    pub fn parse(s: &str) -> anyhow::Result<Bound> {
        match s {
            "normal" => Ok(Bound::Normal),
            "bernstein" => Ok(Bound::Bernstein),
            _ => anyhow::bail!("unknown bound '{s}' (normal or bernstein)"),
        }
    }
    /// "normal" or "bernstein".
    pub fn name(&self) -> &'static str {
        match self {
            Bound::Normal => "normal",
            Bound::Bernstein => "bernstein",
        }
    }
}

/// Half-width h with P(x̄ − μ > h) ≤ δ for a sample of values in a range of width `range`
/// (∞ when n < 2).
pub fn half_width(m: &Moments, delta: f64, bound: Bound, range: f64) -> f64 {
    if m.n < 2 {
        return f64::INFINITY;
    }
    let n = m.n as f64;
    match bound {
        Bound::Normal => normal_quantile(1.0 - delta) * m.se(),
        Bound::Bernstein => {
            let l = (2.0 / delta).ln();
            (2.0 * m.var() * l / n).sqrt() + 7.0 * range * l / (3.0 * (n - 1.0))
        }
    }
}

/// Φ⁻¹(p), the standard normal quantile (Acklam's rational approximation, relative error
/// < 1.2e-9).
pub fn normal_quantile(p: f64) -> f64 {
    if p <= 0.0 {
        return f64::NEG_INFINITY;
    }
    if p >= 1.0 {
        return f64::INFINITY;
    }
    const A: [f64; 6] = [
        -3.969683028665376e1,
        2.209460984245205e2,
        -2.759285104469687e2,
        1.383_577_518_672_69e2,
        -3.066479806614716e1,
        2.506628277459239,
    ];
    const B: [f64; 5] = [
        -5.447609879822406e1,
        1.615858368580409e2,
        -1.556989798598866e2,
        6.680131188771972e1,
        -1.328068155288572e1,
    ];
    const C: [f64; 6] = [
        -7.784894002430293e-3,
        -3.223964580411365e-1,
        -2.400758277161838,
        -2.549732539343734,
        4.374664141464968,
        2.938163982698783,
    ];
    const D: [f64; 4] = [
        7.784695709041462e-3,
        3.224671290700398e-1,
        2.445134137142996,
        3.754408661907416,
    ];
    let tail = |q: f64| {
        (((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    };
    if p < 0.02425 {
        tail((-2.0 * p.ln()).sqrt())
    } else if p > 1.0 - 0.02425 {
        -tail((-2.0 * (1.0 - p).ln()).sqrt())
    } else {
        let q = p - 0.5;
        let r = q * q;
        (((((A[0] * r + A[1]) * r + A[2]) * r + A[3]) * r + A[4]) * r + A[5]) * q
            / (((((B[0] * r + B[1]) * r + B[2]) * r + B[3]) * r + B[4]) * r + 1.0)
    }
}

/// What the confidence of the elimination tests covers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Correction {
    /// The best candidate survives with probability ≥ confidence: α split over the looks only.
    Best,
    /// No candidate is eliminated while at least as good as its reference, all together, with
    /// probability ≥ confidence: α split over the looks, the candidates and the shards.
    All,
}

impl Correction {
    /// The correction named "best" or "all".
    pub fn parse(s: &str) -> anyhow::Result<Correction> {
        match s {
            "best" => Ok(Correction::Best),
            "all" => Ok(Correction::All),
            _ => anyhow::bail!("unknown correction '{s}' (best or all)"),
        }
    }
    /// "best" or "all".
    pub fn name(&self) -> &'static str {
        match self {
            Correction::Best => "best",
            Correction::All => "all",
        }
    }
    /// The correction of a results folder written before the choice existed.
    pub fn legacy() -> Correction {
        Correction::All
    }
}

/// δ per test: α split evenly over `looks` planned looks (stage 0's block is one look, a later
/// block up to [`EARLY_LOOKS`] + 1, [`looks`]) and, with [`Correction::All`], over the
/// `candidates` tested in the stage and the `shards` shards (Bonferroni).
pub fn stage_delta(
    alpha: f64,
    looks: usize,
    candidates: usize,
    shards: usize,
    correction: Correction,
) -> f64 {
    let tests = match correction {
        Correction::Best => looks.max(1),
        Correction::All => looks.max(1) * candidates.max(1) * shards.max(1),
    };
    alpha / tests as f64
}

/// Why a candidate left the race: the only reason is evidence.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Elimination {
    /// Worse than the stage reference with the stated confidence.
    Confidence,
}

/// One candidate's statistics on a stage block.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StageStats {
    /// Candidate index.
    pub index: u64,
    /// Errors e on the block.
    pub e: Moments,
    /// Paired differences d = e − e_R to the stage reference on the same fragments.
    pub d: Moments,
}

/// The stage's decision rule.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rule {
    /// Per-test error probability (see [`stage_delta`]).
    pub delta: f64,
    /// One-sided bound of the test.
    pub bound: Bound,
    /// Paired differences (true) or independent intervals: c is worse when its lower bound is
    /// above the reference's upper bound, each at δ/2 (for comparison only).
    pub paired: bool,
    /// Factor on every half-width: 1 in a run; 1/√s in the plan's proxy race, which decides on
    /// 1/s of each block with the threshold the full block would have ([`super::plan`]).
    pub width: f64,
}

/// Lower confidence bound of μ_c − μ_R (in per-fragment error units) under `rule`.
pub fn gap_lower_bound(c: &StageStats, r: &StageStats, rule: &Rule) -> f64 {
    if rule.paired {
        c.d.mean() - rule.width * half_width(&c.d, rule.delta, rule.bound, 2.0)
    } else {
        let h = |m: &Moments| rule.width * half_width(m, rule.delta / 2.0, rule.bound, 1.0);
        (c.e.mean() - h(&c.e)) - (r.e.mean() + h(&r.e))
    }
}

/// Decisions for every candidate of a stage: `Some(lower)` when c is eliminated by confidence,
/// with `lower` the lower confidence bound of μ_c − μ_R (> 0, per-fragment error units) that
/// removed it; None: it stays. `reference` = index of R, never eliminated. Panics if
/// `reference` is not among `stats`.
pub fn decide(stats: &[StageStats], reference: u64, rule: &Rule) -> Vec<Option<f64>> {
    let r = stats
        .iter()
        .find(|s| s.index == reference)
        .expect("the stage reference is scored in its stage");
    stats
        .iter()
        .map(|c| {
            if c.index == reference {
                return None;
            }
            let lower = gap_lower_bound(c, r, rule);
            (lower > 0.0).then_some(lower)
        })
        .collect()
}

/// The block plan over `total` fragments of the stratified order: a pilot block (picks the
/// stage-0 reference) of min(first, total/4) fragments, then stage blocks of first·growᵏ
/// fragments, the last one taking what remains.
pub fn blocks(
    total: usize,
    first: usize,
    growth: usize,
) -> (std::ops::Range<usize>, Vec<std::ops::Range<usize>>) {
    let pilot = 0..first.min(total / 4).max(1).min(total);
    let mut out = Vec::new();
    let (mut start, mut size) = (pilot.end, first.max(1));
    while start < total {
        let end = start.saturating_add(size).min(total);
        out.push(start..end);
        start = end;
        size = size.saturating_mul(growth.max(1));
    }
    (pilot, out)
}

/// Early looks of a stage block after stage 0 at most: the looks end at 1/2^EARLY_LOOKS, …,
/// 1/4, 1/2 of the block and at the whole block ([`looks`]).
pub const EARLY_LOOKS: usize = 3;

/// The looks of stage `stage`'s block of `len` fragments (consecutive ranges into the block,
/// each look's new fragments): stage 0 is one look at the whole block (the *common sample*:
/// every candidate is scored on all of it); a later stage is looked at on the prefixes of
/// len/2^j fragments, j = [`EARLY_LOOKS`], …, 1, that hold at least `early_look` fragments
/// (0: never), then on the whole block: the candidates are tested on each prefix, the
/// survivors go on to the next. Each look counts as a test in [`stage_delta`].
pub fn looks(stage: usize, len: usize, early_look: usize) -> Vec<std::ops::Range<usize>> {
    let mut ends = vec![len];
    if stage > 0 && early_look > 0 {
        let mut size = len;
        for _ in 0..EARLY_LOOKS {
            size /= 2;
            if size < early_look {
                break;
            }
            ends.push(size);
        }
    }
    ends.reverse();
    let mut start = 0;
    ends.into_iter()
        .map(|end| {
            let r = start..end;
            start = end;
            r
        })
        .collect()
}

/// Mean and standard error of a difference pooled over blocks: `parts` are
/// (n_b, mean_b, se_b); mean = Σ n_b mean_b / N, se = √Σ (n_b/N)² se_b².
pub fn pooled(parts: &[(u64, f64, f64)]) -> (f64, f64) {
    let n: u64 = parts.iter().map(|p| p.0).sum();
    if n == 0 {
        return (0.0, f64::INFINITY);
    }
    let nf = n as f64;
    let mean = parts.iter().map(|p| p.0 as f64 * p.1).sum::<f64>() / nf;
    let var = parts
        .iter()
        .map(|p| (p.0 as f64 / nf).powi(2) * p.2 * p.2)
        .sum::<f64>();
    (mean, var.sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A test on n/s fragments with every half-width × 1/√s has the threshold of the test on
    /// n fragments with the same mean and spread: the same samples repeated s times give the
    /// same lower bound up to the sample variance's n − 1.
    #[test]
    fn a_scaled_half_width_is_the_full_blocks_threshold() {
        let d: Vec<f64> = (0..64)
            .map(|k| 0.02 + 0.05 * ((k * 37 % 11) as f64 - 5.0) / 5.0)
            .collect();
        let e: Vec<f64> = d.iter().map(|x| x + 0.5).collect();
        let stats = |d: &[f64], e: &[f64]| StageStats {
            index: 1,
            e: Moments::of(e),
            d: Moments::of(d),
        };
        let reference = StageStats {
            index: 0,
            e: Moments::of(&e),
            d: Moments::of(&vec![0.0; e.len()]),
        };
        for s in [4usize, 8, 16] {
            let full_d: Vec<f64> = d.iter().cycle().take(d.len() * s).copied().collect();
            let full_e: Vec<f64> = e.iter().cycle().take(e.len() * s).copied().collect();
            let rule = Rule {
                delta: 1e-4,
                bound: Bound::Normal,
                paired: true,
                width: 1.0,
            };
            let full = gap_lower_bound(&stats(&full_d, &full_e), &reference, &rule);
            let proxy_rule = Rule {
                width: 1.0 / (s as f64).sqrt(),
                ..rule
            };
            let proxy = gap_lower_bound(&stats(&d, &e), &reference, &proxy_rule);
            let h_full = Moments::of(&d).mean() - full;
            let h_proxy = Moments::of(&d).mean() - proxy;
            // s² with n − 1: the ratio of the half-widths is √((n/(n−1)) / (sn/(sn−1))).
            let n = d.len() as f64;
            let sn = n * s as f64;
            let want = ((n / (n - 1.0)) / (sn / (sn - 1.0))).sqrt();
            assert!(
                (h_proxy / h_full - want).abs() < 1e-9,
                "s = {s}: {h_proxy} vs {h_full}"
            );
            // Without the factor the proxy's threshold is √s times the run's.
            let plain = Moments::of(&d).mean() - gap_lower_bound(&stats(&d, &e), &reference, &rule);
            assert!((plain / h_full - (s as f64).sqrt()).abs() < 0.05 * (s as f64).sqrt());
        }
    }

    #[test]
    fn normal_quantile_matches_tables() {
        // Φ⁻¹ values from standard tables (R: qnorm).
        for (p, z) in [
            (0.5, 0.0),
            (0.975, 1.959963984540054),
            (0.995, 2.5758293035489),
            (0.999, 3.090232306167813),
            (1.0 - 1e-6, 4.753424308822899),
            (1.0 - 1e-9, 5.997807015007686),
            (0.01, -2.326347874040841),
            (1e-12, -7.034483825673621),
        ] {
            let q = normal_quantile(p);
            assert!((q - z).abs() < 1e-6 * z.abs().max(1.0), "p {p}: {q} vs {z}");
        }
        // Monotone and antisymmetric on a fine grid.
        let mut last = f64::NEG_INFINITY;
        for k in 1..2000 {
            let p = k as f64 / 2000.0;
            let q = normal_quantile(p);
            assert!(q > last);
            assert!((q + normal_quantile(1.0 - p)).abs() < 1e-7);
            last = q;
        }
    }

    #[test]
    fn moments_and_pooling() {
        let xs = [1.0, 2.0, 4.0, 7.0];
        let m = Moments::of(&xs);
        assert_eq!(m.mean(), 3.5);
        assert!((m.var() - 7.0).abs() < 1e-12);
        assert!((m.se() - (7.0f64 / 4.0).sqrt()).abs() < 1e-12);
        assert!(Moments::of(&[1.0]).se().is_infinite());
        let (mean, se) = pooled(&[(1, 1.0, 0.3), (3, 2.0, 0.4)]);
        assert!((mean - 1.75).abs() < 1e-12);
        assert!((se - (0.0625f64 * 0.09 + 0.5625 * 0.16).sqrt()).abs() < 1e-12);
    }

    #[test]
    fn block_plan_covers_the_order_once() {
        for (total, first, growth) in [(131_071, 1024, 4), (180, 40, 2), (3, 1024, 4), (1, 5, 2)] {
            let (p, b) = blocks(total, first, growth);
            let mut next = p.end;
            assert!(!p.is_empty());
            for r in &b {
                assert_eq!(r.start, next);
                assert!(r.end > r.start);
                next = r.end;
            }
            assert_eq!(next, total, "{total} {first} {growth}");
        }
        let (p, b) = blocks(131_071, 1024, 4);
        assert_eq!(p, 0..1024);
        let sizes: Vec<usize> = b.iter().map(|r| r.len()).collect();
        assert_eq!(sizes, vec![1024, 4096, 16384, 65536, 44031 - 1024]);
    }

    fn stats(index: u64, e: &[f64], r: &[f64]) -> StageStats {
        let d: Vec<f64> = e.iter().zip(r).map(|(a, b)| a - b).collect();
        StageStats {
            index,
            e: Moments::of(e),
            d: Moments::of(&d),
        }
    }

    /// A shared fragment effect dominates the errors: pairing sees a small constant gap that
    /// independent intervals cannot; the reference itself is never eliminated; a candidate
    /// that is not shown worse stays, however bad its mean looks.
    #[test]
    fn paired_test_sees_what_independent_intervals_miss() {
        let n = 400;
        let r: Vec<f64> = (0..n)
            .map(|k| 0.5 + 0.4 * ((k * 37 % 101) as f64 / 101.0 - 0.5))
            .collect();
        let worse: Vec<f64> = r
            .iter()
            .enumerate()
            .map(|(k, x)| x + 0.01 + 0.002 * ((k % 7) as f64 - 3.0))
            .collect();
        let tied: Vec<f64> = r
            .iter()
            .enumerate()
            .map(|(k, x)| x + 0.003 * ((k % 5) as f64 - 2.0))
            .collect();
        let s = vec![stats(0, &r, &r), stats(1, &worse, &r), stats(2, &tied, &r)];
        let rule = Rule {
            delta: 1e-6,
            bound: Bound::Normal,
            paired: true,
            width: 1.0,
        };
        assert_eq!(
            decide(&s, 0, &rule)
                .iter()
                .map(Option::is_some)
                .collect::<Vec<_>>(),
            vec![false, true, false]
        );
        let indep = Rule {
            paired: false,
            ..rule
        };
        assert_eq!(decide(&s, 0, &indep), vec![None, None, None]);
        // Bernstein is valid for any distribution, hence wider: at n = 400 its range term
        // 7·2·ln(2/δ)/(3·399) ≈ 0.17 is far above the gap 0.01, so nothing is eliminated.
        let eb = Rule {
            bound: Bound::Bernstein,
            ..rule
        };
        let h_eb = half_width(&s[1].d, 1e-6, Bound::Bernstein, 2.0);
        let h_n = half_width(&s[1].d, 1e-6, Bound::Normal, 2.0);
        assert!(h_eb > h_n);
        assert_eq!(decide(&s, 0, &eb)[1], None);
        let far: Vec<f64> = r.iter().map(|x| x + 0.3).collect();
        let s2 = vec![stats(0, &r, &r), stats(1, &far, &r)];
        let lower = decide(&s2, 0, &eb)[1].expect("far is shown worse");
        // The evidence returned is the lower bound that removed it: below the gap 0.3.
        assert!(lower > 0.0 && lower < 0.3, "{lower}");
        // The paired lower bound of `worse` is d̄ − z·s_d/√n, returned as its evidence.
        let lower = decide(&s, 0, &rule)[1].unwrap();
        let want = s[1].d.mean() - normal_quantile(1.0 - 1e-6) * s[1].d.se();
        assert!((lower - want).abs() < 1e-15);
        // A candidate far worse by its mean but with too few fragments for evidence stays.
        let short = stats(3, &far[..1], &r[..1]);
        assert_eq!(decide(&[s2[0], short], 0, &rule), vec![None, None]);
    }

    #[test]
    fn early_looks_split_large_blocks_geometrically() {
        assert_eq!(looks(1, 2048, 1024), vec![0..1024, 1024..2048]);
        assert_eq!(looks(1, 2047, 1024), vec![0..2047]);
        assert_eq!(looks(1, 4096, 1024), vec![0..1024, 1024..2048, 2048..4096]);
        assert_eq!(
            looks(1, 16_384, 1024),
            vec![0..2048, 2048..4096, 4096..8192, 8192..16_384]
        );
        assert_eq!(
            looks(3, 87_040, 1024),
            vec![0..10_880, 10_880..21_760, 21_760..43_520, 43_520..87_040]
        );
        assert_eq!(looks(1, 4096, 0), vec![0..4096]);
        assert_eq!(looks(1, 1, 1), vec![0..1]);
        // Stage 0 is the common sample: one look, whatever its size.
        assert_eq!(looks(0, 8192, 1024), vec![0..8192]);
    }

    #[test]
    fn stage_delta_splits_alpha() {
        assert!((stage_delta(0.01, 5, 1000, 2, Correction::All) - 1e-6).abs() < 1e-18);
        assert_eq!(stage_delta(0.01, 0, 0, 0, Correction::All), 0.01);
        // Only the best candidate's own tests count: the candidates and shards do not.
        assert!((stage_delta(0.01, 5, 1000, 2, Correction::Best) - 2e-3).abs() < 1e-18);
        assert_eq!(stage_delta(0.01, 0, 0, 0, Correction::Best), 0.01);
        assert_eq!(Correction::parse("best").unwrap(), Correction::Best);
        assert_eq!(Correction::parse("all").unwrap().name(), "all");
        assert!(Correction::parse("holm").is_err());
    }
}
