//! GLSL and HLSL text of a [`Module`]: one `MOMENTLAB_PRECISE float t_N = …;` line per
//! statement, in node order, with one operation each; a loop is a `for` with a constant trip
//! count, its variables declared before it and assigned at the end of its body. Constants
//! print as the shortest decimal of their f64 value in exponent form (`1.5e-3`, negative ones
//! parenthesized), which parses back to exactly the same f32.
//!
//! `MOMENTLAB_PRECISE` is the `precise` qualifier, which forbids the compiler to fuse a·b + c
//! into an FMA or to reorder, where the language has it: HLSL, GLSL ≥ 4.00 and GLSL ES ≥ 3.20.
//! The GLSL text chooses by `__VERSION__` and `GL_ES` and defines it empty in older GLSL
//! (3.30, ES 3.00, ES 3.10), so it compiles as shipped in every version; a definition made
//! before the text overrides the choice. Without `precise` the driver may fuse: the
//! interpreter's fused order ([`super::eval::Order::Fused`]) computes that case.
//!
//! Everything else printed is GLSL 3.30 / GLSL ES 3.00 and HLSL SM 5: scalar `float`,
//! `vecN`/`floatN`, `float x[n]` (also as `out` parameters), `for` loops over an `int`,
//! `?:`, and the built-ins abs, sqrt, min, max, clamp, cos, sin, acos, atan(y, x) / atan2,
//! exp, log.

use super::ir::{Cmp, Func, Module, Node, Op, Shape, V};
use anyhow::{bail, Result};
use std::fmt::Write;

/// Shader dialect.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Lang {
    /// GLSL (Vulkan/OpenGL).
    Glsl,
    /// HLSL (Direct3D).
    Hlsl,
}

impl Lang {
    fn vec(self, n: usize) -> String {
        match self {
            Lang::Glsl => format!("vec{n}"),
            Lang::Hlsl => format!("float{n}"),
        }
    }
}

/// A literal that parses back to exactly `v` (finite).
pub fn literal(v: f32) -> String {
    let s = format!("{:e}", v as f64);
    if v.is_sign_negative() {
        format!("({s})")
    } else {
        s
    }
}

const COMP: [&str; 4] = ["x", "y", "z", "w"];

fn param_decl(lang: Lang, name: &str, shape: Shape) -> String {
    match shape {
        Shape::Scalar => format!("float {name}"),
        Shape::Array(n) => format!("float {name}[{n}]"),
        Shape::Vector(n) => format!("{} {name}", lang.vec(n)),
    }
}

fn component(name: &str, shape: Shape, c: usize) -> String {
    match shape {
        Shape::Scalar => name.to_string(),
        Shape::Array(_) => format!("{name}[{c}]"),
        Shape::Vector(_) => format!("{name}.{}", COMP[c]),
    }
}

