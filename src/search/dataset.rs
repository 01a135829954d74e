//! The fragments the sweep scores candidates on.
//!
//! Each fragment has a depth distribution Z on the LP grid (the 9×9 Gaussian weights over the
//! front-layer depths around its texel, snapped to grid points; all layers of a texel share it),
//! a fragment depth z_f as a grid index (snapped after the technique bias), and its PCF value.
//! Moments of any function f are Σ_l w_l f(z_{idx_l}) (Section 3.2: the filtered shadow map).
//!
//! Trivial fragments (F_Z(z_f) = Σ_{z_i < z_f} w_i = 0) have G = 0 for every candidate (Z itself
//! is feasible and G ≥ 0), so they are not stored: their error contribution Σ |0 − PCF| is kept in
//! closed form ([`Dataset::trivial_error`]).

use crate::kernel::{self, Gaussian};
use crate::metrics::{self, Bias};
use crate::stack::DepthStack;
use crate::Grid;
use anyhow::{bail, Context, Result};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, HashMap};

/// One non-trivial fragment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fragment {
    /// View (shadow map) number, for stratification.
    pub view: u32,
    /// Layer (0 = front surface), for stratification.
    pub layer: u32,
    /// Texel within the view.
    pub texel: u32,
    /// Index of its depth distribution.
    pub dist: u32,
    /// Fragment depth as a grid index.
    pub zf: u32,
    /// The PCF reference value.
    pub pcf: f64,
}

/// Fragments with their depth distributions (see the module documentation).
#[derive(Clone, Debug)]
pub struct Dataset {
    grid: Grid,
    /// (grid index, weight) entries of all distributions.
    entries: Vec<(u32, f64)>,
    /// (start, len) into `entries` per distribution.
    dists: Vec<(u32, u32)>,
    /// Non-trivial fragments sorted by (dist, zf, layer): consecutive fragments share moments.
    fragments: Vec<Fragment>,
    trivial_count: u64,
    trivial_error: f64,
    /// Non-trivial fragments of the population the stored ones were sampled from (equal to
    /// `fragments.len()` when nothing was sampled away).
    nontrivial_population: u64,
    views: Vec<String>,
}

/// How [`Dataset::from_stacks`] samples the non-trivial fragments.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SamplePlan {
    /// Keep at most about this many non-trivial fragments (None: all of them).
    pub max_fragments: Option<usize>,
    /// Seed of the stratified sample.
    pub seed: u64,
}

/// Default cap on the non-trivial fragments kept by [`Dataset::from_stacks`] (see
/// docs/search.md: it bounds the cost of the final full-sample stage and of late racing stages,
/// and sets the sampling standard error of every reported error).
pub const DEFAULT_MAX_FRAGMENTS: usize = 131_072;

impl Default for SamplePlan {
    fn default() -> Self {
        SamplePlan {
            max_fragments: Some(DEFAULT_MAX_FRAGMENTS),
            seed: 1,
        }
    }
}

/// Builds a [`Dataset`] from raw kernels and fragments (depths in [0,1], snapped here).
#[derive(Debug)]
pub struct DatasetBuilder {
    data: Dataset,
}

impl DatasetBuilder {
    /// An empty dataset on `grid`.
    pub fn new(grid: &Grid) -> DatasetBuilder {
        DatasetBuilder {
            data: Dataset {
                grid: grid.clone(),
                entries: Vec::new(),
                dists: Vec::new(),
                fragments: Vec::new(),
                trivial_count: 0,
                trivial_error: 0.0,
                nontrivial_population: 0,
                views: Vec::new(),
            },
        }
    }

    /// Register a view name; returns its number.
    pub fn add_view(&mut self, name: &str) -> u32 {
        self.data.views.push(name.to_string());
        (self.data.views.len() - 1) as u32
    }

