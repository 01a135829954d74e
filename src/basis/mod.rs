//! Candidate basis functions b_j : [0,1] → R (Peters & Klein 2015, Section 3.2: 37 smooth
//! functions), their catalog file `basis_functions/catalog.json`, formula parsing, and
//! candidates (m-subsets of the catalog, indexed by the combinatorial number system).
//!
//! OWNER: basis helper. Public API used by other modules (keep these signatures):
//! * [`Function::eval`], [`Function::name`], [`Function::formula`]
//! * [`Catalog::embedded`], [`Catalog::load`], [`Catalog::resolve`], [`Catalog::functions`]
//! * [`Basis::new`], [`Basis::len`], [`Basis::eval`], [`Basis::names`]

use anyhow::Result;

/// One named scalar function of depth z, parsed from a formula string.
#[derive(Clone, Debug)]
pub struct Function {
    name: String,
    formula: String,
}

impl Function {
    pub fn name(&self) -> &str {
        &self.name
    }
    pub fn formula(&self) -> &str {
        &self.formula
    }
    /// Value at depth z.
    pub fn eval(&self, _z: f64) -> f64 {
        todo!("basis helper")
    }
}

/// The list of candidate functions (default: the embedded `basis_functions/catalog.json`).
#[derive(Clone, Debug)]
pub struct Catalog {
    functions: Vec<Function>,
}

impl Catalog {
    /// The catalog compiled into the binary (`basis_functions/catalog.json`).
    pub fn embedded() -> Catalog {
        todo!("basis helper")
    }
    /// Load a catalog file; errors name the file and the offending entry.
    pub fn load(_path: &std::path::Path) -> Result<Catalog> {
        todo!("basis helper")
    }
    pub fn functions(&self) -> &[Function] {
        &self.functions
    }
    /// A catalog name ("z^2", "exp(20z)") or else a formula string in z.
    pub fn resolve(&self, _name_or_formula: &str) -> Result<Function> {
        todo!("basis helper")
    }
}

/// An ordered list of m functions: b(z) = (b_1(z), …, b_m(z)).
#[derive(Clone, Debug)]
pub struct Basis {
    functions: Vec<Function>,
}

impl Basis {
    pub fn new(functions: Vec<Function>) -> Basis {
        Basis { functions }
    }
    pub fn len(&self) -> usize {
        self.functions.len()
    }
    pub fn is_empty(&self) -> bool {
        self.functions.is_empty()
    }
    pub fn functions(&self) -> &[Function] {
        &self.functions
    }
    pub fn names(&self) -> Vec<String> {
        self.functions.iter().map(|f| f.name.clone()).collect()
    }
    /// out[j] = b_j(z); `out.len() == self.len()`.
    pub fn eval(&self, z: f64, out: &mut [f64]) {
        for (o, f) in out.iter_mut().zip(&self.functions) {
            *o = f.eval(z);
        }
    }
}
