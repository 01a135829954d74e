//! The export of a tuned setting: `setting.json` (the constants) and `shadow.glsl`,
//! `shadow.hlsl` and `shadow.wgsl` with three functions written in the shader IR
//! (`crate::shader`):
//! `tunedEncode(z)` → the values a texel stores (θ(b(z)) for 16-bit UNORM with θ, b(z) else),
//! `tunedDecode(s)` → the moments b, and `tunedShadow(s, z_f)` → G: decode, bias
//! b' = (1 − α)·b + α·b*, the technique's reconstruction in f32 in the same operations and order
//! as momentlab's own f32 path, clamped to [0,1]. The depth bias is the caller's:
//! z_f = z − (ε + s·(|dz/du| + |dz/dv|)), its constants are in the header and the JSON.
//!
//! Reconstructions: VSM, ESM, EVSM, Hamburger 4MSM, Hausdorff 4MSM, 6MSM and TMSM, each a
//! transcript of the f32 solver with `select` for its branches (every branch is computed, the
//! selects keep the one the solver takes):
//! * Hausdorff 4MSM: Algorithm 3 (support z_f, z₂, z₃) while z₂ ≥ 0 and z₃ ≤ 1, else the
//!   distribution on {0, z_f, z_free, 1} with its weight sum through the Newton interpolation
//!   polynomial;
//! * 6MSM: the 4×4 LDLᵀ solve, the trigonometric cubic (Cardano's single real root when
//!   p ≥ 0, with x^{1/3} = sign(x)·e^{ln|x|/3} where the solver takes the f64 cube root; valid
//!   moments do not reach it), the weight sum; a Hankel matrix numerically singular at size 2
//!   or 3 goes to Algorithm 2 on the first 2 or 4 moments, whose quadratic is solved by
//!   Laguerre's iteration unrolled `LAGUERRE_STEPS` times (the solver loops until a step is
//!   at rounding level, at most 200 times) followed by the same three Newton steps;
//! * TMSM (`tmsm` below): the G-only path of `technique::tmsm::sharp_bound::<f32>` operation for
//!   operation — one or two Diracs, the lit arc, the certificates of (III-s), (I), (II), the
//!   quartic's root in the bracket of the canonical nodes, its roots by derivative isolation,
//!   the full enumeration — with its safeguarded Newton solves as loops of the solver's
//!   30 steps (`Func::repeat`) whose state freezes where the solver stops.

mod tmsm;

use super::space::{Own, Setting, StorageKind, TechniqueKind};
use crate::quantize::codegen;
use crate::quantize::curve::MonomialCurve;
use crate::shader::{Cmp, Func, Module, Shape, V};
use crate::technique::{hamburger6, Technique};
use anyhow::Result;

/// The biased moments b'_j = b_j + α·(b*_j − b_j) (`technique::linalg::bias`, f32).
fn biased(f: &mut Func, b: &[V], alpha: f64, b_star: &[f64]) -> Vec<V> {
    let a = f.c64(alpha);
    b.iter()
        .zip(b_star)
        .map(|(&bj, &s)| {
            let s = f.c64(s);
            let d = f.sub(s, bj);
            let ad = f.mul(a, d);
            f.add(bj, ad)
        })
        .collect()
}

/// Cantelli's bound (`technique::vsm::vsm`): var = max(b₂ − b₁², σ²_min),
/// t = z_f − b₁, G = t²/(var + t²) if t > 0 else 0.
fn vsm_into(f: &mut Func, b1: V, b2: V, zf: V, min_var: V) -> V {
    let sq = f.mul(b1, b1);
    let v = f.sub(b2, sq);
    let var = f.max(v, min_var);
    let t = f.sub(zf, b1);
    let t2 = f.mul(t, t);
    let den = f.add(var, t2);
    let q = f.div(t2, den);
    let zero = f.c(0.0);
    f.select(Cmp::Gt, t, zero, q, zero)
}

/// The result of Algorithm 3: G (unclamped) and the support roots z₂ ≤ z₃ (both b'₁ in the
/// single-Dirac branch), as `technique::hamburger4::Msm4`.
struct Msm4 {
    g: V,
    z2: V,
    z3: V,
}

/// A 0/1 flag: 1 if `a cmp b` (false for NaN).
fn flag(f: &mut Func, cmp: Cmp, a: V, b: V) -> V {
    let one = f.c(1.0);
    let zero = f.c(0.0);
    f.select(cmp, a, b, one, zero)
}

/// 1 if x is finite (|x| ≤ f32::MAX; NaN and ±∞ give 0).
fn finite(f: &mut Func, x: V) -> V {
    let ax = f.abs(x);
    let big = f.c(f32::MAX);
    flag(f, Cmp::Le, ax, big)
}

/// 1 if x = 0 (|x| ≤ 0; NaN gives 0).
fn is_zero(f: &mut Func, x: V) -> V {
    let ax = f.abs(x);
    let zero = f.c(0.0);
    flag(f, Cmp::Le, ax, zero)
}

/// `flag ? x : y` for a 0/1 flag.
fn when(f: &mut Func, flag: V, x: V, y: V) -> V {
    let half = f.c(0.5);
    f.select(Cmp::Gt, flag, half, x, y)
}

