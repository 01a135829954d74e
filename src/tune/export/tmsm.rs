//! TMSM's G-only f32 path (`technique::tmsm::sharp_bound::<f32>`, docs/tmsm.md) in the shader
//! IR, operation for operation: complex numbers as (re, im) pairs, every branch computed and
//! `select`ed by the flags the solver tests, the safeguarded Newton solves of the quartic as
//! loops of the solver's maximum step count whose state freezes where the solver breaks.

use super::{flag, is_zero, when};
use crate::shader::{Cmp, Func, V};
use crate::technique::tmsm::roots::{NEWTON_FLOOR, NEWTON_STEPS, TOUCHING};
use crate::technique::tmsm::Tol;

/// A complex number of the transcript.
#[derive(Clone, Copy)]
struct C {
    re: V,
    im: V,
}

fn add(f: &mut Func, a: C, b: C) -> C {
    C {
        re: f.add(a.re, b.re),
        im: f.add(a.im, b.im),
    }
}

fn sub(f: &mut Func, a: C, b: C) -> C {
    C {
        re: f.sub(a.re, b.re),
        im: f.sub(a.im, b.im),
    }
}

/// (a.re b.re − a.im b.im, a.re b.im + a.im b.re)
fn mul(f: &mut Func, a: C, b: C) -> C {
    let rr = f.mul(a.re, b.re);
    let ii = f.mul(a.im, b.im);
    let ri = f.mul(a.re, b.im);
    let ir = f.mul(a.im, b.re);
    C {
        re: f.sub(rr, ii),
        im: f.add(ri, ir),
    }
}

/// |z|² = re² + im²
fn norm2(f: &mut Func, a: C) -> V {
    let rr = f.mul(a.re, a.re);
    let ii = f.mul(a.im, a.im);
    f.add(rr, ii)
}

/// Re(a/b) = (a.re b.re + a.im b.im)/|b|²
fn div_re(f: &mut Func, a: C, b: C) -> V {
    let d = norm2(f, b);
    let rr = f.mul(a.re, b.re);
    let ii = f.mul(a.im, b.im);
    let n = f.add(rr, ii);
    f.div(n, d)
}

/// a/b = ((a.re b.re + a.im b.im)/|b|², (a.im b.re − a.re b.im)/|b|²)
fn div(f: &mut Func, a: C, b: C) -> C {
    let re = div_re(f, a, b);
    let d = norm2(f, b);
    let ir = f.mul(a.im, b.re);
    let ri = f.mul(a.re, b.im);
    let n = f.sub(ir, ri);
    C {
        re,
        im: f.div(n, d),
    }
}

fn neg(f: &mut Func, a: C) -> C {
    C {
        re: f.neg(a.re),
        im: f.neg(a.im),
    }
}

fn conj(f: &mut Func, a: C) -> C {
    C {
        re: a.re,
        im: f.neg(a.im),
    }
}

fn scale(f: &mut Func, a: C, s: V) -> C {
    C {
        re: f.mul(a.re, s),
        im: f.mul(a.im, s),
    }
}

/// The real number x as (x, 0).
fn real(f: &mut Func, x: V) -> C {
    C {
        re: x,
        im: f.c(0.0),
    }
}

/// `flag ? a : b` for complex values.
fn pick(f: &mut Func, flag: V, a: C, b: C) -> C {
    C {
        re: when(f, flag, a.re, b.re),
        im: when(f, flag, a.im, b.im),
    }
}

/// z/|z|, or 1 for |z| = 0 (`Cx::normalized`).
fn normalized(f: &mut Func, a: C) -> C {
    let n = norm2(f, a);
    let r = f.sqrt(n);
    let one = f.c(1.0);
    let zero = f.c(0.0);
    let inv = f.div(one, r);
    let s = scale(f, a, inv);
    C {
        re: f.select(Cmp::Gt, r, zero, s.re, one),
        im: f.select(Cmp::Gt, r, zero, s.im, zero),
    }
}

/// The principal square root (`Cx::sqrt`): (√((r + re)/2), ±√((r − re)/2)), r = |z|, the
/// sign of Im z.
fn csqrt(f: &mut Func, a: C) -> C {
    let n = norm2(f, a);
    let r = f.sqrt(n);
    let half = f.c(0.5);
    let p = f.add(r, a.re);
    let p = f.mul(p, half);
    let re = f.sqrt(p);
    let m = f.sub(r, a.re);
    let m = f.mul(m, half);
    let im = f.sqrt(m);
    let nim = f.neg(im);
    let zero = f.c(0.0);
    C {
        re,
        im: f.select(Cmp::Lt, a.im, zero, nim, im),
    }
}

/// `tmsm::min`: b if b < a, else a (NaN in b keeps a).
fn tmin(f: &mut Func, a: V, b: V) -> V {
    f.select(Cmp::Lt, b, a, b, a)
}

/// `tmsm::max`: b if b > a, else a.
fn tmax(f: &mut Func, a: V, b: V) -> V {
    f.select(Cmp::Gt, b, a, b, a)
}

/// max(0, min(1, g)) as the solver clamps.
fn unit(f: &mut Func, g: V) -> V {
    let zero = f.c(0.0);
    let one = f.c(1.0);
    let m = tmin(f, one, g);
    tmax(f, zero, m)
}

fn and(f: &mut Func, a: V, b: V) -> V {
    f.min(a, b)
}

fn or(f: &mut Func, a: V, b: V) -> V {
    f.max(a, b)
}

fn not(f: &mut Func, a: V) -> V {
    let one = f.c(1.0);
    f.sub(one, a)
}

/// 1 unless x is NaN (x ≥ x).
fn not_nan(f: &mut Func, x: V) -> V {
    flag(f, Cmp::Ge, x, x)
}

/// Mass of the Diracs (point, weight) on the shadowed arc (`tmsm::mass_on_arc`): w counts if
/// Re(z·(1 + i·tol)) > cos a; clamped to [0,1].
fn mass_on_arc(f: &mut Func, atoms: &[(C, V)], ca: V, tol: f32) -> V {
    let one = f.c(1.0);
    let t = f.c(tol);
    let turn = C { re: one, im: t };
    let mut g = f.c(0.0);
    for &(z, w) in atoms {
        let zt = mul(f, z, turn);
        let gw = f.add(g, w);
        g = f.select(Cmp::Gt, zt.re, ca, gw, g);
    }
    unit(f, g)
}

