//! The export of a tuned setting: `setting.json` (the constants) and `shadow.glsl` /
//! `shadow.hlsl` with three functions written in the shader IR (`crate::shader`):
//! `tunedEncode(z)` → the values a texel stores (θ(b(z)) for 16-bit UNORM with θ, b(z) else),
//! `tunedDecode(s)` → the moments b, and `tunedShadow(s, z_f)` → G: decode, bias
//! b' = (1 − α)·b + α·b*, the technique's reconstruction in f32 in the same operations and order
//! as momentlab's own f32 path, clamped to [0,1]. The depth bias is the caller's:
//! z_f = z − (ε + s·(|dz/du| + |dz/dv|)), its constants are in the header and the JSON.
//!
//! Reconstructions: VSM, ESM, EVSM, Hamburger 4MSM. Hausdorff 4MSM, 6MSM and TMSM have no
//! straight-line form here yet: their export holds the JSON only.

use super::space::{Own, Setting, StorageKind, TechniqueKind};
use crate::quantize::codegen;
use crate::quantize::curve::MonomialCurve;
use crate::shader::{Cmp, Func, Module, Shape, V};
use crate::technique::Technique;
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

/// Hamburger 4MSM (`technique::hamburger4::msm4_hamburger`, Algorithm 3) for biased b.
fn msm4_into(f: &mut Func, b: &[V], zf: V) -> V {
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
    f.select(Cmp::Gt, d22, tol_b, g, g_single)
}

/// b* of the setting's technique (the registry's default preset).
fn b_star(t: &dyn Technique, kind: TechniqueKind) -> Vec<f64> {
    let m = t.moment_count();
    match kind {
        TechniqueKind::Hamburger4 | TechniqueKind::Hausdorff4 => vec![0.5; m],
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
            msm4_into(f, &bb, zf)
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
    if fam.technique == TechniqueKind::Tmsm {
        return Ok(None);
    }
    let theta = fam.technique.theta(fam.storage);
    let with_theta = fam.storage == StorageKind::Unorm16Theta;
    // encode
    let mut enc = Func::new("tunedEncode");
    let z = enc.input_scalar("depth");
    let stored = if with_theta {
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

/// What `setting.json` of an export holds.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Exported<'a> {
    pub scene: &'a str,
    pub setting: &'a Setting,
    pub label: String,
    pub bits_per_texel: u32,
    pub error: f64,
    pub leak: f64,
    pub darkening: f64,
    /// Files with the shader code (empty when the technique has no export here).
    pub shaders: Vec<String>,
}

/// Write the export of every target's chosen setting into `out`/`<scene>/` (scene "all" for
/// all scenes): `setting.json`, and `shadow.glsl` + `shadow.hlsl` where a reconstruction exists.
pub fn write(out: &crate::artefact::OutDir, t: &super::Tuning) -> Result<()> {
    for target in t.scenes.iter().chain(std::iter::once(&t.overall)) {
        let dir = crate::artefact::safe_name(&target.scene);
        let s = &target.chosen.setting;
        let mut shaders = Vec::new();
        if let Some(m) = module(s, header(s))? {
            out.write_text(&format!("{dir}/shadow.glsl"), &crate::shader::glsl(&m)?)?;
            out.write_text(&format!("{dir}/shadow.hlsl"), &crate::shader::hlsl(&m)?)?;
            shaders = vec!["shadow.glsl".into(), "shadow.hlsl".into()];
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
                shaders,
            },
        )?;
    }
    Ok(())
}