/// Hamburger 4MSM (`technique::hamburger4::msm4_hamburger`, Algorithm 3) for biased b.
fn msm4_into(f: &mut Func, b: &[V], zf: V) -> Msm4 {
    let zero = f.c(0.0);
    let one = f.c(1.0);
    let eps = f32::EPSILON;
    // single Dirac when b₂ − b₁² ≤ 4ε·b₂
    let sq = f.mul(b[0], b[0]);
    let d22 = f.sub(b[1], sq);
    let tol = f.c(4.0 * eps);
    let tol_b = f.mul(tol, b[1]);
    let g_single = f.select(Cmp::Lt, b[0], zf, one, zero);
    // LDLᵀ of the Hankel matrix, D33 floored at ε²(1 + |b₄|)
    let b01 = f.mul(b[0], b[1]);
    let l32d22 = f.sub(b[2], b01);
    let l32 = f.div(l32d22, d22);
    let b11 = f.mul(b[1], b[1]);
    let d33a = f.sub(b[3], b11);
    let ll = f.mul(l32, l32d22);
    let d33 = f.sub(d33a, ll);
    let floor = f.c(eps * eps);
    let ab3 = f.abs(b[3]);
    let one_ab3 = f.add(one, ab3);
    let f33 = f.mul(floor, one_ab3);
    let d33 = f.select(Cmp::Gt, d33, f33, d33, f33);
    let y1 = f.sub(zf, b[0]);
    let zz = f.mul(zf, zf);
    let zzb = f.sub(zz, b[1]);
    let ly = f.mul(l32, y1);
    let y2 = f.sub(zzb, ly);
    let c3 = f.div(y2, d33);
    let yd = f.div(y1, d22);
    let lc = f.mul(l32, c3);
    let c2 = f.sub(yd, lc);
    let bc2 = f.mul(b[0], c2);
    let c1a = f.sub(one, bc2);
    let bc3 = f.mul(b[1], c3);
    let c1 = f.sub(c1a, bc3);
    // quadratic_roots(c1, c2, c3)
    let p = f.mul(c2, c2);
    let four = f.c(4.0);
    let fc = f.mul(four, c1);
    let fcc = f.mul(fc, c3);
    let disc = f.sub(p, fcc);
    let disc = f.max(disc, zero);
    let s = f.sqrt(disc);
    let half = f.c(0.5);
    let cs = f.add(c2, s);
    let ncs = f.neg(cs);
    let qa = f.mul(ncs, half);
    let sc = f.sub(s, c2);
    let qb = f.mul(sc, half);
    let q = f.select(Cmp::Ge, c2, zero, qa, qb);
    let r1 = f.div(q, c3);
    let r2 = f.div(c1, q);
    let aq = f.abs(q);
    let r1 = f.select(Cmp::Gt, aq, zero, r1, zero);
    let r2 = f.select(Cmp::Gt, aq, zero, r2, zero);
    let z2 = f.select(Cmp::Le, r1, r2, r1, r2);
    let z3 = f.select(Cmp::Le, r1, r2, r2, r1);
    // G by the three cases
    let zz3 = f.mul(zf, z3);
    let s1 = f.add(zf, z3);
    let bs1 = f.mul(b[0], s1);
    let n1 = f.sub(zz3, bs1);
    let n1 = f.add(n1, b[1]);
    let e1 = f.sub(z3, z2);
    let e2 = f.sub(zf, z2);
    let den1 = f.mul(e1, e2);
    let g_mid = f.div(n1, den1);
    let z23 = f.mul(z2, z3);
    let s2 = f.add(z2, z3);
    let bs2 = f.mul(b[0], s2);
    let n2 = f.sub(z23, bs2);
    let n2 = f.add(n2, b[1]);
    let e3 = f.sub(zf, z3);
    let den2 = f.mul(e2, e3);
    let w1 = f.div(n2, den2);
    let g_high = f.sub(one, w1);
    let g = f.select(Cmp::Le, zf, z3, g_mid, g_high);
    let g = f.select(Cmp::Le, zf, z2, zero, g);
    Msm4 {
        g: f.select(Cmp::Gt, d22, tol_b, g, g_single),
        z2: f.select(Cmp::Gt, d22, tol_b, z2, b[0]),
        z3: f.select(Cmp::Gt, d22, tol_b, z3, b[0]),
    }
}

/// Σ f_i w_i for the distribution on `nodes` whose power moments are `moments` = (1, b₁, …)
/// (`technique::linalg::weight_sum`): divided differences a of the values f on the nodes
/// (a zero numerator gives 0), then E[p(Z)] = Σ_i a_i·E[π_i(Z)] with the Newton basis
/// π_i(z) = Π_{j<i}(z − x_j) expanded in monomials.
fn weight_sum_into(f: &mut Func, nodes: &[V], fv: &[V], moments: &[V]) -> V {
    let k = nodes.len();
    let zero = f.c(0.0);
    let mut a = fv.to_vec();
    for j in 1..k {
        for i in (j..k).rev() {
            let num = f.sub(a[i], a[i - 1]);
            let den = f.sub(nodes[i], nodes[i - j]);
            let q = f.div(num, den);
            let z = is_zero(f, num);
            a[i] = when(f, z, zero, q);
        }
    }
    let mut pi = vec![zero; k];
    pi[0] = f.c(1.0);
    let mut sum = f.mul(a[0], moments[0]);
    for i in 1..k {
        let x = nodes[i - 1];
        for d in (0..=i).rev() {
            let hi = if d >= 1 { pi[d - 1] } else { zero };
            let lo = if d < i { pi[d] } else { zero };
            if d < k {
                let xl = f.mul(x, lo);
                pi[d] = f.sub(hi, xl);
            }
        }
        let mut e = zero;
        for d in 0..=i {
            let t = f.mul(pi[d], moments[d]);
            e = f.add(e, t);
        }
        let t = f.mul(a[i], e);
        sum = f.add(sum, t);
    }
    sum
}

/// Hausdorff 4MSM (`technique::hausdorff4::msm4_hausdorff`) for biased b: Algorithm 3 while
/// its roots lie in [0,1]; otherwise the distribution on {0, z_f, z_free, 1} with
/// z_free = (b₄ − (1+z_f) b₃ + z_f b₂) / (b₃ − (1+z_f) b₂ + z_f b₁) and
/// G = w₀ + [z_free < z_f]·w_free by [`weight_sum_into`]; z_f ≤ 0 gives 0, z_f > 1 gives 1.
fn hausdorff4_into(f: &mut Func, b: &[V], zf: V) -> V {
    let zero = f.c(0.0);
    let one = f.c(1.0);
    let r = msm4_into(f, b, zf);
    let opz = f.add(one, zf);
    let t = f.mul(opz, b[2]);
    let num = f.sub(b[3], t);
    let t = f.mul(zf, b[1]);
    let num = f.add(num, t);
    let opz = f.add(one, zf);
    let t = f.mul(opz, b[1]);
    let den = f.sub(b[2], t);
    let t = f.mul(zf, b[0]);
    let den = f.add(den, t);
    let zfree = f.div(num, den);
    let ind = flag(f, Cmp::Lt, zfree, zf);
    let g4 = weight_sum_into(
        f,
        &[zero, zf, zfree, one],
        &[one, zero, ind, zero],
        &[one, b[0], b[1], b[2]],
    );
    let g = f.select(Cmp::Le, r.z3, one, r.g, g4);
    let g = f.select(Cmp::Ge, r.z2, zero, g, g4);
    let g = f.select(Cmp::Gt, zf, one, one, g);
    f.select(Cmp::Le, zf, zero, zero, g)
}