/// Roots of z² + p z + q (`tmsm::quadratic_roots`): big = −p/2 ∓ √(p²/4 − q) with the sign
/// avoiding cancellation, the other q/big (big twice if big = 0).
fn quadratic_roots(f: &mut Func, p: C, q: C) -> (C, C) {
    let zero = f.c(0.0);
    let half = f.c(0.5);
    let quarter = f.c(0.25);
    let pp = mul(f, p, p);
    let pp = scale(f, pp, quarter);
    let d = sub(f, pp, q);
    let s = csqrt(f, d);
    let hp = scale(f, p, half);
    let a = f.mul(hp.re, s.re);
    let b = f.mul(hp.im, s.im);
    let dot = f.add(a, b);
    let nhp = neg(f, hp);
    let minus = sub(f, nhp, s);
    let nhp = neg(f, hp);
    let plus = add(f, nhp, s);
    let ge = flag(f, Cmp::Ge, dot, zero);
    let big = pick(f, ge, minus, plus);
    let n = norm2(f, big);
    let degenerate = flag(f, Cmp::Le, n, zero);
    let other = div(f, q, big);
    let other = pick(f, degenerate, big, other);
    (big, other)
}

/// Re of the Lagrange weight of node i of four points of the circle (`tmsm::weight4`).
fn weight4(f: &mut Func, z: &[C; 4], i: usize, c1: C, c2: C) -> V {
    const OTHERS: [[usize; 3]; 4] = [[1, 2, 3], [0, 2, 3], [0, 1, 3], [0, 1, 2]];
    let [p, q, r] = OTHERS[i].map(|j| z[j]);
    let pq = add(f, p, q);
    let pqr = add(f, pq, r);
    let e2 = neg(f, pqr);
    let pq = mul(f, p, q);
    let pr = mul(f, p, r);
    let qr = mul(f, q, r);
    let e1 = add(f, pq, pr);
    let e1 = add(f, e1, qr);
    let pqr = mul(f, pq, r);
    let e0 = neg(f, pqr);
    let t = mul(f, e2, c1);
    let num = add(f, c2, t);
    let num = add(f, num, e1);
    let c1c = conj(f, c1);
    let t = mul(f, e0, c1c);
    let num = add(f, num, t);
    let zc = conj(f, z[i]);
    let d = sub(f, z[i], p);
    let den = mul(f, zc, d);
    let d = sub(f, z[i], q);
    let den = mul(f, den, d);
    let d = sub(f, z[i], r);
    let den = mul(f, den, d);
    div_re(f, num, den)
}

/// Re of the Lagrange weights of three points (`tmsm::weights3`).
fn weights3(f: &mut Func, z: [C; 3], c1: C, c2: C) -> [V; 3] {
    let one = f.c(1.0);
    let one = real(f, one);
    [0, 1, 2].map(|i| {
        let (j, k) = ((i + 1) % 3, (i + 2) % 3);
        let s = add(f, z[j], z[k]);
        let e1 = neg(f, s);
        let e0 = mul(f, z[j], z[k]);
        let t = mul(f, e1, c1);
        let num = add(f, c2, t);
        let t = mul(f, e0, one);
        let num = add(f, num, t);
        let a = sub(f, z[i], z[j]);
        let b = sub(f, z[i], z[k]);
        let den = mul(f, a, b);
        div_re(f, num, den)
    })
}

/// 1 if every weight is ≥ −tol.
fn all_at_least(f: &mut Func, w: &[V], tol: f32) -> V {
    let t = f.c(-tol);
    let mut ok = f.c(1.0);
    for &wi in w {
        let o = flag(f, Cmp::Ge, wi, t);
        ok = and(f, ok, o);
    }
    ok
}

/// p(x) of Σ c_j x^j by Horner (`roots::horner(..).0`).
fn horner_p(f: &mut Func, c: &[V], x: V) -> V {
    let mut p = f.c(0.0);
    for &cj in c.iter().rev() {
        let t = f.mul(p, x);
        p = f.add(t, cj);
    }
    p
}

/// `roots::newton_in_bracket` on Σ c_j x^j (c.len() − 1 = its degree): from the secant point
/// (the midpoint if it is not inside (a, b)), [`NEWTON_STEPS`] iterations of a loop carrying
/// (a, b, x, stopped): p, p′ and Σ|c_j||x|^j by Horner; stop before moving if
/// |p| ≤ 4ε·Σ|c_j||x|^j; shrink the bracket to the side of x; the Newton point if strictly
/// inside, else the midpoint; stop after moving if the Newton step is ≤ 4ε·max(|x|, 1/1024)
/// or the bracket is ≤ 4ε·max(|a|, |b|).
fn newton_into(f: &mut Func, c: &[V], a: V, b: V, pa: V, pb: V) -> V {
    let zero = f.c(0.0);
    let half = f.c(0.5);
    let stop = f.c(f32::EPSILON * 4.0);
    let floor = f.c(NEWTON_FLOOR as f32);
    let neg_at_a = flag(f, Cmp::Lt, pa, zero);
    let w = f.sub(b, a);
    let t = f.mul(pa, w);
    let d = f.sub(pb, pa);
    let t = f.div(t, d);
    let secant = f.sub(a, t);
    let s = f.add(a, b);
    let mid = f.mul(s, half);
    let gt = flag(f, Cmp::Gt, secant, a);
    let lt = flag(f, Cmp::Lt, secant, b);
    let inside = and(f, gt, lt);
    let x = when(f, inside, secant, mid);
    let abs_c: Vec<V> = c.iter().map(|&cj| f.abs(cj)).collect();
    let out = f.repeat(NEWTON_STEPS[0] as u32, &[a, b, x, zero], |f, v| {
        let (a, b, x, stopped) = (v[0], v[1], v[2], v[3]);
        let zero = f.c(0.0);
        let ax = f.abs(x);
        let (mut p, mut dp, mut mag) = (zero, zero, zero);
        for (&cj, &aj) in c.iter().zip(&abs_c).rev() {
            let t = f.mul(dp, x);
            dp = f.add(t, p);
            let t = f.mul(p, x);
            p = f.add(t, cj);
            let t = f.mul(mag, ax);
            mag = f.add(t, aj);
        }
        let ap = f.abs(p);
        let lim = f.mul(stop, mag);
        let converged = flag(f, Cmp::Le, ap, lim);
        let neg = flag(f, Cmp::Lt, p, zero);
        let d = f.sub(neg, neg_at_a);
        let same_side = is_zero(f, d);
        let a1 = when(f, same_side, x, a);
        let b1 = when(f, same_side, b, x);
        let q = f.div(p, dp);
        let nx = f.sub(x, q);
        let flat = is_zero(f, dp);
        let nx = when(f, flat, a1, nx);
        let gt = flag(f, Cmp::Gt, nx, a1);
        let lt = flag(f, Cmp::Lt, nx, b1);
        let inb = and(f, gt, lt);
        let dx = f.sub(nx, x);
        let step = f.abs(dx);
        let s = f.add(a1, b1);
        let mid = f.mul(s, half);
        let x1 = when(f, inb, nx, mid);
        let anx = f.abs(nx);
        let m = tmax(f, anx, floor);
        let lim = f.mul(stop, m);
        let small = flag(f, Cmp::Le, step, lim);
        let small = and(f, inb, small);
        let w = f.sub(b1, a1);
        let aa = f.abs(a1);
        let ab = f.abs(b1);
        let m = tmax(f, aa, ab);
        let lim = f.mul(stop, m);
        let collapsed = flag(f, Cmp::Le, w, lim);
        let hold = or(f, stopped, converged);
        let a = when(f, hold, a, a1);
        let b = when(f, hold, b, b1);
        let x = when(f, hold, x, x1);
        let s = or(f, hold, small);
        let s = or(f, s, collapsed);
        vec![a, b, x, s]
    });
    out[2]
}

