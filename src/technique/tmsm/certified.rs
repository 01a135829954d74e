//! The G-only fast path of the TMSM closed form for a positive definite Toeplitz matrix outside
//! the lit-arc case (docs/tmsm.md §4.6): candidates whose optimality is *certified* by a dual
//! polynomial, so that the quartic of §4.4 is solved only when no certificate holds.
//!
//! In the frame of docs/tmsm.md §1 (shadowed arc A = (−a, a), fragment at e^{ia}, seam at
//! e^{−ia}; a unit point z is in A ⇔ Re z > cos a):
//! * (III-s) is optimal whenever its four weights are ≥ 0: its dual 1 − K·f with
//!   f = (1 − cos(s − d))(1 − cos(s + d)) is feasible for every d ∈ A (f is unimodal on the lit
//!   arc and symmetric, so f ≥ f(a) there). Weights in closed form from the even/odd moment
//!   equations.
//! * (I)/(II): the canonical representation through ζ = e^{±ia} is the Gauss–Szegő rule of the
//!   para-orthogonal polynomial zΦ₂(z) − tΦ₂*(z) (Φ₂ the monic orthogonal polynomial); its nodes
//!   ζ, u·e^{±iθ} come from the product and the sum of the roots without a complex square root,
//!   its weights 1/K₂(z) (Christoffel function K₂(z) = 1 + |z − c₁|²/D₁ + |Φ₂(z)|²/D₂) are
//!   positive. Its value is certified by the dual polynomial interpolating the indicator on the
//!   nodes: for nodes {ζ, x, y} (x ∈ A, y lit) p = K(cos(s − m) − cos φ)(1 − cos(s − y)) positive
//!   on the arc (r, a) with r from the tangency at x, feasible ⇔ r ∈ [−a, x); for nodes
//!   {ζ, x₁, x₂} ⊂ A p = 1 − f/f(ζ), feasible ⇔ f(−ζ̄ side) ≥ f(ζ).
//!
//! A candidate whose value is certified is the sharp bound (weak duality below, a representing
//! measure above). `None` means no certificate held (or a degenerate configuration): the caller
//! enumerates every candidate (docs/tmsm.md §4) as before.

use super::{max, min, Case, Cx, Tol};
use crate::technique::linalg::Real;

/// The monic orthogonal polynomials Φ₁ = z − c₁, Φ₂ = z² + αz + β and their squared norms.
#[derive(Clone, Copy)]
struct Szego<T> {
    c1: Cx<T>,
    alpha: Cx<T>,
    beta: Cx<T>,
    inv_d1: T,
    inv_d2: T,
    /// D₂ = ‖Φ₂‖² = (1 − |c₁|²)(1 − |γ₂|²).
    d2: T,
}

impl<T: Real> Szego<T> {
    #[inline(always)]
    fn new(c1: Cx<T>, c2: Cx<T>) -> Self {
        let one = T::ONE;
        let d1 = one - c1.norm2();
        let gamma = (c2 - c1 * c1).scale(one / d1);
        let beta = -gamma;
        let alpha = -c1 - beta * c1.conj();
        let d2 = d1 * (one - gamma.norm2());
        Szego {
            c1,
            alpha,
            beta,
            inv_d1: one / d1,
            inv_d2: one / d2,
            d2,
        }
    }
    #[inline(always)]
    fn phi2(&self, z: Cx<T>) -> Cx<T> {
        (z + self.alpha) * z + self.beta
    }
    /// The Christoffel function K₂(z); the Gauss–Szegő weight of a node z is 1/K₂(z).
    #[inline(always)]
    fn christoffel(&self, z: Cx<T>) -> T {
        T::ONE + (z - self.c1).norm2() * self.inv_d1 + self.phi2(z).norm2() * self.inv_d2
    }
    /// The same polynomials for the conjugate moments (the problem mirrored by s → −s).
    #[inline(always)]
    fn mirrored(&self) -> Self {
        Szego {
            c1: self.c1.conj(),
            alpha: self.alpha.conj(),
            beta: self.beta.conj(),
            ..*self
        }
    }
    /// The other two nodes of the canonical representation through ζ (|ζ| = 1): with
    /// t = ζ̄·(Φ₂(ζ)/|Φ₂(ζ)|)², their product is tζ̄ = u², u = ζ̄Φ₂(ζ)/|Φ₂(ζ)|, and their sum is
    /// tβ̄ − α − ζ = 2u cos θ.
    #[inline(always)]
    fn canonical(&self, zeta: Cx<T>) -> Option<(Cx<T>, Cx<T>)> {
        let f = self.phi2(zeta);
        let n2 = f.norm2();
        if n2.is_nan() || n2 <= T::ZERO {
            return None;
        }
        let v = f.scale(T::ONE / n2.sqrt());
        let u = zeta.conj() * v;
        let t = u * v;
        let sum = t * self.beta.conj() - self.alpha - zeta;
        let c = (sum * u.conj()).re * T::of(0.5);
        let c = if c > T::ONE {
            T::ONE
        } else if c < -T::ONE {
            -T::ONE
        } else {
            c
        };
        let s = (T::ONE - c * c).sqrt();
        Some((u * Cx::new(c, s), u * Cx::new(c, -s)))
    }
}

