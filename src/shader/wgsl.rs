//! WGSL text of a [`Module`], the third dialect beside GLSL and HLSL ([`super::print`]): one
//! `let t_N = …;` per statement in node order with one operation each, loop variables as
//! `var t_N: f32`, a loop as a `for` with a constant trip count, `out` parameters as
//! `ptr<function, …>` (the caller passes `&local`).
//!
//! WGSL has no `precise`: a driver may contract a·b + c into a fused multiply-add (naga, wgpu's
//! translator, drops SPIR-V `NoContraction` as well). The interpreter's fused order
//! ([`super::eval::Order::Fused`]) computes that case, so the accuracy of an emitted program is
//! tested in both orders.
//!
//! Literals carry the `f` suffix (`1.5e-3f`), so they are f32 values: an operation whose
//! arguments are all literals is a WGSL const-expression, evaluated at shader creation in f32,
//! the same rounding as at run time. WGSL makes a non-finite const-expression a
//! shader-creation error, so a module with one is refused here with the function's name.

use super::ir::{Cmp, Func, Module, Node, Op, Shape, V};
use anyhow::{bail, Result};
use std::fmt::Write;

/// A WGSL f32 literal that parses back to exactly `v` (finite).
pub fn literal(v: f32) -> String {
    let s = format!("{:e}f", v as f64);
    if v.is_sign_negative() {
        format!("({s})")
    } else {
        s
    }
}

const COMP: [&str; 4] = ["x", "y", "z", "w"];

fn type_of(shape: Shape) -> String {
    match shape {
        Shape::Scalar => "f32".into(),
        Shape::Array(n) => format!("array<f32, {n}>"),
        Shape::Vector(n) => format!("vec{n}<f32>"),
    }
}

fn component(name: &str, shape: Shape, c: usize) -> String {
    match shape {
        Shape::Scalar => name.to_string(),
        Shape::Array(_) => format!("{name}[{c}]"),
        Shape::Vector(_) => format!("{name}.{}", COMP[c]),
    }
}

/// The values of the nodes whose value WGSL folds at shader creation (constants and operations
/// on them, outside loops), computed in f32 as the interpreter does; `None` elsewhere.
fn folded(f: &Func) -> Result<Vec<Option<f32>>> {
    let mut out: Vec<Option<f32>> = Vec::with_capacity(f.nodes.len());
    for (i, n) in f.nodes.iter().enumerate() {
        let v = match n {
            Node::Const(c) => Some(*c),
            Node::Op(op) => {
                let args: Option<Vec<f32>> = op.args().iter().map(|a| out[a.0 as usize]).collect();
                match args {
                    Some(_) => {
                        let scratch: Vec<f32> = out.iter().map(|x| x.unwrap_or(0.0)).collect();
                        let v = super::eval::apply_unfused(op, &scratch);
                        if !v.is_finite() {
                            bail!(
                                "{}: statement {i} folds to the non-finite constant {v}, a WGSL \
                                 shader-creation error",
                                f.name
                            );
                        }
                        Some(v)
                    }
                    None => None,
                }
            }
            _ => None,
        };
        out.push(v);
    }
    Ok(out)
}

