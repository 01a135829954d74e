//! The curve b : [0,1] → R^m whose image θ must map into [0,1]^m, with an oracle for the
//! extrema of a row polynomial a·b(z) over [0,1]: exact (derivative roots) for monomial
//! bases, dense sampling plus golden-section refinement otherwise.

use super::poly;

/// A basis curve b(z), z ∈ [0,1].
pub trait Curve: Send + Sync {
    /// m, the number of components.
    fn dim(&self) -> usize;
    /// Names of the components (e.g. "z^2").
    fn names(&self) -> Vec<String>;
    /// out[j] = b_j(z).
    fn eval(&self, z: f64, out: &mut [f64]);
    /// Local-extremum candidates (z, a·b(z)) of the row function a·b on [0,1], always
    /// including both endpoints; the global min and max are among them.
    fn extrema(&self, a: &[f64]) -> Vec<(f64, f64)>;
    /// Exponents if b is a list of monomials z^k (exact verification, shader codegen).
    fn monomial_exponents(&self) -> Option<Vec<u32>>;
    /// True if [`Curve::extrema`] is exact up to rounding.
    fn exact(&self) -> bool {
        self.monomial_exponents().is_some()
    }
}

/// min and max of a·b over [0,1] from the extrema oracle: (z_min, min, z_max, max).
pub fn row_min_max(curve: &dyn Curve, a: &[f64]) -> (f64, f64, f64, f64) {
    poly::arg_min_max(curve.extrema(a))
}

/// b(z) = (z^{e_1}, …, z^{e_m}); the power basis of m moments is exponents 1..=m.
#[derive(Clone, Debug)]
pub struct MonomialCurve {
    exps: Vec<u32>,
}

impl MonomialCurve {
    /// Exponents must be distinct and ≥ 1 (a constant component cannot be stretched).
    pub fn new(exps: Vec<u32>) -> anyhow::Result<MonomialCurve> {
        if exps.is_empty() {
            anyhow::bail!("empty basis");
        }
        let mut s = exps.clone();
        s.sort_unstable();
        s.dedup();
        if s.len() != exps.len() || s[0] == 0 || *s.last().unwrap() > 40 {
            anyhow::bail!("monomial exponents must be distinct and in 1..=40, got {exps:?}");
        }
        Ok(MonomialCurve { exps })
    }
    /// The power basis (z, z², …, z^m) of m moments.
    pub fn power(m: usize) -> anyhow::Result<MonomialCurve> {
        if !(1..=12).contains(&m) {
            anyhow::bail!("--m must be in 1..=12, got {m}");
        }
        MonomialCurve::new((1..=m as u32).collect())
    }
    fn coeffs(&self, a: &[f64]) -> Vec<f64> {
        let d = *self.exps.iter().max().unwrap() as usize;
        let mut c = vec![0.0; d + 1];
        for (&e, &aj) in self.exps.iter().zip(a) {
            c[e as usize] += aj;
        }
        c
    }
}

impl Curve for MonomialCurve {
    fn dim(&self) -> usize {
        self.exps.len()
    }
    fn names(&self) -> Vec<String> {
        self.exps
            .iter()
            .map(|&e| if e == 1 { "z".into() } else { format!("z^{e}") })
            .collect()
    }
    fn eval(&self, z: f64, out: &mut [f64]) {
        for (o, &e) in out.iter_mut().zip(&self.exps) {
            *o = z.powi(e as i32);
        }
    }
    fn extrema(&self, a: &[f64]) -> Vec<(f64, f64)> {
        let c = self.coeffs(a);
        poly::extrema_candidates(&c)
            .into_iter()
            .map(|(z, _)| {
                // evaluate through the basis itself so the value matches what a shader stores
                let mut b = vec![0.0; self.exps.len()];
                self.eval(z, &mut b);
                (z, b.iter().zip(a).map(|(p, q)| p * q).sum())
            })
            .collect()
    }
    fn monomial_exponents(&self) -> Option<Vec<u32>> {
        Some(self.exps.clone())
    }
}

type EvalFn = Box<dyn Fn(f64, &mut [f64]) + Send + Sync>;

/// Any basis given as a function: extrema by dense sampling (`samples` + 1 uniform points)
/// and golden-section refinement of every sampled local extremum. Not exact: a feature
/// narrower than the sample spacing can be missed.
pub struct SampledCurve {
    names: Vec<String>,
    f: EvalFn,
    zs: Vec<f64>,
    table: Vec<f64>,
}

impl SampledCurve {
    /// Tabulates `f` at `samples` + 1 uniform points (at least 17) and checks every value is finite.
    pub fn new(names: Vec<String>, samples: usize, f: EvalFn) -> anyhow::Result<SampledCurve> {
        let m = names.len();
        let samples = samples.max(16);
        let zs: Vec<f64> = (0..=samples).map(|i| i as f64 / samples as f64).collect();
        let mut table = vec![0.0; zs.len() * m];
        for (i, &z) in zs.iter().enumerate() {
            f(z, &mut table[i * m..(i + 1) * m]);
            for (j, v) in table[i * m..(i + 1) * m].iter().enumerate() {
                if !v.is_finite() {
                    anyhow::bail!("basis function '{}' is not finite at z = {z}", names[j]);
                }
            }
        }
        Ok(SampledCurve {
            names,
            f,
            zs,
            table,
        })
    }

    fn value(&self, a: &[f64], z: f64, buf: &mut [f64]) -> f64 {
        (self.f)(z, buf);
        buf.iter().zip(a).map(|(p, q)| p * q).sum()
    }

