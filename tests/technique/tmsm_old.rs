//! The TMSM closed form as it was before the rewrite for speed (commit 491dd4f,
//! src/technique/tmsm.rs, unchanged apart from dropping the unused Ferrari/Cardano solvers and
//! the `Technique` impl): the oracle of tests/technique/tmsm_equiv.rs. Do not edit.
#![allow(dead_code, clippy::all)]

use std::ops::{Add, Div, Mul, Neg, Sub};

/// The floating-point operations the solver needs; implemented for f32 and f64 so the same
/// code gives both precision paths.
pub trait Real:
    Copy
    + PartialOrd
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    fn c(x: f64) -> Self;
    fn to_f64(self) -> f64;
    fn sqrt(self) -> Self;
    fn sin(self) -> Self;
    fn cos(self) -> Self;
    fn atan(self) -> Self;
    fn atan2(self, x: Self) -> Self;
    fn acos(self) -> Self;
    fn cbrt(self) -> Self;
    fn abs(self) -> Self;
    fn is_nan(self) -> bool;
    /// Machine epsilon.
    fn eps() -> Self;
}

macro_rules! impl_real {
    ($t:ty) => {
        impl Real for $t {
            #[inline]
            fn c(x: f64) -> Self {
                x as $t
            }
            #[inline]
            fn to_f64(self) -> f64 {
                self as f64
            }
            #[inline]
            fn sqrt(self) -> Self {
                <$t>::sqrt(self)
            }
            #[inline]
            fn sin(self) -> Self {
                <$t>::sin(self)
            }
            #[inline]
            fn cos(self) -> Self {
                <$t>::cos(self)
            }
            #[inline]
            fn atan(self) -> Self {
                <$t>::atan(self)
            }
            #[inline]
            fn atan2(self, x: Self) -> Self {
                <$t>::atan2(self, x)
            }
            #[inline]
            fn acos(self) -> Self {
                <$t>::acos(self)
            }
            #[inline]
            fn cbrt(self) -> Self {
                <$t>::cbrt(self)
            }
            #[inline]
            fn abs(self) -> Self {
                <$t>::abs(self)
            }
            #[inline]
            fn is_nan(self) -> bool {
                <$t>::is_nan(self)
            }
            #[inline]
            fn eps() -> Self {
                <$t>::EPSILON
            }
        }
    };
}
impl_real!(f32);
impl_real!(f64);

#[inline]
fn min<T: Real>(a: T, b: T) -> T {
    if b < a {
        b
    } else {
        a
    }
}
#[inline]
fn max<T: Real>(a: T, b: T) -> T {
    if b > a {
        b
    } else {
        a
    }
}

/// A complex number (only what the solver needs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cx<T> {
    pub re: T,
    pub im: T,
}

