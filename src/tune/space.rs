//! The search space of `tune`: technique × storage × moment bias α × technique depth bias
//! (constant ε and slope scale s, ε′ = ε + s·(|dz/du| + |dz/dv|)) × the technique's own
//! parameters (ESM c, EVSM c₊/c₋ within the storage's overflow limit).

use crate::quantize::study::{identity_theta, Storage};
use crate::quantize::theta::{published_theta2, published_theta4, published_theta6, Theta};
use crate::technique::registry::{self, Params, Precision};
use crate::technique::Technique;
use anyhow::{bail, Result};
use serde::{Deserialize, Serialize};

/// How a shadow map stores its moment channels.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum StorageKind {
    /// 32-bit float per channel.
    F32,
    /// 16-bit UNORM of θ(b) (θ₂, θ₄, θ₆ of the papers; TMSM: (b + 1)/2).
    Unorm16Theta,
    /// 16-bit UNORM of the canonical moments b themselves (power moments lie in [0,1]).
    Unorm16,
    /// 16-bit half float (binary16) per channel, as engines store EVSM/ESM.
    F16,
}

impl StorageKind {
    /// Every storage format, in search order.
    pub const ALL: [StorageKind; 4] = [
        StorageKind::F32,
        StorageKind::Unorm16Theta,
        StorageKind::Unorm16,
        StorageKind::F16,
    ];

    /// The command-line name ("f32", "unorm16-theta", "unorm16", "f16").
    pub fn name(self) -> &'static str {
        match self {
            StorageKind::F32 => "f32",
            StorageKind::Unorm16Theta => "unorm16-theta",
            StorageKind::Unorm16 => "unorm16",
            StorageKind::F16 => "f16",
        }
    }

    /// The storage format named `s` ([`StorageKind::name`]).
    pub fn parse(s: &str) -> Option<StorageKind> {
        StorageKind::ALL.into_iter().find(|k| k.name() == s.trim())
    }

    /// The texture format the study's storage simulation rounds to.
    pub fn storage(self) -> Storage {
        match self {
            StorageKind::F32 => Storage::Float32,
            StorageKind::Unorm16Theta | StorageKind::Unorm16 => Storage::Unorm(16),
            StorageKind::F16 => Storage::Half,
        }
    }

    /// Bits per stored channel.
    pub fn bits(self) -> u32 {
        self.storage().bits()
    }

    /// Largest finite value of the format (UNORM: 1).
    pub fn max_value(self) -> f64 {
        match self {
            StorageKind::F32 => f32::MAX as f64,
            StorageKind::F16 => 65504.0,
            StorageKind::Unorm16Theta | StorageKind::Unorm16 => 1.0,
        }
    }
}

/// The techniques `tune` chooses among (closed forms with a shader reconstruction).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum TechniqueKind {
    /// Variance shadow maps, b = (z, z²).
    Vsm,
    /// Exponential shadow maps, b = e^{c·z}.
    Esm,
    /// Exponential variance shadow maps (two warps, four moments).
    Evsm,
    /// Hamburger 4MSM, b = (z, z², z³, z⁴) (Algorithm 3).
    Hamburger4,
    /// Hausdorff 4MSM on [0,1], same basis.
    Hausdorff4,
    /// Hamburger 6MSM, six power moments.
    Hamburger6,
    /// Trigonometric MSM.
    Tmsm,
}

impl TechniqueKind {
    /// Every technique, in search order.
    pub const ALL: [TechniqueKind; 7] = [
        TechniqueKind::Vsm,
        TechniqueKind::Esm,
        TechniqueKind::Evsm,
        TechniqueKind::Hamburger4,
        TechniqueKind::Hausdorff4,
        TechniqueKind::Hamburger6,
        TechniqueKind::Tmsm,
    ];

