//! Techniques by name, as used on the command line and in reports.
//!
//! Closed-form names: vsm, esm, evsm, csm, hamburger, hamburger4, hausdorff4, hamburger6, tmsm.
//! LP candidates: "lp:f1,f2,…" with catalog names or formulas.
//!
//! [`build`] takes the technique parameters ([`Params`], all optional with documented
//! defaults); [`by_name`] uses the defaults.

use super::csm::Csm;
use super::esm::Esm;
use super::evsm::Evsm;
use super::hamburger::Hamburger;
use super::hamburger4::{Hamburger4, ALPHA_16BIT, ALPHA_32BIT};
use super::hamburger6::Hamburger6;
use super::hausdorff4::Hausdorff4;
pub use super::linalg::Precision;
use super::vsm::Vsm;
use super::Technique;
use anyhow::{bail, Result};

/// Closed-form technique names handled here (for error messages).
pub const CLOSED_FORM_NAMES: &[&str] = &[
    "vsm",
    "esm",
    "evsm",
    "csm",
    "hamburger",
    "hamburger4",
    "hausdorff4",
    "hamburger6",
    "tmsm",
];

/// The one spelling of a technique name. Older spellings map to it: `4msm`, `6msm`, `8msm` →
/// `hamburger4`, `hamburger6`, `hamburger8`; `hamburger(m=K)` → `hamburgerK` (the general
/// Algorithm 2; `hamburgerK-general` for K = 4, 6, whose `hamburgerK` is the dedicated closed
/// form). Other names are returned trimmed.
pub fn canonical_name(name: &str) -> String {
    let n = name.trim();
    if let Some(k) = n
        .strip_suffix("msm")
        .filter(|k| matches!(*k, "4" | "6" | "8"))
    {
        return format!("hamburger{k}");
    }
    if let Some(k) = n
        .strip_prefix("hamburger(m=")
        .and_then(|r| r.strip_suffix(')'))
    {
        return match k {
            "4" | "6" => format!("hamburger{k}-general"),
            _ => format!("hamburger{k}"),
        };
    }
    n.to_string()
}

/// The moment count m of a general Hamburger MSM name (Algorithm 2): `hamburgerM` for M other
/// than 4 and 6, or `hamburgerM-general` for any M. None for every other name.
pub fn general_hamburger_moments(name: &str) -> Option<usize> {
    let rest = name.strip_prefix("hamburger")?;
    let (digits, general) = match rest.strip_suffix("-general") {
        Some(d) => (d, true),
        None => (rest, false),
    };
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) || digits.len() > 3 {
        return None;
    }
    let m: usize = digits.parse().ok()?;
    (general || !matches!(m, 4 | 6)).then_some(m)
}

/// Whether `name` (in any accepted spelling) names a closed-form technique.
pub fn is_closed_form_name(name: &str) -> bool {
    let n = canonical_name(name);
    CLOSED_FORM_NAMES.contains(&n.as_str()) || general_hamburger_moments(&n).is_some()
}

/// Which constant moment vector b* the bias b' = (1 − α) b + α b* pulls towards.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum BiasPreset {
    /// b* = E_{Z*}[b] with Z* = ½(δ₀ + δ₁); for power moments (½, …, ½) (Peters & Klein 2015,
    /// Section 4.2).
    Standard,
    /// Clamped depths (supplementary Section 4, power moments only): four moments
    /// b* = ⅘·(½,…) + ⅕·(½,⅓,¼,⅕), α = 3·10⁻⁵; six moments b* = ½·(½,…) + ½·(½,…,⅐), α = 4·10⁻³.
    Clamped,
}

/// Parameters of the closed-form techniques; every field is optional (serde default).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Params {
    /// Bias strength α. Default: MSM techniques 2·10⁻⁶ (3·10⁻⁵ with `quant_bits` = 16; the
    /// clamped preset's own α), hamburger6 without a preset the α that meets tune's noise
    /// bound (`hamburger6::ALPHA_NOISE_BOUND_F32`, `_16BIT`), baselines (vsm, esm, evsm, csm) 0.
    pub alpha: Option<f64>,
    /// Explicit b* (length m); overrides `bias`.
    pub b_star: Option<Vec<f64>>,
    /// Bias preset; default `standard`, except hamburger6: `clamped`.
    pub bias: Option<BiasPreset>,
    /// Storage bits per moment, used only to pick the default α (32 or 16).
    pub quant_bits: u32,
    /// Arithmetic precision (f64 default).
    pub precision: Precision,
    /// Moment count m for "hamburger" (even, 2..=30; default 4).
    pub moment_count: Option<usize>,
    /// ESM exponent c (default 80).
    pub esm_c: f64,
    /// EVSM exponents c₊, c₋ (default 40, 5).
    pub evsm_c_pos: f64,
    /// EVSM negative exponent c₋ (default 5).
    pub evsm_c_neg: f64,
    /// CSM Fourier terms M (default 4, m = 2M; at most 32).
    pub csm_terms: usize,
    /// VSM/EVSM minimum depth-space variance; default 10⁻⁶ at f32, 0 at f64.
    pub min_variance: Option<f64>,
}