/// A root candidate of [`isolate_into`]: its value and a 0/1 flag (1: the solver reports it).
#[derive(Clone, Copy)]
struct Slot {
    x: V,
    valid: V,
}

/// `roots::isolate` at degree c.len() − 1 on [lo, hi], one slot per monotone piece in
/// ascending order: the critical points are the slots of the derivative; on each piece from
/// the last reported point a to b a root is a if p(a) = 0 on the first piece, b if p does not
/// change sign and p(b) = 0 or (b a critical point) |p(b)| ≤ 64ε, else the Newton root.
fn isolate_into(f: &mut Func, c: &[V], lo: V, hi: V) -> Vec<Slot> {
    let deg = c.len() - 1;
    let zero = f.c(0.0);
    let one = f.c(1.0);
    if deg == 1 {
        let n = f.neg(c[0]);
        let r = f.div(n, c[1]);
        let ge = flag(f, Cmp::Ge, r, lo);
        let le = flag(f, Cmp::Le, r, hi);
        let valid = and(f, ge, le);
        return vec![Slot { x: r, valid }];
    }
    let d: Vec<V> = (1..=deg)
        .map(|j| {
            let k = f.c(j as f32);
            f.mul(c[j], k)
        })
        .collect();
    let mut pieces = isolate_into(f, &d, lo, hi);
    pieces.push(Slot { x: hi, valid: one });
    let touch = f.c(TOUCHING as f32 * f32::EPSILON);
    let mut a = lo;
    let mut pa = horner_p(f, c, lo);
    let mut first = one;
    let mut out = Vec::with_capacity(deg);
    for (w, piece) in pieces.iter().enumerate() {
        let interior = w + 1 < pieces.len();
        let b = piece.x;
        let pb = horner_p(f, c, b);
        let pa_zero = is_zero(f, pa);
        let at_lo = and(f, first, pa_zero);
        let na = flag(f, Cmp::Lt, pa, zero);
        let nb = flag(f, Cmp::Lt, pb, zero);
        let d = f.sub(na, nb);
        let same = is_zero(f, d);
        let pb_zero = is_zero(f, pb);
        let no_change = or(f, same, pb_zero);
        let touching = if interior {
            let apb = f.abs(pb);
            let tiny = flag(f, Cmp::Le, apb, touch);
            or(f, pb_zero, tiny)
        } else {
            pb_zero
        };
        let newton = newton_into(f, c, a, b, pa, pb);
        let x = when(f, no_change, b, newton);
        let x = when(f, at_lo, a, x);
        let found = when(f, no_change, touching, one);
        let found = or(f, at_lo, found);
        out.push(Slot {
            x,
            valid: and(f, piece.valid, found),
        });
        a = when(f, piece.valid, b, a);
        pa = when(f, piece.valid, pb, pa);
        first = when(f, piece.valid, zero, first);
    }
    out
}

/// `tmsm::roots_in_interval::<f32>` on [−1, 1]: coefficients scaled to max |c_j| = 1 (none
/// if that is 0 or NaN), then [`isolate_into`] at degree 4.
fn roots_into(f: &mut Func, coef: &[V; 5]) -> Vec<Slot> {
    let zero = f.c(0.0);
    let one = f.c(1.0);
    let mut scale = zero;
    for &c in coef {
        let ac = f.abs(c);
        scale = tmax(f, scale, ac);
    }
    let ok = flag(f, Cmp::Gt, scale, zero);
    let inv = f.div(one, scale);
    let c: Vec<V> = coef.iter().map(|&cj| f.mul(cj, inv)).collect();
    let lo = f.c(-1.0);
    isolate_into(f, &c, lo, one)
        .into_iter()
        .map(|s| Slot {
            x: s.x,
            valid: and(f, s.valid, ok),
        })
        .collect()
}

/// The rotated moments and the arc: c₁, c₂, e^{ia}.
#[derive(Clone, Copy)]
struct Frame {
    c1: C,
    c2: C,
    ea: C,
    h0: V,
    h1: C,
}

/// What a (III-q) root offers regardless of the best G so far: its G (the weight at x) and 1
/// if it is a feasible candidate (|σ| < 1, y lit, weights ≥ −tol).
struct Quartic {
    g: V,
    feasible: V,
}

/// `tmsm::quartic_candidate` without the comparison with the best G: τ = kσ,
/// e^{ix} = (1 − τ² + 2iτ)/(1 + τ²), e^{−iu} = conj of (sin x + i(cos x − cos a)) normalized,
/// e^{iy} = e^{ix}·e^{−iu}·e^{−iu}; the weights on {e^{ia}, e^{−ia}, e^{ix}, e^{iy}}.
fn quartic_candidate(f: &mut Func, fr: &Frame, sigma: V, k: V, tol: &Tol<f32>) -> Quartic {
    let one = f.c(1.0);
    let two = f.c(2.0);
    let ca = fr.ea.re;
    let asg = f.abs(sigma);
    let out = flag(f, Cmp::Ge, asg, one);
    let inside = not(f, out);
    let tau = f.mul(k, sigma);
    let t2 = f.mul(tau, tau);
    let d = f.add(one, t2);
    let inv = f.div(one, d);
    let r = f.sub(one, t2);
    let r = f.mul(r, inv);
    let i = f.mul(two, tau);
    let i = f.mul(i, inv);
    let zx = C { re: r, im: i };
    let v = f.sub(zx.re, ca);
    let eu = normalized(f, C { re: zx.im, im: v });
    let eu = conj(f, eu);
    let zy = mul(f, zx, eu);
    let zy = mul(f, zy, eu);
    let y_shadowed = flag(f, Cmp::Ge, zy.re, ca);
    let y_lit = not(f, y_shadowed);
    let ema = conj(f, fr.ea);
    let nodes = [fr.ea, ema, zx, zy];
    let w: Vec<V> = (0..4)
        .map(|i| weight4(f, &nodes, i, fr.c1, fr.c2))
        .collect();
    let ok = all_at_least(f, &w, tol.weight);
    let feasible = and(f, inside, y_lit);
    let feasible = and(f, feasible, ok);
    Quartic { g: w[2], feasible }
}

/// Keep candidate q if it is feasible and below `best`: (new best, 1 if kept).
fn improve(f: &mut Func, best: V, q: &Quartic) -> (V, V) {
    let below = flag(f, Cmp::Lt, q.g, best);
    let keep = and(f, q.feasible, below);
    (when(f, keep, q.g, best), keep)
}

