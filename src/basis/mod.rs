//! Candidate basis functions b_j : [0,1] → R (Peters & Klein 2015, Section 3.2: 37 smooth
//! functions), their catalog file `basis_functions/catalog.json`, formula parsing, and
//! candidates (m-subsets of the catalog, indexed by the combinatorial number system).
//!
//! Public API used by other modules:
//! * [`Function::eval`], [`Function::name`], [`Function::formula`]
//! * [`Catalog::embedded`], [`Catalog::load`], [`Catalog::resolve`], [`Catalog::functions`]
//! * [`Basis::new`], [`Basis::len`], [`Basis::eval`], [`Basis::names`]

pub mod candidates;
pub mod formula;

use anyhow::{bail, Context, Result};
use std::path::Path;
use std::sync::Arc;

/// Points at which a function must be finite: 4097 uniform points on [0,1] (endpoints
/// included), plus points just inside the endpoints.
pub const FINITE_CHECK_POINTS: usize = 4097;

/// One named scalar function of depth z, parsed from a formula string.
#[derive(Clone, Debug)]
pub struct Function {
    name: String,
    formula: String,
    family: String,
    expr: Arc<formula::Expr>,
}

impl Function {
    /// Parses `formula` (see [`formula`] for the grammar) and checks that it is finite on
    /// [0,1] (at [`FINITE_CHECK_POINTS`] uniform points and at 1e-12, 1−1e-12). Errors name
    /// the function, the formula, and the position or the depth z where it fails.
    pub fn new(name: &str, formula_src: &str) -> Result<Function> {
        let expr = formula::parse(formula_src)?;
        let d = (FINITE_CHECK_POINTS - 1) as f64;
        let extra = [1e-12, 1.0 - 1e-12];
        let points = (0..FINITE_CHECK_POINTS)
            .map(|i| i as f64 / d)
            .chain(extra.iter().copied());
        for z in points {
            let v = expr.eval(z);
            if !v.is_finite() {
                if name == formula_src {
                    bail!("function '{name}' is not finite on [0,1]: value {v} at z = {z}");
                }
                bail!(
                    "function '{name}' (formula '{formula_src}') is not finite on [0,1]: \
                     value {v} at z = {z}"
                );
            }
        }
        Ok(Function {
            name: name.to_string(),
            formula: formula_src.to_string(),
            family: String::new(),
            expr: Arc::new(expr),
        })
    }

    /// A formula used as its own name.
    pub fn parse(formula_src: &str) -> Result<Function> {
        Function::new(formula_src.trim(), formula_src.trim())
    }

    /// The function's name (its formula for ad-hoc functions).
    pub fn name(&self) -> &str {
        &self.name
    }
    /// The formula source text.
    pub fn formula(&self) -> &str {
        &self.formula
    }
    /// The catalog family ("power", "exponential", …); empty for ad-hoc formulas.
    pub fn family(&self) -> &str {
        &self.family
    }
    /// Value at depth z.
    #[inline]
    pub fn eval(&self, z: f64) -> f64 {
        self.expr.eval(z)
    }
}

/// The list of candidate functions (default: the embedded `basis_functions/catalog.json`).
///
/// The order of the file is the order of [`Catalog::functions`], which defines candidate
/// indices ([`candidates`]); appending functions keeps all existing indices.
#[derive(Clone, Debug)]
pub struct Catalog {
    functions: Vec<Function>,
}

