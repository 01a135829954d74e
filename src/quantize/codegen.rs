//! Shader encode/decode functions for a θ, built on [`crate::shader`] so that the GLSL, the HLSL
//! and the f32 interpreter run the same operations.
//!
//! * Encoder: each stored channel s_i(z) = t_i + Σ_j A_ij b_j(z) is written as a Chebyshev series
//!   Σ_k c_ik T_k(2z − 1) and evaluated by Clenshaw's recurrence
//!   (β_k = c_k + 2x·β_{k+1} − β_{k+2}, s = c_0 + x·β_1 − β_2). The monomial form has
//!   coefficients up to ~5·10⁴ for θ₈ and loses ~10⁻³ in f32; the Chebyshev coefficients stay
//!   below 1 (|T_k| ≤ 1 on [0,1]). For polynomial bases the series is exact (degree = largest
//!   exponent); for other bases it is the Chebyshev interpolant of θ∘b, with the degree chosen
//!   so that it matches θ∘b to 10⁻⁹ on a dense grid (else the encoder takes b[] from the caller).
//!   The result is clamped to [0,1] (the series is inside up to f32 rounding).
//! * Decoder: b = A⁻¹·(s − t), one product and one sum per coefficient.

use super::curve::Curve;
use super::theta::Theta;
use crate::shader::{Func, Module, Shape, V};
use anyhow::{bail, Result};

/// Chebyshev coefficients of the rows of θ∘b (c[i][k] multiplies T_k(2z − 1)) and the largest
/// deviation of the series from θ∘b on 8193 points of [0,1] (f64).
#[derive(Clone, Debug, PartialEq)]
pub struct ChebyshevRows {
    /// `coeffs[i][k]`: coefficient of T_k(2z − 1) in row i of θ∘b.
    pub coeffs: Vec<Vec<f64>>,
    /// max over the 8193 points and rows of |series − θ∘b|.
    pub max_fit_error: f64,
}

/// Evaluate Σ_k c_k T_k(x) in f64 by Clenshaw's recurrence.
pub fn clenshaw_f64(c: &[f64], x: f64) -> f64 {
    let (mut b1, mut b2) = (0.0, 0.0);
    for &ck in c.iter().skip(1).rev() {
        let b0 = ck + 2.0 * x * b1 - b2;
        b2 = b1;
        b1 = b0;
    }
    c.first().copied().unwrap_or(0.0) + x * b1 - b2
}

/// Chebyshev interpolant of degree n of each row at the n+1 Chebyshev points of the first kind.
fn interpolate(theta: &Theta, curve: &dyn Curve, n: usize) -> Vec<Vec<f64>> {
    let m = theta.m();
    let pts = n + 1;
    let mut vals = vec![vec![0.0; pts]; m];
    let (mut b, mut s) = (vec![0.0; m], vec![0.0; m]);
    for j in 0..pts {
        let x = (std::f64::consts::PI * (j as f64 + 0.5) / pts as f64).cos();
        curve.eval(0.5 * (x + 1.0), &mut b);
        theta.encode(&b, &mut s);
        for i in 0..m {
            vals[i][j] = s[i];
        }
    }
    vals.iter()
        .map(|v| {
            (0..=n)
                .map(|k| {
                    let sum: f64 = (0..pts)
                        .map(|j| {
                            v[j] * (std::f64::consts::PI * k as f64 * (j as f64 + 0.5) / pts as f64)
                                .cos()
                        })
                        .sum();
                    sum * if k == 0 { 1.0 } else { 2.0 } / pts as f64
                })
                .collect()
        })
        .collect()
}

fn fit_error(theta: &Theta, curve: &dyn Curve, coeffs: &[Vec<f64>]) -> f64 {
    let m = theta.m();
    let (mut b, mut s) = (vec![0.0; m], vec![0.0; m]);
    let mut worst: f64 = 0.0;
    for k in 0..=8192 {
        let z = k as f64 / 8192.0;
        curve.eval(z, &mut b);
        theta.encode(&b, &mut s);
        for (row, &si) in coeffs.iter().zip(&s) {
            worst = worst.max((clenshaw_f64(row, 2.0 * z - 1.0) - si).abs());
        }
    }
    worst
}