/// The quartic of docs/tmsm.md §4.4 in σ and tan(a/2) (`tmsm::quartic_coef`).
fn quartic_coef(f: &mut Func, fr: &Frame) -> ([V; 5], V) {
    let one = f.c(1.0);
    let two = f.c(2.0);
    let (ca, sa) = (fr.ea.re, fr.ea.im);
    let (p, q) = (fr.h1.re, fr.h1.im);
    let am = f.sub(one, ca);
    let bm = f.add(one, ca);
    let k = f.div(sa, bm);
    let c0 = f.mul(q, am);
    let t = f.add(one, am);
    let t = f.mul(p, t);
    let t = f.sub(fr.h0, t);
    let t = f.mul(two, t);
    let c1 = f.mul(t, k);
    let m6 = f.c(-6.0);
    let t = f.mul(m6, q);
    let t = f.mul(t, k);
    let c2 = f.mul(t, k);
    let t = f.add(one, bm);
    let t = f.mul(p, t);
    let t = f.add(fr.h0, t);
    let t = f.mul(two, t);
    let t = f.mul(t, k);
    let t = f.mul(t, k);
    let c3 = f.mul(t, k);
    let t = f.mul(q, bm);
    let t = f.mul(t, k);
    let t = f.mul(t, k);
    let t = f.mul(t, k);
    let c4 = f.mul(t, k);
    ([c0, c1, c2, c3, c4], k)
}

/// Φ₁, Φ₂ = z² + αz + β and 1/D₁, 1/D₂ (`certified::Szego`).
#[derive(Clone, Copy)]
struct Szego {
    c1: C,
    alpha: C,
    beta: C,
    inv_d1: V,
    inv_d2: V,
}

impl Szego {
    fn phi2(&self, f: &mut Func, z: C) -> C {
        let t = add(f, z, self.alpha);
        let t = mul(f, t, z);
        add(f, t, self.beta)
    }

    /// K₂(z) = 1 + |z − c₁|²/D₁ + |Φ₂(z)|²/D₂
    fn christoffel(&self, f: &mut Func, z: C) -> V {
        let one = f.c(1.0);
        let d = sub(f, z, self.c1);
        let n = norm2(f, d);
        let t = f.mul(n, self.inv_d1);
        let k = f.add(one, t);
        let p = self.phi2(f, z);
        let n = norm2(f, p);
        let t = f.mul(n, self.inv_d2);
        f.add(k, t)
    }

    fn mirrored(&self, f: &mut Func) -> Szego {
        Szego {
            c1: conj(f, self.c1),
            alpha: conj(f, self.alpha),
            beta: conj(f, self.beta),
            ..*self
        }
    }

    /// The other two nodes of the canonical representation through ζ and 1 if they exist
    /// (`Szego::canonical`: |Φ₂(ζ)|² > 0).
    fn canonical(&self, f: &mut Func, zeta: C) -> (V, C, C) {
        let zero = f.c(0.0);
        let one = f.c(1.0);
        let mone = f.c(-1.0);
        let half = f.c(0.5);
        let fz = self.phi2(f, zeta);
        let n2 = norm2(f, fz);
        let ok = flag(f, Cmp::Gt, n2, zero);
        let r = f.sqrt(n2);
        let inv = f.div(one, r);
        let v = scale(f, fz, inv);
        let zc = conj(f, zeta);
        let u = mul(f, zc, v);
        let t = mul(f, u, v);
        let bc = conj(f, self.beta);
        let s = mul(f, t, bc);
        let s = sub(f, s, self.alpha);
        let s = sub(f, s, zeta);
        let uc = conj(f, u);
        let p = mul(f, s, uc);
        let c = f.mul(p.re, half);
        let lowered = f.select(Cmp::Lt, c, mone, mone, c);
        let c = f.select(Cmp::Gt, c, one, one, lowered);
        let cc = f.mul(c, c);
        let d = f.sub(one, cc);
        let s = f.sqrt(d);
        let ns = f.neg(s);
        let z2 = mul(f, u, C { re: c, im: s });
        let z3 = mul(f, u, C { re: c, im: ns });
        (ok, z2, z3)
    }
}

/// What `certified::through` decided, as flags: optimal (with G) or unknown; failed
/// otherwise, with its nodes in A (the second only if `two`).
struct Through {
    optimal: V,
    unknown: V,
    g: V,
    nodes: [C; 2],
    two: V,
}

/// `certified::through` for the canonical representation through e^{ia} of `sz` with every
/// weight 1/K at least `least`.
fn through(f: &mut Func, sz: &Szego, ea: C, least: f32) -> Through {
    let zero = f.c(0.0);
    let one = f.c(1.0);
    let two = f.c(2.0);
    let ca = ea.re;
    let (exists, z2, z3) = sz.canonical(f, ea);
    let in2 = flag(f, Cmp::Gt, z2.re, ca);
    let in3 = flag(f, Cmp::Gt, z3.re, ca);
    let k = [
        sz.christoffel(f, ea),
        sz.christoffel(f, z2),
        sz.christoffel(f, z3),
    ];
    // every K ≤ 1/least (≤ +∞ when least = 0: K is not NaN)
    let kmax = 1.0f32 / least;
    let mut k_ok = one;
    for &ki in &k {
        let o = if kmax.is_finite() {
            let m = f.c(kmax);
            flag(f, Cmp::Le, ki, m)
        } else {
            not_nan(f, ki)
        };
        k_ok = and(f, k_ok, o);
    }
    // both nodes in A: feasible ⇔ f(e^{−ia}) ≥ f(e^{ia}), f = |· − z₂|²|· − z₃|²
    let prod = |f: &mut Func, z: C| {
        let a = sub(f, z, z2);
        let a = norm2(f, a);
        let b = sub(f, z, z3);
        let b = norm2(f, b);
        f.mul(a, b)
    };
    let eac = conj(f, ea);
    let f_seam = prod(f, eac);
    let f_zeta = prod(f, ea);
    let opt_both = flag(f, Cmp::Ge, f_seam, f_zeta);
    let ik = f.div(one, k[0]);
    let g_both = f.sub(one, ik);
    // one node x in A, y lit: the tangency test
    let x = pick(f, in2, z2, z3);
    let y = pick(f, in2, z3, z2);
    let kx = when(f, in2, k[1], k[2]);
    let u = mul(f, x, eac);
    let yc = conj(f, y);
    let v = mul(f, x, yc);
    let w = mul(f, x, ea);
    let du = f.sub(one, u.re);
    let dv = f.sub(one, v.re);
    let dw = f.sub(one, w.re);
    let at_a = flag(f, Cmp::Le, du, zero);
    let im_neg = flag(f, Cmp::Lt, u.im, zero);
    let im_up = not(f, im_neg);
    let at_a_lit = and(f, at_a, im_up);
    let dv_pos = flag(f, Cmp::Gt, dv, zero);
    let dv_bad = not(f, dv_pos);
    let dw_ok = not_nan(f, dw);
    let dw_nan = not(f, dw_ok);
    let unk_one = or(f, at_a_lit, dv_bad);
    let unk_one = or(f, unk_one, dw_nan);
    let dw_fail = flag(f, Cmp::Le, dw, zero);
    let du = tmax(f, du, zero);
    let t = f.mul(u.im, dv);
    let s = f.mul(two, v.im);
    let s = f.mul(s, du);
    let t = f.add(t, s);
    let t = f.neg(t);
    let lhs = f.mul(t, dw);
    let r = f.mul(w.im, du);
    let rhs = f.mul(r, dv);
    let pass = flag(f, Cmp::Ge, lhs, rhs);
    let dw_ok = not(f, dw_fail);
    let opt_one = and(f, pass, dw_ok);
    let g_one = f.div(one, kx);
    // cases
    let both = and(f, in2, in3);
    let either = or(f, in2, in3);
    let only_one = f.sub(either, both);
    let none = not(f, either);
    let bad = not(f, exists);
    let bad_k = not(f, k_ok);
    let unknown = or(f, bad, bad_k);
    let unknown = or(f, unknown, none);
    let u1 = and(f, only_one, unk_one);
    let unknown = or(f, unknown, u1);
    let known = not(f, unknown);
    let ob = and(f, both, opt_both);
    let oo = and(f, only_one, opt_one);
    let optimal = or(f, ob, oo);
    let optimal = and(f, known, optimal);
    Through {
        optimal,
        unknown,
        g: when(f, both, g_both, g_one),
        nodes: [pick(f, both, z2, x), z3],
        two: both,
    }
}

