//! Ready-to-paste HLSL and GLSL encode/decode functions for a θ: s = A·b + t before storing,
//! b = A⁻¹·(s − t) after filtering. Explicit scalar arithmetic (no matrix-layout pitfalls).

use super::theta::Theta;
use std::fmt::Write;

/// Shader dialect.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Lang {
    Hlsl,
    Glsl,
}

fn lit(v: f64) -> String {
    format!("{v:.17e}")
}

/// Source of `Encode…`/`Decode…` for θ. With monomial `exps` the encoder takes the depth z and
/// computes b(z) itself; otherwise it takes the basis values b[] computed by the caller.
pub fn snippet(
    theta: &Theta,
    exps: Option<&[u32]>,
    tag: &str,
    gain_bits: f64,
    lang: Lang,
) -> String {
    let m = theta.m();
    let mut s = String::new();
    let (enc, dec) = match lang {
        Lang::Hlsl => (format!("EncodeMoments{tag}"), format!("DecodeMoments{tag}")),
        Lang::Glsl => (format!("encodeMoments{tag}"), format!("decodeMoments{tag}")),
    };
    let _ = writeln!(
        s,
        "// Optimized moment quantization θ (momentlab theta; Peters & Klein 2015, Section 4.3)."
    );
    let _ = writeln!(s, "// basis b = ({}), m = {m}", theta.basis.join(", "));
    let _ = writeln!(
        s,
        "// stored s = A*b + t lies in [0,1]^{m}; entropy gain log2|det A| = {gain_bits:.4} bits."
    );
    let _ = writeln!(
        s,
        "// Encode before writing the shadow map; decode the filtered sample."
    );
    match exps {
        Some(e) => {
            let _ = writeln!(s, "void {enc}(float z, out float s[{m}])\n{{");
            let maxe = *e.iter().max().unwrap_or(&1);
            let _ = writeln!(s, "    float z1 = z;");
            for k in 2..=maxe {
                let _ = writeln!(s, "    float z{k} = z{} * z;", k - 1);
            }
            let _ = writeln!(s, "    float b[{m}];");
            for (j, &ej) in e.iter().enumerate() {
                let _ = writeln!(s, "    b[{j}] = z{ej};");
            }
        }
        None => {
            let _ = writeln!(s, "void {enc}(float b[{m}], out float s[{m}])\n{{");
        }
    }
    for i in 0..m {
        let mut line = format!("    s[{i}] = {}", lit(theta.offset[i]));
        for j in 0..m {
            let _ = write!(line, " + {} * b[{j}]", lit(theta.matrix[i][j]));
        }
        let _ = writeln!(s, "{line};");
    }
    let _ = writeln!(s, "}}\n");
    let _ = writeln!(s, "void {dec}(float s[{m}], out float b[{m}])\n{{");
    let _ = writeln!(s, "    float d[{m}];");
    for i in 0..m {
        let _ = writeln!(s, "    d[{i}] = s[{i}] - {};", lit(theta.offset[i]));
    }
    for i in 0..m {
        let mut line = format!("    b[{i}] =");
        for j in 0..m {
            let sep = if j == 0 { " " } else { " + " };
            let _ = write!(line, "{sep}{} * d[{j}]", lit(theta.inverse[i][j]));
        }
        let _ = writeln!(s, "{line};");
    }
    let _ = writeln!(s, "}}");
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quantize::theta::published_theta4;

    #[test]
    fn snippet_coefficients_round_trip() {
        let th = published_theta4();
        for lang in [Lang::Hlsl, Lang::Glsl] {
            let src = snippet(&th, Some(&[1, 2, 3, 4]), "4", th.gain_bits(), lang);
            for i in 0..4 {
                let line = src
                    .lines()
                    .find(|l| l.trim_start().starts_with(&format!("s[{i}] =")))
                    .unwrap();
                let nums: Vec<f64> = line
                    .split(['=', '+', '*', ';'])
                    .filter_map(|w| w.trim().parse::<f64>().ok())
                    .collect();
                assert_eq!(nums.len(), 5, "{line}");
                assert_eq!(nums[0], th.offset[i]);
                assert_eq!(&nums[1..], &th.matrix[i][..]);
            }
            assert!(src.matches("b[").count() >= 8);
        }
    }
}