/// p(x), p′(x), p″(x) of Σ c_k x^k (coefficients ascending) by Horner, p″ as twice the
/// second accumulator (`technique::roots`'s `horner2`).
fn horner2_into(f: &mut Func, c: &[V], x: V) -> (V, V, V) {
    let zero = f.c(0.0);
    let (mut p, mut d1, mut d2) = (zero, zero, zero);
    for &ck in c.iter().rev() {
        let t = f.mul(d2, x);
        d2 = f.add(t, d1);
        let t = f.mul(d1, x);
        d1 = f.add(t, p);
        let t = f.mul(p, x);
        p = f.add(t, ck);
    }
    let two = f.c(2.0);
    let d2 = f.mul(two, d2);
    (p, d1, d2)
}

/// Laguerre iterations unrolled in the straight-line form of `technique::roots::real_roots`,
/// whose loop runs until a step is at rounding level (at most 200 times). For a quadratic
/// Laguerre's step is exact up to rounding, so the loop ends after a few steps; where it does
/// not (the iterate oscillates at rounding level), x after this many steps differs from the
/// solver's at that level, and both are polished by the same three Newton steps.
const LAGUERRE_STEPS: usize = 8;

/// The real roots of Σ c_k z^k with c_n ≠ 0 (n = c.len() − 1; the caller's n ≤ 2), ascending
/// (`technique::roots::real_roots`, whose caller has already dropped zero leading
/// coefficients). While the deflated polynomial has degree n ≥ 2: [`LAGUERRE_STEPS`] Laguerre
/// steps x′ = x − n/(g ± √max((n−1)(n h − g²), 0)) (the sign of g), g = p′/p, h = g² − p″/p,
/// from the Cauchy bound x = −(1 + max_k |c_k/c_n|); x is frozen before the step where p(x) = 0,
/// the denominator is 0 or x′ is not finite, and after the step where
/// |x′ − x| ≤ 4ε·max(|x′|, ε) (ε of f32); then deflation by (z − x). Degree 1: the root −c₀/c₁.
/// Each root then takes up to three Newton steps on the undeflated polynomial, frozen at p′ = 0
/// or a non-finite step; two roots are put in order.
fn real_roots_into(f: &mut Func, c: &[V]) -> Vec<V> {
    let zero = f.c(0.0);
    let one = f.c(1.0);
    let mut p = c.to_vec();
    let mut roots = Vec::new();
    while p.len() > 1 {
        let n = p.len() - 1;
        let x = if n == 1 {
            let np = f.neg(p[0]);
            f.div(np, p[1])
        } else {
            let lead = p[n];
            let mut bound = zero;
            for &ck in &p[..n] {
                let q = f.div(ck, lead);
                let aq = f.abs(q);
                bound = f.max(bound, aq);
            }
            let ob = f.add(one, bound);
            let mut x = f.neg(ob);
            let nf = f.c(n as f32);
            let four_eps = f.c(f32::EPSILON * 4.0);
            let eps = f.c(f32::EPSILON);
            let mut stop = zero;
            for _ in 0..LAGUERRE_STEPS {
                let (v, d1, d2) = horner2_into(f, &p, x);
                let v_zero = is_zero(f, v);
                let g = f.div(d1, v);
                let gg = f.mul(g, g);
                let dv = f.div(d2, v);
                let h = f.sub(gg, dv);
                let n1 = f.sub(nf, one);
                let nh = f.mul(nf, h);
                let gg = f.mul(g, g);
                let w = f.sub(nh, gg);
                let w = f.mul(n1, w);
                let w = f.max(w, zero);
                let s = f.sqrt(w);
                let gps = f.add(g, s);
                let gms = f.sub(g, s);
                let den = f.select(Cmp::Ge, g, zero, gps, gms);
                let den_zero = is_zero(f, den);
                let step = f.div(nf, den);
                let nx = f.sub(x, step);
                let fin = finite(f, nx);
                let dx = f.sub(nx, x);
                let adx = f.abs(dx);
                let anx = f.abs(nx);
                let m = f.max(anx, eps);
                let thr = f.mul(four_eps, m);
                let done = flag(f, Cmp::Le, adx, thr);
                // breaks before the update: p(x) = 0, den = 0, nx not finite
                let not_fin = f.sub(one, fin);
                let brk = f.max(v_zero, den_zero);
                let brk = f.max(brk, not_fin);
                let moved = when(f, brk, x, nx);
                x = when(f, stop, x, moved);
                let st = f.max(stop, brk);
                stop = f.max(st, done);
            }
            x
        };
        roots.push(x);
        // deflation by (z − x)
        let mut q = vec![zero; n];
        let mut carry = p[n];
        for k in (0..n).rev() {
            q[k] = carry;
            if k > 0 {
                let t = f.mul(carry, x);
                carry = f.add(p[k], t);
            }
        }
        p = q;
    }
    for r in roots.iter_mut() {
        let mut stop = zero;
        for _ in 0..3 {
            let (v, d1, _) = horner2_into(f, c, *r);
            let d_zero = is_zero(f, d1);
            let q = f.div(v, d1);
            let nr = f.sub(*r, q);
            let fin = finite(f, nr);
            let not_fin = f.sub(one, fin);
            let brk = f.max(d_zero, not_fin);
            let st = f.max(stop, brk);
            *r = when(f, st, *r, nr);
            stop = st;
        }
    }
    if roots.len() == 2 {
        let (a, b) = (roots[0], roots[1]);
        roots = vec![f.select(Cmp::Lt, b, a, b, a), f.select(Cmp::Lt, b, a, a, b)];
    }
    roots
}