/// What the certificates decided.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Verdict<T> {
    /// This candidate is optimal: G and its branch.
    Optimal(T, Case),
    /// (III-s) is infeasible and (I), (II) are well conditioned but not optimal: only the
    /// quartic's candidates (§4.4) remain. The nodes in A of (I) and (II) (up to four; count in
    /// the second field) bracket the quartic's optimal x in practice (a hint, checked by the
    /// caller).
    Quartic([Cx<T>; 4], usize),
    /// Too close to a boundary to decide here: enumerate every candidate.
    Unknown,
}

/// The certificates for (III-s), (I) and (II) in this order; c₁, c₂ rotated moments,
/// ea = e^{ia}, H₀, H₁ as in docs/tmsm.md §3.
#[inline(always)]
pub(super) fn bound<T: Real>(
    c1: Cx<T>,
    c2: Cx<T>,
    ea: Cx<T>,
    h0: T,
    h1: Cx<T>,
    tol: &Tol<T>,
) -> Verdict<T> {
    match symmetric(c1, c2, ea, h0, h1) {
        Some((g, w)) if w >= tol.certify_weight => return Verdict::Optimal(g, Case::Symmetric),
        Some((_, w)) if w >= tol.uncertain_below => return Verdict::Unknown,
        _ => {}
    }
    let least = max(tol.certify_weight, T::ZERO);
    let sz = Szego::new(c1, c2);
    if sz.d2.is_nan() || sz.d2 < tol.certify_det {
        return Verdict::Unknown;
    }
    // (II) is (I) in the mirrored problem s → −s (conjugate moments); the seam becomes e^{ia}.
    // Mass on the seam side (Im c₁ < 0 in the rotated frame) makes (II) the likelier optimum
    // (85 % of the (II) cases of the bench's random corpus), so it is tried first then.
    let mirrored = sz.mirrored();
    let sides = if c1.im < T::ZERO {
        [(&mirrored, true), (&sz, false)]
    } else {
        [(&sz, false), (&mirrored, true)]
    };
    let mut hint = [ea; 4];
    let mut n = 0;
    for (s, mirror) in sides {
        match through(s, ea, least) {
            Through::Optimal(g) if mirror => return Verdict::Optimal(g, Case::ThroughZero),
            Through::Optimal(g) => return Verdict::Optimal(g, Case::ThroughZf),
            Through::Unknown => return Verdict::Unknown,
            Through::Failed(x, k) => {
                for z in &x[..k] {
                    hint[n] = if mirror { z.conj() } else { *z };
                    n += 1;
                }
            }
        }
    }
    Verdict::Quartic(hint, n)
}

/// What the certificate of a canonical representation decided.
enum Through<T> {
    /// Certified optimal, G.
    Optimal(T),
    /// Its dual polynomial is infeasible; its nodes in A (count in the second field).
    Failed([Cx<T>; 2], usize),
    /// A weight below the guard, or degenerate nodes.
    Unknown,
}

/// (III-s) with Diracs at ±a, ±d, cos d = Re H₁/H₀ (docs/tmsm.md §4.3): G and the least of its
/// weights, or `None` if d ∉ A. S_d = w_d + w_{−d} = H₀/(cos d − cos a) = G, S_a = 1 − G, and
/// the differences from the odd moments
/// D_a = (2 cos d·Im c₁ − Im c₂)/(2 sin a (cos d − cos a)),
/// D_d = (Im c₂ − 2 cos a·Im c₁)/(2 sin d (cos d − cos a)); the weights are (S ± D)/2.
#[inline(always)]
fn symmetric<T: Real>(c1: Cx<T>, c2: Cx<T>, ea: Cx<T>, h0: T, h1: Cx<T>) -> Option<(T, T)> {
    let zero = T::ZERO;
    let one = T::ONE;
    let two = T::of(2.0);
    if h0.is_nan() || h0 <= zero {
        return None;
    }
    let (ca, sa) = (ea.re, ea.im);
    let cd = h1.re / h0;
    if !(cd > ca && cd <= one) {
        return None;
    }
    let gap = cd - ca;
    let g = h0 / gap;
    let sd = (one - cd * cd).sqrt();
    let da = (two * cd * c1.im - c2.im) / (two * sa * gap);
    let dd = (c2.im - two * ca * c1.im) / (two * sd * gap);
    let least = min((one - g) - da.abs(), g - dd.abs()) * T::of(0.5);
    // NaN (sin d = 0 with coincident nodes) is no candidate.
    (!least.is_nan()).then_some((g, least))
}