    /// Add a depth distribution given as (depth, weight) pairs; depths are snapped to the grid,
    /// weights merged per grid point and normalised to sum 1. Returns its id.
    pub fn add_distribution(&mut self, kernel: &[(f64, f64)]) -> Result<u32> {
        let mut pairs: Vec<(u32, f64)> = Vec::with_capacity(kernel.len());
        let mut total = 0.0;
        for (k, &(z, w)) in kernel.iter().enumerate() {
            if !z.is_finite() || !w.is_finite() || w < 0.0 {
                bail!("depth distribution entry {k}: invalid depth {z} or weight {w}");
            }
            if w > 0.0 {
                pairs.push((self.data.snap(z) as u32, w));
                total += w;
            }
        }
        if total <= 0.0 {
            bail!("depth distribution with zero total weight");
        }
        pairs.sort_by_key(|p| p.0);
        let start = self.data.entries.len();
        for (i, w) in pairs {
            let entries = &mut self.data.entries;
            if entries.len() > start && entries[entries.len() - 1].0 == i {
                let k = entries.len() - 1;
                entries[k].1 += w / total;
            } else {
                entries.push((i, w / total));
            }
        }
        let len = self.data.entries.len() - start;
        self.data.dists.push((start as u32, len as u32));
        Ok((self.data.dists.len() - 1) as u32)
    }

    /// Add a fragment at depth `zf` (snapped) with PCF value `pcf`; trivial fragments are only
    /// counted. Returns whether it was kept (non-trivial).
    pub fn add_fragment(
        &mut self,
        view: u32,
        layer: u32,
        texel: u32,
        dist: u32,
        zf: f64,
        pcf: f64,
    ) -> Result<bool> {
        if !zf.is_finite() || !(0.0..=1.0).contains(&pcf) {
            bail!("fragment (view {view}, layer {layer}, texel {texel}): invalid z_f {zf} or PCF {pcf}");
        }
        if dist as usize >= self.data.dists.len() {
            bail!("fragment (view {view}, texel {texel}): unknown distribution {dist}");
        }
        let zf = self.data.snap(zf) as u32;
        if self.data.cdf(dist, zf) <= 0.0 {
            self.data.trivial_count += 1;
            self.data.trivial_error += pcf;
            return Ok(false);
        }
        self.data.fragments.push(Fragment {
            view,
            layer,
            texel,
            dist,
            zf,
            pcf,
        });
        Ok(true)
    }

    /// The dataset, its fragments sorted by (distribution, z_f, layer) for warm starts.
    pub fn finish(mut self) -> Dataset {
        self.data.fragments.sort_by_key(|f| (f.dist, f.zf, f.layer));
        self.data.nontrivial_population = self.data.fragments.len() as u64;
        self.data
    }
}

impl Dataset {
    /// The depth grid I the distributions are snapped to.
    pub fn grid(&self) -> &Grid {
        &self.grid
    }
    /// Non-trivial fragments, sorted for warm starts.
    pub fn fragments(&self) -> &[Fragment] {
        &self.fragments
    }
    /// Number of distributions.
    pub fn distribution_count(&self) -> usize {
        self.dists.len()
    }
    /// (grid index, weight) pairs of distribution `d`.
    pub fn distribution(&self, d: u32) -> &[(u32, f64)] {
        let (s, l) = self.dists[d as usize];
        &self.entries[s as usize..(s + l) as usize]
    }
    /// Trivial fragments (F_Z(z_f) = 0 on the grid): not stored, G = 0.
    pub fn trivial_count(&self) -> u64 {
        self.trivial_count
    }
    /// Σ PCF over trivial fragments (their error, since G = 0 there).
    pub fn trivial_error(&self) -> f64 {
        self.trivial_error
    }
    /// All fragments of the population, trivial ones included (sampled-away ones too).
    pub fn total_count(&self) -> u64 {
        self.trivial_count + self.nontrivial_population
    }
    /// Non-trivial fragments of the population (≥ `fragments().len()`).
    pub fn nontrivial_population(&self) -> u64 {
        self.nontrivial_population
    }
    /// Share of the non-trivial population that is stored (1 when nothing was sampled away).
    pub fn sampled_fraction(&self) -> f64 {
        if self.nontrivial_population == 0 {
            1.0
        } else {
            self.fragments.len() as f64 / self.nontrivial_population as f64
        }
    }
    /// Error and standard error of a candidate from the sum and sum of squares of its errors
    /// e = |G − PCF| on `n` stored fragments: (Σ_trivial PCF + N_nt · ē) / N_all, with standard
    /// error (N_nt / N_all) · s / √n (trivial fragments are exact; N_nt = non-trivial population).
    pub fn error_estimate(&self, n: u64, sum: f64, sumsq: f64) -> (f64, f64) {
        let total = self.total_count() as f64;
        if total == 0.0 {
            return (0.0, 0.0);
        }
        let pop = self.nontrivial_population as f64;
        if n == 0 {
            let se = if pop > 0.0 { f64::INFINITY } else { 0.0 };
            return (self.trivial_error / total, se);
        }
        let nf = n as f64;
        let mean = sum / nf;
        let se = if n < 2 {
            f64::INFINITY
        } else {
            (((sumsq - sum * sum / nf) / (nf - 1.0)).max(0.0) / nf).sqrt()
        };
        ((self.trivial_error + pop * mean) / total, pop / total * se)
    }
    /// View names, indexed by view number.
    pub fn views(&self) -> &[String] {
        &self.views
    }