impl<T: Real> Cx<T> {
    #[inline]
    pub fn new(re: T, im: T) -> Self {
        Cx { re, im }
    }
    #[inline]
    pub fn real(re: T) -> Self {
        Cx { re, im: T::c(0.0) }
    }
    /// e^{iφ}
    #[inline]
    pub fn unit(phi: T) -> Self {
        Cx::new(phi.cos(), phi.sin())
    }
    #[inline]
    pub fn conj(self) -> Self {
        Cx::new(self.re, -self.im)
    }
    #[inline]
    pub fn norm2(self) -> T {
        self.re * self.re + self.im * self.im
    }
    #[inline]
    pub fn abs(self) -> T {
        self.norm2().sqrt()
    }
    #[inline]
    pub fn arg(self) -> T {
        self.im.atan2(self.re)
    }
    #[inline]
    pub fn scale(self, s: T) -> Self {
        Cx::new(self.re * s, self.im * s)
    }
    /// Principal square root.
    pub fn sqrt(self) -> Self {
        let r = self.abs();
        let re = ((r + self.re) * T::c(0.5)).sqrt();
        let im = ((r - self.re) * T::c(0.5)).sqrt();
        Cx::new(re, if self.im < T::c(0.0) { -im } else { im })
    }
}
impl<T: Real> Add for Cx<T> {
    type Output = Self;
    #[inline]
    fn add(self, o: Self) -> Self {
        Cx::new(self.re + o.re, self.im + o.im)
    }
}
impl<T: Real> Sub for Cx<T> {
    type Output = Self;
    #[inline]
    fn sub(self, o: Self) -> Self {
        Cx::new(self.re - o.re, self.im - o.im)
    }
}
impl<T: Real> Mul for Cx<T> {
    type Output = Self;
    #[inline]
    fn mul(self, o: Self) -> Self {
        Cx::new(
            self.re * o.re - self.im * o.im,
            self.re * o.im + self.im * o.re,
        )
    }
}
impl<T: Real> Div for Cx<T> {
    type Output = Self;
    #[inline]
    fn div(self, o: Self) -> Self {
        let d = o.norm2();
        Cx::new(
            (self.re * o.re + self.im * o.im) / d,
            (self.im * o.re - self.re * o.im) / d,
        )
    }
}
impl<T: Real> Neg for Cx<T> {
    type Output = Self;
    #[inline]
    fn neg(self) -> Self {
        Cx::new(-self.re, -self.im)
    }
}

/// Thresholds of the solver per precision.
struct Tol<T> {
    /// 1 − |c₁|² below this: one Dirac.
    single: T,
    /// 1 − |γ₂|² below this: two Diracs (Toeplitz matrix singular).
    double: T,
    /// Accepted negative weight of a candidate distribution.
    weight: T,
    /// Angular tolerance for atoms at 0 or z_f in the singular case.
    angle: T,
}

impl<T: Real> Tol<T> {
    fn get() -> Tol<T> {
        if T::eps().to_f64() > 1e-10 {
            // f32
            Tol {
                single: T::c(1e-5),
                double: T::c(1e-4),
                weight: T::c(1e-4),
                angle: T::c(1e-5),
            }
        } else {
            Tol {
                single: T::c(2.2e-12),
                double: T::c(2.2e-11),
                weight: T::c(2.2e-8),
                angle: T::c(2.2e-10),
            }
        }
    }
}

/// The TMSM basis b(z) = (sin 2πz, cos 2πz, sin 4πz, cos 4πz) (paper, Equation 1).
pub fn basis(z: f64, out: &mut [f64]) {
    let t = std::f64::consts::TAU * z;
    out[0] = t.sin();
    out[1] = t.cos();
    out[2] = (2.0 * t).sin();
    out[3] = (2.0 * t).cos();
}

/// Sharp lower bound G(b, z_f) of Problem 1 for b_TMSM on the circle [0,1) (shadowed arc
/// [0, z_f)), unbiased, in precision T. NaN in → NaN out; z_f ≤ 0 → 0, z_f ≥ 1 → 1.
/// Derivation: docs/tmsm.md.
pub fn sharp_bound<T: Real>(b: [T; 4], zf: T) -> T {
    solve(b, zf).g
}

/// Which branch of docs/tmsm.md produced the result.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Case {
    /// NaN input or z_f outside (0, 1).
    Trivial,
    /// One Dirac (§2).
    OneDirac,
    /// Two Diracs, singular Toeplitz matrix (§2).
    TwoDiracs,
    /// A distribution on the lit arc exists: G = 0 (§3).
    LitArc,
    /// Canonical representation through z_f (§4.1, case I).
    ThroughZf,
    /// Canonical representation through 0 (§4.1, case II).
    ThroughZero,
    /// Diracs at 0, z_f, centre ± d (§4.3).
    Symmetric,
    /// Diracs at 0, z_f and a root pair of the quartic (§4.4).
    Quartic,
}