/// (III-s) of `certified::symmetric`: G = H₀/(cos d − cos a), cos d = Re H₁/H₀, the least of
/// its four weights, and 1 if it is a candidate (H₀ > 0, cos d ∈ (cos a, 1], least not NaN).
fn symmetric(f: &mut Func, fr: &Frame, cd: V, one_m_cd2: V) -> (V, V, V) {
    let zero = f.c(0.0);
    let one = f.c(1.0);
    let two = f.c(2.0);
    let half = f.c(0.5);
    let (ca, sa) = (fr.ea.re, fr.ea.im);
    let h0_pos = flag(f, Cmp::Gt, fr.h0, zero);
    let above = flag(f, Cmp::Gt, cd, ca);
    let at_most = flag(f, Cmp::Le, cd, one);
    let gap = f.sub(cd, ca);
    let g = f.div(fr.h0, gap);
    let sd = f.sqrt(one_m_cd2);
    let t = f.mul(two, cd);
    let t = f.mul(t, fr.c1.im);
    let n = f.sub(t, fr.c2.im);
    let t = f.mul(two, sa);
    let t = f.mul(t, gap);
    let da = f.div(n, t);
    let t = f.mul(two, ca);
    let t = f.mul(t, fr.c1.im);
    let n = f.sub(fr.c2.im, t);
    let t = f.mul(two, sd);
    let t = f.mul(t, gap);
    let dd = f.div(n, t);
    let t = f.sub(one, g);
    let ada = f.abs(da);
    let x = f.sub(t, ada);
    let add_ = f.abs(dd);
    let y = f.sub(g, add_);
    let m = tmin(f, x, y);
    let least = f.mul(m, half);
    let valid = not_nan(f, least);
    let valid = and(f, valid, h0_pos);
    let valid = and(f, valid, above);
    let valid = and(f, valid, at_most);
    (g, least, valid)
}

/// The other two nodes of the canonical representation through ζ from the 2×2 complex system
/// of `tmsm::canonical`, and 1 if they exist.
fn canonical(f: &mut Func, c1: C, c2: C, zeta: C) -> (V, C, C) {
    let zero = f.c(0.0);
    let one = f.c(1.0);
    let one = real(f, one);
    let a11 = sub(f, c1, zeta);
    let c1c = conj(f, c1);
    let t = mul(f, zeta, c1c);
    let a12 = sub(f, one, t);
    let a21 = a12;
    let c2c = conj(f, c2);
    let t = mul(f, zeta, c2c);
    let a22 = sub(f, c1c, t);
    let t = mul(f, zeta, c1);
    let r1 = sub(f, t, c2);
    let r2 = sub(f, zeta, c1);
    let p = mul(f, a11, a22);
    let q = mul(f, a12, a21);
    let det = sub(f, p, q);
    let n = norm2(f, det);
    let n_zero = flag(f, Cmp::Le, n, zero);
    let re_ok = not_nan(f, det.re);
    let p = mul(f, r1, a22);
    let q = mul(f, a12, r2);
    let num = sub(f, p, q);
    let alpha = div(f, num, det);
    let p = mul(f, a11, r2);
    let q = mul(f, a21, r1);
    let num = sub(f, p, q);
    let beta = div(f, num, det);
    let (z2, z3) = quadratic_roots(f, alpha, beta);
    let n2 = norm2(f, z2);
    let n3 = norm2(f, z3);
    let z2_zero = flag(f, Cmp::Le, n2, zero);
    let z3_zero = flag(f, Cmp::Le, n3, zero);
    let bad = or(f, n_zero, z2_zero);
    let bad = or(f, bad, z3_zero);
    let ok = not(f, bad);
    let ok = and(f, ok, re_ok);
    (ok, normalized(f, z2), normalized(f, z3))
}