    /// Index of the grid point nearest to z ([`metrics::snap_index`]: ties to the lower point).
    pub fn snap(&self, z: f64) -> usize {
        metrics::snap_index(&self.grid, z)
    }

    /// F_Z(z_f) = Σ_{idx < zf} w for distribution `d`.
    pub fn cdf(&self, d: u32, zf: u32) -> f64 {
        self.distribution(d)
            .iter()
            .filter(|e| e.0 < zf)
            .map(|e| e.1)
            .sum()
    }

    /// Filtered values of every function of `table` for every distribution: row-major
    /// (distributions × N), `out[d*N + j] = Σ_l w_l f_j(z_{idx_l})`.
    pub fn filtered(&self, table: &super::FunctionTable) -> Vec<f64> {
        let nf = table.len();
        let mut out = vec![0.0; self.dists.len() * nf];
        for d in 0..self.dists.len() {
            let o = &mut out[d * nf..(d + 1) * nf];
            for &(i, w) in self.distribution(d as u32) {
                for (a, v) in o.iter_mut().zip(table.row(i as usize)) {
                    *a += w * v;
                }
            }
        }
        out
    }

    /// A seeded ordering of the non-trivial fragments such that every prefix (and every
    /// consecutive block) is a stratified sample: strata are (view, min(layer, 3)), each stratum
    /// is shuffled and its members spread evenly over the order (proportional allocation).
    pub fn stratified_order(&self, seed: u64) -> Vec<u32> {
        use std::collections::BTreeMap;
        let mut strata: BTreeMap<(u32, u32), Vec<u32>> = BTreeMap::new();
        for (k, f) in self.fragments.iter().enumerate() {
            strata
                .entry((f.view, f.layer.min(3)))
                .or_default()
                .push(k as u32);
        }
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut keyed: Vec<(f64, u32)> = Vec::with_capacity(self.fragments.len());
        for members in strata.values_mut() {
            // Fisher–Yates with our seeded generator (stable across platforms).
            for i in (1..members.len()).rev() {
                let j = rng.gen_range(0..=i);
                members.swap(i, j);
            }
            let u: f64 = rng.gen();
            let len = members.len() as f64;
            for (r, &k) in members.iter().enumerate() {
                keyed.push(((r as f64 + u) / len, k));
            }
        }
        keyed.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        keyed.into_iter().map(|(_, k)| k).collect()
    }

    /// The stored fragments `ids` (indices into [`Self::fragments`]) as a dataset of their own,
    /// with the same distributions, trivial fragments and population, so that its error
    /// estimates are on the same scale: a prefix of [`Self::stratified_order`] is a smaller
    /// stratified sample of the same population. Panics on an index out of range.
    pub fn subset(&self, ids: &[u32]) -> Dataset {
        let mut ids = ids.to_vec();
        ids.sort_unstable();
        ids.dedup();
        Dataset {
            grid: self.grid.clone(),
            entries: self.entries.clone(),
            dists: self.dists.clone(),
            // In the stored order, which is sorted by (dist, zf, layer) already.
            fragments: ids.iter().map(|&i| self.fragments[i as usize]).collect(),
            trivial_count: self.trivial_count,
            trivial_error: self.trivial_error,
            nontrivial_population: self.nontrivial_population,
            views: self.views.clone(),
        }
    }

    /// Fingerprint of the fragments (refuse resuming on different data).
    pub fn fingerprint(&self) -> u64 {
        let mut h = super::Fnv::new();
        for z in self.grid.points() {
            h.u64(z.to_bits());
        }
        for &(i, w) in &self.entries {
            h.u64(i as u64);
            h.u64(w.to_bits());
        }
        for f in &self.fragments {
            h.u64(((f.view as u64) << 32) | f.layer as u64);
            h.u64(((f.texel as u64) << 32) | f.dist as u64);
            h.u64(f.zf as u64);
            h.u64(f.pcf.to_bits());
        }
        h.u64(self.trivial_count);
        h.u64(self.trivial_error.to_bits());
        h.u64(self.nontrivial_population);
        h.finish()
    }