/// Result of [`solve`]: G, the branch and a minimising distribution (depth z ∈ [0,1], weight).
/// A Dirac on the lit side of the seam 0 ≡ 1 is reported at z = 1.0; one on the shadowed side at
/// z = 0.0. Empty for [`Case::Trivial`].
#[derive(Clone, Debug, PartialEq)]
pub struct Detail<T> {
    pub g: T,
    pub case: Case,
    pub support: Vec<(T, T)>,
}

/// [`sharp_bound`] with the branch taken and the minimising distribution.
pub fn solve<T: Real>(b: [T; 4], zf: T) -> Detail<T> {
    let zero = T::c(0.0);
    let one = T::c(1.0);
    let trivial = |g: T| Detail {
        g,
        case: Case::Trivial,
        support: Vec::new(),
    };
    if zf.is_nan() || b.iter().any(|v| v.is_nan()) {
        return trivial(T::c(f64::NAN));
    }
    if zf <= zero {
        return trivial(zero);
    }
    if zf >= one {
        return trivial(one);
    }
    let tol = Tol::<T>::get();
    let a = T::c(std::f64::consts::PI) * zf;
    // Moments in the frame rotated by −a: the shadowed arc is (−a, a) (docs/tmsm.md §1).
    let rot = Cx::unit(-a);
    let c1 = Cx::new(b[1], b[0]) * rot;
    let c2 = Cx::new(b[3], b[2]) * rot * rot;
    let m1 = c1.norm2();
    let to_z = |s: T, shadowed_seam: bool| {
        // rotated angle s → depth z ∈ [0,1]; the seam (s = −a) goes to 0 or 1.
        let tau = T::c(std::f64::consts::TAU);
        let mut t = s + a;
        while t < zero {
            t = t + tau;
        }
        while t >= tau {
            t = t - tau;
        }
        let near_seam = t.abs() <= tol.angle || (tau - t).abs() <= tol.angle;
        if near_seam {
            if shadowed_seam {
                zero
            } else {
                one
            }
        } else {
            t / tau
        }
    };
    if one - m1 <= tol.single {
        // One Dirac (docs/tmsm.md §2).
        let s = c1.arg();
        return Detail {
            g: mass_on_arc(&[(s, one)], a, tol.angle),
            case: Case::OneDirac,
            support: vec![(to_z(s, true), one)],
        };
    }
    // Schur parameter γ₂; |γ₂| = 1 ⇔ Toeplitz matrix singular (two Diracs).
    let gamma = (c2 - c1 * c1).scale(one / (one - m1));
    if one - gamma.norm2() <= tol.double {
        // Atoms are the roots of the orthogonal polynomial z² + αz + β (docs/tmsm.md §2).
        let beta = -gamma;
        let alpha = -c1 - beta * c1.conj();
        let (z1, z2) = quadratic_roots(alpha, beta);
        let (z1, z2) = (Cx::unit(z1.arg()), Cx::unit(z2.arg()));
        let w1 = ((c1 - z2) / (z1 - z2)).re;
        let w1 = max(zero, min(one, w1));
        let atoms = [(z1.arg(), w1), (z2.arg(), one - w1)];
        return Detail {
            g: mass_on_arc(&atoms, a, tol.angle),
            case: Case::TwoDiracs,
            support: atoms.iter().map(|&(s, w)| (to_z(s, true), w)).collect(),
        };
    }
    let (g, case, atoms) = pd_bound(c1, c2, a, &tol);
    Detail {
        g,
        case,
        support: atoms.iter().map(|&(s, w)| (to_z(s, false), w)).collect(),
    }
}

/// Mass of a few Diracs (angle in the rotated frame, weight) on the shadowed arc [−a, a):
/// an atom within `tol` of −a (z = 0) is shadowed, within `tol` of a (z = z_f) is lit.
fn mass_on_arc<T: Real>(atoms: &[(T, T)], a: T, tol: T) -> T {
    let mut g = T::c(0.0);
    for &(s, w) in atoms {
        if s >= -a - tol && s < a - tol {
            g = g + w;
        }
    }
    max(T::c(0.0), min(T::c(1.0), g))
}