/// (min, max) of a pair as `if a > b { swap }`.
fn ordered(f: &mut Func, a: V, b: V) -> (V, V) {
    (f.select(Cmp::Gt, a, b, b, a), f.select(Cmp::Gt, a, b, a, b))
}

/// x^{1/3} with the sign of x as sign(x)·e^{ln|x|/3}.
fn cbrt_into(f: &mut Func, x: V) -> V {
    let ax = f.abs(x);
    let l = f.log(ax);
    let third = f.c((1.0f64 / 3.0) as f32);
    let l3 = f.mul(l, third);
    let e = f.exp(l3);
    let ne = f.neg(e);
    let zero = f.c(0.0);
    f.select(Cmp::Lt, x, zero, ne, e)
}

/// The three real roots of c₀ + c₁z + c₂z² + c₃z³ (c₃ ≠ 0), ascending
/// (`technique::roots::cubic_roots`): the depressed cubic t³ + p t + q (z = t − a/3,
/// a = c₂/c₃, b = c₁/c₃, c = c₀/c₃). Both branches are computed and p < 0 selects: the
/// trigonometric form z_k = m cos(φ − 2πk/3) − a/3, k = 0, 1, 2, with m = 2√(−p/3),
/// φ = acos(clamp(3q/(p m), −1, 1))/3 (cos(φ ∓ 2π/3) = −½cos φ ± (√3/2) sin φ), else the one
/// real root u + v − a/3 of Cardano's formula, u, v = ∛(−q/2 ± √max(q²/4 + p³/27, 0)) by
/// [`cbrt_into`], three times. One Newton step per root on the monic cubic, kept when p′ ≠ 0
/// and the step is finite; then sorted by three compare-and-swaps.
fn cubic_roots_into(f: &mut Func, c0: V, c1: V, c2: V, c3: V) -> [V; 3] {
    let zero = f.c(0.0);
    let one = f.c(1.0);
    let a = f.div(c2, c3);
    let b = f.div(c1, c3);
    let c = f.div(c0, c3);
    let third = f.c((1.0f64 / 3.0) as f32);
    let aa = f.mul(a, a);
    let aa3 = f.mul(aa, third);
    let p = f.sub(b, aa3);
    let k = f.c((2.0f64 / 27.0) as f32);
    let t = f.mul(k, a);
    let t = f.mul(t, a);
    let t = f.mul(t, a);
    let ab = f.mul(a, b);
    let ab3 = f.mul(ab, third);
    let q = f.sub(t, ab3);
    let q = f.add(q, c);
    let shift = f.mul(a, third);
    // p < 0: three real roots
    let two = f.c(2.0);
    let np = f.neg(p);
    let np3 = f.mul(np, third);
    let sq = f.sqrt(np3);
    let m = f.mul(two, sq);
    let three = f.c(3.0);
    let q3 = f.mul(three, q);
    let pm = f.mul(p, m);
    let arg = f.div(q3, pm);
    let mone = f.c(-1.0);
    let arg = f.max(arg, mone);
    let arg = f.min(arg, one);
    let ac = f.acos(arg);
    let phi = f.mul(ac, third);
    let cp = f.cos(phi);
    let sp = f.sin(phi);
    let half = f.c(0.5);
    let h = f.mul(half, cp);
    let r34 = f.c(0.75f64.sqrt() as f32);
    let s3 = f.mul(r34, sp);
    let t = f.mul(m, cp);
    let t0 = f.sub(t, shift);
    let d = f.sub(s3, h);
    let t = f.mul(m, d);
    let t1 = f.sub(t, shift);
    let nh = f.neg(h);
    let d = f.sub(nh, s3);
    let t = f.mul(m, d);
    let t2 = f.sub(t, shift);
    // p ≥ 0: one real root
    let qq = f.mul(q, q);
    let quarter = f.c(0.25);
    let qq4 = f.mul(qq, quarter);
    let ppp = f.mul(p, p);
    let ppp = f.mul(ppp, p);
    let k27 = f.c((1.0f64 / 27.0) as f32);
    let ppp = f.mul(ppp, k27);
    let disc = f.add(qq4, ppp);
    let disc = f.max(disc, zero);
    let sd = f.sqrt(disc);
    let nq = f.neg(q);
    let nqh = f.mul(nq, half);
    let u = f.add(nqh, sd);
    let u = cbrt_into(f, u);
    let nq = f.neg(q);
    let nqh = f.mul(nq, half);
    let v = f.sub(nqh, sd);
    let v = cbrt_into(f, v);
    let uv = f.add(u, v);
    let t_one = f.sub(uv, shift);
    let mut r = [
        f.select(Cmp::Lt, p, zero, t0, t_one),
        f.select(Cmp::Lt, p, zero, t1, t_one),
        f.select(Cmp::Lt, p, zero, t2, t_one),
    ];
    for z in r.iter_mut() {
        let za = f.add(*z, a);
        let t = f.mul(za, *z);
        let t = f.add(t, b);
        let t = f.mul(t, *z);
        let fz = f.add(t, c);
        let z3 = f.mul(three, *z);
        let a2 = f.mul(two, a);
        let t = f.add(z3, a2);
        let t = f.mul(t, *z);
        let df = f.add(t, b);
        let step = f.div(fz, df);
        let nz = f.sub(*z, step);
        let fin = finite(f, nz);
        let upd = when(f, fin, nz, *z);
        let dz = is_zero(f, df);
        *z = when(f, dz, *z, upd);
    }
    let (a0, a1) = ordered(f, r[0], r[1]);
    let (a1, a2) = ordered(f, a1, r[2]);
    let (a0, a1) = ordered(f, a0, a1);
    [a0, a1, a2]
}