impl Default for Params {
    fn default() -> Params {
        Params {
            alpha: None,
            b_star: None,
            bias: None,
            quant_bits: 32,
            precision: Precision::F64,
            moment_count: None,
            esm_c: super::esm::DEFAULT_C,
            evsm_c_pos: super::evsm::DEFAULT_C_POS,
            evsm_c_neg: super::evsm::DEFAULT_C_NEG,
            csm_terms: super::csm::DEFAULT_TERMS,
            min_variance: None,
        }
    }
}

impl Params {
    /// Defaults with the given precision and α.
    pub fn with(precision: Precision, alpha: Option<f64>) -> Params {
        Params {
            precision,
            alpha,
            ..Params::default()
        }
    }

    fn check(&self) -> Result<()> {
        if let Some(a) = self.alpha {
            if !(a.is_finite() && (0.0..1.0).contains(&a)) {
                bail!("alpha must be in [0, 1), got {a}");
            }
        }
        if let Some(s) = &self.b_star {
            if let Some(v) = s.iter().find(|v| !v.is_finite()) {
                bail!("b_star contains a non-finite value ({v})");
            }
        }
        if self.quant_bits != 16 && self.quant_bits != 32 {
            bail!("quant_bits must be 16 or 32, got {}", self.quant_bits);
        }
        for (name, v) in [
            ("esm_c", self.esm_c),
            ("evsm_c_pos", self.evsm_c_pos),
            ("evsm_c_neg", self.evsm_c_neg),
        ] {
            if !(v.is_finite() && v > 0.0 && v <= 200.0) {
                bail!("{name} must be in (0, 200], got {v}");
            }
        }
        if let Some(v) = self.min_variance {
            if !(v.is_finite() && v >= 0.0) {
                bail!("min_variance must be finite and ≥ 0, got {v}");
            }
        }
        Ok(())
    }

    fn min_variance(&self) -> f64 {
        self.min_variance.unwrap_or(match self.precision {
            Precision::F32 => 1e-6,
            Precision::F64 => 0.0,
        })
    }

    /// α for a power-moment (MSM) technique with m moments.
    fn msm_alpha(&self, m: usize) -> f64 {
        if let Some(a) = self.alpha {
            return a;
        }
        match (self.bias, m) {
            (Some(BiasPreset::Clamped), 6) => super::hamburger6::ALPHA_CLAMPED,
            (Some(BiasPreset::Clamped), _) => ALPHA_16BIT,
            _ if self.quant_bits == 16 => ALPHA_16BIT,
            _ => ALPHA_32BIT,
        }
    }

    /// b* for power moments of count m under the chosen preset.
    fn msm_b_star(&self, name: &str, m: usize) -> Result<Vec<f64>> {
        if let Some(s) = &self.b_star {
            if s.len() != m {
                bail!("{name}: b_star has {} values, expected {m}", s.len());
            }
            return Ok(s.clone());
        }
        Ok(match self.bias.unwrap_or(BiasPreset::Standard) {
            BiasPreset::Standard => vec![0.5; m],
            BiasPreset::Clamped => match m {
                4 => super::hamburger4::B_STAR_CLAMPED.to_vec(),
                6 => super::hamburger6::B_STAR_CLAMPED.to_vec(),
                _ => bail!("{name}: the clamped bias is defined for 4 and 6 moments only, not {m}"),
            },
        })
    }

    /// b* of a non-power basis: explicit, or the moments of ½(δ₀ + δ₁).
    fn basis_b_star(&self, name: &str, t: &dyn Technique) -> Result<Vec<f64>> {
        let m = t.moment_count();
        if let Some(s) = &self.b_star {
            if s.len() != m {
                bail!("{name}: b_star has {} values, expected {m}", s.len());
            }
            return Ok(s.clone());
        }
        if self.bias == Some(BiasPreset::Clamped) {
            bail!("{name}: the clamped bias is defined for power moments only");
        }
        let (mut b0, mut b1) = (vec![0.0; m], vec![0.0; m]);
        t.basis(0.0, &mut b0);
        t.basis(1.0, &mut b1);
        Ok(b0.iter().zip(&b1).map(|(a, b)| 0.5 * (a + b)).collect())
    }
}

