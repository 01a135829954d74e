//! Sparse representation of three moments by two Diracs (supplementary document of Peters et al.
//! 2016, Section 2, Theorem 1).
//!
//! For b₁, b₂, b₃ with σ² = b₂ − b₁² > 0, the kernel vector c of the Hankel matrix
//! B = [[1, b₁, b₂], [b₁, b₂, b₃], [b₂, b₃, b₄]] (b₄ chosen to make B singular) is
//! c₂ = b₂ − b₁², c₁ = b₁b₂ − b₃ and, from the first row of B·c = 0, c₀ = −b₁c₁ − b₂c₂ — the
//! form the document recommends over the expanded c₀ = b₁b₃ − b₂² (it follows the Cholesky
//! factorization and is numerically more stable). The roots z₂ < z₃ of c₂z² + c₁z + c₀ carry the
//! weights w₃ = (b₁ − z₂)/(z₃ − z₂), w₂ = 1 − w₃ (evaluated as (z₃ − b₁)/(z₃ − z₂)), and w₂z₂ʲ + w₃z₃ʲ = b_j for j = 1, 2, 3.

use super::linalg::Real;

/// Two Diracs at `z[0] < z[1]` with weights `w` (w ≥ 0, w[0] + w[1] = 1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TwoDiracs<T> {
    /// Depths, z[0] < z[1].
    pub z: [T; 2],
    /// Weights, w ≥ 0 with w[0] + w[1] = 1.
    pub w: [T; 2],
}

/// How c₀ is computed (for the comparison in docs/stability.md; use [`C0::FromC1C2`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum C0 {
    /// c₀ = −b₁c₁ − b₂c₂ (recommended by the supplementary document).
    FromC1C2,
    /// c₀ = b₁b₃ − b₂² (the expanded form of Theorem 1).
    Expanded,
}

/// Theorem 1 with c₀ from c₁ and c₂. `None` when σ² ≤ 0 or an input is not finite.
pub fn two_diracs<T: Real>(b1: T, b2: T, b3: T) -> Option<TwoDiracs<T>> {
    two_diracs_with(b1, b2, b3, C0::FromC1C2)
}

/// Theorem 1 with a choice of the c₀ formula.
pub fn two_diracs_with<T: Real>(b1: T, b2: T, b3: T, c0_form: C0) -> Option<TwoDiracs<T>> {
    let zero = T::of(0.0);
    let finite = |v: T| v.abs().to_f64().is_finite();
    if !(finite(b1) && finite(b2) && finite(b3)) {
        return None;
    }
    let c2 = b2 - b1 * b1;
    if c2 <= zero {
        return None;
    }
    let c1 = b1 * b2 - b3;
    let c0 = match c0_form {
        C0::FromC1C2 => -b1 * c1 - b2 * c2,
        C0::Expanded => b1 * b3 - b2 * b2,
    };
    // Roots of c₂z² + c₁z + c₀ (distinct and real by Theorem 1; clamp rounding).
    let p = c1 / c2;
    let q = c0 / c2;
    let hp = p * T::of(0.5);
    let disc = max0(hp * hp - q);
    let s = disc.sqrt();
    let big = if hp >= zero { -hp - s } else { -hp + s };
    let (mut z2, mut z3) = if big == zero {
        (zero, zero)
    } else {
        (big, q / big)
    };
    if z3 < z2 {
        std::mem::swap(&mut z2, &mut z3);
    }
    if z3 == z2 {
        return None;
    }
    // w₃ = (b₁ − z₂)/(z₃ − z₂) and w₂ = 1 − w₃ written as (z₃ − b₁)/(z₃ − z₂): the same number
    // without the cancellation when w₂ is tiny (a far-away Dirac).
    let d = z3 - z2;
    let w3 = clamp01((b1 - z2) / d);
    let w2 = clamp01((z3 - b1) / d);
    Some(TwoDiracs {
        z: [z2, z3],
        w: [w2, w3],
    })
}

fn clamp01<T: Real>(v: T) -> T {
    if v < T::of(0.0) {
        T::of(0.0)
    } else if v > T::of(1.0) {
        T::of(1.0)
    } else {
        v
    }
}

fn max0<T: Real>(v: T) -> T {
    if v > T::of(0.0) {
        v
    } else {
        T::of(0.0)
    }
}