fn quadratic_roots<T: Real>(p: Cx<T>, q: Cx<T>) -> (Cx<T>, Cx<T>) {
    // z² + p z + q = 0, the numerically stable pair.
    let half = T::c(0.5);
    let d = (p * p).scale(T::c(0.25)) - q;
    let s = d.sqrt();
    let hp = p.scale(half);
    // Choose the sign that avoids cancellation.
    let big = if (hp.re * s.re + hp.im * s.im) >= T::c(0.0) {
        -hp - s
    } else {
        -hp + s
    };
    if big.norm2() == T::c(0.0) {
        return (big, big);
    }
    (big, q / big)
}

/// Positive definite Toeplitz matrix: the candidate enumeration of docs/tmsm.md §3–§4.
fn pd_bound<T: Real>(c1: Cx<T>, c2: Cx<T>, a: T, tol: &Tol<T>) -> (T, Case, Vec<(T, T)>) {
    let zero = T::c(0.0);
    let one = T::c(1.0);
    let half = T::c(0.5);
    let (sa, ca) = (a.sin(), a.cos());
    // h(s) = cos s − cos a ≥ 0 exactly on the shadowed arc; H0 = E[h], H1 = E[h e^{is}].
    let h0 = c1.re - ca;
    let h1 = (c2 + Cx::real(one)).scale(half) - c1.scale(ca);
    // The localizing matrix of the lit arc is PSD: a distribution on the lit arc exists and
    // G = 0; the canonical representation through z_f or 0 is one (docs/tmsm.md §3).
    let lit_arc = -h0 >= h1.abs();
    let ea = Cx::unit(a);
    let ema = ea.conj();
    let mut best = one;
    let mut case = Case::LitArc;
    let mut support: Vec<(T, T)> = Vec::new();
    // (I), (II): canonical representations through z_f (s = a) and through 0 (s = −a).
    for (zeta, this) in [(ea, Case::ThroughZf), (ema, Case::ThroughZero)] {
        if let Some((z2, z3)) = canonical(c1, c2, zeta) {
            let w = weights3([zeta, z2, z3], c1, c2);
            let mut g = zero;
            for (z, wi) in [(z2, w[1]), (z3, w[2])] {
                if z.arg().abs() < a {
                    g = g + wi;
                }
            }
            if w.iter().all(|&wi| wi >= -tol.weight) && g < best {
                best = g;
                case = this;
                support = vec![(zeta.arg(), w[0]), (z2.arg(), w[1]), (z3.arg(), w[2])];
            }
        }
    }
    // (III-s): Diracs at ±a and ±d, cos d = Re H1 / H0 (docs/tmsm.md §4.3).
    if h0 > zero {
        let cd = h1.re / h0;
        if cd > ca && cd <= one {
            let d = cd.acos();
            let nodes = [ea, ema, Cx::unit(d), Cx::unit(-d)];
            let w = weights4(nodes, c1, c2);
            let g = h0 * h0 / (h1.re - h0 * ca);
            if w.iter().all(|&wi| wi >= -tol.weight) && g < best {
                best = g;
                case = Case::Symmetric;
                support = vec![(a, w[0]), (-a, w[1]), (d, w[2]), (-d, w[3])];
            }
        }
    }
    // (III-q): Diracs at ±a, x ∈ (−a, a), y outside; τ = tan(x/2) = k σ solves the quartic of
    // docs/tmsm.md §4.4.
    let (p, q) = (h1.re, h1.im);
    let (am, bm) = (one - ca, one + ca);
    let k = sa / bm; // tan(a/2)
    let coef = [
        q * am,
        T::c(2.0) * (h0 - p * (one + am)) * k,
        T::c(-6.0) * q * k * k,
        T::c(2.0) * (h0 + p * (one + bm)) * k * k * k,
        q * bm * k * k * k * k,
    ];
    let mut roots = [zero; 4];
    let nr = roots_in_interval(coef, -one, one, &mut roots);
    for &sigma in &roots[..nr] {
        if sigma.abs() >= one {
            continue;
        }
        let x = T::c(2.0) * (k * sigma).atan();
        let u = (x.cos() - ca).atan2(x.sin());
        let zy = Cx::unit(x - T::c(2.0) * u);
        if zy.arg().abs() <= a {
            continue;
        }
        let zx = Cx::unit(x);
        let w = weights4([ea, ema, zx, zy], c1, c2);
        if w.iter().all(|&wi| wi >= -tol.weight) && w[2] < best {
            best = w[2];
            case = Case::Quartic;
            support = vec![(a, w[0]), (-a, w[1]), (x, w[2]), (zy.arg(), w[3])];
        }
    }
    if lit_arc {
        return (zero, Case::LitArc, support);
    }
    (max(zero, min(one, best)), case, support)
}

