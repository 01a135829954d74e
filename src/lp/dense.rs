//! Small dense kernels shared by the certificates and the scaled simplex: error-free
//! transformations (exact products and sums), a compensated dot product, exact power-of-two
//! scales, and the double-double LU with its eta file (the f64 LU is [`crate::linalg::Lu`]).

#![allow(clippy::needless_range_loop)] // index-heavy dense linear algebra on tiny matrices

pub use crate::linalg::Lu;

/// Exact product a·b = p + e (Dekker's splitting; no FMA needed).
#[inline]
pub fn two_prod(a: f64, b: f64) -> (f64, f64) {
    const SPLIT: f64 = 134_217_729.0; // 2^27 + 1
    let p = a * b;
    let split = |v: f64| {
        let c = SPLIT * v;
        let h = c - (c - v);
        (h, v - h)
    };
    let (ah, al) = split(a);
    let (bh, bl) = split(b);
    let e = ((ah * bh - p) + ah * bl + al * bh) + al * bl;
    (p, e)
}

/// Exact sum a + b = s + e (Knuth's TwoSum).
#[inline]
pub fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    (s, (a - (s - bb)) + (b - bb))
}

/// c − Σ_t a_t·x_t as accurately as if computed in twice the working precision (Ogita, Rump
/// & Oishi's Dot2), then rounded.
/// The same bits on every CPU (with fused multiply-add where the CPU has it).
#[inline]
pub fn residual2(c: f64, terms: impl Iterator<Item = (f64, f64)>) -> f64 {
    #[cfg(target_arch = "x86_64")]
    if has_fma() {
        // SAFETY: the CPU has FMA.
        return unsafe { residual2_fma(c, terms) };
    }
    residual2_in::<Dekker>(c, terms)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "fma")]
unsafe fn residual2_fma(c: f64, terms: impl Iterator<Item = (f64, f64)>) -> f64 {
    residual2_in::<Fused>(c, terms)
}

#[inline(always)]
fn residual2_in<P: ExactProduct>(c: f64, terms: impl Iterator<Item = (f64, f64)>) -> f64 {
    let (mut s, mut err) = (c, 0.0);
    for (a, x) in terms {
        let (p, ep) = P::two_prod(a, x);
        let (t, es) = two_sum(s, -p);
        s = t;
        err += es - ep;
    }
    s + err
}

/// The power of two 2^e closest above or at 1/v (v > 0 finite): an exact scale factor, so that
/// scaling by it introduces no rounding. Clamped to the normal range.
pub fn inv_pow2(v: f64) -> f64 {
    let biased = ((v.to_bits() >> 52) & 0x7ff) as i32;
    let e = if !(v > 0.0 && v.is_finite()) {
        0
    } else if biased > 0 {
        // floor(log2 v), exactly, from the exponent field of a normal number.
        1023 - biased
    } else {
        -(v.log2().floor() as i32)
    };
    pow2(e.clamp(-1000, 1000))
}

/// 2^e for |e| ≤ 1022, exactly.
pub fn pow2(e: i32) -> f64 {
    f64::from_bits(((1023 + e) as u64) << 52)
}

/// A double-double number hi + lo (about 32 significant digits).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Dd(pub f64, pub f64);

impl Dd {
    pub fn from(v: f64) -> Dd {
        Dd(v, 0.0)
    }
    pub fn add(self, o: Dd) -> Dd {
        let (s, e) = two_sum(self.0, o.0);
        let e = e + self.1 + o.1;
        let (h, l) = two_sum(s, e);
        Dd(h, l)
    }
    pub fn neg(self) -> Dd {
        Dd(-self.0, -self.1)
    }
    pub fn mul(self, o: Dd) -> Dd {
        self.mul_in::<Dekker>(o)
    }
    #[inline(always)]
    fn mul_in<P: ExactProduct>(self, o: Dd) -> Dd {
        let (p, e) = P::two_prod(self.0, o.0);
        let e = e + self.0 * o.1 + self.1 * o.0;
        let (h, l) = two_sum(p, e);
        Dd(h, l)
    }
    #[inline(always)]
    fn div_in<P: ExactProduct>(self, o: Dd) -> Dd {
        let q1 = self.0 / o.0;
        let r = self.add(o.mul_in::<P>(Dd::from(q1)).neg());
        let q2 = r.0 / o.0;
        let r = r.add(o.mul_in::<P>(Dd::from(q2)).neg());
        let q3 = r.0 / o.0;
        let (h, l) = two_sum(q1, q2);
        Dd(h, l).add(Dd::from(q3))
    }
}

