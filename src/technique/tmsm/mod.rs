//! Trigonometric moment shadow mapping (TMSM), Peters & Klein 2015, Section 4: Problem 1 with
//! b(z) = (sin 2πz, cos 2πz, sin 4πz, cos 4πz) on the circle I = [0,1) (0 ≡ 1), solved in closed
//! form. The derivation (dual certificate, case analysis, the quartic) is in `docs/tmsm.md`;
//! the comments below refer to its sections.
//!
//! With t = 2πz, c_k = E[e^{ikt}] (c₁ = b₂ + i·b₁, c₂ = b₄ + i·b₃) and the shadowed arc
//! A = [0, 2πz_f), rotated by a = πz_f so that A = (−a, a):
//! * Toeplitz matrix singular (≤ 2 Diracs): the distribution is unique, G = its mass on A.
//! * `E[h] ≤ −|E[h e^{is}]|` with h(s) = cos s − cos a: a distribution on the lit arc exists, G = 0
//!   (checked first: the G-only path returns here without building any candidate).
//! * otherwise G = the minimum over the primal-feasible candidates (docs/tmsm.md §4):
//!   (I)/(II) the canonical 3-Dirac representations through z_f and through 0 (a quadratic);
//!   (III-s) Diracs at 0, z_f and symmetric ±d (closed form);
//!   (III-q) Diracs at 0, z_f, x ∈ A, y ∉ A with x from a quartic in tan(x/2).
//!   The G-only path ([`sharp_bound`]) stops at the first of (III-s), (I), (II) whose optimality
//!   a dual polynomial certifies and solves the quartic only when none is (`certified`,
//!   docs/tmsm.md §4.6); [`solve`] enumerates every candidate.
//!
//! Points of the circle are kept as unit complex numbers (one sin/cos pair per evaluation for
//! e^{ia}; a point is in A ⇔ its real part exceeds cos a), angles are formed only for the
//! reported support. [`sharp_bound`] allocates nothing.

use super::linalg::{bias, Real};
use super::{ClosedForm, Technique};
use std::ops::{Add, Div, Mul, Neg, Sub};

mod certified;
use certified::Verdict;
pub(crate) mod roots;
pub use roots::roots_in_interval;

#[inline(always)]
fn min<T: Real>(a: T, b: T) -> T {
    if b < a {
        b
    } else {
        a
    }
}
#[inline(always)]
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
    /// Real part.
    pub re: T,
    /// Imaginary part.
    pub im: T,
}

impl<T: Real> Cx<T> {
    /// re + i·im
    #[inline(always)]
    pub fn new(re: T, im: T) -> Self {
        Cx { re, im }
    }
    /// The real number re.
    #[inline(always)]
    pub fn real(re: T) -> Self {
        Cx { re, im: T::ZERO }
    }
    /// e^{iφ}
    #[inline]
    pub fn unit(phi: T) -> Self {
        Cx::new(phi.cos(), phi.sin())
    }
    /// Complex conjugate re − i·im.
    #[inline(always)]
    pub fn conj(self) -> Self {
        Cx::new(self.re, -self.im)
    }
    /// |z|² = re² + im²
    #[inline(always)]
    pub fn norm2(self) -> T {
        self.re * self.re + self.im * self.im
    }
    /// |z|
    #[inline(always)]
    pub fn abs(self) -> T {
        self.norm2().sqrt()
    }
    /// arg z = atan2(im, re) ∈ (−π, π].
    #[inline]
    pub fn arg(self) -> T {
        self.im.atan2(self.re)
    }
    /// s·z for real s.
    #[inline(always)]
    pub fn scale(self, s: T) -> Self {
        Cx::new(self.re * s, self.im * s)
    }
    /// z/|z| (the point of the unit circle with the same argument); 1 for z = 0 (arg 0 = 0).
    #[inline(always)]
    pub fn normalized(self) -> Self {
        let r = self.abs();
        if r > T::ZERO {
            self.scale(T::ONE / r)
        } else {
            Cx::real(T::ONE)
        }
    }
    /// Principal square root.
    #[inline]
    pub fn sqrt(self) -> Self {
        let r = self.abs();
        let re = ((r + self.re) * T::of(0.5)).sqrt();
        let im = ((r - self.re) * T::of(0.5)).sqrt();
        Cx::new(re, if self.im < T::ZERO { -im } else { im })
    }
}
impl<T: Real> Add for Cx<T> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        Cx::new(self.re + o.re, self.im + o.im)
    }
}
impl<T: Real> Sub for Cx<T> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        Cx::new(self.re - o.re, self.im - o.im)
    }
}
impl<T: Real> Mul for Cx<T> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        Cx::new(
            self.re * o.re - self.im * o.im,
            self.re * o.im + self.im * o.re,
        )
    }
}
impl<T: Real> Div for Cx<T> {
    type Output = Self;
    #[inline(always)]
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
    #[inline(always)]
    fn neg(self) -> Self {
        Cx::new(-self.re, -self.im)
    }
}