/// LDLᵀ solve of the n×n Hankel matrix H_jk = mo[j + k] with right-hand side (1, z_f, …,
/// z_f^{n−1}) (`technique::linalg::ldlt_solve` with tolerance 4ε): pivots
/// D_j = H_jj − Σ_{k<j} L_jk² D_k, the last one raised to 4ε·|H_jj| (4ε if that is 0) when it
/// is not above it; forward, diagonal and back substitution. Returns the solution and, for
/// every pivot before the last, (D_j, 4ε·|H_jj|): the factorisation reaches the last pivot iff
/// every D_j exceeds its bound.
fn hankel_solve_into(f: &mut Func, mo: &[V], zf: V, n: usize) -> (Vec<V>, Vec<(V, V)>) {
    let zero = f.c(0.0);
    let one = f.c(1.0);
    let tol = f.c(4.0 * f32::EPSILON);
    let mut rhs = vec![one];
    let mut pw = one;
    for _ in 1..n {
        pw = f.mul(pw, zf);
        rhs.push(pw);
    }
    // lower triangle: l[i][j] (i > j) and the pivots d[j]
    let mut l = vec![vec![zero; n]; n];
    let mut d = vec![zero; n];
    let mut checks = Vec::new();
    for j in 0..n {
        let ajj = mo[2 * j];
        let mut dj = ajj;
        for k in 0..j {
            let ll = f.mul(l[j][k], l[j][k]);
            let t = f.mul(ll, d[k]);
            dj = f.sub(dj, t);
        }
        let aa = f.abs(ajj);
        let thr = f.mul(tol, aa);
        if j + 1 < n {
            checks.push((dj, thr));
        } else {
            let fl = f.select(Cmp::Gt, thr, zero, thr, tol);
            dj = f.select(Cmp::Gt, dj, thr, dj, fl);
        }
        d[j] = dj;
        for i in j + 1..n {
            let mut s = mo[i + j];
            for k in 0..j {
                let t = f.mul(l[i][k], l[j][k]);
                let t = f.mul(t, d[k]);
                s = f.sub(s, t);
            }
            l[i][j] = f.div(s, dj);
        }
    }
    for i in 0..n {
        for k in 0..i {
            let t = f.mul(l[i][k], rhs[k]);
            rhs[i] = f.sub(rhs[i], t);
        }
    }
    for i in 0..n {
        rhs[i] = f.div(rhs[i], d[i]);
    }
    for i in (0..n).rev() {
        for k in i + 1..n {
            let t = f.mul(l[k][i], rhs[k]);
            rhs[i] = f.sub(rhs[i], t);
        }
    }
    (rhs, checks)
}

/// 1 if the factorisation of [`hankel_solve_into`] reached its last pivot.
fn full_rank(f: &mut Func, checks: &[(V, V)]) -> V {
    let mut ok = f.c(1.0);
    for &(d, thr) in checks {
        let o = flag(f, Cmp::Gt, d, thr);
        ok = f.min(ok, o);
    }
    ok
}

/// Algorithm 2 with the leading r×r Hankel block (`technique::hamburger`'s `solve_size`, r = 2
/// or 3) when its factorisation reaches the last pivot: c = B⁻¹(1, z_f, …), the roots of
/// Σ c_k z^k by [`real_roots_into`] (a zero leading coefficient lowers the degree, no root at
/// all gives G = 0), G = Σ_{z_i < z_f} w_i by [`weight_sum_into`].
fn hamburger_block_into(f: &mut Func, mo: &[V], zf: V, r: usize) -> V {
    let zero = f.c(0.0);
    let one = f.c(1.0);
    let (c, _) = hankel_solve_into(f, mo, zf, r);
    let mut g = Vec::new();
    for deg in 0..r {
        let roots = real_roots_into(f, &c[..=deg]);
        let mut nodes = vec![zf];
        nodes.extend_from_slice(&roots);
        let fv: Vec<V> = nodes
            .iter()
            .map(|&z| f.select(Cmp::Lt, z, zf, one, zero))
            .collect();
        g.push(weight_sum_into(f, &nodes, &fv, &mo[..nodes.len()]));
    }
    // the degree is the highest k ≤ r − 1 with c_k ≠ 0
    let mut out = g[0];
    for deg in 1..r {
        let z = is_zero(f, c[deg]);
        out = when(f, z, out, g[deg]);
    }
    out
}

/// 6MSM (`technique::hamburger6::msm6`) for biased b: 4×4 LDLᵀ solve, the cubic's three roots,
/// G = Σ_{z_i < z_f} w_i by [`weight_sum_into`]; a Hankel matrix that is numerically singular
/// already at size 2 or 3 (at most two Diracs) goes to Algorithm 2 with the first 2 or 4
/// moments ([`hamburger_block_into`]).
fn msm6_into(f: &mut Func, b: &[V], zf: V) -> V {
    let zero = f.c(0.0);
    let one = f.c(1.0);
    let mut mo = vec![one];
    mo.extend_from_slice(b);
    let (c, checks) = hankel_solve_into(f, &mo, zf, 4);
    let r = cubic_roots_into(f, c[0], c[1], c[2], c[3]);
    let nodes = [zf, r[0], r[1], r[2]];
    let ind: Vec<V> = r
        .iter()
        .map(|&z| f.select(Cmp::Lt, z, zf, one, zero))
        .collect();
    let g = weight_sum_into(f, &nodes, &[zero, ind[0], ind[1], ind[2]], &mo[..4]);
    let g2 = hamburger_block_into(f, &mo[..5], zf, 3);
    let g1 = hamburger_block_into(f, &mo[..3], zf, 2);
    // checks[0] is the pivot 1 ≥ 4ε (never fails), checks[1] = D22, checks[2] = D33
    let ok2 = full_rank(f, &checks[..2]);
    let ok3 = full_rank(f, &checks[2..]);
    let g = when(f, ok3, g, g2);
    when(f, ok2, g, g1)
}