/// Print one function.
pub fn func(f: &Func, lang: Lang) -> Result<String> {
    f.validate()?;
    let mut s = String::new();
    for d in &f.doc {
        let _ = writeln!(s, "// {d}");
    }
    let refs: Vec<String> = f
        .nodes
        .iter()
        .enumerate()
        .map(|(i, n)| match n {
            Node::Input(p, c) => {
                let p = &f.inputs[*p];
                component(&p.name, p.shape, *c)
            }
            Node::Const(v) => literal(*v),
            Node::Op(_) | Node::Var(_) => format!("t_{i}"),
            Node::Loop(_) | Node::EndLoop(_) => String::new(),
        })
        .collect();
    if let Some(bad) = f.nodes.iter().find_map(|n| match n {
        Node::Const(v) if !v.is_finite() => Some(*v),
        _ => None,
    }) {
        bail!("{}: constant {bad} is not finite", f.name);
    }
    let r = |v: &V| refs[v.0 as usize].as_str();
    let ret = match &f.ret {
        None => "void".to_string(),
        Some((Shape::Vector(n), _)) => lang.vec(*n),
        Some(_) => "float".to_string(),
    };
    let params: Vec<String> = f
        .inputs
        .iter()
        .map(|p| param_decl(lang, &p.name, p.shape))
        .chain(
            f.outs
                .iter()
                .map(|(p, _)| format!("out {}", param_decl(lang, &p.name, p.shape))),
        )
        .collect();
    let _ = writeln!(s, "{ret} {}({})\n{{", f.name, params.join(", "));
    let notes = |i: usize| -> String {
        let notes: Vec<&str> = f
            .notes
            .iter()
            .filter(|(v, _)| v.0 as usize == i)
            .map(|(_, t)| t.as_str())
            .collect();
        if notes.is_empty() {
            String::new()
        } else {
            format!(" // {}", notes.join("; "))
        }
    };
    let mut ind = "    ";
    for (i, n) in f.nodes.iter().enumerate() {
        let op = match n {
            Node::Op(op) => op,
            Node::Var(init) => {
                let tail = notes(i);
                let _ = writeln!(s, "{ind}MOMENTLAB_PRECISE float t_{i} = {};{tail}", r(init));
                continue;
            }
            Node::Loop(count) => {
                let _ = writeln!(
                    s,
                    "{ind}for (int t_loop{i} = 0; t_loop{i} < {count}; ++t_loop{i})\n{ind}{{"
                );
                ind = "        ";
                continue;
            }
            Node::EndLoop(updates) => {
                for (var, val) in updates {
                    let _ = writeln!(s, "{ind}{} = {};", r(var), r(val));
                }
                ind = "    ";
                let _ = writeln!(s, "{ind}}}");
                continue;
            }
            Node::Input(..) | Node::Const(_) => continue,
        };
        let e = match *op {
            Op::Add(a, b) => format!("{} + {}", r(&a), r(&b)),
            Op::Sub(a, b) => format!("{} - {}", r(&a), r(&b)),
            Op::Mul(a, b) => format!("{} * {}", r(&a), r(&b)),
            Op::Div(a, b) => format!("{} / {}", r(&a), r(&b)),
            Op::Neg(a) => format!("-{}", r(&a)),
            Op::Abs(a) => format!("abs({})", r(&a)),
            Op::Sqrt(a) => format!("sqrt({})", r(&a)),
            Op::Min(a, b) => format!("min({}, {})", r(&a), r(&b)),
            Op::Max(a, b) => format!("max({}, {})", r(&a), r(&b)),
            Op::Clamp(x, lo, hi) => format!("clamp({}, {}, {})", r(&x), r(&lo), r(&hi)),
            Op::Select(c, a, b, x, y) => {
                let c = match c {
                    Cmp::Lt => "<",
                    Cmp::Le => "<=",
                    Cmp::Gt => ">",
                    Cmp::Ge => ">=",
                };
                format!("({} {c} {}) ? {} : {}", r(&a), r(&b), r(&x), r(&y))
            }
            Op::Cos(a) => format!("cos({})", r(&a)),
            Op::Sin(a) => format!("sin({})", r(&a)),
            Op::Acos(a) => format!("acos({})", r(&a)),
            Op::Atan2(y, x) => match lang {
                Lang::Glsl => format!("atan({}, {})", r(&y), r(&x)),
                Lang::Hlsl => format!("atan2({}, {})", r(&y), r(&x)),
            },
            Op::Exp(a) => format!("exp({})", r(&a)),
            Op::Log(a) => format!("log({})", r(&a)),
        };
        let tail = notes(i);
        let _ = writeln!(s, "{ind}MOMENTLAB_PRECISE float t_{i} = {e};{tail}");
    }
    for (p, vals) in &f.outs {
        match p.shape {
            Shape::Vector(n) => {
                let args: Vec<&str> = vals.iter().map(r).collect();
                let _ = writeln!(s, "    {} = {}({});", p.name, lang.vec(n), args.join(", "));
            }
            _ => {
                for (c, v) in vals.iter().enumerate() {
                    let _ = writeln!(s, "    {} = {};", component(&p.name, p.shape, c), r(v));
                }
            }
        }
    }
    if let Some((shape, vals)) = &f.ret {
        let args: Vec<&str> = vals.iter().map(r).collect();
        match shape {
            Shape::Vector(n) => {
                let _ = writeln!(s, "    return {}({});", lang.vec(*n), args.join(", "));
            }
            _ => {
                let _ = writeln!(s, "    return {};", args[0]);
            }
        }
    }
    s.push_str("}\n");
    Ok(s)
}

/// The `MOMENTLAB_PRECISE` default of a module: a comment line and the preprocessor lines.
pub fn precise_default(lang: Lang) -> &'static str {
    match lang {
        Lang::Glsl => {
            "// MOMENTLAB_PRECISE: `precise` (no fused a*b + c) in GLSL >= 4.00 and GLSL ES >= 3.20, \
             empty in older GLSL; define it before this text to override.\n\
             #ifndef MOMENTLAB_PRECISE\n\
             #if (defined(GL_ES) && __VERSION__ >= 320) || (!defined(GL_ES) && __VERSION__ >= 400)\n\
             #define MOMENTLAB_PRECISE precise\n\
             #else\n\
             #define MOMENTLAB_PRECISE\n\
             #endif\n\
             #endif\n"
        }
        Lang::Hlsl => {
            "// MOMENTLAB_PRECISE: `precise` (no fused a*b + c); define it before this text to \
             override.\n\
             #ifndef MOMENTLAB_PRECISE\n\
             #define MOMENTLAB_PRECISE precise\n\
             #endif\n"
        }
    }
}

/// Print a module: header comment, the `MOMENTLAB_PRECISE` default ([`precise_default`]),
/// then every function.
pub fn module(m: &Module, lang: Lang) -> Result<String> {
    m.validate()?;
    let mut s = String::new();
    for h in &m.header {
        let _ = writeln!(s, "// {h}");
    }
    s.push_str(precise_default(lang));
    for f in &m.funcs {
        s.push('\n');
        s.push_str(&func(f, lang)?);
    }
    Ok(s)
}

/// GLSL text of a module.
pub fn glsl(m: &Module) -> Result<String> {
    module(m, Lang::Glsl)
}

/// HLSL text of a module.
pub fn hlsl(m: &Module) -> Result<String> {
    module(m, Lang::Hlsl)
}