/// Thresholds of the solver per precision.
pub(crate) struct Tol<T> {
    /// 1 − |c₁|² below this: one Dirac.
    pub(crate) single: T,
    /// 1 − |γ₂|² below this: two Diracs (Toeplitz matrix singular).
    pub(crate) double: T,
    /// Accepted negative weight of a candidate distribution.
    pub(crate) weight: T,
    /// Angular tolerance for atoms at 0 or z_f in the singular case.
    pub(crate) angle: T,
    /// The certified fast path (§4.6) is used only when every weight of its candidate is at
    /// least this and D₂ = (1 − |c₁|²)(1 − |γ₂|²) is at least `certify_det`; closer to the
    /// boundary of the moment space the full enumeration decides (in f64 it reproduces the
    /// previous implementation, which accepts weights down to −`weight`, to 1e-9). In f32
    /// (judged against the f64 bound) (III-s) is accepted down to −`weight` like every
    /// candidate of the enumeration, and canonical weights are not guarded.
    pub(crate) certify_weight: T,
    pub(crate) certify_det: T,
    /// (III-s) with its least weight in [`uncertain_below`, `certify_weight`): undecided, the
    /// full enumeration decides; below: infeasible.
    pub(crate) uncertain_below: T,
}

impl<T: Real> Tol<T> {
    #[inline(always)]
    pub(crate) fn get() -> Tol<T> {
        if is_single::<T>() {
            Tol {
                single: T::of(1e-5),
                double: T::of(1e-4),
                weight: T::of(1e-4),
                angle: T::of(1e-5),
                certify_weight: T::of(-1e-4),
                certify_det: T::ZERO,
                uncertain_below: T::of(-1e-4),
            }
        } else {
            Tol {
                single: T::of(2.2e-12),
                double: T::of(2.2e-11),
                weight: T::of(2.2e-8),
                angle: T::of(2.2e-10),
                certify_weight: T::of(1e-6),
                certify_det: T::of(1e-6),
                uncertain_below: T::of(-4.4e-8),
            }
        }
    }
}

#[inline(always)]
fn is_single<T: Real>() -> bool {
    T::EPS.to_f64() > 1e-10
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
/// Derivation: docs/tmsm.md. No heap allocation; the minimiser is not built.
pub fn sharp_bound<T: Real>(b: [T; 4], zf: T) -> T {
    evaluate::<T, false>(b, zf).g
}

/// [`sharp_bound`] and the branch that decided it on that (G-only) path.
pub fn sharp_bound_case<T: Real>(b: [T; 4], zf: T) -> (T, Case) {
    let out = evaluate::<T, false>(b, zf);
    (out.g, out.case)
}

/// [`sharp_bound_case`] and how the G-only path got there.
#[cfg(test)]
pub(crate) fn sharp_bound_route<T: Real>(b: [T; 4], zf: T) -> (T, Case, Route) {
    let out = evaluate::<T, false>(b, zf);
    (out.g, out.case, out.route)
}

/// How the G-only path of a positive definite Toeplitz matrix found G.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Route {
    /// Before the candidates: trivial, one or two Diracs, the lit arc.
    Direct,
    /// A certificate of (III-s), (I) or (II) (docs/tmsm.md §4.6).
    Certified,
    /// (III-q) from the Newton solve in the bracket of the canonical nodes.
    Bracketed,
    /// (III-q) from every root of the quartic in (−1, 1).
    Isolated,
    /// The full enumeration of docs/tmsm.md §4.
    Enumerated,
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
    /// The lower bound G.
    pub g: T,
    /// The branch of the solver that produced G.
    pub case: Case,
    /// Minimising distribution: (depth z ∈ [0,1], weight) per Dirac.
    pub support: Vec<(T, T)>,
}