    /// Golden-section search for an extremum of sign `s` (+1 max, −1 min) in [lo, hi].
    fn refine(&self, a: &[f64], lo: f64, hi: f64, s: f64, buf: &mut [f64]) -> (f64, f64) {
        let g = 0.5 * (5f64.sqrt() - 1.0);
        let (mut lo, mut hi) = (lo, hi);
        let mut x1 = hi - g * (hi - lo);
        let mut x2 = lo + g * (hi - lo);
        let mut f1 = s * self.value(a, x1, buf);
        let mut f2 = s * self.value(a, x2, buf);
        for _ in 0..80 {
            if hi - lo < 1e-14 {
                break;
            }
            if f1 > f2 {
                hi = x2;
                x2 = x1;
                f2 = f1;
                x1 = hi - g * (hi - lo);
                f1 = s * self.value(a, x1, buf);
            } else {
                lo = x1;
                x1 = x2;
                f1 = f2;
                x2 = lo + g * (hi - lo);
                f2 = s * self.value(a, x2, buf);
            }
        }
        let z = 0.5 * (lo + hi);
        (z, self.value(a, z, buf))
    }
}

impl Curve for SampledCurve {
    fn dim(&self) -> usize {
        self.names.len()
    }
    fn names(&self) -> Vec<String> {
        self.names.clone()
    }
    fn eval(&self, z: f64, out: &mut [f64]) {
        (self.f)(z, out)
    }
    fn extrema(&self, a: &[f64]) -> Vec<(f64, f64)> {
        let m = self.names.len();
        let n = self.zs.len();
        let v: Vec<f64> = (0..n)
            .map(|i| {
                self.table[i * m..(i + 1) * m]
                    .iter()
                    .zip(a)
                    .map(|(p, q)| p * q)
                    .sum()
            })
            .collect();
        let mut buf = vec![0.0; m];
        let mut out = vec![(0.0, v[0]), (1.0, v[n - 1])];
        for i in 0..n {
            let l = if i > 0 { v[i - 1] } else { f64::NAN };
            let r = if i + 1 < n { v[i + 1] } else { f64::NAN };
            let is_max = !(l > v[i]) && !(r > v[i]);
            let is_min = !(l < v[i]) && !(r < v[i]);
            if !(is_max || is_min) {
                continue;
            }
            let lo = self.zs[i.saturating_sub(1)];
            let hi = self.zs[(i + 1).min(n - 1)];
            for (flag, s) in [(is_max, 1.0), (is_min, -1.0)] {
                if flag {
                    let (z, val) = self.refine(a, lo, hi, s, &mut buf);
                    // keep the better of the sample and the refined point
                    if s * val >= s * v[i] {
                        out.push((z, val));
                    } else {
                        out.push((self.zs[i], v[i]));
                    }
                }
            }
        }
        out.sort_by(|p, q| p.0.total_cmp(&q.0));
        out
    }
    fn monomial_exponents(&self) -> Option<Vec<u32>> {
        None
    }
}

/// The curve of a basis given by names: exact monomials when every name is "z" or "z^k",
/// otherwise catalog functions or formulas (crate::basis) verified by dense sampling.
pub fn from_names(names: &[String]) -> anyhow::Result<Box<dyn Curve>> {
    use anyhow::Context;
    if names.is_empty() {
        anyhow::bail!("basis: empty list");
    }
    if let Some(e) = parse_monomials(names) {
        return Ok(Box::new(MonomialCurve::new(e).context("basis")?));
    }
    let cat = crate::basis::Catalog::embedded();
    let funcs = names
        .iter()
        .map(|n| cat.resolve(n).with_context(|| format!("basis entry '{n}'")))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let b = crate::basis::Basis::new(funcs);
    Ok(Box::new(SampledCurve::new(
        b.names(),
        1 << 14,
        Box::new(move |z, out: &mut [f64]| b.eval(z, out)),
    )?))
}

/// Parse "z" / "z^k" names into exponents (None if any name is not a plain monomial).
pub fn parse_monomials(names: &[String]) -> Option<Vec<u32>> {
    names
        .iter()
        .map(|n| {
            let n = n.trim().replace(' ', "");
            if n == "z" {
                Some(1)
            } else {
                n.strip_prefix("z^")?.parse::<u32>().ok()
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    #[test]
    fn sampled_oracle_agrees_with_exact_oracle_on_polynomials() {
        let exact = MonomialCurve::power(5).unwrap();
        let sampled = SampledCurve::new(
            exact.names(),
            4096,
            Box::new(|z, o: &mut [f64]| {
                for (j, v) in o.iter_mut().enumerate() {
                    *v = z.powi(j as i32 + 1);
                }
            }),
        )
        .unwrap();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        for _ in 0..1000 {
            let a: Vec<f64> = (0..5).map(|_| rng.gen_range(-40.0..40.0)).collect();
            let e = row_min_max(&exact, &a);
            let s = row_min_max(&sampled, &a);
            assert!(
                (e.1 - s.1).abs() < 1e-9 && (e.3 - s.3).abs() < 1e-9,
                "{e:?} {s:?}"
            );
        }
    }

    #[test]
    fn monomial_names_parse() {
        let n: Vec<String> = ["z", "z^2", " z^4"].iter().map(|s| s.to_string()).collect();
        assert_eq!(parse_monomials(&n), Some(vec![1, 2, 4]));
        assert_eq!(parse_monomials(&["exp(z)".to_string()]), None);
        assert!(MonomialCurve::new(vec![1, 1]).is_err());
        assert!(MonomialCurve::power(0).is_err());
    }
}