    /// The sweep dataset of depth stacks, built with kernel/metrics exactly as
    /// [`metrics::evaluate`] treats a grid technique ([`Technique::depth_grid`]):
    ///
    /// * fragments and their biased depth z_f − ε′ as [`metrics::fragments`] gives them (same
    ///   bias), PCF ([`metrics::fragments_at`]) only for the trivial fragments (their error) and
    ///   the kept ones;
    /// * the front map ([`kernel::front_map`]) snapped to the grid, the depth distribution of a
    ///   texel from [`kernel::depth_distribution`] with [`Gaussian::paper`] (9×9, σ = 2.4,
    ///   clamped edges) over the snapped depths, z_f snapped with [`metrics::snap_index`];
    /// * trivial ⇔ F_Z(z_f) = 0 on the grid ⇔ the 9×9 min of the snapped front map ≥ snapped
    ///   z_f (the rule of `metrics`); all trivial fragments are counted exactly (G = 0).
    ///
    /// Non-trivial fragments are sampled, stratified by (view, layer): with p = cap / N_nt and
    /// C_h = p·(N_1 + … + N_h), stratum h keeps ⌊C_h + u⌋ − ⌊C_{h−1} + u⌋ fragments (one seeded
    /// u ~ U[0,1), systematic allocation: ⌊p·N_h⌋ or ⌈p·N_h⌉, expected share p in every stratum,
    /// self-weighting, and exactly `cap` in all), chosen by a seeded shuffle. Errors are then estimated
    /// as (Σ_trivial PCF + N_nt · mean over the sample) / N_all ([`Dataset::error_estimate`]).
    ///
    /// [`Technique::depth_grid`]: crate::technique::Technique::depth_grid
    pub fn from_stacks(
        stacks: &[DepthStack],
        grid: &Grid,
        bias: &Bias,
        plan: &SamplePlan,
    ) -> Result<Dataset> {
        bias.validate()?;
        if plan.max_fragments == Some(0) {
            bail!("sample plan: max_fragments must be positive");
        }
        if stacks.is_empty() {
            bail!("no depth stacks");
        }
        let kern = Gaussian::paper();
        let z = grid.points();
        let mut b = DatasetBuilder::new(grid);
        // (view, layer) -> (texel, zf index) of the non-trivial fragments. PCF is computed only
        // where it is used: the trivial fragments (their error) and the kept ones.
        type Stratum = Vec<(u32, u32)>;
        let mut strata: BTreeMap<(u32, u32), Stratum> = BTreeMap::new();
        let mut fronts = Vec::with_capacity(stacks.len());
        for (v, s) in stacks.iter().enumerate() {
            let name = format!("{}/{}", s.meta.scene, s.meta.view);
            metrics::check_stack(s).with_context(|| format!("view {v} ({name})"))?;
            let view = b.add_view(&name);
            let (w, h) = (s.meta.width, s.meta.height);
            let snapped: Vec<f64> = kernel::front_map(s)
                .iter()
                .map(|&d| metrics::snap(grid, d))
                .collect();
            let min_map = kernel::min_filter(&snapped, w, h, kern.radius());
            let mut trivial = Vec::new();
            for (layer, texel) in metrics::fragment_positions(s) {
                let zi = metrics::snap_index(grid, metrics::technique_depth(s, layer, texel, bias));
                if min_map[texel] >= z[zi] {
                    trivial.push((layer, texel));
                } else {
                    strata
                        .entry((view, layer as u32))
                        .or_default()
                        .push((texel as u32, zi as u32));
                }
            }
            // Summed in fragment order, as the fragments come.
            for f in metrics::fragments_at(s, v, bias, &trivial) {
                b.data.trivial_count += 1;
                b.data.trivial_error += f.pcf;
            }
            fronts.push(snapped);
        }
        let population: usize = strata.values().map(|v| v.len()).sum();
        let cap = plan.max_fragments.unwrap_or(population).min(population);
        let mut rng = ChaCha8Rng::seed_from_u64(plan.seed);
        // Systematic allocation in exact integers: C_h·N_nt = cap·(N_1 + … + N_h), u·N_nt = U.
        let pop = population.max(1) as u128;
        let offset: u128 = rng.gen_range(0..pop as u64) as u128;
        let mut before = 0u128;
        // (view, texel, layer, zf index) of the kept fragments.
        let mut kept: Vec<(u32, u32, u32, u32)> = Vec::new();
        for (&(view, layer), members) in strata.iter_mut() {
            let upto = before + members.len() as u128;
            let quota = |n: u128| (cap as u128 * n + offset) / pop;
            let k = ((quota(upto) - quota(before)) as usize).min(members.len());
            before = upto;
            // Partial Fisher–Yates: the first k of a seeded shuffle.
            for i in 0..k {
                let j = rng.gen_range(i..members.len());
                members.swap(i, j);
            }
            kept.extend(members[..k].iter().map(|&(t, zi)| (view, t, layer, zi)));
        }
        // The kept fragments' PCF, one batch per view.
        let mut pcf_of: HashMap<(u32, u32, u32), f64> = HashMap::with_capacity(kept.len());
        for (v, s) in stacks.iter().enumerate() {
            let picked: Vec<(usize, usize)> = kept
                .iter()
                .filter(|f| f.0 as usize == v)
                .map(|f| (f.2 as usize, f.1 as usize))
                .collect();
            for f in metrics::fragments_at(s, v, bias, &picked) {
                pcf_of.insert((v as u32, f.texel as u32, f.layer as u32), f.pcf);
            }
        }
        // Distributions in (view, texel) order: neighbouring ids are neighbouring texels.
        kept.sort_by_key(|f| (f.0, f.1, f.2));
        let mut dist_of: HashMap<(u32, u32), u32> = HashMap::new();
        for &(view, t, layer, zi) in &kept {
            let pcf = pcf_of[&(view, t, layer)];
            let d = match dist_of.get(&(view, t)) {
                Some(&d) => d,
                None => {
                    let s = &stacks[view as usize];
                    let (w, h) = (s.meta.width, s.meta.height);
                    let (x, y) = (t as usize % w, t as usize / w);
                    let dist =
                        kernel::depth_distribution(&fronts[view as usize], w, h, x, y, &kern);
                    let d = b.add_distribution(&dist)?;
                    dist_of.insert((view, t), d);
                    d
                }
            };
            if !b.add_fragment(view, layer, t, d, z[zi as usize], pcf)? {
                bail!(
                    "view {view} texel {t} layer {layer}: trivial on the distribution but not \
                     by the min filter (internal inconsistency)"
                );
            }
        }
        let mut data = b.finish();
        data.nontrivial_population = population as u64;
        Ok(data)
    }