/// The Chebyshev form of θ∘b: exact degree for monomial bases, otherwise the smallest
/// interpolant (degree ≤ 160) within 10⁻⁹ of θ∘b, trimmed of negligible trailing terms.
pub fn chebyshev_rows(theta: &Theta, curve: &dyn Curve) -> Result<ChebyshevRows> {
    if curve.dim() != theta.m() {
        bail!(
            "theta has {} rows but the basis has {} functions",
            theta.m(),
            curve.dim()
        );
    }
    if let Some(e) = curve.monomial_exponents() {
        let n = *e.iter().max().unwrap_or(&0) as usize;
        let coeffs = interpolate(theta, curve, n);
        let max_fit_error = fit_error(theta, curve, &coeffs);
        return Ok(ChebyshevRows {
            coeffs,
            max_fit_error,
        });
    }
    const TOL: f64 = 1e-9;
    let mut n = 8;
    while n <= 160 {
        let mut coeffs = interpolate(theta, curve, n);
        // trim trailing terms whose absolute sum stays below TOL / 4
        let mut keep = n + 1;
        while keep > 1 {
            let tail: f64 = coeffs
                .iter()
                .map(|r| r[keep - 1..].iter().map(|c| c.abs()).sum::<f64>())
                .fold(0.0, f64::max);
            if tail > TOL / 4.0 {
                break;
            }
            keep -= 1;
        }
        coeffs.iter_mut().for_each(|r| r.truncate(keep));
        let max_fit_error = fit_error(theta, curve, &coeffs);
        if max_fit_error <= TOL {
            return Ok(ChebyshevRows {
                coeffs,
                max_fit_error,
            });
        }
        n = n * 3 / 2;
    }
    bail!("theta∘b has no Chebyshev series of degree ≤ 160 within 1e-9 (basis not smooth enough)")
}

/// Append Clenshaw's recurrence for Σ_k c_k T_k(x) to `f` (x and 2x given); returns the value.
/// Terms with a zero coefficient still take part (the recurrence is the same for every row).
pub fn clenshaw_into(f: &mut Func, x: V, x2: V, c: &[f64]) -> V {
    let n = c.len();
    if n == 0 {
        return f.c(0.0);
    }
    if n == 1 {
        return f.c64(c[0]);
    }
    // β_{n-1} = c_{n-1}; β_n = 0
    let mut b1 = f.c64(c[n - 1]);
    let mut b2: Option<V> = None;
    for k in (1..n - 1).rev() {
        let p = f.mul(x2, b1);
        let q = match b2 {
            Some(b2) => f.sub(p, b2),
            None => p,
        };
        let ck = f.c64(c[k]);
        let b0 = f.add(q, ck);
        b2 = Some(b1);
        b1 = b0;
    }
    let p = f.mul(x, b1);
    let q = match b2 {
        Some(b2) => f.sub(p, b2),
        None => p,
    };
    let c0 = f.c64(c[0]);
    f.add(q, c0)
}

/// Append the encoder of θ for depth `z` to `f`: s_i by Clenshaw, clamped to [0,1].
pub fn encode_into(f: &mut Func, rows: &ChebyshevRows, z: V) -> Vec<V> {
    let two = f.c(2.0);
    let one = f.c(1.0);
    let zero = f.c(0.0);
    let z2 = f.mul(z, two);
    let x = f.sub(z2, one);
    f.note(x, "x = 2z - 1");
    let x2 = f.add(x, x);
    rows.coeffs
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let s = clenshaw_into(f, x, x2, c);
            let s = f.clamp(s, zero, one);
            f.note(s, &format!("stored channel {i}"));
            s
        })
        .collect()
}

/// Append the matrix form of the encoder, s = A·b + t for basis values b computed by the
/// caller, clamped to [0,1] (for bases without a Chebyshev form).
pub fn encode_matrix_into(f: &mut Func, theta: &Theta, b: &[V]) -> Vec<V> {
    let zero = f.c(0.0);
    let one = f.c(1.0);
    theta
        .matrix
        .iter()
        .zip(&theta.offset)
        .map(|(row, &t)| {
            let mut acc = f.c64(t);
            for (&a, &bj) in row.iter().zip(b) {
                let a = f.c64(a);
                let p = f.mul(a, bj);
                acc = f.add(acc, p);
            }
            f.clamp(acc, zero, one)
        })
        .collect()
}

