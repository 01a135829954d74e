//! Cost of a technique: nanoseconds per shadow evaluation on one core, over the moments of
//! random few-Dirac depth distributions. Shared by `momentlab bench shadow`, `recommend` and
//! `reproduce` so every reported speed comes from the same loop.

use super::Technique;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::hint::black_box;
use std::time::Instant;

/// A depth distribution of up to four Diracs (depth, weight); unused slots have weight 0.
pub type Mixture = [(f64, f64); 4];

/// `n` seeded mixtures of 1–4 Diracs with depths uniform in [0,1], and a z_f per mixture.
pub fn random_inputs(n: usize, seed: u64) -> (Vec<Mixture>, Vec<f64>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut dists = Vec::with_capacity(n);
    let mut zfs = Vec::with_capacity(n);
    for _ in 0..n {
        let k = rng.gen_range(1..=4);
        let mut d = [(0.0, 0.0); 4];
        let mut s = 0.0;
        for x in d.iter_mut().take(k) {
            *x = (rng.gen_range(0.0..1.0), rng.gen_range(0.05..1.0));
            s += x.1;
        }
        d.iter_mut().for_each(|x| x.1 /= s);
        dists.push(d);
        zfs.push(rng.gen_range(0.0..1.0));
    }
    (dists, zfs)
}

/// The moments Σ w b(z) of each mixture with the technique's basis, row-major (n × m). For
/// techniques on a grid (LP candidates) depths and z_f are snapped to the grid first, so the
/// problems are feasible; the snapped z_f are returned.
pub fn moments_of(t: &dyn Technique, dists: &[Mixture], zfs: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let m = t.moment_count();
    let snap = |z: f64| match t.depth_grid() {
        Some(g) => crate::metrics::snap(g, z),
        None => z,
    };
    let mut moments = vec![0.0; dists.len() * m];
    let mut tmp = vec![0.0; m];
    for (i, d) in dists.iter().enumerate() {
        let row = &mut moments[i * m..(i + 1) * m];
        for &(z, w) in d.iter().filter(|x| x.1 > 0.0) {
            t.basis(snap(z), &mut tmp);
            row.iter_mut().zip(&tmp).for_each(|(a, b)| *a += w * b);
        }
    }
    (moments, zfs.iter().map(|&z| snap(z)).collect())
}

/// Median over `reps` timed passes of the nanoseconds per [`super::Evaluator::shadow`] call,
/// and the mean G of the last pass (keeps the work observable).
pub fn ns_per_eval(t: &dyn Technique, moments: &[f64], zfs: &[f64], reps: usize) -> (f64, f64) {
    let m = t.moment_count();
    let n = zfs.len().max(1);
    let mut ev = t.evaluator();
    let mut times = Vec::with_capacity(reps.max(1));
    let mut sum = 0.0;
    for _ in 0..reps.max(1) {
        let start = Instant::now();
        let mut acc = 0.0;
        for (i, &zf) in zfs.iter().enumerate() {
            acc += ev.shadow(black_box(&moments[i * m..(i + 1) * m]), black_box(zf));
        }
        times.push(start.elapsed().as_secs_f64());
        sum = black_box(acc);
    }
    times.sort_by(f64::total_cmp);
    (times[times.len() / 2] * 1e9 / n as f64, sum / n as f64)
}

/// Convenience: [`random_inputs`] + [`moments_of`] + [`ns_per_eval`].
pub fn measure(t: &dyn Technique, inputs: usize, reps: usize, seed: u64) -> f64 {
    let (d, z) = random_inputs(inputs, seed);
    let (mom, zf) = moments_of(t, &d, &z);
    ns_per_eval(t, &mom, &zf, reps).0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn moments_of_vsm_are_mean_and_second_moment() {
        let t = crate::technique::by_name("vsm").unwrap();
        let d = [[(0.25, 0.5), (0.75, 0.5), (0.0, 0.0), (0.0, 0.0)]];
        let (mom, zf) = moments_of(t.as_ref(), &d, &[0.3]);
        assert!((mom[0] - 0.5).abs() < 1e-15);
        assert!((mom[1] - (0.0625 + 0.5625) / 2.0).abs() < 1e-15);
        assert_eq!(zf, vec![0.3]);
        let (_, mean_g) = ns_per_eval(t.as_ref(), &mom, &zf, 1);
        assert!((0.0..=1.0).contains(&mean_g));
    }
}