/// b* of the setting's technique (the registry's default preset).
fn b_star(t: &dyn Technique, kind: TechniqueKind) -> Vec<f64> {
    let m = t.moment_count();
    match kind {
        TechniqueKind::Hamburger4 | TechniqueKind::Hausdorff4 => vec![0.5; m],
        // the registry's default preset for six moments is the clamped one
        TechniqueKind::Hamburger6 => hamburger6::B_STAR_CLAMPED.to_vec(),
        TechniqueKind::Tmsm => vec![0.0; m],
        _ => {
            let (mut b0, mut b1) = (vec![0.0; m], vec![0.0; m]);
            t.basis(0.0, &mut b0);
            t.basis(1.0, &mut b1);
            b0.iter().zip(&b1).map(|(a, b)| 0.5 * (a + b)).collect()
        }
    }
}

/// Append the reconstruction of `s` for biased-free moments `b` at depth `zf`: G clamped to
/// [0,1], or None when the technique has no straight-line form here.
pub fn reconstruction_into(f: &mut Func, s: &Setting, b: &[V], zf: V) -> Result<Option<V>> {
    let fam = &s.family;
    let t = fam.build(s.alpha)?;
    let bs = b_star(t.as_ref(), fam.technique);
    let min_var = 1e-6; // the registry's f32 default
    let g = match (fam.technique, fam.own) {
        (TechniqueKind::Vsm, _) => {
            let bb = biased(f, b, s.alpha, &bs);
            let mv = f.c64(min_var);
            vsm_into(f, bb[0], bb[1], zf, mv)
        }
        (TechniqueKind::Esm, Own::Esm { c }) => {
            let bb = biased(f, b, s.alpha, &bs);
            let c = f.c64(c);
            let nc = f.neg(c);
            let x = f.mul(nc, zf);
            let e = f.exp(x);
            let p = f.mul(bb[0], e);
            let one = f.c(1.0);
            f.sub(one, p)
        }
        (TechniqueKind::Evsm, Own::Evsm { c_pos, c_neg }) => {
            let bb = biased(f, b, s.alpha, &bs);
            let cp = f.c64(c_pos);
            let cn = f.c64(c_neg);
            let mv = f.c64(min_var);
            let x = f.mul(cp, zf);
            let wp = f.exp(x);
            let ncn = f.neg(cn);
            let y = f.mul(ncn, zf);
            let e = f.exp(y);
            let wn = f.neg(e);
            let dp = f.mul(cp, wp);
            let dn = f.mul(cn, wn);
            let mp = f.mul(mv, dp);
            let mp = f.mul(mp, dp);
            let gp = vsm_into(f, bb[0], bb[1], wp, mp);
            let mn = f.mul(mv, dn);
            let mn = f.mul(mn, dn);
            let gn = vsm_into(f, bb[2], bb[3], wn, mn);
            f.max(gp, gn)
        }
        (TechniqueKind::Hamburger4, _) => {
            let bb = biased(f, b, s.alpha, &bs);
            msm4_into(f, &bb, zf).g
        }
        (TechniqueKind::Hausdorff4, _) => {
            let bb = biased(f, b, s.alpha, &bs);
            hausdorff4_into(f, &bb, zf)
        }
        (TechniqueKind::Hamburger6, _) => {
            let bb = biased(f, b, s.alpha, &bs);
            msm6_into(f, &bb, zf)
        }
        (TechniqueKind::Tmsm, _) => {
            let bb = biased(f, b, s.alpha, &bs);
            tmsm::tmsm_into(f, &bb, zf)
        }
        _ => return Ok(None),
    };
    let zero = f.c(0.0);
    let one = f.c(1.0);
    Ok(Some(f.clamp(g, zero, one)))
}

/// The basis values b(z) of the setting's technique (power moments, or the exponential warps).
fn basis_into(f: &mut Func, s: &Setting, z: V) -> Vec<V> {
    match s.family.own {
        Own::Esm { c } => {
            let c = f.c64(c);
            let x = f.mul(c, z);
            vec![f.exp(x)]
        }
        Own::Evsm { c_pos, c_neg } => {
            let cp = f.c64(c_pos);
            let cn = f.c64(c_neg);
            let x = f.mul(cp, z);
            let p = f.exp(x);
            let ncn = f.neg(cn);
            let y = f.mul(ncn, z);
            let n = f.exp(y);
            let pp = f.mul(p, p);
            let nn = f.mul(n, n);
            let mn = f.neg(n);
            vec![p, pp, mn, nn]
        }
        Own::None if s.family.technique == TechniqueKind::Tmsm => {
            // t = 2πz: (sin t, cos t, sin 2t, cos 2t)
            let tau = f.c(std::f32::consts::TAU);
            let t = f.mul(tau, z);
            let t2 = f.add(t, t);
            vec![f.sin(t), f.cos(t), f.sin(t2), f.cos(t2)]
        }
        Own::None => {
            let m = s.family.technique.moment_count();
            let mut out = vec![z];
            for _ in 1..m {
                let last = *out.last().expect("non-empty");
                out.push(f.mul(last, z));
            }
            out
        }
    }
}