    /// A random synthetic dataset for tests and demos: per texel a distribution of 1–3 clusters
    /// of nearby depths, fragments at `layers` depths per texel (cluster depths plus a small
    /// offset), PCF = the exact F_Z(z_f) on the grid.
    pub fn synthetic(
        seed: u64,
        grid: &Grid,
        views: usize,
        texels: usize,
        layers: usize,
    ) -> Result<Dataset> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut b = DatasetBuilder::new(grid);
        for v in 0..views {
            let view = b.add_view(&format!("synthetic{v}"));
            for t in 0..texels {
                let clusters = rng.gen_range(1..=3);
                let centres: Vec<f64> = (0..clusters).map(|_| rng.gen_range(0.05..0.95)).collect();
                let mut kernel = Vec::new();
                for &c in &centres {
                    let spread: f64 = rng.gen_range(0.0..0.05);
                    let mass: f64 = rng.gen_range(0.2..1.0);
                    for _ in 0..rng.gen_range(1..6) {
                        let z: f64 = (c + rng.gen_range(-spread..=spread)).clamp(0.0, 1.0);
                        kernel.push((z, mass * rng.gen_range(0.1..1.0)));
                    }
                }
                let d = b.add_distribution(&kernel)?;
                let mut depths = centres.clone();
                depths.sort_by(f64::total_cmp);
                for (l, &c) in depths.iter().take(layers).enumerate() {
                    let zf = (c + rng.gen_range(0.0..0.08)).clamp(0.0, 1.0);
                    let zi = b.data.snap(zf) as u32;
                    let pcf = b.data.cdf(d, zi).min(1.0);
                    b.add_fragment(view, l as u32, t as u32, d, zf, pcf)?;
                }
            }
        }
        Ok(b.finish())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::search::FunctionTable;