fn arr<const N: usize>(v: Vec<f64>) -> [f64; N] {
    let mut a = [0.0; N];
    a.copy_from_slice(&v[..N]);
    a
}

/// The closed-form technique `name` with parameters `p`.
pub fn build(name: &str, p: &Params) -> Result<Box<dyn Technique>> {
    p.check()?;
    let canonical = canonical_name(name);
    let name = canonical.as_str();
    if let Some(m) = general_hamburger_moments(name) {
        if p.moment_count.is_some_and(|k| k != m) {
            bail!("{name}: moment_count must be {m} (or omitted)");
        }
        let q = Params {
            moment_count: Some(m),
            ..p.clone()
        };
        return build("hamburger", &q);
    }
    let prec = p.precision;
    let t: Box<dyn Technique> = match name {
        "vsm" => {
            let mut t = Vsm {
                alpha: p.alpha.unwrap_or(0.0),
                b_star: [0.0; 2],
                min_variance: p.min_variance(),
                precision: prec,
            };
            t.b_star = arr(p.basis_b_star(name, &t)?);
            Box::new(t)
        }
        "esm" => {
            let mut t = Esm {
                c: p.esm_c,
                alpha: p.alpha.unwrap_or(0.0),
                b_star: 0.0,
                precision: prec,
            };
            t.b_star = p.basis_b_star(name, &t)?[0];
            Box::new(t)
        }
        "evsm" => {
            let mut t = Evsm {
                c_pos: p.evsm_c_pos,
                c_neg: p.evsm_c_neg,
                alpha: p.alpha.unwrap_or(0.0),
                b_star: [0.0; 4],
                min_variance: p.min_variance(),
                precision: prec,
            };
            t.b_star = arr(p.basis_b_star(name, &t)?);
            Box::new(t)
        }
        "csm" => {
            if !(1..=32).contains(&p.csm_terms) {
                bail!("csm_terms must be in 1..=32, got {}", p.csm_terms);
            }
            let mut t = Csm {
                b_star: vec![0.0; 2 * p.csm_terms],
                alpha: p.alpha.unwrap_or(0.0),
                precision: prec,
            };
            t.b_star = p.basis_b_star(name, &t)?;
            Box::new(t)
        }
        "hamburger" => {
            let m = p.moment_count.unwrap_or(4);
            if !(2..=30).contains(&m) || !m.is_multiple_of(2) {
                bail!("hamburger: moment count must be even and in 2..=30, got {m}");
            }
            let b_star = p.msm_b_star(name, m)?;
            Box::new(Hamburger::new(p.msm_alpha(m), b_star, prec))
        }
        "hamburger4" => Box::new(Hamburger4::new(
            p.msm_alpha(4),
            arr(p.msm_b_star(name, 4)?),
            prec,
        )),
        "hausdorff4" => Box::new(Hausdorff4::new(
            p.msm_alpha(4),
            arr(p.msm_b_star(name, 4)?),
            prec,
        )),
        "hamburger6" => {
            let mut q = p.clone();
            q.bias = Some(p.bias.unwrap_or(BiasPreset::Clamped));
            // Without α or a bias preset: the α that meets tune's noise bound.
            let alpha = match (p.alpha, p.bias, p.quant_bits) {
                (None, None, 16) => super::hamburger6::ALPHA_NOISE_BOUND_16BIT,
                (None, None, _) => super::hamburger6::ALPHA_NOISE_BOUND_F32,
                _ => q.msm_alpha(6),
            };
            Box::new(Hamburger6::new(alpha, arr(q.msm_b_star(name, 6)?), prec))
        }
        "tmsm" => {
            if p.bias == Some(BiasPreset::Clamped) {
                bail!("tmsm: the clamped bias is defined for power moments only");
            }
            let mut t = super::tmsm::Tmsm::new(
                p.alpha.unwrap_or(if p.quant_bits == 16 {
                    super::tmsm::Tmsm::ALPHA_16BIT
                } else {
                    super::tmsm::Tmsm::DEFAULT_ALPHA
                }),
                prec == Precision::F32,
            );
            if let Some(b) = &p.b_star {
                if b.len() != 4 {
                    bail!("tmsm: b_star needs 4 values, got {}", b.len());
                }
                t.b_star = arr(b.clone());
            }
            Box::new(t)
        }
        other => bail!(
            "unknown technique '{other}' (valid: {}, hamburgerM (even M: Algorithm 2), lp:f1,f2,…)",
            CLOSED_FORM_NAMES.join(", ")
        ),
    };
    Ok(t)
}