/// The module of a setting (None: no reconstruction for its technique here).
pub fn module(s: &Setting, header: Vec<String>) -> Result<Option<Module>> {
    let fam = &s.family;
    let m = fam.technique.moment_count();
    let theta = fam.technique.theta(fam.storage);
    let with_theta = fam.storage == StorageKind::Unorm16Theta;
    // encode
    let mut enc = Func::new("tunedEncode");
    let z = enc.input_scalar("depth");
    let stored = if with_theta && fam.technique == TechniqueKind::Tmsm {
        let b = basis_into(&mut enc, s, z);
        codegen::encode_matrix_into(&mut enc, &theta, &b)
    } else if with_theta {
        let rows = codegen::chebyshev_rows(&theta, &MonomialCurve::power(m)?)?;
        codegen::encode_into(&mut enc, &rows, z)
    } else {
        basis_into(&mut enc, s, z)
    };
    enc.output("stored", Shape::Array(m), &stored);
    // decode
    let mut dec = Func::new("tunedDecode");
    let sv = dec.input("stored", Shape::Array(m));
    let b = if with_theta {
        codegen::decode_into(&mut dec, &theta, &sv)
    } else {
        sv.clone()
    };
    dec.output("moments", Shape::Array(m), &b);
    // shadow
    let mut sh = Func::new("tunedShadow");
    let sv = sh.input("stored", Shape::Array(m));
    let zf = sh.input_scalar("fragmentDepth");
    let b = if with_theta {
        codegen::decode_into(&mut sh, &theta, &sv)
    } else {
        sv.clone()
    };
    let Some(g) = reconstruction_into(&mut sh, s, &b, zf)? else {
        return Ok(None);
    };
    sh.ret(Shape::Scalar, &[g]);
    let module = Module {
        header,
        funcs: vec![enc, dec, sh],
    };
    module.validate()?;
    Ok(Some(module))
}

/// The header lines of an export: what the functions expect and the tuned constants.
pub fn header(s: &Setting) -> Vec<String> {
    vec![
        format!("momentlab tune: {}", s.label()),
        format!(
            "Storage: {} ({} bits per texel); depths z in [0,1], 0 = near.",
            s.family.storage.name(),
            s.family.bits_per_texel()
        ),
        "tunedEncode(z): values a texel stores; filter them linearly; tunedShadow(filtered, zf)."
            .into(),
        format!(
            "Depth bias (caller): zf = z - ({:e} + {} * (|dz/du| + |dz/dv|)), slopes per texel.",
            s.depth_bias.constant, s.depth_bias.slope_scale
        ),
        format!("Moment bias alpha = {:e} (inside tunedShadow).", s.alpha),
    ]
}

/// The shader files of an export, in the order of [`shader_texts`].
pub const SHADER_FILES: [&str; 3] = ["shadow.glsl", "shadow.hlsl", "shadow.wgsl"];

/// The text of each of the [`SHADER_FILES`] for an export's module.
pub fn shader_texts(m: &Module) -> Result<[String; 3]> {
    Ok([
        crate::shader::glsl(m)?,
        crate::shader::hlsl(m)?,
        crate::shader::wgsl(m)?,
    ])
}

/// What `setting.json` of an export holds.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Exported<'a> {
    /// Scene name, or "all".
    pub scene: &'a str,
    /// The exported setting.
    pub setting: &'a Setting,
    /// Its label.
    pub label: String,
    /// Bits stored per texel.
    pub bits_per_texel: u32,
    /// Its score (leak + darkening + noise).
    pub error: f64,
    /// Mean max(PCF − G_exact, 0).
    pub leak: f64,
    /// Mean max(G_exact − PCF, 0).
    pub darkening: f64,
    /// Mean |G − G_exact| of the setting in the modelled pipeline ([`super::score`]).
    pub noise: f64,
    /// Share of fragments with |G − G_exact| > 1/255.
    pub noise_share: f64,
    /// GPU cost per lookup in ns ([`super::Options::cost`]; 0 where none was given).
    pub gpu_ns: f64,
    /// Files with the shader code (empty when the technique has no export here).
    pub shaders: Vec<String>,
    /// Lines of the GLSL file (0 without shader code).
    pub glsl_lines: usize,
    /// `glsl_lines` > [`EXPORT_LINES_BOUND`]: the export is larger than an engine's shader
    /// budget for one lookup usually allows.
    pub over_size_bound: bool,
}

/// Lines of the GLSL file [`write`] emits for setting `s` (0 where it has no shader code).
pub fn glsl_lines(s: &Setting) -> Result<usize> {
    Ok(match module(s, header(s))? {
        Some(m) => module_glsl_lines(&m)?,
        None => 0,
    })
}

/// Lines of module `m` printed as GLSL (`shadow.glsl`): the one measure of an export's size.
pub fn module_glsl_lines(m: &Module) -> Result<usize> {
    Ok(crate::shader::glsl(m)?.lines().count())
}

/// Largest GLSL export (lines of `shadow.glsl`) that is not flagged. The largest export of a
/// closed form that is not TMSM is 6MSM with θ₆ (about 1 500 lines: decode, the 4×4 Hankel
/// solve, the cubic's roots and the fallbacks to two and four moments); the bound is at least
/// a quarter above it (a test in `gpu::cost` keeps it so). TMSM's exports (over 5 000 lines,
/// ten loops) are above it.
pub const EXPORT_LINES_BOUND: usize = 2000;

/// The folder of target `scene`'s export inside `dir`: `<dir>/<scene>` (the scene name made
/// safe as one component).
fn target_dir(dir: &str, scene: &str) -> String {
    format!("{dir}/{}", crate::artefact::safe_name(scene))
}

/// Every file [`write`] may write into folder `dir` of its writer for the targets of `scenes`
/// and `all` (all scenes): `<dir>/<scene>/setting.json` and the [`SHADER_FILES`]. Known
/// before the tuning, so the caller can [`reserve`](crate::artefact::OutDir::reserve) them first.
pub fn file_names<S: AsRef<str>>(dir: &str, scenes: &[S]) -> Vec<String> {
    scenes
        .iter()
        .map(|s| s.as_ref())
        .chain(std::iter::once("all"))
        .flat_map(|scene| {
            let d = target_dir(dir, scene);
            std::iter::once("setting.json")
                .chain(SHADER_FILES)
                .map(move |f| format!("{d}/{f}"))
        })
        .collect()
}