/// The embedded catalog file.
pub const EMBEDDED_CATALOG: &str = include_str!("../../basis_functions/catalog.json");

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct CatalogFile {
    #[serde(default)]
    #[allow(dead_code)]
    description: Option<serde_json::Value>,
    functions: Vec<CatalogEntry>,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct CatalogEntry {
    name: String,
    /// Defaults to the name.
    #[serde(default)]
    formula: Option<String>,
    #[serde(default)]
    family: Option<String>,
    #[serde(default)]
    #[allow(dead_code)]
    note: Option<String>,
}

impl Catalog {
    /// The catalog compiled into the binary (`basis_functions/catalog.json`).
    pub fn embedded() -> Catalog {
        static EMBEDDED: std::sync::OnceLock<Catalog> = std::sync::OnceLock::new();
        EMBEDDED
            .get_or_init(|| {
                Catalog::from_json(EMBEDDED_CATALOG)
                    .context("embedded catalog basis_functions/catalog.json")
                    .expect("the embedded catalog is checked by tests")
            })
            .clone()
    }

    /// Load a catalog file; errors name the file and the offending entry.
    pub fn load(path: &Path) -> Result<Catalog> {
        let text =
            crate::artefact::read_text(path, crate::artefact::Limit::CATALOG).context("catalog")?;
        Catalog::from_json(&text).with_context(|| format!("catalog {}", path.display()))
    }

    /// Parse catalog JSON: `{"functions": [{"name": .., "formula": .., "family": ..}, ..]}`.
    pub fn from_json(text: &str) -> Result<Catalog> {
        let file: CatalogFile = serde_json::from_str(text).context("malformed JSON")?;
        let mut functions: Vec<Function> = Vec::with_capacity(file.functions.len());
        for (i, e) in file.functions.into_iter().enumerate() {
            let name = e.name.trim();
            if name.is_empty() {
                bail!("entry {i}: empty name");
            }
            // Names are listed one per line and given on command lines as comma- and
            // semicolon-separated lists.
            if let Some(c) = name
                .chars()
                .find(|&c| c == ',' || c == ';' || c.is_control())
            {
                bail!(
                    "entry {i}: name '{}' contains {}; names cannot hold ',', ';' or control \
                     characters",
                    name.escape_debug(),
                    match c {
                        ',' => "a comma".to_string(),
                        ';' => "a semicolon".to_string(),
                        c => format!("the control character {:?}", c),
                    }
                );
            }
            if functions.iter().any(|f| f.name == name) {
                bail!("entry {i}: duplicate name '{name}'");
            }
            let src = e.formula.as_deref().unwrap_or(name);
            let mut f = Function::new(name, src).with_context(|| format!("entry {i}"))?;
            f.family = e.family.unwrap_or_default();
            functions.push(f);
        }
        if functions.is_empty() {
            bail!("no functions");
        }
        Ok(Catalog { functions })
    }

    /// The functions in catalog order.
    pub fn functions(&self) -> &[Function] {
        &self.functions
    }

    /// Number of functions.
    pub fn len(&self) -> usize {
        self.functions.len()
    }

    /// True when the catalog has no functions (never, once built).
    pub fn is_empty(&self) -> bool {
        self.functions.is_empty()
    }

    /// Position of the function named exactly `name`.
    pub fn position(&self, name: &str) -> Option<usize> {
        self.functions.iter().position(|f| f.name == name.trim())
    }

    /// A catalog name ("z^2", "exp(20z)") or else a formula string in z.
    pub fn resolve(&self, name_or_formula: &str) -> Result<Function> {
        match self.position(name_or_formula) {
            Some(i) => Ok(self.functions[i].clone()),
            None => Function::parse(name_or_formula)
                .with_context(|| format!("'{}' is not in the catalog", name_or_formula.trim())),
        }
    }

    /// Resolves every entry of a list (see [`Catalog::resolve`]) into a [`Basis`].
    pub fn basis(&self, names: &[impl AsRef<str>]) -> Result<Basis> {
        if names.is_empty() {
            bail!("basis: need at least one function");
        }
        let fs = names
            .iter()
            .enumerate()
            .map(|(i, n)| {
                self.resolve(n.as_ref())
                    .with_context(|| format!("basis entry {i}"))
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(Basis::new(fs))
    }
}

/// Splits "f1,f2(a,b),f3" on commas outside parentheses (entries trimmed).
pub fn split_list(spec: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut depth = 0i32;
    let mut cur = String::new();
    for c in spec.chars() {
        match c {
            '(' => depth += 1,
            ')' => depth -= 1,
            ',' if depth == 0 => {
                out.push(cur.trim().to_string());
                cur.clear();
                continue;
            }
            _ => {}
        }
        cur.push(c);
    }
    out.push(cur.trim().to_string());
    out
}

/// An ordered list of m functions: b(z) = (b_1(z), …, b_m(z)).
#[derive(Clone, Debug)]
pub struct Basis {
    functions: Vec<Function>,
}

impl Basis {
    /// The basis b = (functions[0], …, functions[m−1]).
    pub fn new(functions: Vec<Function>) -> Basis {
        Basis { functions }
    }
    /// m, the number of functions.
    pub fn len(&self) -> usize {
        self.functions.len()
    }
    /// True when m = 0.
    pub fn is_empty(&self) -> bool {
        self.functions.is_empty()
    }
    /// b_1, …, b_m in order.
    pub fn functions(&self) -> &[Function] {
        &self.functions
    }
    /// The names of b_1, …, b_m.
    pub fn names(&self) -> Vec<String> {
        self.functions.iter().map(|f| f.name.clone()).collect()
    }
    /// out[j] = b_j(z); `out.len() == self.len()`.
    #[inline]
    pub fn eval(&self, z: f64, out: &mut [f64]) {
        for (o, f) in out.iter_mut().zip(&self.functions) {
            *o = f.eval(z);
        }
    }
}