/// The [`Params`] fields (JSON keys) the technique `name` reads; None for a name [`build`]
/// does not know (LP candidates `lp:…` read none).
pub fn parameters_of(name: &str) -> Option<&'static [&'static str]> {
    const VSM: [&str; 5] = ["alpha", "b_star", "bias", "precision", "min_variance"];
    const ESM: [&str; 5] = ["alpha", "b_star", "bias", "precision", "esm_c"];
    const EVSM: [&str; 7] = [
        "alpha",
        "b_star",
        "bias",
        "precision",
        "evsm_c_pos",
        "evsm_c_neg",
        "min_variance",
    ];
    const CSM: [&str; 5] = ["alpha", "b_star", "bias", "precision", "csm_terms"];
    const MSM: [&str; 5] = ["alpha", "b_star", "bias", "precision", "quant_bits"];
    const HAMBURGER: [&str; 6] = [
        "alpha",
        "b_star",
        "bias",
        "precision",
        "quant_bits",
        "moment_count",
    ];
    if name.trim().starts_with("lp:") {
        return Some(&[]);
    }
    let canonical = canonical_name(name);
    if general_hamburger_moments(&canonical).is_some() {
        return Some(&HAMBURGER);
    }
    Some(match canonical.as_str() {
        "vsm" => &VSM,
        "esm" => &ESM,
        "evsm" => &EVSM,
        "csm" => &CSM,
        "hamburger" => &HAMBURGER,
        "hamburger4" | "hausdorff4" | "hamburger6" | "tmsm" => &MSM,
        _ => return None,
    })
}

/// The technique named by `spec` with default parameters; a one-line error for unknown names.
pub fn by_name(spec: &str) -> Result<Box<dyn Technique>> {
    if let Some(list) = spec.strip_prefix("lp:") {
        return Ok(Box::new(super::lp_candidate::LpCandidate::from_spec(list)?));
    }
    build(spec, &Params::default())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_name_per_technique_and_old_spellings_map_to_it() {
        for (old, new) in [
            ("4msm", "hamburger4"),
            ("6msm", "hamburger6"),
            ("8msm", "hamburger8"),
            ("hamburger(m=8)", "hamburger8"),
            ("hamburger(m=4)", "hamburger4-general"),
            ("hamburger(m=6)", "hamburger6-general"),
            (" vsm ", "vsm"),
        ] {
            assert_eq!(canonical_name(old), new);
            // The built technique is named by the canonical name.
            assert_eq!(by_name(old).unwrap().name(), new, "{old}");
        }
        assert_eq!(by_name("hamburger8").unwrap().moment_count(), 8);
        assert_eq!(by_name("hamburger4").unwrap().name(), "hamburger4");
        assert_eq!(general_hamburger_moments("hamburger4"), None);
        assert_eq!(general_hamburger_moments("hamburger4-general"), Some(4));
        assert_eq!(general_hamburger_moments("hamburger10"), Some(10));
        assert_eq!(general_hamburger_moments("hamburgerx"), None);
        assert!(by_name("hamburger7").is_err());
        assert!(by_name("9msm").is_err());
        assert!(is_closed_form_name("8msm") && !is_closed_form_name("z^2"));
    }

    /// Every closed form's parameter list names only fields of `Params`, holds the ones its
    /// builder reads, and LP candidates read none.
    #[test]
    fn parameters_of_each_technique() {
        let fields = serde_json::to_value(Params::default()).unwrap();
        for name in CLOSED_FORM_NAMES
            .iter()
            .chain(&["hamburger", "hamburger8", "4msm"])
        {
            let keys = parameters_of(name).unwrap_or_else(|| panic!("{name}"));
            for k in keys {
                assert!(fields.get(k).is_some(), "{name}: {k} is not a field");
            }
        }
        assert!(parameters_of("esm").unwrap().contains(&"esm_c"));
        assert!(!parameters_of("vsm").unwrap().contains(&"esm_c"));
        assert!(parameters_of("hamburger10")
            .unwrap()
            .contains(&"moment_count"));
        assert!(parameters_of("lp:z,z^2").unwrap().is_empty());
        assert!(parameters_of("nonsense").is_none());
    }
}