/// How the exact product a·b = p + e is formed: the same (p, e) either way for finite
/// products whose operands stay below ~1e300 (Dekker's splitting overflows beyond).
trait ExactProduct {
    fn two_prod(a: f64, b: f64) -> (f64, f64);
}

/// Dekker's splitting ([`two_prod`]), on every CPU.
struct Dekker;

impl ExactProduct for Dekker {
    #[inline(always)]
    fn two_prod(a: f64, b: f64) -> (f64, f64) {
        two_prod(a, b)
    }
}

/// A fused multiply-add: e = fma(a, b, −p). Used only inside functions compiled with the
/// `fma` target feature (there `mul_add` is one instruction, elsewhere a library call).
struct Fused;

impl ExactProduct for Fused {
    #[inline(always)]
    fn two_prod(a: f64, b: f64) -> (f64, f64) {
        let p = a * b;
        (p, a.mul_add(b, -p))
    }
}

use super::cpu::has_fma;

/// LU factorisation with partial pivoting in double-double arithmetic: solves systems whose
/// condition is far beyond 1/ε (clusters of neighbouring grid points under a power basis).
#[derive(Clone, Debug, Default)]
pub struct DdLu {
    r: usize,
    lu: Vec<Dd>,
    perm: Vec<usize>,
}

