//! A shader function: scalar f32 inputs, constants and statements `tN = op(args)`, with
//! outputs gathered into scalars, arrays or vectors; straight-line except for loops with a
//! constant trip count ([`Func::repeat`]) that carry a few variables from one iteration to the
//! next. The printers ([`super::print`]) and the interpreter ([`super::eval`]) read the same
//! nodes in the same order, so the interpreter computes what the shader computes (IEEE f32,
//! each operation rounded on its own, or every a·b ± c contracted: [`super::eval::Order`]).

use anyhow::{bail, Result};

/// A value of a [`Func`]: an input component, a constant or the result of a statement.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct V(pub(crate) u32);

/// Shape of a parameter or of the return value.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shape {
    /// `float x`
    Scalar,
    /// `float x[n]`
    Array(usize),
    /// `float2/3/4` (HLSL), `vec2/3/4` (GLSL); n in 2..=4.
    Vector(usize),
}

impl Shape {
    /// Number of f32 components.
    pub fn len(self) -> usize {
        match self {
            Shape::Scalar => 1,
            Shape::Array(n) | Shape::Vector(n) => n,
        }
    }

    /// True when the shape has no components (`Array(0)`).
    pub fn is_empty(self) -> bool {
        self.len() == 0
    }
}

/// Comparison of a [`Op::Select`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Cmp {
    /// `a < b`
    Lt,
    /// `a <= b`
    Le,
    /// `a > b`
    Gt,
    /// `a >= b`
    Ge,
}

/// Operations. Arithmetic is IEEE f32 and printed as written: `a * b + c` is two operations
/// (GLSL/HLSL temporaries are `precise` where the language has it, so compilers may not fuse
/// it there; elsewhere they may, which the interpreter's fused order computes).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Op {
    /// a + b
    Add(V, V),
    /// a − b
    Sub(V, V),
    /// a · b
    Mul(V, V),
    /// a / b
    Div(V, V),
    /// −a
    Neg(V),
    /// |a|
    Abs(V),
    /// √a
    Sqrt(V),
    /// min(a, b)
    Min(V, V),
    /// max(a, b)
    Max(V, V),
    /// clamp(x, lo, hi) = min(max(x, lo), hi)
    Clamp(V, V, V),
    /// `(a cmp b) ? x : y`
    Select(Cmp, V, V, V, V),
    /// cos(a)
    Cos(V),
    /// sin(a)
    Sin(V),
    /// acos(a)
    Acos(V),
    /// atan2(y, x)
    Atan2(V, V),
    /// exp(a)
    Exp(V),
    /// log(a) (natural logarithm)
    Log(V),
}

impl Op {
    /// The largest argument index (a statement may only use earlier nodes).
    pub(crate) fn last_arg(&self) -> u32 {
        use Op::*;
        match *self {
            Neg(a) | Abs(a) | Sqrt(a) | Cos(a) | Sin(a) | Acos(a) | Exp(a) | Log(a) => a.0,
            Add(a, b) | Sub(a, b) | Mul(a, b) | Div(a, b) | Min(a, b) | Max(a, b) | Atan2(a, b) => {
                a.0.max(b.0)
            }
            Clamp(a, b, c) => a.0.max(b.0).max(c.0),
            Select(_, a, b, x, y) => a.0.max(b.0).max(x.0).max(y.0),
        }
    }

