//! f32 interpreter of a [`Func`]: every statement in order (a loop body as many times as its
//! count, the loop variables assigned at its end), each operation rounded to f32
//! (IEEE add/sub/mul/div/sqrt are exact roundings, as in a shader with `precise`; Rust never
//! contracts a·b + c into an FMA). Transcendentals (cos, sin, acos, atan2, exp, log) use the
//! Rust f32 functions; GPUs implement them to a few ulp, so only they can differ.
//!
//! Two orders ([`Order`]): `Unfused` rounds every operation; `Fused` computes every sum or
//! difference with a product operand as one fused multiply-add, fma(a, b, c) = round(a·b + c),
//! which is what a driver may do where `precise` is unavailable or dropped (WGSL, naga):
//! `a·b + c` and `c + a·b` → fma(a, b, c), `a·b − c` → fma(a, b, −c), `c − a·b` → fma(−a, b, c)
//! (the first operand is taken when both are products).

use super::ir::{Cmp, Func, Node, Op, V};
use anyhow::{bail, Result};

/// The order of the interpreter's floating-point operations.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Order {
    /// Every operation rounded on its own (a shader with `precise`).
    #[default]
    Unfused,
    /// Every a·b ± c fused into one rounding (a contracting compiler).
    Fused,
}

impl Func {
    /// Run the function on flattened inputs (parameters in order); returns the flattened
    /// outputs (return value first, then the out parameters in order).
    pub fn eval(&self, inputs: &[f32]) -> Result<Vec<f32>> {
        self.eval_in(Order::Unfused, inputs)
    }

    /// As [`Func::eval`], in the given operation order.
    pub fn eval_in(&self, order: Order, inputs: &[f32]) -> Result<Vec<f32>> {
        let mut scratch = Vec::new();
        let mut out = vec![0.0; self.n_outputs()];
        self.eval_order_into(order, inputs, &mut scratch, &mut out)?;
        Ok(out)
    }

    /// As [`Func::eval`], reusing `scratch` and writing into `out` (length n_outputs).
    pub fn eval_into(&self, inputs: &[f32], scratch: &mut Vec<f32>, out: &mut [f32]) -> Result<()> {
        self.eval_order_into(Order::Unfused, inputs, scratch, out)
    }

    /// As [`Func::eval_into`], in the given operation order.
    pub fn eval_order_into(
        &self,
        order: Order,
        inputs: &[f32],
        scratch: &mut Vec<f32>,
        out: &mut [f32],
    ) -> Result<()> {
        if inputs.len() != self.n_inputs() {
            bail!(
                "{}: {} inputs given, the function takes {}",
                self.name,
                inputs.len(),
                self.n_inputs()
            );
        }
        if out.len() != self.n_outputs() {
            bail!(
                "{}: room for {} outputs, the function has {}",
                self.name,
                out.len(),
                self.n_outputs()
            );
        }
        let offsets: Vec<usize> = self
            .inputs
            .iter()
            .scan(0, |acc, p| {
                let o = *acc;
                *acc += p.shape.len();
                Some(o)
            })
            .collect();
        scratch.clear();
        scratch.resize(self.nodes.len(), 0.0);
        // the open loop: index of its `Loop` node and the iterations left after this one
        let mut open: Option<(usize, u32)> = None;
        let mut i = 0;
        while i < self.nodes.len() {
            let v = match &self.nodes[i] {
                Node::Input(p, c) => inputs[offsets[*p] + c],
                Node::Const(c) => *c,
                Node::Op(op) => {
                    if op.last_arg() as usize >= i {
                        bail!("{}: statement {i} uses a later value", self.name);
                    }
                    match order {
                        Order::Unfused => apply_unfused(op, scratch),
                        Order::Fused => apply_fused(op, &self.nodes, scratch),
                    }
                }
                Node::Var(init) => {
                    if init.0 as usize >= i {
                        bail!("{}: loop variable {i} uses a later value", self.name);
                    }
                    scratch[init.0 as usize]
                }
                Node::Loop(count) => {
                    if open.is_some() || *count == 0 {
                        bail!("{}: loop {i} is nested or runs zero times", self.name);
                    }
                    open = Some((i, count - 1));
                    0.0
                }
                Node::EndLoop(updates) => {
                    let Some((start, left)) = open else {
                        bail!("{}: loop end {i} without a loop", self.name);
                    };
                    // in order, as printed (validation refuses a value assigned before it is read)
                    for &(var, val) in updates {
                        scratch[var.0 as usize] = scratch[val.0 as usize];
                    }
                    if left > 0 {
                        open = Some((start, left - 1));
                        i = start + 1;
                        continue;
                    }
                    open = None;
                    0.0
                }
            };
            scratch[i] = v;
            i += 1;
        }
        if open.is_some() {
            bail!("{}: a loop is not closed", self.name);
        }
        let vals = self
            .ret
            .iter()
            .flat_map(|r| r.1.iter())
            .chain(self.outs.iter().flat_map(|o| o.1.iter()));
        for (o, v) in out.iter_mut().zip(vals) {
            *o = *scratch
                .get(v.0 as usize)
                .ok_or_else(|| anyhow::anyhow!("{}: output value out of range", self.name))?;
        }
        Ok(())
    }
}