    /// The registry name.
    pub fn name(self) -> &'static str {
        match self {
            TechniqueKind::Vsm => "vsm",
            TechniqueKind::Esm => "esm",
            TechniqueKind::Evsm => "evsm",
            TechniqueKind::Hamburger4 => "hamburger4",
            TechniqueKind::Hausdorff4 => "hausdorff4",
            TechniqueKind::Hamburger6 => "hamburger6",
            TechniqueKind::Tmsm => "tmsm",
        }
    }

    /// The technique named `s` (its registry name).
    pub fn parse(s: &str) -> Option<TechniqueKind> {
        TechniqueKind::ALL
            .into_iter()
            .find(|k| k.name() == s.trim())
    }

    /// Moment count m.
    pub fn moment_count(self) -> usize {
        match self {
            TechniqueKind::Esm => 1,
            TechniqueKind::Vsm => 2,
            TechniqueKind::Evsm
            | TechniqueKind::Hamburger4
            | TechniqueKind::Hausdorff4
            | TechniqueKind::Tmsm => 4,
            TechniqueKind::Hamburger6 => 6,
        }
    }

    /// The storages that make sense for the technique: UNORM needs values in a bounded range
    /// (power and trigonometric moments), half floats are what engines use for the exponential
    /// warps (whose values UNORM cannot hold).
    pub fn storages(self) -> &'static [StorageKind] {
        match self {
            TechniqueKind::Esm | TechniqueKind::Evsm => &[StorageKind::F32, StorageKind::F16],
            TechniqueKind::Tmsm => &[StorageKind::F32, StorageKind::Unorm16Theta],
            _ => &[
                StorageKind::F32,
                StorageKind::Unorm16Theta,
                StorageKind::Unorm16,
            ],
        }
    }

    /// The transform θ of `storage` (identity unless 16-bit UNORM with θ).
    pub fn theta(self, storage: StorageKind) -> Theta {
        let m = self.moment_count();
        if storage != StorageKind::Unorm16Theta {
            return identity_theta(m);
        }
        match self {
            TechniqueKind::Vsm => published_theta2(),
            TechniqueKind::Hamburger4 | TechniqueKind::Hausdorff4 => published_theta4(),
            TechniqueKind::Hamburger6 => published_theta6(),
            // (sin, cos) ∈ [−1,1] → [0,1]
            _ => Theta::new(
                (1..=m).map(|j| format!("b{j}")).collect(),
                (0..m)
                    .map(|i| (0..m).map(|j| if i == j { 0.5 } else { 0.0 }).collect())
                    .collect(),
                vec![0.5; m],
            )
            .expect("(b + 1)/2 is regular"),
        }
    }

    /// Moment-bias grid α (b' = (1 − α)·b + α·b*, b* of the registry's default preset).
    pub fn alphas(self) -> &'static [f64] {
        match self {
            TechniqueKind::Vsm | TechniqueKind::Esm | TechniqueKind::Evsm => {
                &[0.0, 1e-5, 1e-4, 1e-3]
            }
            TechniqueKind::Hamburger6 => &[1e-6, 1e-5, 1e-4, 1e-3, 4e-3, 1e-2, 3e-2],
            _ => &[1e-7, 6e-7, 2e-6, 6e-6, 2e-5, 6e-5, 2e-4, 6e-4],
        }
    }

    /// The technique's own parameter sets for a storage (empty slice = none).
    pub fn own_params(self, storage: StorageKind) -> Vec<Own> {
        let limit = overflow_limit(self, storage);
        let keep =
            |cs: &[f64]| -> Vec<f64> { cs.iter().copied().filter(|&c| c <= limit).collect() };
        match (self, storage) {
            (TechniqueKind::Esm, StorageKind::F16) => keep(&[4.0, 7.0, 11.0])
                .into_iter()
                .map(|c| Own::Esm { c })
                .collect(),
            (TechniqueKind::Esm, _) => keep(&[20.0, 40.0, 80.0])
                .into_iter()
                .map(|c| Own::Esm { c })
                .collect(),
            (TechniqueKind::Evsm, st) => {
                let (pos, neg): (&[f64], &[f64]) = if st == StorageKind::F16 {
                    (&[2.5, 4.0, 5.54], &[2.5, 5.54])
                } else {
                    (&[10.0, 20.0, 42.0], &[5.0, 20.0])
                };
                let mut v = Vec::new();
                for &p in &keep(pos) {
                    for &n in &keep(neg) {
                        v.push(Own::Evsm { c_pos: p, c_neg: n });
                    }
                }
                v
            }
            _ => vec![Own::None],
        }
    }
}

/// Largest exponent c whose moments stay finite in `storage` on depths in [0,1]: ESM stores
/// e^{c z} (c ≤ ln max), EVSM e^{2 c z} (c ≤ ln(max)/2; the same bound for c₋, whose warp is
/// mirrored). ∞ for the other techniques.
pub fn overflow_limit(t: TechniqueKind, storage: StorageKind) -> f64 {
    let ln_max = storage.max_value().ln();
    match t {
        TechniqueKind::Esm => ln_max,
        TechniqueKind::Evsm => ln_max / 2.0,
        _ => f64::INFINITY,
    }
}