    pub(crate) fn args(&self) -> Vec<V> {
        use Op::*;
        match *self {
            Neg(a) | Abs(a) | Sqrt(a) | Cos(a) | Sin(a) | Acos(a) | Exp(a) | Log(a) => vec![a],
            Add(a, b) | Sub(a, b) | Mul(a, b) | Div(a, b) | Min(a, b) | Max(a, b) | Atan2(a, b) => {
                vec![a, b]
            }
            Clamp(a, b, c) => vec![a, b, c],
            Select(_, a, b, x, y) => vec![a, b, x, y],
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Node {
    /// component `comp` of input parameter `param`
    Input(usize, usize),
    Const(f32),
    Op(Op),
    /// A variable carried by the next loop: `init` before it, the last iteration's value after.
    Var(V),
    /// Start of a loop body run this many times (≥ 1).
    Loop(u32),
    /// End of the loop body: each variable takes its value (in order; no value is a variable
    /// assigned here), then the body runs again until its count is reached.
    EndLoop(Vec<(V, V)>),
}

/// A parameter: name and shape.
#[derive(Clone, Debug, PartialEq)]
pub struct Param {
    /// Identifier in the printed source.
    pub name: String,
    /// Scalar, array or vector.
    pub shape: Shape,
}

/// One shader function, built statement by statement.
#[derive(Clone, Debug, PartialEq)]
pub struct Func {
    /// Function name (an identifier, unique within a [`Module`]).
    pub name: String,
    /// Comment lines printed above the function.
    pub doc: Vec<String>,
    pub(crate) inputs: Vec<Param>,
    pub(crate) nodes: Vec<Node>,
    pub(crate) notes: Vec<(V, String)>,
    pub(crate) ret: Option<(Shape, Vec<V>)>,
    pub(crate) outs: Vec<(Param, Vec<V>)>,
}

fn valid_ident(s: &str) -> bool {
    let mut c = s.chars();
    matches!(c.next(), Some(f) if f.is_ascii_alphabetic() || f == '_')
        && c.all(|x| x.is_ascii_alphanumeric() || x == '_')
}

impl Func {
    /// An empty function called `name`: no inputs, no statements, no doc lines.
    pub fn new(name: &str) -> Func {
        Func {
            name: name.to_string(),
            doc: Vec::new(),
            inputs: Vec::new(),
            nodes: Vec::new(),
            notes: Vec::new(),
            ret: None,
            outs: Vec::new(),
        }
    }

    fn push(&mut self, n: Node) -> V {
        self.nodes.push(n);
        V(self.nodes.len() as u32 - 1)
    }

    /// Declare an input parameter; returns its components in order.
    pub fn input(&mut self, name: &str, shape: Shape) -> Vec<V> {
        let p = self.inputs.len();
        self.inputs.push(Param {
            name: name.to_string(),
            shape,
        });
        (0..shape.len())
            .map(|c| self.push(Node::Input(p, c)))
            .collect()
    }

    /// Declare a scalar input.
    pub fn input_scalar(&mut self, name: &str) -> V {
        self.input(name, Shape::Scalar)[0]
    }

    /// A constant (printed so that it parses back to exactly this f32).
    pub fn c(&mut self, v: f32) -> V {
        self.push(Node::Const(v))
    }

    /// A constant given in f64, rounded to nearest f32.
    pub fn c64(&mut self, v: f64) -> V {
        self.c(v as f32)
    }

    /// A statement.
    pub fn op(&mut self, op: Op) -> V {
        self.push(Node::Op(op))
    }

    /// Statement `a + b`.
    pub fn add(&mut self, a: V, b: V) -> V {
        self.op(Op::Add(a, b))
    }
    /// Statement `a − b`.
    pub fn sub(&mut self, a: V, b: V) -> V {
        self.op(Op::Sub(a, b))
    }
    /// Statement `a · b`.
    pub fn mul(&mut self, a: V, b: V) -> V {
        self.op(Op::Mul(a, b))
    }
    /// Statement `a / b`.
    pub fn div(&mut self, a: V, b: V) -> V {
        self.op(Op::Div(a, b))
    }
    /// Statement `−a`.
    pub fn neg(&mut self, a: V) -> V {
        self.op(Op::Neg(a))
    }
    /// Statement `|a|`.
    pub fn abs(&mut self, a: V) -> V {
        self.op(Op::Abs(a))
    }
    /// Statement `√a`.
    pub fn sqrt(&mut self, a: V) -> V {
        self.op(Op::Sqrt(a))
    }
    /// Statement `min(a, b)`.
    pub fn min(&mut self, a: V, b: V) -> V {
        self.op(Op::Min(a, b))
    }
    /// Statement `max(a, b)`.
    pub fn max(&mut self, a: V, b: V) -> V {
        self.op(Op::Max(a, b))
    }
    /// Statement `clamp(x, lo, hi) = min(max(x, lo), hi)`.
    pub fn clamp(&mut self, x: V, lo: V, hi: V) -> V {
        self.op(Op::Clamp(x, lo, hi))
    }
    /// `(a cmp b) ? x : y`
    pub fn select(&mut self, cmp: Cmp, a: V, b: V, x: V, y: V) -> V {
        self.op(Op::Select(cmp, a, b, x, y))
    }
    /// Statement `cos(a)`.
    pub fn cos(&mut self, a: V) -> V {
        self.op(Op::Cos(a))
    }
    /// Statement `sin(a)`.
    pub fn sin(&mut self, a: V) -> V {
        self.op(Op::Sin(a))
    }
    /// Statement `acos(a)`.
    pub fn acos(&mut self, a: V) -> V {
        self.op(Op::Acos(a))
    }
    /// Statement `atan2(y, x)`.
    pub fn atan2(&mut self, y: V, x: V) -> V {
        self.op(Op::Atan2(y, x))
    }
    /// Statement `exp(a)`.
    pub fn exp(&mut self, a: V) -> V {
        self.op(Op::Exp(a))
    }
    /// Statement `log(a)` (natural logarithm).
    pub fn log(&mut self, a: V) -> V {
        self.op(Op::Log(a))
    }

    /// A loop of `count` ≥ 1 iterations carrying the values `init`: `body` receives the
    /// variables (their current values) and returns their next values, in the same order;
    /// the result is the variables, which hold the last iteration's values after the loop.
    /// Statements of the body are visible only inside it; loops do not nest.
    pub fn repeat(
        &mut self,
        count: u32,
        init: &[V],
        body: impl FnOnce(&mut Func, &[V]) -> Vec<V>,
    ) -> Vec<V> {
        let vars: Vec<V> = init.iter().map(|&v| self.push(Node::Var(v))).collect();
        self.push(Node::Loop(count));
        let next = body(self, &vars);
        assert_eq!(
            next.len(),
            vars.len(),
            "repeat: one next value per variable"
        );
        let updates = vars
            .iter()
            .zip(&next)
            .filter(|(v, n)| v != n)
            .map(|(&v, &n)| (v, n))
            .collect();
        self.push(Node::EndLoop(updates));
        vars
    }

    /// Trailing comment on the statement that defines `v`.
    pub fn note(&mut self, v: V, text: &str) {
        self.notes.push((v, text.replace('\n', " ")));
    }

    /// The function returns these values with `shape` (Scalar or Vector).
    pub fn ret(&mut self, shape: Shape, vals: &[V]) {
        self.ret = Some((shape, vals.to_vec()));
    }

    /// An `out` parameter holding these values (declared after the inputs, in call order).
    pub fn output(&mut self, name: &str, shape: Shape, vals: &[V]) {
        self.outs.push((
            Param {
                name: name.to_string(),
                shape,
            },
            vals.to_vec(),
        ));
    }

    /// Input parameters in order.
    pub fn inputs(&self) -> &[Param] {
        &self.inputs
    }

    /// Out parameters in order.
    pub fn outputs(&self) -> Vec<&Param> {
        self.outs.iter().map(|o| &o.0).collect()
    }

    /// Shape of the return value (None: `void`).
    pub fn return_shape(&self) -> Option<Shape> {
        self.ret.as_ref().map(|r| r.0)
    }

    /// Number of f32 inputs (all parameters flattened).
    pub fn n_inputs(&self) -> usize {
        self.inputs.iter().map(|p| p.shape.len()).sum()
    }

    /// Number of f32 outputs (return value first, then the out parameters, flattened).
    pub fn n_outputs(&self) -> usize {
        self.ret.as_ref().map_or(0, |r| r.1.len())
            + self.outs.iter().map(|o| o.1.len()).sum::<usize>()
    }

    /// Number of statements (operations) the function executes.
    /// A statement in a loop body counts once per iteration.
    pub fn n_ops(&self) -> usize {
        let scope = self
            .scopes()
            .unwrap_or_else(|_| vec![None; self.nodes.len()]);
        self.nodes
            .iter()
            .zip(&scope)
            .map(|(n, s)| match (n, s) {
                (Node::Op(_), Some(b)) => match self.nodes[*b] {
                    Node::Loop(count) => count as usize,
                    _ => 1,
                },
                (Node::Op(_), None) => 1,
                _ => 0,
            })
            .sum()
    }

    /// Number of statements as printed (a loop body once).
    pub fn n_statements(&self) -> usize {
        self.nodes
            .iter()
            .filter(|n| matches!(n, Node::Op(_)))
            .count()
    }

    /// For every node, the index of the `Loop` whose body (or `EndLoop`) it is in; an error
    /// for nested, empty-count, unmatched or unclosed loops.
    pub(crate) fn scopes(&self) -> Result<Vec<Option<usize>>> {
        let mut open: Option<usize> = None;
        let mut out = Vec::with_capacity(self.nodes.len());
        for (i, n) in self.nodes.iter().enumerate() {
            match n {
                Node::Loop(count) => {
                    if open.is_some() || *count == 0 {
                        bail!("{}: loop {i} is nested or runs zero times", self.name);
                    }
                    out.push(None);
                    open = Some(i);
                }
                Node::EndLoop(_) => {
                    if open.is_none() {
                        bail!("{}: loop end {i} without a loop", self.name);
                    }
                    out.push(open.take());
                }
                _ => out.push(open),
            }
        }
        if let Some(b) = open {
            bail!("{}: loop {b} is not closed", self.name);
        }
        Ok(out)
    }

    /// Check names, shapes and that every value refers to an earlier node.
    pub fn validate(&self) -> Result<()> {
        if !valid_ident(&self.name) {
            bail!("shader function name '{}' is not an identifier", self.name);
        }
        let mut names = std::collections::HashSet::new();
        let params = self.inputs.iter().chain(self.outs.iter().map(|o| &o.0));
        for p in params {
            if !valid_ident(&p.name) || p.name.starts_with("t_") || !names.insert(&p.name) {
                bail!(
                    "{}: parameter name '{}' is not an unused identifier",
                    self.name,
                    p.name
                );
            }
            if let Shape::Vector(n) = p.shape {
                if !(2..=4).contains(&n) {
                    bail!("{}: vector '{}' has {n} components", self.name, p.name);
                }
            }
            if p.shape.is_empty() {
                bail!("{}: parameter '{}' is empty", self.name, p.name);
            }
        }
        let scope = self.scopes()?;
        // j is a value usable at node i: a value node before i, outside every loop body or in
        // the body i is in.
        let usable = |j: V, i: usize| {
            let j = j.0 as usize;
            let here = scope.get(i).copied().flatten();
            j < i
                && matches!(
                    self.nodes[j],
                    Node::Input(..) | Node::Const(_) | Node::Op(_) | Node::Var(_)
                )
                && (scope[j].is_none() || scope[j] == here)
        };
        for (i, n) in self.nodes.iter().enumerate() {
            match n {
                Node::Op(op) => {
                    if op.args().iter().any(|&a| !usable(a, i)) {
                        bail!(
                            "{}: statement {i} uses a later or out-of-scope value",
                            self.name
                        );
                    }
                }
                Node::Var(init) => {
                    if scope[i].is_some() || !usable(*init, i) {
                        bail!(
                            "{}: loop variable {i} is not declared before its loop",
                            self.name
                        );
                    }
                }
                Node::EndLoop(updates) => {
                    let start = scope[i].expect("scopes() pairs every EndLoop");
                    let mut targets = std::collections::HashSet::new();
                    for &(var, _) in updates {
                        let ok = (var.0 as usize) < start
                            && matches!(self.nodes[var.0 as usize], Node::Var(_));
                        if !ok || !targets.insert(var) {
                            bail!(
                                "{}: loop {start} assigns a non-variable or twice",
                                self.name
                            );
                        }
                    }
                    // values are read after earlier assignments of the same loop end
                    for &(var, val) in updates {
                        if !usable(val, i) || (val != var && targets.contains(&val)) {
                            bail!("{}: loop {start} assigns an unusable value", self.name);
                        }
                    }
                }
                Node::Input(..) | Node::Const(_) | Node::Loop(_) => {}
            }
        }
        let len = self.nodes.len() as u32;
        if let Some((shape, v)) = &self.ret {
            if matches!(shape, Shape::Array(_)) || shape.len() != v.len() {
                bail!("{}: return value shape does not fit", self.name);
            }
            if let Shape::Vector(n) = shape {
                if !(2..=4).contains(n) {
                    bail!("{}: returns a vector of {n} components", self.name);
                }
            }
        }
        for (p, v) in &self.outs {
            if p.shape.len() != v.len() {
                bail!("{}: output '{}' has the wrong length", self.name, p.name);
            }
        }
        let used = self
            .ret
            .iter()
            .flat_map(|r| r.1.iter())
            .chain(self.outs.iter().flat_map(|o| o.1.iter()));
        if used.clone().any(|v| v.0 >= len) || self.notes.iter().any(|n| n.0 .0 >= len) {
            bail!("{}: a value does not belong to this function", self.name);
        }
        let end = self.nodes.len();
        if used.clone().any(|&v| !usable(v, end)) {
            bail!("{}: an output is not a value outside the loops", self.name);
        }
        if self.ret.is_none() && self.outs.is_empty() {
            bail!("{}: no outputs", self.name);
        }
        Ok(())
    }
}

/// Several functions printed together, with a header comment.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Module {
    /// Comment lines printed at the top.
    pub header: Vec<String>,
    /// The functions, printed in this order.
    pub funcs: Vec<Func>,
}

impl Module {
    /// Validates every function and rejects two functions with the same name.
    pub fn validate(&self) -> Result<()> {
        let mut names = std::collections::HashSet::new();
        for f in &self.funcs {
            f.validate()?;
            if !names.insert(&f.name) {
                bail!("shader module: function '{}' defined twice", f.name);
            }
        }
        Ok(())
    }

    /// The function called `name`.
    pub fn func(&self, name: &str) -> Option<&Func> {
        self.funcs.iter().find(|f| f.name == name)
    }
}