impl DdLu {
    /// Factorise `a` (row-major r × r, f64 entries taken exactly); false if singular.
    pub fn factor(&mut self, a: &[f64], r: usize) -> bool {
        #[cfg(target_arch = "x86_64")]
        if has_fma() {
            // SAFETY: the CPU has FMA.
            return unsafe { self.factor_fma(a, r) };
        }
        self.factor_in::<Dekker>(a, r)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "fma")]
    unsafe fn factor_fma(&mut self, a: &[f64], r: usize) -> bool {
        self.factor_in::<Fused>(a, r)
    }

    #[inline(always)]
    fn factor_in<P: ExactProduct>(&mut self, a: &[f64], r: usize) -> bool {
        self.r = r;
        self.lu.clear();
        self.lu.extend(a[..r * r].iter().map(|&v| Dd::from(v)));
        self.perm.clear();
        self.perm.extend(0..r);
        let lu = &mut self.lu;
        for k in 0..r {
            let p = (k..r)
                .max_by(|&i, &j| lu[i * r + k].0.abs().total_cmp(&lu[j * r + k].0.abs()))
                .unwrap_or(k);
            let piv = lu[p * r + k];
            if piv.0 == 0.0 || !piv.0.is_finite() {
                return false;
            }
            if p != k {
                for c in 0..r {
                    lu.swap(p * r + c, k * r + c);
                }
                self.perm.swap(p, k);
            }
            for i in k + 1..r {
                let l = lu[i * r + k].div_in::<P>(piv);
                lu[i * r + k] = l;
                for c in k + 1..r {
                    lu[i * r + c] = lu[i * r + c].add(l.mul_in::<P>(lu[k * r + c]).neg());
                }
            }
        }
        true
    }

    /// Solve A x = b in place.
    pub fn solve(&self, x: &mut [f64]) {
        #[cfg(target_arch = "x86_64")]
        if has_fma() {
            // SAFETY: the CPU has FMA.
            return unsafe { self.solve_fma(x) };
        }
        self.solve_in::<Dekker>(x)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "fma")]
    unsafe fn solve_fma(&self, x: &mut [f64]) {
        self.solve_in::<Fused>(x)
    }

    #[inline(always)]
    fn solve_in<P: ExactProduct>(&self, x: &mut [f64]) {
        let mut y = [Dd::default(); 32];
        for i in 0..self.r {
            y[i] = Dd::from(x[i]);
        }
        self.solve_dd_in::<P>(&mut y);
        for i in 0..self.r {
            x[i] = y[i].0 + y[i].1;
        }
    }

    /// Solve A x = b in place in double-double (the first r entries of `x`).
    #[inline(always)]
    fn solve_dd_in<P: ExactProduct>(&self, x: &mut [Dd]) {
        let (r, lu) = (self.r, &self.lu);
        let mut y = [Dd::default(); 32];
        for i in 0..r {
            y[i] = x[self.perm[i]];
        }
        for i in 0..r {
            for c in 0..i {
                y[i] = y[i].add(lu[i * r + c].mul_in::<P>(y[c]).neg());
            }
        }
        for i in (0..r).rev() {
            for c in i + 1..r {
                y[i] = y[i].add(lu[i * r + c].mul_in::<P>(y[c]).neg());
            }
            y[i] = y[i].div_in::<P>(lu[i * r + i]);
        }
        x[..r].copy_from_slice(&y[..r]);
    }

    /// Solve Aᵀ x = b in place.
    pub fn solve_t(&self, x: &mut [f64]) {
        let mut out = [Dd::default(); 32];
        self.solve_t_dd(x, &mut out);
        for i in 0..self.r {
            x[i] = out[i].0 + out[i].1;
        }
    }

    /// Solve Aᵀ x = b, keeping x in double-double (duals whose products with a column cancel).
    pub fn solve_t_dd(&self, b: &[f64], out: &mut [Dd]) {
        #[cfg(target_arch = "x86_64")]
        if has_fma() {
            // SAFETY: the CPU has FMA.
            return unsafe { self.solve_t_dd_fma(b, out) };
        }
        self.solve_t_dd_in::<Dekker>(b, out)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "fma")]
    unsafe fn solve_t_dd_fma(&self, b: &[f64], out: &mut [Dd]) {
        self.solve_t_dd_in::<Fused>(b, out)
    }

    #[inline(always)]
    fn solve_t_dd_in<P: ExactProduct>(&self, b: &[f64], out: &mut [Dd]) {
        for i in 0..self.r {
            out[i] = Dd::from(b[i]);
        }
        self.solve_t_in_place::<P>(out);
    }

    /// Solve Aᵀ x = b in place in double-double (the first r entries of `x`).
    #[inline(always)]
    fn solve_t_in_place<P: ExactProduct>(&self, x: &mut [Dd]) {
        let (r, lu) = (self.r, &self.lu);
        let mut y = [Dd::default(); 32];
        y[..r].copy_from_slice(&x[..r]);
        for i in 0..r {
            for c in 0..i {
                y[i] = y[i].add(lu[c * r + i].mul_in::<P>(y[c]).neg());
            }
            y[i] = y[i].div_in::<P>(lu[i * r + i]);
        }
        for i in (0..r).rev() {
            for c in i + 1..r {
                y[i] = y[i].add(lu[c * r + i].mul_in::<P>(y[c]).neg());
            }
        }
        for i in 0..r {
            x[self.perm[i]] = y[i];
        }
    }
}

/// The double-double LU of a matrix B₀ and the eta file of the column replacements made since
/// (the product form of the inverse). Replacing column l of B by a, with α = B⁻¹a and α_l ≠ 0,
/// gives B′ = B F with F = I + (α − e_l) e_lᵀ; after k replacements B = B₀ F₁ ⋯ F_k, so
/// B⁻¹ = F_k⁻¹ ⋯ F₁⁻¹ B₀⁻¹ and B⁻ᵀ = B₀⁻ᵀ F₁⁻ᵀ ⋯ F_k⁻ᵀ, where
///
/// * (F⁻¹v)_l = v_l / α_l and (F⁻¹v)_i = v_i − α_i v_l / α_l for i ≠ l,
/// * (F⁻ᵀv)_l = (v_l − Σ_{i≠l} α_i v_i) / α_l and (F⁻ᵀv)_i = v_i for i ≠ l.
///
/// Each eta is stored as α with 1/α_l (in double-double) in place of α_l, so applying it is
/// r − 1 multiply-adds and one product.
#[derive(Clone, Debug, Default)]
pub struct DdEtaLu {
    lu: DdLu,
    /// The etas, r entries each.
    eta: Vec<Dd>,
    /// The replaced position l of each eta.
    at: Vec<usize>,
}