/// The factors of `v` if it is a product statement.
fn product(nodes: &[Node], v: V) -> Option<(V, V)> {
    match nodes.get(v.0 as usize) {
        Some(Node::Op(Op::Mul(a, b))) => Some((*a, *b)),
        _ => None,
    }
}

/// One operation in the fused order: a sum or difference with a product operand is one fma.
pub(crate) fn apply_fused(op: &Op, nodes: &[Node], s: &[f32]) -> f32 {
    let g = |v: V| s[v.0 as usize];
    match *op {
        Op::Add(x, y) => match (product(nodes, x), product(nodes, y)) {
            (Some((a, b)), _) => g(a).mul_add(g(b), g(y)),
            (None, Some((a, b))) => g(a).mul_add(g(b), g(x)),
            _ => g(x) + g(y),
        },
        Op::Sub(x, y) => match (product(nodes, x), product(nodes, y)) {
            (Some((a, b)), _) => g(a).mul_add(g(b), -g(y)),
            (None, Some((a, b))) => (-g(a)).mul_add(g(b), g(x)),
            _ => g(x) - g(y),
        },
        _ => apply_unfused(op, s),
    }
}

/// One operation, rounded on its own.
pub(crate) fn apply_unfused(op: &Op, s: &[f32]) -> f32 {
    let g = |v: &super::ir::V| s[v.0 as usize];
    match op {
        Op::Add(a, b) => g(a) + g(b),
        Op::Sub(a, b) => g(a) - g(b),
        Op::Mul(a, b) => g(a) * g(b),
        Op::Div(a, b) => g(a) / g(b),
        Op::Neg(a) => -g(a),
        Op::Abs(a) => g(a).abs(),
        Op::Sqrt(a) => g(a).sqrt(),
        Op::Min(a, b) => g(a).min(g(b)),
        Op::Max(a, b) => g(a).max(g(b)),
        Op::Clamp(x, lo, hi) => g(x).max(g(lo)).min(g(hi)),
        Op::Select(c, a, b, x, y) => {
            let (a, b) = (g(a), g(b));
            let t = match c {
                Cmp::Lt => a < b,
                Cmp::Le => a <= b,
                Cmp::Gt => a > b,
                Cmp::Ge => a >= b,
            };
            if t {
                g(x)
            } else {
                g(y)
            }
        }
        Op::Cos(a) => g(a).cos(),
        Op::Sin(a) => g(a).sin(),
        Op::Acos(a) => g(a).acos(),
        Op::Atan2(y, x) => g(y).atan2(g(x)),
        Op::Exp(a) => g(a).exp(),
        Op::Log(a) => g(a).ln(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shader::Shape;

    /// z·z + c where the fused rounding differs from the two-step one: z = 1 + 2⁻¹², c = −1.
    #[test]
    fn fused_order_rounds_a_product_and_sum_once() {
        let mut f = Func::new("k");
        let z = f.input_scalar("z");
        let c = f.input_scalar("c");
        let p = f.mul(z, z);
        let s = f.add(p, c);
        let one = f.c(1.0);
        let d = f.sub(one, p);
        f.ret(Shape::Vector(2), &[s, d]);
        let z = 1.0 + 2f32.powi(-12);
        let unfused = f.eval_in(Order::Unfused, &[z, -1.0]).unwrap();
        let fused = f.eval_in(Order::Fused, &[z, -1.0]).unwrap();
        // z² = 1 + 2⁻¹¹ + 2⁻²⁴: the product alone rounds 2⁻²⁴ away
        assert_eq!(unfused, vec![2f32.powi(-11), -(2f32.powi(-11))]);
        assert_eq!(
            fused,
            vec![
                2f32.powi(-11) + 2f32.powi(-24),
                -(2f32.powi(-11) + 2f32.powi(-24))
            ]
        );
        assert_eq!(f.eval(&[z, -1.0]).unwrap(), unfused);
    }
}
