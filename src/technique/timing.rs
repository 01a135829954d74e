//! Cost of a technique: nanoseconds per shadow evaluation on one core. Shared by
//! `momentlab bench shadow`, `recommend` and `reproduce` so every reported speed comes from the
//! same loop. Inputs are a [`Corpus`] of depth distributions and fragment depths: random
//! few-Dirac mixtures ([`random_corpus`]) or the filtered windows of fragments sampled from real
//! depth stacks (`metrics::windows::stacks_corpus`).

use super::Technique;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use std::hint::black_box;
use std::time::Instant;

/// Depth distributions (depth, weight) and a fragment depth z_f for each.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Corpus {
    /// Each distribution as (depth, weight) pairs; weights sum to 1.
    pub dists: Vec<Vec<(f64, f64)>>,
    /// Fragment depth z_f of each distribution.
    pub zfs: Vec<f64>,
}

/// `n` seeded mixtures of 1–4 Diracs with depths uniform in [0,1] and weights normalised to 1,
/// and a z_f per mixture uniform in [0,1].
pub fn random_corpus(n: usize, seed: u64) -> Corpus {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut c = Corpus::default();
    for _ in 0..n {
        let k = rng.gen_range(1..=4);
        let mut d: Vec<(f64, f64)> = (0..k)
            .map(|_| (rng.gen_range(0.0..1.0), rng.gen_range(0.05..1.0)))
            .collect();
        let s: f64 = d.iter().map(|x| x.1).sum();
        d.iter_mut().for_each(|x| x.1 /= s);
        c.dists.push(d);
        c.zfs.push(rng.gen_range(0.0..1.0));
    }
    c
}

/// The moments Σ w b(z) of each distribution with the technique's basis, row-major (n × m). For
/// techniques on a grid (LP candidates) depths and z_f are snapped to the grid first, so the
/// problems are feasible; the snapped z_f are returned.
pub fn moments_of(t: &dyn Technique, corpus: &Corpus) -> (Vec<f64>, Vec<f64>) {
    let m = t.moment_count();
    let snap = |z: f64| match t.depth_grid() {
        Some(g) => g.snap(z),
        None => z,
    };
    let mut moments = vec![0.0; corpus.dists.len() * m];
    // Rows in parallel (preparation, not timed); each row sums in the same order as serially.
    moments
        .par_chunks_mut(m.max(1))
        .zip(&corpus.dists)
        .for_each_init(
            || vec![0.0; m],
            |tmp, (row, d)| {
                for &(z, w) in d.iter().filter(|x| x.1 > 0.0) {
                    t.basis(snap(z), tmp);
                    row.iter_mut()
                        .zip(tmp.iter())
                        .for_each(|(a, b)| *a += w * b);
                }
            },
        );
    (moments, corpus.zfs.iter().map(|&z| snap(z)).collect())
}

/// Nanoseconds per evaluation over consecutive batches of the corpus, in every timed pass.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Speed {
    /// Total time / evaluations over all passes.
    pub mean: f64,
    /// Median, 99th percentile and maximum over the batches.
    pub median: f64,
    /// 99th percentile over the batches.
    pub p99: f64,
    /// Maximum over the batches.
    pub max: f64,
    /// Mean G of the last pass (keeps the work observable; a cheap sanity figure).
    pub mean_g: f64,
}

/// Evaluations per timed batch: large enough that `Instant` overhead (≈ 20 ns) is < 1 %, small
/// enough that a batch of hard fragments shows in the tail.
pub const BATCH: usize = 256;

/// [`Speed`] of [`super::Evaluator::shadow`] over `moments`/`zfs` (from [`moments_of`]) in
/// `reps` passes, each timed in batches of [`BATCH`] consecutive inputs.
pub fn speed(t: &dyn Technique, moments: &[f64], zfs: &[f64], reps: usize) -> Speed {
    let m = t.moment_count();
    let n = zfs.len();
    let mut ev = t.evaluator();
    let mut per_batch = Vec::with_capacity(reps.max(1) * n.div_ceil(BATCH));
    let (mut total, mut evals) = (0.0, 0usize);
    let mut mean_g = 0.0;
    for _ in 0..reps.max(1) {
        let mut acc = 0.0;
        for start in (0..n).step_by(BATCH) {
            let end = (start + BATCH).min(n);
            let t0 = Instant::now();
            for (i, &zf) in zfs.iter().enumerate().take(end).skip(start) {
                acc += ev.shadow(black_box(&moments[i * m..(i + 1) * m]), black_box(zf));
            }
            let s = t0.elapsed().as_secs_f64();
            total += s;
            evals += end - start;
            per_batch.push(s * 1e9 / (end - start) as f64);
        }
        mean_g = black_box(acc) / n.max(1) as f64;
    }
    if per_batch.is_empty() {
        return Speed::default();
    }
    per_batch.sort_by(f64::total_cmp);
    let q = |p: f64| per_batch[((per_batch.len() - 1) as f64 * p).round() as usize];
    Speed {
        mean: total * 1e9 / evals as f64,
        median: q(0.5),
        p99: q(0.99),
        max: *per_batch.last().unwrap(),
        mean_g,
    }
}

/// Convenience: [`moments_of`] + [`speed`] on a corpus.
pub fn measure(t: &dyn Technique, corpus: &Corpus, reps: usize) -> Speed {
    let (mom, zf) = moments_of(t, corpus);
    speed(t, &mom, &zf, reps)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn moments_of_vsm_are_mean_and_second_moment() {
        let t = crate::technique::by_name("vsm").unwrap();
        let c = Corpus {
            dists: vec![vec![(0.25, 0.5), (0.75, 0.5)]],
            zfs: vec![0.3],
        };
        let (mom, zf) = moments_of(t.as_ref(), &c);
        assert!((mom[0] - 0.5).abs() < 1e-15);
        assert!((mom[1] - (0.0625 + 0.5625) / 2.0).abs() < 1e-15);
        assert_eq!(zf, vec![0.3]);
        let s = speed(t.as_ref(), &mom, &zf, 2);
        assert!((0.0..=1.0).contains(&s.mean_g));
        assert!(s.median <= s.p99 && s.p99 <= s.max && s.mean > 0.0);
    }

    #[test]
    fn random_corpus_is_normalised_and_seeded() {
        let a = random_corpus(100, 5);
        assert_eq!(a, random_corpus(100, 5));
        assert_eq!(a.dists.len(), 100);
        for d in &a.dists {
            let s: f64 = d.iter().map(|x| x.1).sum();
            assert!((s - 1.0).abs() < 1e-12 && (1..=4).contains(&d.len()));
        }
    }
}