/// The other two atoms of the canonical 3-Dirac representation through ζ: P(z) = (z−ζ)(z²+αz+β)
/// with E[z^{−1}P] = E[z^{−2}P] = 0 (docs/tmsm.md §4.1).
fn canonical<T: Real>(c1: Cx<T>, c2: Cx<T>, zeta: Cx<T>) -> Option<(Cx<T>, Cx<T>)> {
    let one = Cx::real(T::c(1.0));
    let a11 = c1 - zeta;
    let a12 = one - zeta * c1.conj();
    let a21 = a12;
    let a22 = c1.conj() - zeta * c2.conj();
    let r1 = zeta * c1 - c2;
    let r2 = zeta - c1;
    let det = a11 * a22 - a12 * a21;
    if det.norm2() == T::c(0.0) || det.re.is_nan() {
        return None;
    }
    let alpha = (r1 * a22 - a12 * r2) / det;
    let beta = (a11 * r2 - a21 * r1) / det;
    let (z2, z3) = quadratic_roots(alpha, beta);
    if z2.norm2() == T::c(0.0) || z3.norm2() == T::c(0.0) {
        return None;
    }
    Some((Cx::unit(z2.arg()), Cx::unit(z3.arg())))
}

/// Weights of a distribution on three points of the unit circle from c₁, c₂ (Lagrange basis).
fn weights3<T: Real>(z: [Cx<T>; 3], c1: Cx<T>, c2: Cx<T>) -> [T; 3] {
    let one = Cx::real(T::c(1.0));
    let mut w = [T::c(0.0); 3];
    for i in 0..3 {
        let (j, k) = ((i + 1) % 3, (i + 2) % 3);
        let e1 = -(z[j] + z[k]);
        let e0 = z[j] * z[k];
        let num = c2 + e1 * c1 + e0 * one;
        let den = (z[i] - z[j]) * (z[i] - z[k]);
        w[i] = (num / den).re;
    }
    w
}

/// Weights of a distribution on four points of the unit circle from c₋₁, c₀, c₁, c₂ (Lagrange
/// basis in span{z⁻¹, 1, z, z²}); valid when the moments are consistent with these points.
fn weights4<T: Real>(z: [Cx<T>; 4], c1: Cx<T>, c2: Cx<T>) -> [T; 4] {
    let mut w = [T::c(0.0); 4];
    for i in 0..4 {
        let o: Vec<usize> = (0..4).filter(|&j| j != i).collect();
        let (p, q, r) = (z[o[0]], z[o[1]], z[o[2]]);
        let e2 = -(p + q + r);
        let e1 = p * q + p * r + q * r;
        let e0 = -(p * q * r);
        let num = c2 + e2 * c1 + e1 + e0 * c1.conj();
        let den = z[i].conj() * (z[i] - p) * (z[i] - q) * (z[i] - r);
        w[i] = (num / den).re;
    }
    w
}