/// Append the decoder b = A⁻¹·(s − t) to `f`; returns b (basis values, e.g. z, z², …).
pub fn decode_into(f: &mut Func, theta: &Theta, s: &[V]) -> Vec<V> {
    let d: Vec<V> = s
        .iter()
        .zip(&theta.offset)
        .map(|(&si, &t)| {
            if t as f32 == 0.0 {
                si
            } else {
                let t = f.c64(t);
                f.sub(si, t)
            }
        })
        .collect();
    theta
        .inverse
        .iter()
        .map(|row| {
            let mut acc: Option<V> = None;
            for (&a, &dj) in row.iter().zip(&d) {
                let a = f.c64(a);
                let p = f.mul(a, dj);
                acc = Some(match acc {
                    Some(acc) => f.add(acc, p),
                    None => p,
                });
            }
            acc.unwrap_or_else(|| f.c(0.0))
        })
        .collect()
}

/// Vector parameters holding m channels: float4 chunks, the last one float2/3 or a scalar.
pub fn vector_shapes(m: usize) -> Vec<Shape> {
    (0..m)
        .step_by(4)
        .map(|i| match (m - i).min(4) {
            1 => Shape::Scalar,
            n => Shape::Vector(n),
        })
        .collect()
}

/// Names of the vector chunks ("s0123", "s45", …) with the given prefix.
fn chunk_names(prefix: &str, m: usize) -> Vec<String> {
    (0..m)
        .step_by(4)
        .map(|i| {
            let ids: String = (i..m.min(i + 4)).map(|k| k.to_string()).collect();
            format!("{prefix}{ids}")
        })
        .collect()
}

/// How the stored channels are passed: one array, or float4 chunks (m ≤ 4: returned).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Layout {
    /// One `float m[]` array.
    Array,
    /// float4 chunks (the last one shorter when m is not a multiple of 4).
    Vectors,
}

/// Shader function names for θ with tag `tag` ("4", "_3eae1070", …).
pub fn names(tag: &str, layout: Layout, hlsl_style: bool) -> (String, String) {
    let suffix = match layout {
        Layout::Array => "",
        Layout::Vectors => "Vec",
    };
    if hlsl_style {
        (
            format!("EncodeMoments{tag}{suffix}"),
            format!("DecodeMoments{tag}{suffix}"),
        )
    } else {
        (
            format!("encodeMoments{tag}{suffix}"),
            format!("decodeMoments{tag}{suffix}"),
        )
    }
}

/// What the encoder takes.
#[derive(Clone, Debug, PartialEq)]
pub enum EncoderForm {
    /// From the depth z, Chebyshev/Clenshaw.
    Chebyshev(ChebyshevRows),
    /// From basis values b[] computed by the caller, s = A·b + t.
    Matrix,
}

fn set_outputs(f: &mut Func, name: &str, layout: Layout, vals: &[V], ret_if_single: bool) {
    let m = vals.len();
    match layout {
        Layout::Array => f.output(name, Shape::Array(m), vals),
        Layout::Vectors => {
            let shapes = vector_shapes(m);
            let names = chunk_names(name, m);
            if ret_if_single && shapes.len() == 1 {
                f.ret(shapes[0], vals);
            } else {
                for (k, (sh, n)) in shapes.iter().zip(&names).enumerate() {
                    f.output(n, *sh, &vals[4 * k..(4 * k + sh.len()).min(m)]);
                }
            }
        }
    }
}

fn inputs(f: &mut Func, name: &str, layout: Layout, m: usize) -> Vec<V> {
    match layout {
        Layout::Array => f.input(name, Shape::Array(m)),
        Layout::Vectors => vector_shapes(m)
            .into_iter()
            .zip(chunk_names(name, m))
            .flat_map(|(sh, n)| f.input(&n, sh))
            .collect(),
    }
}

/// The encoder function: `encodeMoments{tag}(float z, out float s[m])` (array layout) or
/// `vec4 encodeMoments{tag}Vec(float z)` / `void …Vec(float z, out vec4 s0123, out vec2 s45)`.
pub fn encoder(theta: &Theta, form: &EncoderForm, name: &str, layout: Layout) -> Func {
    let m = theta.m();
    let mut f = Func::new(name);
    let s = match form {
        EncoderForm::Chebyshev(rows) => {
            let z = f.input_scalar("z");
            encode_into(&mut f, rows, z)
        }
        EncoderForm::Matrix => {
            let b = inputs(&mut f, "b", layout, m);
            encode_matrix_into(&mut f, theta, &b)
        }
    };
    set_outputs(&mut f, "s", layout, &s, true);
    f
}