/// [`sharp_bound`] with the branch taken and the minimising distribution.
pub fn solve<T: Real>(b: [T; 4], zf: T) -> Detail<T> {
    let out = evaluate::<T, true>(b, zf);
    let tol = Tol::<T>::get();
    let tau = T::of(std::f64::consts::TAU);
    let a = out.a;
    let shadowed_seam = matches!(out.case, Case::OneDirac | Case::TwoDiracs);
    // rotated point e^{is} → depth z ∈ [0,1]; the seam (s = −a) goes to 0 or 1.
    let to_z = |p: Cx<T>| {
        let mut t = p.arg() + a;
        while t < T::ZERO {
            t += tau;
        }
        while t >= tau {
            t -= tau;
        }
        let near_seam = t.abs() <= tol.angle || (tau - t).abs() <= tol.angle;
        match (near_seam, shadowed_seam) {
            (true, true) => T::ZERO,
            (true, false) => T::ONE,
            _ => t / tau,
        }
    };
    Detail {
        g: out.g,
        case: out.case,
        support: out.atoms[..out.n]
            .iter()
            .map(|&(p, w)| (to_z(p), w))
            .collect(),
    }
}

/// What [`evaluate`] found: G, the branch, and (when asked for) the minimiser as unit complex
/// numbers in the frame rotated by −a with their weights.
struct Outcome<T> {
    g: T,
    case: Case,
    route: Route,
    a: T,
    atoms: [(Cx<T>, T); 4],
    n: usize,
}

impl<T: Real> Outcome<T> {
    #[inline(always)]
    fn bare(g: T, case: Case, a: T) -> Self {
        Outcome {
            g,
            case,
            route: Route::Direct,
            a,
            atoms: [(Cx::real(T::ZERO), T::ZERO); 4],
            n: 0,
        }
    }
    #[inline(always)]
    fn set(&mut self, g: T, case: Case, atoms: &[(Cx<T>, T)]) {
        self.g = g;
        self.case = case;
        self.atoms[..atoms.len()].copy_from_slice(atoms);
        self.n = atoms.len();
    }
}

/// The solver; with `SUPPORT = false` only G is meaningful (no minimiser is kept, the lit-arc
/// branch returns at once).
#[inline(always)]
fn evaluate<T: Real, const SUPPORT: bool>(b: [T; 4], zf: T) -> Outcome<T> {
    let zero = T::ZERO;
    let one = T::ONE;
    if zf.is_nan() || b.iter().any(|v| v.is_nan()) {
        return Outcome::bare(T::of(f64::NAN), Case::Trivial, zero);
    }
    if zf <= zero {
        return Outcome::bare(zero, Case::Trivial, zero);
    }
    if zf >= one {
        return Outcome::bare(one, Case::Trivial, zero);
    }
    let tol = Tol::<T>::get();
    let a = T::of(std::f64::consts::PI) * zf;
    // e^{ia}: the only trigonometry of the PD path.
    let ea = Cx::new(a.cos(), a.sin());
    // Moments in the frame rotated by −a: the shadowed arc is (−a, a) (docs/tmsm.md §1).
    let rot = ea.conj();
    let c1 = Cx::new(b[1], b[0]) * rot;
    let c2 = Cx::new(b[3], b[2]) * rot * rot;
    let m1 = c1.norm2();
    if one - m1 <= tol.single {
        // One Dirac (docs/tmsm.md §2).
        let g = mass_on_arc(&[(c1.normalized(), one)], ea.re, tol.angle);
        let mut out = Outcome::bare(g, Case::OneDirac, a);
        if SUPPORT {
            out.set(g, Case::OneDirac, &[(c1.normalized(), one)]);
        }
        return out;
    }
    // Schur parameter γ₂; |γ₂| = 1 ⇔ Toeplitz matrix singular (two Diracs).
    let gamma = (c2 - c1 * c1).scale(one / (one - m1));
    if one - gamma.norm2() <= tol.double {
        // Atoms are the roots of the orthogonal polynomial z² + αz + β (docs/tmsm.md §2).
        let beta = -gamma;
        let alpha = -c1 - beta * c1.conj();
        let (z1, z2) = quadratic_roots(alpha, beta);
        let (z1, z2) = (z1.normalized(), z2.normalized());
        let w1 = ((c1 - z2) / (z1 - z2)).re;
        let w1 = max(zero, min(one, w1));
        let g = mass_on_arc(&[(z1, w1), (z2, one - w1)], ea.re, tol.angle);
        let mut out = Outcome::bare(g, Case::TwoDiracs, a);
        if SUPPORT {
            out.set(g, Case::TwoDiracs, &[(z1, w1), (z2, one - w1)]);
        }
        return out;
    }
    pd_bound::<T, SUPPORT>(c1, c2, ea, a, &tol)
}