impl DdEtaLu {
    /// Factorise B₀ = `a` (row-major r × r, f64 entries taken exactly) and empty the eta file;
    /// false if singular.
    pub fn factor(&mut self, a: &[f64], r: usize) -> bool {
        self.eta.clear();
        self.at.clear();
        self.lu.factor(a, r)
    }

    /// Replacements since the factorisation.
    pub fn etas(&self) -> usize {
        self.at.len()
    }

    /// Record the replacement of column l by a column with α = B⁻¹a (B before the
    /// replacement, α_l ≠ 0): B becomes B F.
    pub fn push(&mut self, alpha: &[Dd], l: usize) {
        let r = self.lu.r;
        let start = self.eta.len();
        self.eta.extend_from_slice(&alpha[..r]);
        self.eta[start + l] = Dd::from(1.0).div_in::<Dekker>(alpha[l]);
        self.at.push(l);
    }

    /// x ← B⁻¹x in place (the first r entries).
    pub fn ftran(&self, x: &mut [Dd]) {
        #[cfg(target_arch = "x86_64")]
        if has_fma() {
            // SAFETY: the CPU has FMA.
            return unsafe { self.ftran_fma(x) };
        }
        self.ftran_in::<Dekker>(x)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "fma")]
    unsafe fn ftran_fma(&self, x: &mut [Dd]) {
        self.ftran_in::<Fused>(x)
    }

    #[inline(always)]
    fn ftran_in<P: ExactProduct>(&self, x: &mut [Dd]) {
        self.lu.solve_dd_in::<P>(x);
        for j in 0..self.at.len() {
            self.apply_in::<P>(j, x);
        }
    }

    /// x ← F_k⁻¹x for the last replacement only: the basic solution B⁻¹b of the basis before
    /// it becomes that of the basis after it.
    pub fn ftran_last(&self, x: &mut [Dd]) {
        let Some(j) = self.at.len().checked_sub(1) else {
            return;
        };
        #[cfg(target_arch = "x86_64")]
        if has_fma() {
            // SAFETY: the CPU has FMA.
            return unsafe { self.apply_fma(j, x) };
        }
        self.apply_in::<Dekker>(j, x)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "fma")]
    unsafe fn apply_fma(&self, j: usize, x: &mut [Dd]) {
        self.apply_in::<Fused>(j, x)
    }

    /// x ← F_j⁻¹x.
    #[inline(always)]
    fn apply_in<P: ExactProduct>(&self, j: usize, x: &mut [Dd]) {
        let r = self.lu.r;
        let (l, eta) = (self.at[j], &self.eta[j * r..(j + 1) * r]);
        let z = x[l].mul_in::<P>(eta[l]);
        x[l] = z;
        if z.0 == 0.0 {
            return;
        }
        for i in 0..r {
            if i != l {
                x[i] = x[i].add(eta[i].mul_in::<P>(z).neg());
            }
        }
    }

    /// y ← B⁻ᵀy in place (the first r entries).
    pub fn btran(&self, y: &mut [Dd]) {
        #[cfg(target_arch = "x86_64")]
        if has_fma() {
            // SAFETY: the CPU has FMA.
            return unsafe { self.btran_fma(y) };
        }
        self.btran_in::<Dekker>(y)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "fma")]
    unsafe fn btran_fma(&self, y: &mut [Dd]) {
        self.btran_in::<Fused>(y)
    }

    #[inline(always)]
    fn btran_in<P: ExactProduct>(&self, y: &mut [Dd]) {
        let r = self.lu.r;
        for j in (0..self.at.len()).rev() {
            let (l, eta) = (self.at[j], &self.eta[j * r..(j + 1) * r]);
            let mut s = y[l];
            for i in 0..r {
                if i != l {
                    s = s.add(eta[i].mul_in::<P>(y[i]).neg());
                }
            }
            y[l] = s.mul_in::<P>(eta[l]);
        }
        self.lu.solve_t_in_place::<P>(y);
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn residual2_gives_the_same_bits_with_and_without_fma() {
        let a: Vec<f64> = (0..40).map(|k| (k as f64 * 0.37).sin() * 1e5).collect();
        let x: Vec<f64> = (0..40).map(|k| (k as f64 * 1.3).cos() / 3.0).collect();
        let terms = || a.iter().copied().zip(x.iter().copied());
        let c = terms().map(|(a, x)| a * x).sum::<f64>();
        let dekker = residual2_in::<Dekker>(c, terms());
        assert_eq!(residual2(c, terms()), dekker);
        // Exact to double-double accuracy: the f64 sum's own rounding error, not 0.
        assert!(dekker != 0.0 && dekker.abs() < 1e-9);
    }

    #[test]
    fn dd_lu_gives_the_same_bits_with_and_without_fma() {
        let r = 9;
        // Ill-conditioned: powers of clustered points (a Vandermonde matrix).
        let a: Vec<f64> = (0..r * r)
            .map(|k| (0.6 + 1e-3 * (k / r) as f64).powi((k % r) as i32 + 1) * 3.7)
            .collect();
        let b: Vec<f64> = (0..r).map(|k| (k as f64 * 0.7).cos()).collect();
        let mut dekker = DdLu::default();
        assert!(dekker.factor_in::<Dekker>(&a, r));
        let mut x1 = b.clone();
        dekker.solve_in::<Dekker>(&mut x1);
        let mut y1 = vec![Dd::default(); r];
        dekker.solve_t_dd_in::<Dekker>(&b, &mut y1);
        // The dispatching entry points (FMA where the CPU has it).
        let mut fused = DdLu::default();
        assert!(fused.factor(&a, r));
        assert_eq!(fused.lu, dekker.lu);
        let mut x2 = b.clone();
        fused.solve(&mut x2);
        assert_eq!(x1, x2);
        let mut y2 = vec![Dd::default(); r];
        fused.solve_t_dd(&b, &mut y2);
        assert_eq!(y1, y2);
        // And it solves: A x = b to double-double accuracy, rounded.
        for i in 0..r {
            let terms = (0..r).map(|c| (a[i * r + c], x1[c]));
            let mag: f64 = (0..r).map(|c| (a[i * r + c] * x1[c]).abs()).sum();
            assert!(residual2(b[i], terms).abs() <= 1e-14 * mag, "row {i}");
        }
    }

    use super::*;

    #[test]
    fn dd_lu_solves_a_vandermonde_beyond_f64() {
        // Five nodes 1e-4 apart under z..z^4: cond ≈ 1e17, hopeless in f64.
        let r = 5;
        let z: Vec<f64> = (0..r).map(|k| 0.7 + k as f64 * 1e-4).collect();
        let a: Vec<f64> = (0..r * r).map(|e| z[e % r].powi((e / r) as i32)).collect();
        let xs = [0.1, 0.2, 0.3, 0.25, 0.15];
        let b: Vec<f64> = (0..r)
            .map(|k| -residual2(0.0, (0..r).map(|t| (a[k * r + t], xs[t]))))
            .collect();
        let mut lu = DdLu::default();
        assert!(lu.factor(&a, r));
        let mut x = b.clone();
        lu.solve(&mut x);
        for k in 0..r {
            let res = residual2(b[k], (0..r).map(|t| (a[k * r + t], x[t])));
            assert!(res.abs() < 1e-15 * b[k].abs(), "{k}: residual {res:e}");
        }
        assert!(x.iter().all(|v| v.is_finite()));
    }
}