/// G of `tmsm::sharp_bound::<f32>` for (biased) moments b = (sin, cos, sin 2·, cos 2·) and
/// z_f: NaN for NaN input, 0 for z_f ≤ 0, 1 for z_f ≥ 1; one Dirac, two Diracs, the lit arc
/// (G = 0), the certificates of (III-s), (I), (II) (docs/tmsm.md §4.6), the quartic's root
/// in the bracket of the canonical nodes, every root of the quartic, the full enumeration —
/// the first that applies, as in the solver.
pub(super) fn tmsm_into(f: &mut Func, b: &[V], zf: V) -> V {
    let tol = Tol::<f32>::get();
    let zero = f.c(0.0);
    let one = f.c(1.0);
    let half = f.c(0.5);
    let pi = f.c(std::f32::consts::PI);
    let a = f.mul(pi, zf);
    let ca = f.cos(a);
    let sa = f.sin(a);
    let ea = C { re: ca, im: sa };
    let rot = conj(f, ea);
    let c1 = mul(f, C { re: b[1], im: b[0] }, rot);
    let c2 = mul(f, C { re: b[3], im: b[2] }, rot);
    let c2 = mul(f, c2, rot);
    // one Dirac (§2)
    let m1 = norm2(f, c1);
    let d1 = f.sub(one, m1);
    let single = f.c(tol.single);
    let is_one = flag(f, Cmp::Le, d1, single);
    let p1 = normalized(f, c1);
    let g_one = mass_on_arc(f, &[(p1, one)], ca, tol.angle);
    // two Diracs: Schur parameter γ₂ (§2)
    let inv_d1 = f.div(one, d1);
    let cc = mul(f, c1, c1);
    let t = sub(f, c2, cc);
    let gamma = scale(f, t, inv_d1);
    let ng = norm2(f, gamma);
    let og = f.sub(one, ng);
    let double = f.c(tol.double);
    let is_two = flag(f, Cmp::Le, og, double);
    let beta = neg(f, gamma);
    let nc1 = neg(f, c1);
    let c1c = conj(f, c1);
    let t = mul(f, beta, c1c);
    let alpha = sub(f, nc1, t);
    let (z1, z2) = quadratic_roots(f, alpha, beta);
    let z1 = normalized(f, z1);
    let z2 = normalized(f, z2);
    let n = sub(f, c1, z2);
    let d = sub(f, z1, z2);
    let w1 = div_re(f, n, d);
    let w1 = tmin(f, one, w1);
    let w1 = tmax(f, zero, w1);
    let w2 = f.sub(one, w1);
    let g_two = mass_on_arc(f, &[(z1, w1), (z2, w2)], ca, tol.angle);
    // positive definite: H₀ = E[cos s − cos a], H₁ = E[(cos s − cos a) e^{is}] (§3)
    let h0 = f.sub(c1.re, ca);
    let one_c = real(f, one);
    let t = add(f, c2, one_c);
    let t = scale(f, t, half);
    let u = scale(f, c1, ca);
    let h1 = sub(f, t, u);
    let fr = Frame { c1, c2, ea, h0, h1 };
    let nh0 = f.neg(h0);
    let ah1 = {
        let n = norm2(f, h1);
        f.sqrt(n)
    };
    let lit = flag(f, Cmp::Ge, nh0, ah1);
    // the certificates (§4.6): (III-s), then (I)/(II) in the order of the side of Im c₁
    let cd = f.div(h1.re, h0);
    let cd2 = f.mul(cd, cd);
    let one_m_cd2 = f.sub(one, cd2);
    let (g_sym, least_sym, sym) = symmetric(f, &fr, cd, one_m_cd2);
    let cw = f.c(tol.certify_weight);
    let ub = f.c(tol.uncertain_below);
    let w_ok = flag(f, Cmp::Ge, least_sym, cw);
    let opt_sym = and(f, sym, w_ok);
    let w_unc = flag(f, Cmp::Ge, least_sym, ub);
    let unk_sym = and(f, sym, w_unc);
    let not_opt_sym = not(f, opt_sym);
    let unk_sym = and(f, unk_sym, not_opt_sym);
    let least = if 0.0 > tol.certify_weight {
        0.0
    } else {
        tol.certify_weight
    };
    let d2 = f.mul(d1, og);
    let inv_d2 = f.div(one, d2);
    let cdet = f.c(tol.certify_det);
    let det_ok = flag(f, Cmp::Ge, d2, cdet);
    let sz = Szego {
        c1,
        alpha,
        beta,
        inv_d1,
        inv_d2,
    };
    let mz = sz.mirrored(f);
    let th = through(f, &sz, ea, least);
    let tm = through(f, &mz, ea, least);
    let tm_nodes = [conj(f, tm.nodes[0]), conj(f, tm.nodes[1])];
    let mirror_first = flag(f, Cmp::Lt, c1.im, zero);
    let sel = |f: &mut Func, first: bool, x: V, y: V| {
        if first {
            when(f, mirror_first, y, x)
        } else {
            when(f, mirror_first, x, y)
        }
    };
    let o1 = sel(f, true, th.optimal, tm.optimal);
    let u1 = sel(f, true, th.unknown, tm.unknown);
    let g1 = sel(f, true, th.g, tm.g);
    let o2 = sel(f, false, th.optimal, tm.optimal);
    let u2 = sel(f, false, th.unknown, tm.unknown);
    let g2 = sel(f, false, th.g, tm.g);
    let hint_of = |f: &mut Func, first: bool| -> [(C, V); 2] {
        let flip = if first {
            mirror_first
        } else {
            not(f, mirror_first)
        };
        [
            (pick(f, flip, tm_nodes[0], th.nodes[0]), one),
            (
                pick(f, flip, tm_nodes[1], th.nodes[1]),
                when(f, flip, tm.two, th.two),
            ),
        ]
    };
    let h1s = hint_of(f, true);
    let h2s = hint_of(f, false);
    // verdict: Optimal (G), Unknown, or Quartic
    let gate = not(f, unk_sym);
    let gate = and(f, gate, det_ok);
    let gate = and(f, gate, not_opt_sym);
    let f1 = or(f, o1, u1);
    let failed1 = not(f, f1);
    let o2_ok = and(f, failed1, o2);
    let opt_canon = or(f, o1, o2_ok);
    let opt_canon = and(f, gate, opt_canon);
    let optimal = or(f, opt_sym, opt_canon);
    let g_canon = when(f, o1, g1, g2);
    let g_cert = when(f, opt_sym, g_sym, g_canon);
    let f2 = or(f, o2, u2);
    let failed2 = not(f, f2);
    let quartic = and(f, gate, failed1);
    let quartic = and(f, quartic, failed2);
    // (III-q) in the bracket of the hint nodes (§4.6)
    let (coef, k) = quartic_coef(f, &fr);
    let mut lo = one;
    let mut hi = f.c(-1.0);
    for &(z, valid) in h1s.iter().chain(&h2s) {
        let t = f.add(one, z.re);
        let t = f.mul(t, k);
        let s = f.div(z.im, t);
        let l = tmin(f, lo, s);
        lo = when(f, valid, l, lo);
        let h = tmax(f, hi, s);
        hi = when(f, valid, h, hi);
    }
    let mone = f.c(-1.0);
    let lo = tmax(f, lo, mone);
    let hi = tmin(f, hi, one);
    let ordered = flag(f, Cmp::Lt, lo, hi);
    let plo = horner_p(f, &coef, lo);
    let phi = horner_p(f, &coef, hi);
    let nlo = flag(f, Cmp::Lt, plo, zero);
    let nhi = flag(f, Cmp::Lt, phi, zero);
    let d = f.sub(nlo, nhi);
    let same = is_zero(f, d);
    let zlo = is_zero(f, plo);
    let zhi = is_zero(f, phi);
    let no_change = or(f, same, zlo);
    let no_change = or(f, no_change, zhi);
    let change = not(f, no_change);
    let sigma = newton_into(f, &coef, lo, hi, plo, phi);
    let qb = quartic_candidate(f, &fr, sigma, k, &tol);
    let (g_b, kept_b) = improve(f, one, &qb);
    let bracketed = and(f, ordered, change);
    let bracketed = and(f, bracketed, kept_b);
    // every root of the quartic in (−1, 1) (§4.4)
    let roots = roots_into(f, &coef);
    let cands: Vec<Quartic> = roots
        .iter()
        .map(|s| {
            let q = quartic_candidate(f, &fr, s.x, k, &tol);
            Quartic {
                g: q.g,
                feasible: and(f, q.feasible, s.valid),
            }
        })
        .collect();
    let mut g_iso = one;
    let mut isolated = zero;
    for q in &cands {
        let (g, kept) = improve(f, g_iso, q);
        g_iso = g;
        isolated = or(f, isolated, kept);
    }
    // the full enumeration (§4): (I), (II), (III-s), then (III-q) unless G = 0 already
    let mut best = one;
    let ema = conj(f, ea);
    for zeta in [ea, ema] {
        let (exists, z2, z3) = canonical(f, c1, c2, zeta);
        let w = weights3(f, [zeta, z2, z3], c1, c2);
        let mut g = zero;
        for (z, wi) in [(z2, w[1]), (z3, w[2])] {
            let gw = f.add(g, wi);
            g = f.select(Cmp::Gt, z.re, ca, gw, g);
        }
        let ok = all_at_least(f, &w, tol.weight);
        let below = flag(f, Cmp::Lt, g, best);
        let take = and(f, exists, ok);
        let take = and(f, take, below);
        best = when(f, take, g, best);
    }
    let h0_pos = flag(f, Cmp::Gt, h0, zero);
    let above = flag(f, Cmp::Gt, cd, ca);
    let at_most = flag(f, Cmp::Le, cd, one);
    let hh = f.mul(h0, h0);
    let t = f.mul(h0, ca);
    let t = f.sub(h1.re, t);
    let g_s = f.div(hh, t);
    let m = tmax(f, zero, one_m_cd2);
    let sd = f.sqrt(m);
    let ed = C { re: cd, im: sd };
    let edc = conj(f, ed);
    let nodes = [ea, ema, ed, edc];
    let w: Vec<V> = (0..4).map(|i| weight4(f, &nodes, i, c1, c2)).collect();
    let ok = all_at_least(f, &w, tol.weight);
    let below = flag(f, Cmp::Lt, g_s, best);
    let take = and(f, h0_pos, above);
    let take = and(f, take, at_most);
    let take = and(f, take, below);
    let take = and(f, take, ok);
    best = when(f, take, g_s, best);
    let positive = flag(f, Cmp::Gt, best, zero);
    let mut g_q = best;
    for q in &cands {
        g_q = improve(f, g_q, q).0;
    }
    let g_enum = when(f, positive, g_q, best);
    // the first that applies
    let g_enum = unit(f, g_enum);
    let g_iso = unit(f, g_iso);
    let g_b = unit(f, g_b);
    let g_cert = unit(f, g_cert);
    let q_iso = and(f, quartic, isolated);
    let g = when(f, q_iso, g_iso, g_enum);
    let q_b = and(f, quartic, bracketed);
    let g = when(f, q_b, g_b, g);
    let g = when(f, optimal, g_cert, g);
    let g = when(f, lit, zero, g);
    let g = when(f, is_two, g_two, g);
    let g = when(f, is_one, g_one, g);
    let g = f.select(Cmp::Ge, zf, one, one, g);
    let g = f.select(Cmp::Le, zf, zero, zero, g);
    // NaN in → NaN out
    let mut ok = not_nan(f, zf);
    let mut sum = zf;
    for &bj in b {
        let o = not_nan(f, bj);
        ok = and(f, ok, o);
        sum = f.add(sum, bj);
    }
    when(f, ok, g, sum)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shader::Shape;
    use crate::technique::linalg::bias;
    use crate::technique::tmsm::{self, roots_in_interval, Case, Route};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use std::collections::BTreeMap;

    /// TMSM moments (sin 2πz, cos 2πz, sin 4πz, cos 4πz) of Diracs (depth, weight), in f64.
    fn moments(atoms: &[(f64, f64)]) -> [f64; 4] {
        let s: f64 = atoms.iter().map(|a| a.1).sum();
        let mut b = [0.0; 4];
        let mut row = [0.0; 4];
        for &(z, w) in atoms {
            tmsm::basis(z, &mut row);
            for j in 0..4 {
                b[j] += w / s * row[j];
            }
        }
        b
    }

    /// Distributions of the families of tests/technique/tmsm_equiv.rs: random 1–6 Diracs (some
    /// clustered), one Dirac with z_f at it or next to it, two Diracs (one at the seam, or
    /// 1e-5…1e-3 apart with z_f at one of them), tight clusters, Diracs at 0 or z_f, lit arcs,
    /// z_f near 0 or 1, near-singular Toeplitz matrices, moments just outside the moment space.
    fn input(rng: &mut ChaCha8Rng, i: usize) -> ([f64; 4], f64) {
        let mut z = || rng.gen::<f64>();
        match i % 12 {
            0 => {
                let d = z();
                let zf = d + [0.0, 1e-7, -1e-7, 1e-4, -1e-4][i / 12 % 5];
                (moments(&[(d, 1.0)]), zf)
            }
            1 => {
                let d0 = if i.is_multiple_of(5) { 0.0 } else { z() };
                (moments(&[(d0, z() + 0.01), (z(), z() + 0.01)]), z())
            }
            2 => {
                let c = z() * 0.9 + 0.05;
                let atoms: Vec<_> = (0..3 + i % 3)
                    .map(|_| (c + 1e-4 * z(), z() + 0.01))
                    .collect();
                (moments(&atoms), c + 2e-4 * (z() - 0.25))
            }
            3 => {
                let zf = z();
                let first = if i.is_multiple_of(2) { 0.0 } else { zf };
                (moments(&[(first, 0.3), (z(), 0.3), (z(), 0.4)]), zf)
            }
            4 => {
                let zf = 0.05 + 0.5 * z();
                let atoms: Vec<_> = (0..4)
                    .map(|_| (zf + (1.0 - zf) * z(), z() + 0.01))
                    .collect();
                (moments(&atoms), zf)
            }
            5 => {
                let atoms: Vec<_> = (0..3).map(|_| (z(), z() + 0.01)).collect();
                (
                    moments(&atoms),
                    [1e-7, 1e-5, 1.0 - 1e-5, 1.0 - 1e-7][i / 12 % 4],
                )
            }
            6 => {
                let eps = [1e-9, 1e-7, 1e-5, 1e-3][i / 12 % 4];
                (moments(&[(z(), 0.5), (z(), 0.5 - eps), (z(), eps)]), z())
            }
            7 => {
                let b = moments(&[(z(), 0.5), (z(), 0.5)]).map(|v| v * (1.0 + 1e-6));
                (b, z())
            }
            8 => {
                let d = 0.05 + 0.9 * z();
                let gap = [1e-5, 1e-4, 1e-3][i / 12 % 3];
                let zf = [d, d + gap, d + 0.5 * gap, d + 2.0 * gap][i / 36 % 4];
                (moments(&[(d, 0.2 + 0.6 * z()), (d + gap, 1.0)]), zf)
            }
            9 => {
                let (c0, c1) = (0.1 + 0.3 * z(), 0.6 + 0.3 * z());
                let atoms = [
                    (c0, 0.3),
                    (c0 + 1e-3, 0.2),
                    (c1, 0.3),
                    (c1 + 1e-3 * z(), 0.2),
                ];
                (moments(&atoms), 0.5 * (c0 + c1))
            }
            _ => {
                let k = 1 + i / 12 % 6;
                let centre = z();
                let spread = if i.is_multiple_of(3) { 0.05 } else { 1.0 };
                let atoms: Vec<_> = (0..k)
                    .map(|_| ((centre + spread * z()).fract(), z() + 0.02))
                    .collect();
                (moments(&atoms), z())
            }
        }
    }

    fn kernel() -> Func {
        let mut f = Func::new("k");
        let b = f.input("b", Shape::Array(4));
        let zf = f.input_scalar("zf");
        let g = tmsm_into(&mut f, &b, zf);
        f.ret(Shape::Scalar, &[g]);
        f
    }

    #[test]
    fn tmsm_equals_the_f32_solver_bit_for_bit_in_every_branch() {
        let k = kernel();
        k.validate().unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(31);
        let (mut cases, mut routes) = (BTreeMap::new(), BTreeMap::new());
        let (mut scratch, mut out) = (Vec::new(), [0.0f32]);
        let mut check = |b: [f32; 4], zf: f32| {
            let (own, case, route) = tmsm::sharp_bound_route(b, zf);
            *cases.entry(format!("{case:?}")).or_insert(0usize) += 1;
            *routes.entry(format!("{route:?}")).or_insert(0usize) += 1;
            let input = [b[0], b[1], b[2], b[3], zf];
            k.eval_into(&input, &mut scratch, &mut out).unwrap();
            let ir = out[0];
            assert!(
                ir.to_bits() == own.to_bits() || (ir.is_nan() && own.is_nan()),
                "b = {b:?}, z_f = {zf}: {ir} vs {own} ({case:?}, {route:?})"
            );
        };
        // Every 59th input, and every input that leaves the certified or bracketed routes
        // (a few in 10⁵: the full enumeration, and every root of the quartic).
        for i in 0..1_500_000 {
            let (b, zf) = input(&mut rng, i);
            let alpha = [0.0f32, 1e-6, 3e-5][i % 3];
            let b = b.map(|v| bias(v as f32, alpha, 0.0));
            let route = tmsm::sharp_bound_route(b, zf as f32).2;
            if i.is_multiple_of(59) || matches!(route, Route::Enumerated | Route::Isolated) {
                check(b, zf as f32);
            }
        }
        for i in 0..40 {
            let (b, _) = input(&mut rng, i);
            let zf = [-0.1f32, 0.0, 1.0, 1.5][i % 4];
            check(b.map(|v| v as f32), zf);
        }
        check([0.1, 0.2, 0.3, 0.4], f32::NAN);
        check([f32::NAN, 0.0, 0.0, 0.0], 0.5);
        eprintln!("cases {cases:?}, routes {routes:?}");
        for c in [
            Case::Trivial,
            Case::OneDirac,
            Case::TwoDiracs,
            Case::LitArc,
            Case::ThroughZf,
            Case::ThroughZero,
            Case::Symmetric,
            Case::Quartic,
        ] {
            assert!(
                cases.get(&format!("{c:?}")).is_some_and(|&n| n > 20),
                "{c:?}: {cases:?}"
            );
        }
        for r in [Route::Certified, Route::Bracketed, Route::Enumerated] {
            assert!(
                routes.get(&format!("{r:?}")).is_some_and(|&n| n > 20),
                "{r:?}: {routes:?}"
            );
        }
    }

    /// Ascending coefficients of lead·Π(σ − r_i) in f64, rounded to f32.
    fn poly(roots: &[f64], lead: f64) -> [f32; 5] {
        let mut c = [0.0f64; 5];
        c[0] = lead;
        for (n, &x) in roots.iter().enumerate() {
            for j in (0..=n + 1).rev() {
                let lower = if j > 0 { c[j - 1] } else { 0.0 };
                c[j] = lower - x * c[j];
            }
        }
        c.map(|v| v as f32)
    }

    #[test]
    fn quartic_roots_equal_the_f32_isolation_bit_for_bit() {
        let mut f = Func::new("roots");
        let c = f.input("c", Shape::Array(5));
        let slots = roots_into(&mut f, &[c[0], c[1], c[2], c[3], c[4]]);
        let vals: Vec<V> = slots.iter().flat_map(|s| [s.x, s.valid]).collect();
        f.output("slots", Shape::Array(8), &vals);
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        let mut counts = [0usize; 5];
        for i in 0..20_000 {
            let r = |rng: &mut ChaCha8Rng| rng.gen_range(-1.3..1.3);
            let c = match i % 5 {
                // four roots, some in (−1, 1)
                0 => poly(&[r(&mut rng), r(&mut rng), r(&mut rng), r(&mut rng)], 1.7),
                // a double or nearly double root
                1 => {
                    let x = r(&mut rng);
                    let gap = [0.0, 1e-7, 1e-5, 1e-3][i / 5 % 4];
                    poly(&[x, x + gap, r(&mut rng), r(&mut rng)], -0.6)
                }
                // a root near infinity (the leading coefficient small)
                2 => poly(&[r(&mut rng), r(&mut rng), r(&mut rng), 3e4], 1e-4),
                // lower degree (leading coefficients exactly 0)
                3 => {
                    let n = 1 + i / 5 % 3;
                    let roots: Vec<f64> = (0..n).map(|_| r(&mut rng)).collect();
                    poly(&roots, 2.0)
                }
                // random coefficients, sometimes all 0
                _ => {
                    let z = i / 5 % 50 == 0;
                    [0; 5].map(|_| if z { 0.0 } else { rng.gen_range(-1.0f32..1.0) })
                }
            };
            let mut want = [0.0f32; 4];
            let n = roots_in_interval(c, -1.0, 1.0, &mut want);
            counts[n] += 1;
            let got = f.eval(&c).unwrap();
            let found: Vec<f32> = got
                .chunks(2)
                .filter(|p| p[1] == 1.0)
                .map(|p| p[0])
                .collect();
            assert!(got.chunks(2).all(|p| p[1] == 0.0 || p[1] == 1.0));
            assert_eq!(found.len(), n, "{c:?}: {found:?} vs {:?}", &want[..n]);
            for (g, w) in found.iter().zip(&want[..n]) {
                assert_eq!(
                    g.to_bits(),
                    w.to_bits(),
                    "{c:?}: {found:?} vs {:?}",
                    &want[..n]
                );
            }
        }
        // every root count occurs
        assert!(counts.iter().all(|&n| n > 100), "{counts:?}");
    }
}