/// Mass of a few Diracs (unit points in the rotated frame, weight) on the shadowed arc
/// [−a, a): an atom within `tol` (radians) of −a (z = 0) is shadowed, within `tol` of a
/// (z = z_f) is lit. Turning the points by +tol (factor 1 + i·tol, unit to rounding) makes that
/// "Re > cos a".
#[inline(always)]
fn mass_on_arc<T: Real>(atoms: &[(Cx<T>, T)], ca: T, tol: T) -> T {
    let turn = Cx::new(T::ONE, tol);
    let mut g = T::ZERO;
    for &(z, w) in atoms {
        if (z * turn).re > ca {
            g += w;
        }
    }
    max(T::ZERO, min(T::ONE, g))
}

#[inline(always)]
fn quadratic_roots<T: Real>(p: Cx<T>, q: Cx<T>) -> (Cx<T>, Cx<T>) {
    // z² + p z + q = 0, the numerically stable pair.
    let half = T::of(0.5);
    let d = (p * p).scale(T::of(0.25)) - q;
    let s = d.sqrt();
    let hp = p.scale(half);
    // Choose the sign that avoids cancellation.
    let big = if (hp.re * s.re + hp.im * s.im) >= T::ZERO {
        -hp - s
    } else {
        -hp + s
    };
    if big.norm2() == T::ZERO {
        return (big, big);
    }
    (big, q / big)
}

/// Positive definite Toeplitz matrix: the candidate enumeration of docs/tmsm.md §3–§4, with
/// ea = e^{ia}. A unit point z lies in the open shadowed arc ⇔ Re z > cos a.
#[inline(always)]
fn pd_bound<T: Real, const SUPPORT: bool>(
    c1: Cx<T>,
    c2: Cx<T>,
    ea: Cx<T>,
    a: T,
    tol: &Tol<T>,
) -> Outcome<T> {
    let zero = T::ZERO;
    let one = T::ONE;
    let half = T::of(0.5);
    let ca = ea.re;
    // h(s) = cos s − cos a ≥ 0 exactly on the shadowed arc; H0 = E[h], H1 = E[h e^{is}].
    let h0 = c1.re - ca;
    let h1 = (c2 + Cx::real(one)).scale(half) - c1.scale(ca);
    // The localizing matrix of the lit arc is PSD: a distribution on the lit arc exists and
    // G = 0; the canonical representation through z_f or 0 is one (docs/tmsm.md §3).
    let lit_arc = -h0 >= h1.abs();
    let mut out = Outcome::bare(one, Case::LitArc, a);
    if lit_arc && !SUPPORT {
        out.g = zero;
        return out;
    }
    // G only: a candidate certified optimal by its dual polynomial ends the search (§4.6).
    if !SUPPORT {
        match certified::bound(c1, c2, ea, h0, h1, tol) {
            Verdict::Optimal(g, case) => {
                out.g = max(zero, min(one, g));
                out.case = case;
                out.route = Route::Certified;
                return out;
            }
            Verdict::Quartic(hint, n) => {
                if quartic_bracketed(c1, c2, ea, h0, h1, tol, &hint[..n], &mut out) {
                    out.g = max(zero, min(one, out.g));
                    out.route = Route::Bracketed;
                    return out;
                }
                quartic_candidates(c1, c2, ea, h0, h1, tol, &mut out);
                if out.case == Case::Quartic {
                    out.g = max(zero, min(one, out.g));
                    out.route = Route::Isolated;
                    return out;
                }
            }
            Verdict::Unknown => {}
        }
    }
    out.route = Route::Enumerated;
    let ema = ea.conj();
    let ok = |w: &[T]| w.iter().all(|&wi| wi >= -tol.weight);
    // (I), (II): canonical representations through z_f (s = a) and through 0 (s = −a).
    for (zeta, this) in [(ea, Case::ThroughZf), (ema, Case::ThroughZero)] {
        if let Some((z2, z3)) = canonical(c1, c2, zeta) {
            let w = weights3([zeta, z2, z3], c1, c2);
            let mut g = zero;
            for (z, wi) in [(z2, w[1]), (z3, w[2])] {
                if z.re > ca {
                    g += wi;
                }
            }
            if ok(&w) && g < out.g {
                out.set(g, this, &[(zeta, w[0]), (z2, w[1]), (z3, w[2])]);
            }
        }
    }
    // (III-s): Diracs at ±a and ±d, cos d = Re H1 / H0 (docs/tmsm.md §4.3).
    if h0 > zero {
        let cd = h1.re / h0;
        if cd > ca && cd <= one {
            let g = h0 * h0 / (h1.re - h0 * ca);
            let ed = Cx::new(cd, max(zero, one - cd * cd).sqrt());
            // The weights (feasibility) only matter if the candidate improves G.
            if g < out.g {
                let w = weights4([ea, ema, ed, ed.conj()], c1, c2);
                if ok(&w) {
                    out.set(
                        g,
                        Case::Symmetric,
                        &[(ea, w[0]), (ema, w[1]), (ed, w[2]), (ed.conj(), w[3])],
                    );
                }
            }
        }
    }
    // (III-q) can only lower G below the current best; a best of 0 is final (G is clamped).
    if SUPPORT || out.g > zero {
        quartic_candidates(c1, c2, ea, h0, h1, tol, &mut out);
    }
    if lit_arc {
        out.g = zero;
        out.case = Case::LitArc;
        return out;
    }
    out.g = max(zero, min(one, out.g));
    out
}