/// Write the export of every target's chosen setting into folder `dir` of `out`, one folder
/// per target (`<dir>/<scene>/`, scene "all" for all scenes): `setting.json`, and
/// the [`SHADER_FILES`] where a reconstruction exists. The names are among [`file_names`].
pub fn write(out: &crate::artefact::OutDir, dir: &str, t: &super::Tuning) -> Result<()> {
    for target in t.scenes.iter().chain(std::iter::once(&t.overall)) {
        let dir = target_dir(dir, &target.scene);
        let s = &target.chosen.setting;
        let mut shaders = Vec::new();
        let mut glsl_lines = 0;
        if let Some(m) = module(s, header(s))? {
            for (name, text) in SHADER_FILES.into_iter().zip(shader_texts(&m)?) {
                if name.ends_with(".glsl") {
                    glsl_lines = text.lines().count();
                }
                out.write_text(&format!("{dir}/{name}"), &text)?;
                shaders.push(name.to_string());
            }
        }
        out.write_json(
            &format!("{dir}/setting.json"),
            &Exported {
                scene: &target.scene,
                setting: s,
                label: target.chosen.label.clone(),
                bits_per_texel: target.chosen.bits_per_texel,
                error: target.chosen.error,
                leak: target.chosen.leak,
                darkening: target.chosen.darkening,
                noise: target.chosen.noise,
                noise_share: target.chosen.noise_share,
                gpu_ns: target.chosen.ns_per_fragment,
                shaders,
                glsl_lines,
                over_size_bound: glsl_lines > EXPORT_LINES_BOUND,
            },
        )?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::technique::hamburger6::msm6;
    use crate::technique::hausdorff4::msm4_hausdorff;
    use crate::technique::linalg::{ldlt_solve, pivot_tol};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// A function of m moments and z_f returning `body(moments, z_f)`.
    fn kernel(m: usize, body: impl Fn(&mut Func, &[V], V) -> V) -> Func {
        let mut f = Func::new("k");
        let b = f.input("b", Shape::Array(m));
        let zf = f.input_scalar("zf");
        let g = body(&mut f, &b, zf);
        f.ret(Shape::Scalar, &[g]);
        f
    }

    /// Power moments (z, …, z^m) in f32 of the Diracs (depth, weight).
    fn moments<const M: usize>(atoms: &[(f64, f64)]) -> [f32; M] {
        let mut b = [0.0f64; M];
        for &(z, w) in atoms {
            for (j, bj) in b.iter_mut().enumerate() {
                *bj += w * z.powi(j as i32 + 1);
            }
        }
        b.map(|x| x as f32)
    }

    /// Rank at which the f32 LDLᵀ of the 4×4 Hankel matrix of (1, b) stops (4: none).
    fn hankel_rank(b: &[f32; 6], zf: f32) -> usize {
        let mo = [1.0, b[0], b[1], b[2], b[3], b[4], b[5]];
        let mut a = [0.0f32; 16];
        for j in 0..4 {
            for k in 0..4 {
                a[j * 4 + k] = mo[j + k];
            }
        }
        let mut c = [1.0, zf, zf * zf, zf * zf * zf];
        ldlt_solve(&mut a, 4, &mut c, pivot_tol::<f32>())
    }

    /// Distributions of one to four Diracs, some with atoms at 0 or 1 and near-coincident ones.
    fn distributions() -> Vec<Vec<(f64, f64)>> {
        let mut rng = ChaCha8Rng::seed_from_u64(31);
        let mut out = vec![
            vec![(0.4, 1.0)],
            vec![(0.0, 1.0)],
            vec![(0.25, 0.5), (0.75, 0.5)],
            vec![(0.0, 0.3), (1.0, 0.7)],
            vec![(0.3, 0.5), (0.30001, 0.5)],
            vec![(0.1, 0.2), (0.5, 0.3), (0.9, 0.5)],
        ];
        for n in 1..=4 {
            for _ in 0..50 {
                let w: Vec<f64> = (0..n).map(|_| rng.gen_range(0.05..1.0)).collect();
                let s: f64 = w.iter().sum();
                out.push(
                    w.iter()
                        .map(|wi| (rng.gen_range(0.0..1.0), wi / s))
                        .collect(),
                );
            }
        }
        out
    }

    const DEPTHS: [f32; 9] = [-0.1, 0.0, 0.05, 0.2999, 0.3, 0.45, 0.8, 1.0, 1.2];

    #[test]
    fn msm6_equals_the_f32_solver_bit_for_bit_in_every_branch() {
        let k = kernel(6, msm6_into);
        let mut ranks = [0usize; 5];
        for d in distributions() {
            let b = moments::<6>(&d);
            for zf in DEPTHS {
                ranks[hankel_rank(&b, zf)] += 1;
                let mut input = b.to_vec();
                input.push(zf);
                let ir = k.eval(&input).unwrap()[0];
                let own = msm6(b, zf).0;
                assert!(
                    ir.to_bits() == own.to_bits() || (ir.is_nan() && own.is_nan()),
                    "{d:?} z_f = {zf}: {ir} vs {own}"
                );
            }
        }
        // the fallbacks to Algorithm 2 on two and four moments are exercised
        assert!(
            ranks[1] > 0 && ranks[2] > 0 && ranks[3] + ranks[4] > 0,
            "{ranks:?}"
        );
    }

    #[test]
    fn hausdorff4_equals_the_f32_solver_bit_for_bit_in_every_branch() {
        let k = kernel(4, hausdorff4_into);
        let mut outside = 0;
        for d in distributions() {
            let b = moments::<4>(&d);
            for alpha in [0.0f32, 1e-4] {
                let b = b.map(|x| x + alpha * (0.5 - x));
                for zf in DEPTHS {
                    let mut input = b.to_vec();
                    input.push(zf);
                    let ir = k.eval(&input).unwrap()[0];
                    let own = msm4_hausdorff(b, zf);
                    assert!(
                        ir.to_bits() == own.to_bits() || (ir.is_nan() && own.is_nan()),
                        "{d:?} α = {alpha} z_f = {zf}: {ir} vs {own}"
                    );
                    let r = crate::technique::hamburger4::msm4_hamburger(b, zf);
                    outside += (zf > 0.0 && zf <= 1.0 && (r.z2 < 0.0 || r.z3 > 1.0)) as usize;
                }
            }
        }
        // the four-Dirac branch on {0, z_f, z_free, 1} is exercised
        assert!(outside > 0);
    }
}