/// The decoder function: `decodeMoments{tag}(float s[m], out float b[m])` or
/// `vec4 decodeMoments{tag}Vec(vec4 s)` / `void …Vec(vec4 s0123, vec2 s45, out vec4 b0123, out vec2 b45)`.
pub fn decoder(theta: &Theta, name: &str, layout: Layout) -> Func {
    let m = theta.m();
    let mut f = Func::new(name);
    let s = inputs(&mut f, "s", layout, m);
    let b = decode_into(&mut f, theta, &s);
    set_outputs(&mut f, "b", layout, &b, true);
    f
}

/// The module with the array and the vector variants of encoder and decoder.
pub fn module(
    theta: &Theta,
    form: &EncoderForm,
    tag: &str,
    hlsl_style: bool,
    header: &[String],
) -> Module {
    let mut funcs = Vec::new();
    for layout in [Layout::Array, Layout::Vectors] {
        let (e, d) = names(tag, layout, hlsl_style);
        funcs.push(encoder(theta, form, &e, layout));
        funcs.push(decoder(theta, &d, layout));
    }
    Module {
        header: header.to_vec(),
        funcs,
    }
}

/// Channel order of emitted θ₂/θ₄ (other transforms have only the search's order).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ChannelOrder {
    /// The 2015 paper's rows and signs (MJP's Shadows sample, Unity HDRP), where they exist.
    Paper,
    /// The rows as the search found them.
    Search,
}

/// Everything emitted for one θ: GLSL-named and HLSL-named modules (array and vector variants of
/// encoder and decoder), the θ in the emitted channel order, and the encoder form.
#[derive(Clone, Debug)]
pub struct Snippet {
    /// Modules with GLSL-style names.
    pub glsl: Module,
    /// Modules with HLSL-style names.
    pub hlsl: Module,
    /// θ with its rows in the emitted channel order.
    pub theta: Theta,
    /// What the encoder takes (the depth, or the basis values).
    pub form: EncoderForm,
    /// "paper" or "search".
    pub order: &'static str,
}

/// Recommended moment bias for the power basis with m moments: b' = (1 − α)·b + α·b*.
fn bias_lines(m: usize) -> Vec<String> {
    match m {
        2 => vec!["Reconstruction: VSM (Chebyshev/Cantelli); no moment bias α, clamp the variance from below instead.".into()],
        4 => vec![
            "Reconstruction: Hamburger or Hausdorff 4MSM with biased moments b' = (1 - α) b + α b*, b* = (0.5, 0.5, 0.5, 0.5);".into(),
            "α = 3e-5 with 16-bit UNORM storage, α = 2e-6 with 32-bit float storage (Peters & Klein 2015, Sections 4.3 and 5).".into(),
        ],
        6 => vec![
            "Reconstruction: Hamburger 6MSM with b' = (1 - α) b + α b*, b* = (0.5, ..., 0.5);".into(),
            "α = 1e-4 with 16-bit UNORM storage, α = 1e-6 with 32-bit float storage (smallest usable α, momentlab quantize study, docs/theta.md).".into(),
        ],
        8 => vec![
            "Reconstruction: Hamburger MSM with 8 moments, b* = (0.5, ..., 0.5); momentlab's quantize study found no α that makes it".into(),
            "usable with 16-bit storage (deviation ≈ 2e-2), and 32-bit floats deviate ≈ 8e-3 at every α (docs/theta.md).".into(),
        ],
        _ => vec!["Moment bias α, b*: depend on the reconstruction (none recommended for this m).".into()],
    }
}