/// The quartic of docs/tmsm.md §4.4 in σ = tan(x/2)/tan(a/2) ∈ (−1, 1), and tan(a/2).
#[inline(always)]
fn quartic_coef<T: Real>(ea: Cx<T>, h0: T, h1: Cx<T>) -> ([T; 5], T) {
    let one = T::ONE;
    let two = T::of(2.0);
    let (ca, sa) = (ea.re, ea.im);
    let (p, q) = (h1.re, h1.im);
    let (am, bm) = (one - ca, one + ca);
    let k = sa / bm; // tan(a/2)
    let coef = [
        q * am,
        two * (h0 - p * (one + am)) * k,
        T::of(-6.0) * q * k * k,
        two * (h0 + p * (one + bm)) * k * k * k,
        q * bm * k * k * k * k,
    ];
    (coef, k)
}

/// The (III-q) candidate of a root σ: Diracs at ±a, x ∈ (−a, a), y outside, with
/// τ = tan(x/2) = k σ, e^{ix} = (1 − τ² + 2iτ)/(1 + τ²), e^{iu} ∝ sin x + i(cos x − cos a),
/// e^{iy} = e^{ix}·e^{−2iu}. Kept in `out` if y is lit, its weights are ≥ −tol and its G
/// (the weight at x) is below `out.g`; true if kept.
#[inline(always)]
fn quartic_candidate<T: Real>(
    sigma: T,
    k: T,
    c1: Cx<T>,
    c2: Cx<T>,
    ea: Cx<T>,
    tol: &Tol<T>,
    out: &mut Outcome<T>,
) -> bool {
    let one = T::ONE;
    let two = T::of(2.0);
    if sigma.abs() >= one {
        return false;
    }
    let ca = ea.re;
    let tau = k * sigma;
    let t2 = tau * tau;
    let inv = one / (one + t2);
    let zx = Cx::new((one - t2) * inv, two * tau * inv);
    let eu = Cx::new(zx.im, zx.re - ca).normalized().conj();
    let zy = zx * eu * eu;
    if zy.re >= ca {
        return false;
    }
    let ema = ea.conj();
    let nodes = [ea, ema, zx, zy];
    // G of this candidate is the weight at x; the other weights only if it improves G.
    if out.g < one
        && weight4(&nodes, 2, c1, c2).partial_cmp(&out.g) != Some(std::cmp::Ordering::Less)
    {
        return false;
    }
    let w = weights4(nodes, c1, c2);
    if w.iter().all(|&wi| wi >= -tol.weight) && w[2] < out.g {
        out.set(
            w[2],
            Case::Quartic,
            &[(ea, w[0]), (ema, w[1]), (zx, w[2]), (zy, w[3])],
        );
        return true;
    }
    false
}

