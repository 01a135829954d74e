//! The speed corpus of real windows: fragments sampled from depth stacks with their biased depth
//! z_f (as in [`super::evaluate`]) and the filter window of the shadow map around them — the
//! depth distribution Σ_taps w·δ(z₀(texel + tap)) whose moments a renderer's filtered shadow map
//! holds (paper kernel: 9×9 Gaussian, σ = 2.4, edge-clamped).

use super::{fragments_subsampled, Bias, Subsample};
use crate::kernel::{self, Gaussian};
use crate::stack::DepthStack;
use crate::technique::timing::Corpus;
use anyhow::{bail, Result};

/// About `count` fragments drawn uniformly (seeded hash sampling, `Subsample::Random`) from all
/// layers of all `stacks`, each with its kernel window over the front depth map.
pub fn stacks_corpus(stacks: &[DepthStack], count: usize, seed: u64) -> Result<Corpus> {
    let total: usize = stacks.iter().map(|s| s.fragment_count()).sum();
    if total == 0 || count == 0 {
        bail!("speed corpus: no fragments to sample (stacks have {total}, asked for {count})");
    }
    let fraction = (count as f64 / total as f64 * 1.05).min(1.0);
    let taps = Gaussian::paper().taps();
    let mut c = Corpus::default();
    for (v, s) in stacks.iter().enumerate() {
        super::check_stack(s)?;
        let (w, h) = (s.meta.width, s.meta.height);
        let front = kernel::front_map(s);
        let sub = Subsample::Random { fraction, seed };
        for f in fragments_subsampled(s, v, &Bias::default(), &sub) {
            let (x, y) = (f.texel % w, f.texel / w);
            let window = taps
                .iter()
                .map(|&(dx, dy, wt)| {
                    let t = kernel::clamp_coord(y, dy, h) * w + kernel::clamp_coord(x, dx, w);
                    (front[t], wt)
                })
                .collect();
            c.dists.push(window);
            c.zfs.push(f.zf);
        }
    }
    // Spread the cut over all views: keep every k-th when more than `count` were drawn.
    if c.zfs.len() > count {
        let keep: Vec<usize> = (0..count).map(|i| i * c.zfs.len() / count).collect();
        c = Corpus {
            dists: keep.iter().map(|&i| c.dists[i].clone()).collect(),
            zfs: keep.iter().map(|&i| c.zfs[i]).collect(),
        };
    }
    Ok(c)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn windows_are_normalised_kernels_around_sampled_fragments() {
        let stacks = crate::render::default_dataset(32).unwrap();
        let c = stacks_corpus(&stacks[..2], 300, 1).unwrap();
        assert!(!c.zfs.is_empty() && c.zfs.len() <= 300);
        assert_eq!(c.dists.len(), c.zfs.len());
        for (d, &zf) in c.dists.iter().zip(&c.zfs) {
            assert_eq!(d.len(), 81);
            let s: f64 = d.iter().map(|x| x.1).sum();
            assert!((s - 1.0).abs() < 1e-9, "kernel weights sum to {s}");
            assert!(d.iter().all(|x| (0.0..=1.0).contains(&x.0)));
            assert!(zf.is_finite());
        }
        // Seeded.
        assert_eq!(c, stacks_corpus(&stacks[..2], 300, 1).unwrap());
        assert!(stacks_corpus(&stacks[..2], 0, 1).is_err());
    }
}