/// The shader snippet for θ over `curve` with function tag `tag` ("4", "_3eae1070").
pub fn snippet(
    theta: &Theta,
    curve: &dyn Curve,
    tag: &str,
    order: ChannelOrder,
) -> Result<Snippet> {
    let m = theta.m();
    // θ₂/θ₄ by default: the published transform itself, so that engines' existing decoders
    // read the texels (a search's θ₄ lies on the same optimum up to flat directions of det A,
    // rows permuted and reflected; see theta::paper_order)
    let (th, order) = match (order, super::theta::paper_order(theta)) {
        (ChannelOrder::Paper, Some(_)) => (
            super::theta::published(m).unwrap_or_else(|| theta.clone()),
            "paper",
        ),
        _ => (theta.clone(), "search"),
    };
    let form = match chebyshev_rows(&th, curve) {
        Ok(rows) => EncoderForm::Chebyshev(rows),
        Err(_) => EncoderForm::Matrix,
    };
    let power = matches!(curve.monomial_exponents(), Some(e) if e.iter().copied().eq(1..=m as u32));
    let mut h = vec![
        format!(
            "Moment quantization θ{} (momentlab theta; Peters & Klein 2015, Section 4.3): stored s = A*b(z) + t in [0,1]^{m}.",
            if power { m.to_string() } else { String::new() }
        ),
        format!(
            "Basis b = ({}), m = {m}; entropy gain log2|det A| = {:.4} bits.",
            th.basis.join(", "),
            th.gain_bits()
        ),
        format!(
            "Depth range: z in [0,1] (for depths d in [-1,1], e.g. HDRP's HDIMS path, encode z = 0.5*d + 0.5 and use [0,1] depths in the reconstruction)."
        ),
        format!(
            "Moment order: the decoder returns b = ({}) of the filtered depth distribution, in this order.",
            th.basis.join(", ")
        ),
    ];
    h.push(match (order, m) {
        ("paper", 4) => "Transform: the 2015 paper's θ4 as published (the one MJP's Shadows sample and Unity HDRP ship; offset 0.035955884801 there, 0.0359558848 in the paper), so engines' decoders read these texels.".into(),
        ("paper", _) => "Transform: the 2015 paper's θ2 as published (rows [1, 0] and [4, -4]).".into(),
        _ => "Channel order: as found by momentlab's search.".into(),
    });
    h.push(match &form {
        EncoderForm::Chebyshev(_) => "Encoder: each channel as a Chebyshev series in x = 2z - 1 (Clenshaw's recurrence), accurate in f32; clamped to [0,1].".into(),
        EncoderForm::Matrix => "Encoder: takes the basis values b[] computed by the caller (no accurate polynomial form); clamped to [0,1].".into(),
    });
    h.push(
        "Store s (16-bit UNORM or 32-bit float), filter linearly, decode the filtered sample."
            .into(),
    );
    if power {
        h.extend(bias_lines(m));
    }
    h.push("Accuracy: momentlab checks it with every operation rounded on its own (`precise`) and with every a*b + c fused, as drivers may without `precise` (WGSL, GLSL before 4.00 / ES 3.20).".into());
    let glsl = module(&th, &form, tag, false, &h);
    let hlsl = module(&th, &form, tag, true, &h);
    Ok(Snippet {
        glsl,
        hlsl,
        theta: th,
        form,
        order,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quantize::curve::MonomialCurve;
    use crate::quantize::theta::{published_theta4, published_theta6};
    use crate::shader::Order;
    use rand::{Rng, SeedableRng};

    #[test]
    fn clenshaw_sums_the_chebyshev_series() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(4);
        for _ in 0..2000 {
            let n = rng.gen_range(1..12);
            let c: Vec<f64> = (0..n).map(|_| rng.gen_range(-1.0..1.0)).collect();
            let x: f64 = rng.gen_range(-1.0..1.0);
            let direct: f64 = c
                .iter()
                .enumerate()
                .map(|(k, ck)| ck * (k as f64 * x.acos()).cos())
                .sum();
            assert!((clenshaw_f64(&c, x) - direct).abs() < 1e-12);
        }
    }

    #[test]
    fn chebyshev_rows_reproduce_theta_and_stay_small() {
        for th in [published_theta4(), published_theta6()] {
            let c = MonomialCurve::power(th.m()).unwrap();
            let rows = chebyshev_rows(&th, &c).unwrap();
            assert_eq!(rows.coeffs[0].len(), th.m() + 1);
            assert!(rows.max_fit_error < 1e-11, "{}", rows.max_fit_error);
            let big = rows
                .coeffs
                .iter()
                .flatten()
                .fold(0.0f64, |a, v| a.max(v.abs()));
            assert!(big < 1.0, "largest Chebyshev coefficient {big}");
            // the f32 interpreter of the emitted encoder agrees with θ∘b, in both orders
            let enc = encoder(&th, &EncoderForm::Chebyshev(rows), "e", Layout::Array);
            let mut b = vec![0.0; th.m()];
            let mut s = vec![0.0; th.m()];
            for (k, order) in (0..=1000).flat_map(|k| [(k, Order::Unfused), (k, Order::Fused)]) {
                let z = k as f64 / 1000.0;
                c.eval(z, &mut b);
                th.encode(&b, &mut s);
                let got = enc.eval_in(order, &[z as f32]).unwrap();
                for (g, w) in got.iter().zip(&s) {
                    assert!(
                        (*g as f64 - w.clamp(0.0, 1.0)).abs() < 2e-6,
                        "z={z}: {g} vs {w}"
                    );
                }
            }
        }
    }
}