/// (III-q): every real root of the quartic in (−1, 1) is a candidate.
#[inline(always)]
fn quartic_candidates<T: Real>(
    c1: Cx<T>,
    c2: Cx<T>,
    ea: Cx<T>,
    h0: T,
    h1: Cx<T>,
    tol: &Tol<T>,
    out: &mut Outcome<T>,
) {
    let (coef, k) = quartic_coef(ea, h0, h1);
    let mut roots = [T::ZERO; 4];
    let nr = roots_in_interval(coef, -T::ONE, T::ONE, &mut roots);
    for &sigma in &roots[..nr] {
        quartic_candidate(sigma, k, c1, c2, ea, tol, out);
    }
}

/// (III-q) when every other structure is ruled out (certified path, §4.6): the quartic's root
/// between the nodes in A of the canonical representations (`hint`), if the quartic changes
/// sign there, by one safeguarded Newton solve. Every root with y lit gives a feasible dual
/// polynomial p_y (§4.4), so a root whose weights are ≥ 0 is optimal. False (nothing kept) if
/// the bracket has no sign change or its candidate is not feasible: the caller then isolates
/// every root.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn quartic_bracketed<T: Real>(
    c1: Cx<T>,
    c2: Cx<T>,
    ea: Cx<T>,
    h0: T,
    h1: Cx<T>,
    tol: &Tol<T>,
    hint: &[Cx<T>],
    out: &mut Outcome<T>,
) -> bool {
    let one = T::ONE;
    let (coef, k) = quartic_coef(ea, h0, h1);
    let (mut lo, mut hi) = (one, -one);
    for z in hint {
        // σ = tan(x/2)/k with tan(x/2) = Im z/(1 + Re z).
        let s = z.im / ((one + z.re) * k);
        lo = min(lo, s);
        hi = max(hi, s);
    }
    let (lo, hi) = (max(lo, -one), min(hi, one));
    if lo.is_nan() || hi.is_nan() || lo >= hi {
        return false;
    }
    let (plo, phi) = (roots::eval(&coef, lo), roots::eval(&coef, hi));
    if plo == T::ZERO || phi == T::ZERO || (plo < T::ZERO) == (phi < T::ZERO) {
        return false;
    }
    let sigma = roots::newton_in_bracket(&coef, 4, lo, hi, plo, phi);
    quartic_candidate(sigma, k, c1, c2, ea, tol, out)
}

/// The other two atoms of the canonical 3-Dirac representation through ζ: P(z) = (z−ζ)(z²+αz+β)
/// with E[z^{−1}P] = E[z^{−2}P] = 0 (docs/tmsm.md §4.1), projected onto the unit circle.
#[inline(always)]
fn canonical<T: Real>(c1: Cx<T>, c2: Cx<T>, zeta: Cx<T>) -> Option<(Cx<T>, Cx<T>)> {
    let one = Cx::real(T::ONE);
    let a11 = c1 - zeta;
    let a12 = one - zeta * c1.conj();
    let a21 = a12;
    let a22 = c1.conj() - zeta * c2.conj();
    let r1 = zeta * c1 - c2;
    let r2 = zeta - c1;
    let det = a11 * a22 - a12 * a21;
    if det.norm2() == T::ZERO || det.re.is_nan() {
        return None;
    }
    let alpha = (r1 * a22 - a12 * r2) / det;
    let beta = (a11 * r2 - a21 * r1) / det;
    let (z2, z3) = quadratic_roots(alpha, beta);
    if z2.norm2() == T::ZERO || z3.norm2() == T::ZERO {
        return None;
    }
    Some((z2.normalized(), z3.normalized()))
}