/// The technique's own parameters.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum Own {
    /// No own parameters.
    None,
    /// ESM exponent c.
    Esm {
        /// Exponent c of b = e^{c·z}.
        c: f64,
    },
    /// EVSM exponents c₊, c₋.
    Evsm {
        /// Positive exponent c₊.
        c_pos: f64,
        /// Negative exponent c₋.
        c_neg: f64,
    },
}

/// Technique depth bias ε′ = constant + slope_scale·(|dz/du| + |dz/dv|), subtracted from z_f.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct DepthBias {
    /// Constant part ε.
    pub constant: f64,
    /// Slope scale s, per texel step.
    pub slope_scale: f64,
}

/// The depth-bias grid (the default of `momentlab evaluate` is ε = 10⁻⁴, s = 2).
pub const CONSTANTS: [f64; 3] = [0.0, 1e-4, 5e-4];
/// Slope scales s of the depth-bias grid.
pub const SLOPE_SCALES: [f64; 5] = [0.0, 1.0, 2.0, 3.0, 4.0];

/// One family of settings: everything that changes the stored moments (technique basis,
/// storage, own parameters). The settings of a family share the decoded moment maps.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Family {
    /// The technique.
    pub technique: TechniqueKind,
    /// How the moments are stored.
    pub storage: StorageKind,
    /// The technique's own parameters.
    pub own: Own,
}

impl Family {
    /// m × bits per channel.
    pub fn bits_per_texel(&self) -> u32 {
        self.technique.moment_count() as u32 * self.storage.bits()
    }

    /// "hamburger4 unorm16-theta", "evsm f16 c+=5.54 c-=2.5".
    pub fn label(&self) -> String {
        let own = match self.own {
            Own::None => String::new(),
            Own::Esm { c } => format!(" c={c}"),
            Own::Evsm { c_pos, c_neg } => format!(" c+={c_pos} c-={c_neg}"),
        };
        format!("{} {}{own}", self.technique.name(), self.storage.name())
    }

    /// Registry parameters: arithmetic in f32 (the shader's), the given α.
    pub fn params(&self, alpha: f64) -> Params {
        let mut p = Params::with(Precision::F32, Some(alpha));
        p.quant_bits = if self.storage.bits() == 16 { 16 } else { 32 };
        match self.own {
            Own::None => {}
            Own::Esm { c } => p.esm_c = c,
            Own::Evsm { c_pos, c_neg } => {
                p.evsm_c_pos = c_pos;
                p.evsm_c_neg = c_neg;
            }
        }
        p
    }

    /// The technique at bias α (f32 arithmetic).
    pub fn build(&self, alpha: f64) -> Result<Box<dyn Technique>> {
        registry::build(self.technique.name(), &self.params(alpha))
    }
}

/// A point of the search space.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Setting {
    /// Technique, storage and own parameters.
    pub family: Family,
    /// Moment bias α of b' = (1 − α)·b + α·b*.
    pub alpha: f64,
    /// Technique depth bias ε′.
    pub depth_bias: DepthBias,
}

/// `x` in scientific notation with at most three significant digits and no trailing zeros
/// (1.2649e-5 → "1.26e-5", 3e-5 → "3e-5", 0 → "0e0").
pub fn short_e(x: f64) -> String {
    let t = format!("{x:.2e}");
    match t.split_once('e') {
        Some((m, e)) if m.contains('.') => {
            format!("{}e{e}", m.trim_end_matches('0').trim_end_matches('.'))
        }
        _ => t,
    }
}

impl Setting {
    /// "<family> α=… ε=… s=…".
    pub fn label(&self) -> String {
        format!(
            "{} α={} ε={} s={}",
            self.family.label(),
            short_e(self.alpha),
            short_e(self.depth_bias.constant),
            self.depth_bias.slope_scale
        )
    }
}