/// Real roots in [lo, hi] of Σ coef[j] σ^j (degree ≤ 4) by derivative isolation: the roots of
/// the derivative split [lo, hi] into monotone pieces, each sign change is bracketed and
/// bisected (Newton-accelerated). Unlike Ferrari this never loses a root in the interval when
/// the quartic also has a root near infinity (the f32 failure mode), at the price of iterations.
pub fn roots_in_interval<T: Real>(coef: [T; 5], lo: T, hi: T, out: &mut [T; 4]) -> usize {
    let zero = T::c(0.0);
    let scale = coef.iter().fold(zero, |m, c| max(m, c.abs()));
    if scale == zero || scale.is_nan() {
        return 0;
    }
    let mut c = [zero; 5];
    for j in 0..5 {
        c[j] = coef[j] / scale;
    }
    let mut deg = 4;
    while deg > 0 && c[deg] == zero {
        deg -= 1;
    }
    isolate(&c, deg, lo, hi, out)
}

fn horner<T: Real>(c: &[T; 5], deg: usize, x: T) -> (T, T) {
    let (mut p, mut dp) = (T::c(0.0), T::c(0.0));
    for j in (0..=deg).rev() {
        dp = dp * x + p;
        p = p * x + c[j];
    }
    (p, dp)
}

fn isolate<T: Real>(c: &[T; 5], deg: usize, lo: T, hi: T, out: &mut [T; 4]) -> usize {
    let zero = T::c(0.0);
    match deg {
        0 => 0,
        1 => {
            let r = -c[0] / c[1];
            if r >= lo && r <= hi {
                out[0] = r;
                1
            } else {
                0
            }
        }
        _ => {
            // Critical points from the derivative.
            let mut d = [zero; 5];
            for j in 1..=deg {
                d[j - 1] = c[j] * T::c(j as f64);
            }
            let mut crit = [zero; 4];
            let nc = isolate(&d, deg - 1, lo, hi, &mut crit);
            crit[..nc].sort_by(|a, b| a.partial_cmp(b).unwrap_or(std::cmp::Ordering::Equal));
            let mut pts = [lo; 6];
            pts[1..1 + nc].copy_from_slice(&crit[..nc]);
            pts[1 + nc] = hi;
            let np = nc + 2;
            let mut n = 0;
            let iters = if T::eps().to_f64() > 1e-10 { 30 } else { 60 };
            for w in 0..np - 1 {
                let (mut a, mut b) = (pts[w], pts[w + 1]);
                let (pa, _) = horner(c, deg, a);
                let (pb, _) = horner(c, deg, b);
                if pa == zero && w == 0 {
                    if n < 4 {
                        out[n] = a;
                        n += 1;
                    }
                    continue;
                }
                if (pa < zero) == (pb < zero) || pb == zero {
                    // No sign change; a touching (double) root at a critical point shows up
                    // as |p| tiny there.
                    let touching =
                        pb == zero || (w + 1 < np - 1 && pb.abs() <= T::c(64.0) * T::eps());
                    if touching && n < 4 {
                        out[n] = b;
                        n += 1;
                    }
                    continue;
                }
                let neg_at_a = pa < zero;
                let mut x = (a + b) * T::c(0.5);
                for _ in 0..iters {
                    let (px, dpx) = horner(c, deg, x);
                    if px == zero {
                        break;
                    }
                    if (px < zero) == neg_at_a {
                        a = x;
                    } else {
                        b = x;
                    }
                    // Newton step if it stays inside the bracket, else bisection.
                    let nx = if dpx != zero { x - px / dpx } else { a };
                    x = if nx > a && nx < b {
                        nx
                    } else {
                        (a + b) * T::c(0.5)
                    };
                    if b - a <= T::eps() * T::c(4.0) * max(a.abs(), b.abs()) {
                        break;
                    }
                }
                if n < 4 {
                    out[n] = x;
                    n += 1;
                }
            }
            n
        }
    }
}