    /// A subset keeps the population, trivial fragments and distributions: all fragments give
    /// the same dataset (fingerprint), a prefix of the stratified order fewer fragments on the
    /// same error scale.
    #[test]
    fn a_subset_is_a_smaller_sample_of_the_same_population() {
        let grid = Grid::uniform(16).unwrap();
        let data = Dataset::synthetic(3, &grid, 2, 50, 3).unwrap();
        let n = data.fragments().len();
        let all: Vec<u32> = (0..n as u32).rev().collect();
        assert_eq!(data.subset(&all).fingerprint(), data.fingerprint());
        let order = data.stratified_order(7);
        let sub = data.subset(&order[..n / 4]);
        assert_eq!(sub.fragments().len(), n / 4);
        assert_eq!(sub.nontrivial_population(), data.nontrivial_population());
        assert_eq!(sub.total_count(), data.total_count());
        assert_eq!(
            sub.error_estimate(10, 1.0, 0.2),
            data.error_estimate(10, 1.0, 0.2)
        );
        let mut want: Vec<Fragment> = order[..n / 4]
            .iter()
            .map(|&k| data.fragments()[k as usize])
            .collect();
        want.sort_by_key(|f| (f.dist, f.zf, f.layer, f.view, f.texel));
        let mut got = sub.fragments().to_vec();
        got.sort_by_key(|f| (f.dist, f.zf, f.layer, f.view, f.texel));
        assert_eq!(got, want);
        assert!(sub.fingerprint() != data.fingerprint());
    }

    #[test]
    fn snapping_merging_and_trivial_fragments() {
        let g = Grid::uniform(11).unwrap();
        let mut b = DatasetBuilder::new(&g);
        let v = b.add_view("v");
        let d = b
            .add_distribution(&[(0.31, 1.0), (0.29, 1.0), (0.72, 2.0)])
            .unwrap();
        assert!(b.add_distribution(&[(f64::NAN, 1.0)]).is_err());
        assert!(b.add_distribution(&[(0.5, 0.0)]).is_err());
        // z_f at 0.3: nothing strictly in front -> trivial, error = PCF.
        assert!(!b.add_fragment(v, 0, 0, d, 0.3, 0.25).unwrap());
        assert!(b.add_fragment(v, 1, 0, d, 0.7, 0.5).unwrap());
        assert!(b.add_fragment(v, 1, 0, d, 0.7, 1.5).is_err());
        assert!(b.add_fragment(v, 1, 0, 9, 0.7, 0.5).is_err());
        let ds = b.finish();
        assert_eq!(ds.distribution(d), &[(3, 0.5), (7, 0.5)]);
        assert_eq!(ds.trivial_count(), 1);
        assert_eq!(ds.trivial_error(), 0.25);
        assert_eq!(ds.fragments().len(), 1);
        assert_eq!(ds.cdf(d, 7), 0.5);
        let t = FunctionTable::new(&g, vec!["z".into(), "z^2".into()], |j, z| {
            z.powi(j as i32 + 1)
        })
        .unwrap();
        let f = ds.filtered(&t);
        assert!((f[0] - 0.5).abs() < 1e-12 && (f[1] - (0.09 + 0.49) / 2.0).abs() < 1e-12);
    }

    #[test]
    fn stratified_prefixes_are_proportional() {
        let g = Grid::uniform(64).unwrap();
        let ds = Dataset::synthetic(7, &g, 3, 200, 3).unwrap();
        let order = ds.stratified_order(1);
        let mut sorted = order.clone();
        sorted.sort();
        assert_eq!(sorted, (0..ds.fragments().len() as u32).collect::<Vec<_>>());
        assert_eq!(order, ds.stratified_order(1));
        assert_ne!(order, ds.stratified_order(2));
        // Any prefix holds each view in proportion (±1 per stratum).
        let total = ds.fragments().len() as f64;
        for prefix in [50usize, 200, 333] {
            for v in 0..3 {
                let all = ds.fragments().iter().filter(|f| f.view == v).count() as f64;
                let got = order[..prefix]
                    .iter()
                    .filter(|&&k| ds.fragments()[k as usize].view == v)
                    .count() as f64;
                assert!(
                    (got - all * prefix as f64 / total).abs() <= 4.0 + 1e-9,
                    "{got} {all}"
                );
            }
        }
    }
}