/// Weights of a distribution on three points of the unit circle from c₁, c₂ (Lagrange basis).
#[inline(always)]
fn weights3<T: Real>(z: [Cx<T>; 3], c1: Cx<T>, c2: Cx<T>) -> [T; 3] {
    let one = Cx::real(T::ONE);
    let mut w = [T::ZERO; 3];
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
#[inline(always)]
fn weights4<T: Real>(z: [Cx<T>; 4], c1: Cx<T>, c2: Cx<T>) -> [T; 4] {
    [0, 1, 2, 3].map(|i| weight4(&z, i, c1, c2))
}

/// The weight of node i in [`weights4`]: Re[(c₂ + e₂c₁ + e₁ + e₀c̄₁) / (z̄_i Π_{j≠i}(z_i − z_j))]
/// with e_k the coefficients of Π_{j≠i}(z − z_j).
#[inline(always)]
fn weight4<T: Real>(z: &[Cx<T>; 4], i: usize, c1: Cx<T>, c2: Cx<T>) -> T {
    const OTHERS: [[usize; 3]; 4] = [[1, 2, 3], [0, 2, 3], [0, 1, 3], [0, 1, 2]];
    let [p, q, r] = OTHERS[i].map(|j| z[j]);
    let e2 = -(p + q + r);
    let e1 = p * q + p * r + q * r;
    let e0 = -(p * q * r);
    let num = c2 + e2 * c1 + e1 + e0 * c1.conj();
    let den = z[i].conj() * (z[i] - p) * (z[i] - q) * (z[i] - r);
    (num / den).re
}

/// TMSM as a [`Technique`]: biased moments b' = (1 − α)·b + α·b*, by default b* = 0 (the
/// moments of the uniform distribution on the circle, the centre of the moment space), then
/// [`sharp_bound`] in f64, or both in f32.
#[derive(Clone, Debug, PartialEq)]
pub struct Tmsm {
    /// Bias weight α.
    pub alpha: f64,
    /// Bias target b* (default 0).
    pub b_star: [f64; 4],
    /// Evaluate in f32 (the GPU path) instead of f64.
    pub single: bool,
}

impl Tmsm {
    /// Default bias for f64/f32 evaluation of 32-bit moments.
    pub const DEFAULT_ALPHA: f64 = 1e-6;

    /// Default bias for moments stored with 16 bits: the smallest of 1e-5, 3e-5, 1e-4, 1e-3 with
    /// no G above the sharp bound in `momentlab stability` (docs/stability.md).
    pub const ALPHA_16BIT: f64 = 3e-5;

    /// TMSM with bias α toward b* = 0, evaluated in f32 if `single`.
    pub fn new(alpha: f64, single: bool) -> Tmsm {
        Tmsm {
            alpha,
            b_star: [0.0; 4],
            single,
        }
    }

    fn biased(&self, m: &[f64]) -> [f64; 4] {
        let (a, s) = (self.alpha, 1.0 - self.alpha);
        let bs = &self.b_star;
        [
            s * m[0] + a * bs[0],
            s * m[1] + a * bs[1],
            s * m[2] + a * bs[2],
            s * m[3] + a * bs[3],
        ]
    }
}

impl Default for Tmsm {
    fn default() -> Self {
        Tmsm::new(Tmsm::DEFAULT_ALPHA, false)
    }
}

impl ClosedForm for Tmsm {
    /// G(b + α·(b* − b), z_f): in f64, or if `single` with the moments, α, b* and z_f rounded
    /// to f32 and the bias applied in f32 (`linalg::bias`, as the GPU path and the other
    /// closed forms do).
    fn shadow(&self, moments: &[f64], zf: f64) -> f64 {
        if moments.len() != 4 {
            return f64::NAN;
        }
        if self.single {
            let a = self.alpha as f32;
            let b = [0, 1, 2, 3].map(|j| bias(moments[j] as f32, a, self.b_star[j] as f32));
            sharp_bound(b, zf as f32) as f64
        } else {
            sharp_bound(self.biased(moments), zf)
        }
    }
}

impl Technique for Tmsm {
    fn name(&self) -> String {
        "tmsm".into()
    }
    fn moment_count(&self) -> usize {
        4
    }
    fn basis(&self, z: f64, out: &mut [f64]) {
        basis(z, out)
    }
    stateless_evaluator!();
}
#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn single_dirac_is_exact() {
        let mut b = [0.0; 4];
        basis(0.3, &mut b);
        assert_eq!(sharp_bound(b, 0.5), 1.0);
        assert_eq!(sharp_bound(b, 0.2), 0.0);
        assert_eq!(sharp_bound(b, 0.3), 0.0);
    }
}