/// The families of the techniques and storages asked for; an error names an empty space.
pub fn families(techniques: &[TechniqueKind], storages: &[StorageKind]) -> Result<Vec<Family>> {
    if techniques.is_empty() {
        bail!("empty search space: no technique given");
    }
    if storages.is_empty() {
        bail!("empty search space: no storage given");
    }
    let mut out = Vec::new();
    for &t in techniques {
        for &s in t.storages().iter().filter(|s| storages.contains(s)) {
            for own in t.own_params(s) {
                out.push(Family {
                    technique: t,
                    storage: s,
                    own,
                });
            }
        }
    }
    if out.is_empty() {
        bail!(
            "empty search space: none of the techniques {} can use the storages {} ({})",
            techniques
                .iter()
                .map(|t| t.name())
                .collect::<Vec<_>>()
                .join(","),
            storages
                .iter()
                .map(|s| s.name())
                .collect::<Vec<_>>()
                .join(","),
            techniques
                .iter()
                .map(|t| format!(
                    "{}: {}",
                    t.name(),
                    t.storages()
                        .iter()
                        .map(|s| s.name())
                        .collect::<Vec<_>>()
                        .join("/")
                ))
                .collect::<Vec<_>>()
                .join("; ")
        );
    }
    Ok(out)
}

/// Every setting of a family (α × ε × s) on the technique's α grid.
pub fn grid(f: &Family) -> Vec<Setting> {
    grid_at(f, f.technique.alphas())
}

/// Every setting of a family at the moment biases `alphas` (α × ε × s).
pub fn grid_at(f: &Family, alphas: &[f64]) -> Vec<Setting> {
    let mut out = Vec::new();
    for &alpha in alphas {
        for &constant in &CONSTANTS {
            for &slope_scale in &SLOPE_SCALES {
                out.push(Setting {
                    family: *f,
                    alpha,
                    depth_bias: DepthBias {
                        constant,
                        slope_scale,
                    },
                });
            }
        }
    }
    out
}

/// Parse a comma-separated list with `parse`, naming the flag and the valid names on error.
pub fn parse_list<T: Copy>(
    flag: &str,
    list: &str,
    parse: impl Fn(&str) -> Option<T>,
    valid: &[&str],
) -> Result<Vec<T>> {
    let mut out = Vec::new();
    for item in list.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        match parse(item) {
            Some(v) => out.push(v),
            None => bail!("{flag}: unknown '{item}' (valid: {})", valid.join(", ")),
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn short_e_keeps_three_significant_digits() {
        assert_eq!(short_e(1.2649110640673518e-5), "1.26e-5");
        assert_eq!(short_e(3e-5), "3e-5");
        assert_eq!(short_e(5e-4), "5e-4");
        assert_eq!(short_e(0.0), "0e0");
        assert_eq!(short_e(2.5e-6), "2.5e-6");
    }

    #[test]
    fn exponents_respect_the_overflow_limit_of_the_storage() {
        // binary16: e^{2c} ≤ 65504 ⇔ c ≤ 5.545 (Filament's 5.54); f32: c ≤ 44.36 (Filament's 42)
        assert!((overflow_limit(TechniqueKind::Evsm, StorageKind::F16) - 5.5452).abs() < 1e-3);
        assert!((overflow_limit(TechniqueKind::Evsm, StorageKind::F32) - 44.3614).abs() < 1e-3);
        for s in [StorageKind::F16, StorageKind::F32] {
            for t in [TechniqueKind::Esm, TechniqueKind::Evsm] {
                for own in t.own_params(s) {
                    let c = match own {
                        Own::Esm { c } => c,
                        Own::Evsm { c_pos, c_neg } => c_pos.max(c_neg),
                        Own::None => unreachable!(),
                    };
                    let top = if t == TechniqueKind::Esm { c } else { 2.0 * c };
                    let stored = s.storage().store(top.exp());
                    assert!(stored.is_finite(), "{t:?} {s:?} c = {c}");
                }
            }
        }
    }

    #[test]
    fn empty_spaces_are_named() {
        let e = families(&[TechniqueKind::Esm], &[StorageKind::Unorm16]).unwrap_err();
        assert!(format!("{e}").contains("empty search space"), "{e}");
        assert!(families(&[], &[StorageKind::F32]).is_err());
        assert!(families(&[TechniqueKind::Vsm], &[]).is_err());
        let f = families(&TechniqueKind::ALL, &StorageKind::ALL).unwrap();
        assert!(f.iter().any(|f| f.storage == StorageKind::F16));
        assert!(f
            .iter()
            .all(|f| f.technique.storages().contains(&f.storage)));
    }
}