/// The canonical representation through the end ζ = e^{ia} (case I) and its certificate;
/// `least` guards the weights.
#[inline(always)]
fn through<T: Real>(sz: &Szego<T>, ea: Cx<T>, least: T) -> Through<T> {
    let one = T::ONE;
    let ca = ea.re;
    let zeta = ea;
    let Some((z2, z3)) = sz.canonical(zeta) else {
        return Through::Unknown;
    };
    let (in2, in3) = (z2.re > ca, z3.re > ca);
    let k = [sz.christoffel(zeta), sz.christoffel(z2), sz.christoffel(z3)];
    // Every weight 1/K ≥ least (K > 0; NaN fails).
    let kmax = one / least;
    if !(k[0] <= kmax && k[1] <= kmax && k[2] <= kmax) {
        return Through::Unknown;
    }
    match (in2, in3) {
        (true, true) => {
            // Nodes {ζ, x₁, x₂}: p = 1 − f/f(ζ) with f(s) = |e^{is} − x₁|²|e^{is} − x₂|²,
            // feasible ⇔ f ≥ f(ζ) at the other end e^{−ia} of the lit arc.
            let f = |z: Cx<T>| (z - z2).norm2() * (z - z3).norm2();
            if f(ea.conj()) >= f(zeta) {
                Through::Optimal(one - one / k[0])
            } else {
                Through::Failed([z2, z3], 2)
            }
        }
        (true, false) | (false, true) => {
            let (x, y, kx) = if in2 { (z2, z3, k[1]) } else { (z3, z2, k[2]) };
            // Tangency at x: cot((x − r)/2) = −cot((x − a)/2) − 2 cot((x − y)/2); r ∈ [−a, x)
            // ⇔ that is ≥ cot((x + a)/2). With cot(δ/2) = sin δ/(1 − cos δ) and the
            // denominators (> 0 for distinct points) multiplied out:
            // x within rounding of a (du = 0) is the limit x → a⁻ (−cot → +∞), which the
            // multiplied-out test gets right when Im u < 0; x within rounding of −a (dw = 0) is
            // the limit x → −a⁺, where cot((x + a)/2) → +∞ and the test fails.
            let (u, v, w) = (x * ea.conj(), x * y.conj(), x * ea);
            let (du, dv, dw) = (one - u.re, one - v.re, one - w.re);
            let at_a = du <= T::ZERO;
            let at_a_lit = at_a && (u.im >= T::ZERO || u.im.is_nan());
            if at_a_lit || dv <= T::ZERO || dv.is_nan() || dw.is_nan() {
                return Through::Unknown;
            }
            if dw <= T::ZERO {
                return Through::Failed([x, x], 1);
            }
            let du = max(du, T::ZERO);
            let lhs = -(u.im * dv + T::of(2.0) * v.im * du) * dw;
            let rhs = w.im * du * dv;
            if lhs >= rhs {
                Through::Optimal(one / kx)
            } else {
                Through::Failed([x, x], 1)
            }
        }
        // Both other nodes lit: G would be 0, which the lit-arc test rules out.
        (false, false) => Through::Unknown,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn moments(atoms: &[(f64, f64)]) -> (Cx<f64>, Cx<f64>) {
        let mut c1 = Cx::real(0.0);
        let mut c2 = Cx::real(0.0);
        for &(s, w) in atoms {
            c1 = c1 + Cx::unit(s).scale(w);
            c2 = c2 + Cx::unit(2.0 * s).scale(w);
        }
        (c1, c2)
    }

    #[test]
    fn canonical_nodes_and_christoffel_weights_reproduce_the_moments() {
        // Interior moments of 4 Diracs; the rule through ζ must reproduce c₁, c₂ with
        // positive weights summing to 1.
        let (c1, c2) = moments(&[(0.3, 0.2), (1.9, 0.3), (-2.2, 0.25), (-0.4, 0.25)]);
        let sz = Szego::new(c1, c2);
        for phi in [0.0, 0.7, 2.0, -1.3, 3.1] {
            let zeta = Cx::unit(phi);
            let (z2, z3) = sz.canonical(zeta).unwrap();
            let nodes = [zeta, z2, z3];
            let w = nodes.map(|z| 1.0 / sz.christoffel(z));
            let (mut m0, mut m1, mut m2) = (0.0, Cx::real(0.0), Cx::real(0.0));
            for (z, wi) in nodes.iter().zip(w) {
                assert!(wi > 0.0 && (z.abs() - 1.0).abs() < 1e-12);
                m0 += wi;
                m1 = m1 + z.scale(wi);
                m2 = m2 + (*z * *z).scale(wi);
            }
            assert!((m0 - 1.0).abs() < 1e-12, "{phi}: {w:?}");
            assert!((m1 - c1).abs() < 1e-12 && (m2 - c2).abs() < 1e-12, "{phi}");
        }
    }
}