/// Print one function.
pub fn func(f: &Func) -> Result<String> {
    f.validate()?;
    if let Some(bad) = f.nodes.iter().find_map(|n| match n {
        Node::Const(v) if !v.is_finite() => Some(*v),
        _ => None,
    }) {
        bail!("{}: constant {bad} is not finite", f.name);
    }
    folded(f)?;
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
    let r = |v: &V| refs[v.0 as usize].as_str();
    let params: Vec<String> = f
        .inputs
        .iter()
        .map(|p| format!("{}: {}", p.name, type_of(p.shape)))
        .chain(
            f.outs
                .iter()
                .map(|(p, _)| format!("{}: ptr<function, {}>", p.name, type_of(p.shape))),
        )
        .collect();
    let ret = match &f.ret {
        None => String::new(),
        Some((shape, _)) => format!(" -> {}", type_of(*shape)),
    };
    let _ = writeln!(s, "fn {}({}){ret}\n{{", f.name, params.join(", "));
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
                let _ = writeln!(s, "{ind}var t_{i}: f32 = {};{}", r(init), notes(i));
                continue;
            }
            Node::Loop(count) => {
                let _ = writeln!(
                    s,
                    "{ind}for (var t_loop{i}: i32 = 0; t_loop{i} < {count}; t_loop{i}++)\n{ind}{{"
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
                format!("select({}, {}, {} {c} {})", r(&y), r(&x), r(&a), r(&b))
            }
            Op::Cos(a) => format!("cos({})", r(&a)),
            Op::Sin(a) => format!("sin({})", r(&a)),
            Op::Acos(a) => format!("acos({})", r(&a)),
            Op::Atan2(y, x) => format!("atan2({}, {})", r(&y), r(&x)),
            Op::Exp(a) => format!("exp({})", r(&a)),
            Op::Log(a) => format!("log({})", r(&a)),
        };
        let _ = writeln!(s, "{ind}let t_{i}: f32 = {e};{}", notes(i));
    }
    for (p, vals) in &f.outs {
        match p.shape {
            Shape::Vector(n) => {
                let args: Vec<&str> = vals.iter().map(r).collect();
                let _ = writeln!(s, "    *{} = vec{n}<f32>({});", p.name, args.join(", "));
            }
            Shape::Scalar => {
                let _ = writeln!(s, "    *{} = {};", p.name, r(&vals[0]));
            }
            Shape::Array(_) => {
                for (c, v) in vals.iter().enumerate() {
                    let _ = writeln!(s, "    (*{})[{c}] = {};", p.name, r(v));
                }
            }
        }
    }
    if let Some((shape, vals)) = &f.ret {
        let args: Vec<&str> = vals.iter().map(r).collect();
        match shape {
            Shape::Vector(n) => {
                let _ = writeln!(s, "    return vec{n}<f32>({});", args.join(", "));
            }
            _ => {
                let _ = writeln!(s, "    return {};", args[0]);
            }
        }
    }
    s.push_str("}\n");
    Ok(s)
}

/// WGSL text of a module: header comment, then every function.
pub fn wgsl(m: &Module) -> Result<String> {
    m.validate()?;
    let mut s = String::new();
    for h in &m.header {
        let _ = writeln!(s, "// {h}");
    }
    s.push_str(
        "// WGSL has no `precise`: drivers may fuse a*b + c; the accuracy stated holds for both.\n",
    );
    for f in &m.funcs {
        s.push('\n');
        s.push_str(&func(f)?);
    }
    Ok(s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn literals_carry_the_f32_suffix_and_parse_back() {
        for v in [
            0.0f32,
            -0.0,
            1.0,
            -2.5,
            1e-7,
            f32::MAX,
            f32::MIN_POSITIVE,
            0.1,
        ] {
            let s = literal(v);
            let t = s.trim_start_matches('(').trim_end_matches(')');
            assert!(t.ends_with('f'), "{s}");
            let back: f64 = t.trim_end_matches('f').parse().unwrap();
            assert_eq!((back as f32).to_bits(), v.to_bits(), "{s}");
        }
    }

    #[test]
    fn prints_lets_vars_loops_and_out_pointers() {
        let mut f = Func::new("k");
        let z = f.input_scalar("z");
        let b = f.input("b", Shape::Array(2));
        let h = f.c(0.5);
        let x = f.mul(z, h);
        let y = f.select(Cmp::Lt, x, b[0], b[1], x);
        let v = f.repeat(3, &[y], |f, v| vec![f.add(v[0], h)]);
        f.output("o", Shape::Array(2), &[x, v[0]]);
        f.ret(Shape::Vector(2), &[x, y]);
        let s = func(&f).unwrap();
        assert!(
            s.contains(
                "fn k(z: f32, b: array<f32, 2>, o: ptr<function, array<f32, 2>>) -> vec2<f32>"
            ),
            "{s}"
        );
        assert!(s.contains("let t_4: f32 = z * 5e-1f;"), "{s}");
        assert!(s.contains("select(t_4, b[1], t_4 < b[0])"), "{s}");
        assert!(s.contains("var t_6: f32 = t_5;"), "{s}");
        assert!(s.contains("t_loop7 < 3"), "{s}");
        assert!(s.contains("(*o)[1] = t_6;"), "{s}");
    }

    #[test]
    fn a_non_finite_constant_expression_is_refused() {
        let mut f = Func::new("k");
        let z = f.input_scalar("z");
        let big = f.c(f32::MAX);
        let inf = f.add(big, big);
        let y = f.add(z, inf);
        f.ret(Shape::Scalar, &[y]);
        let e = func(&f).unwrap_err().to_string();
        assert!(
            e.contains("k: statement") && e.contains("non-finite"),
            "{e}"
        );
    }
}
