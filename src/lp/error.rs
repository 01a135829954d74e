//! The LP's typed errors and its solver names.

use std::fmt;

/// Why an LP call was refused before any work (a bad table, problem, distribution, warm basis
/// or solver name) or failed outright (the reference backend). A problem no solver settles is
/// not an error: it is answered with [`super::Status::Failed`] and the reason.
#[derive(Clone, Debug, PartialEq)]
pub enum Error {
    /// The basis has no function.
    NoFunctions,
    /// More basis functions than [`super::MAX_FUNCTIONS`].
    TooManyFunctions {
        /// The number of functions asked for.
        m: usize,
    },
    /// More table values n·m than [`super::MAX_TABLE_VALUES`].
    TableTooLarge {
        /// Grid points.
        n: usize,
        /// Functions.
        m: usize,
    },
    /// A table given as values whose count is not n·m (or m = 0).
    TableShape {
        /// The number of values given.
        values: usize,
        /// Grid points.
        n: usize,
        /// Functions.
        m: usize,
    },
    /// b_j(z) is not finite.
    NotFinite {
        /// The function j, counted from 1.
        function: usize,
        /// The grid point.
        z: f64,
    },
    /// A column index at or beyond the table's number of functions.
    ColumnOutOfRange {
        /// The index asked for.
        index: usize,
        /// The table's number of functions.
        m: usize,
    },
    /// A solver name [`SolverKind`] does not know.
    UnknownSolver(String),
    /// A moment vector whose length is not m.
    MomentCount {
        /// m, one moment per basis function.
        expected: usize,
        /// The length given.
        got: usize,
    },
    /// A moment that is not finite.
    MomentNotFinite {
        /// The moment j, counted from 1.
        index: usize,
        /// Its value.
        value: f64,
    },
    /// z_f is NaN.
    ZfNaN,
    /// A distribution entry off the grid or with a negative or non-finite weight.
    DistributionEntry {
        /// The entry's position in the distribution.
        entry: usize,
        /// Its grid index.
        index: usize,
        /// The number of grid points.
        n: usize,
        /// Its weight.
        weight: f64,
    },
    /// A distribution whose weights sum to zero or to infinity.
    DistributionWeight,
    /// A warm-start basis whose size is not the LP's number of rows.
    WarmBasisSize {
        /// The number of rows, m + 1 less dropped dependent rows.
        expected: usize,
        /// The size given.
        got: usize,
    },
    /// A warm-start basis index off the grid or repeated.
    WarmBasisIndex {
        /// The index.
        index: usize,
    },
    /// The reference backend (good_lp + microlp) failed other than by infeasibility.
    Reference(String),
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        use super::{MAX_FUNCTIONS, MAX_TABLE_VALUES};
        match self {
            Error::NoFunctions => write!(f, "basis: need at least one function"),
            Error::TooManyFunctions { m } => write!(
                f,
                "basis: {m} functions is more than the LP's limit of {MAX_FUNCTIONS}"
            ),
            Error::TableTooLarge { n, m } => write!(
                f,
                "grid × basis: {n} points × {m} functions is more than the limit of \
                 {MAX_TABLE_VALUES} table values"
            ),
            Error::TableShape { values, n, m } => write!(
                f,
                "function table: {values} values for {n} points × {m} functions"
            ),
            Error::NotFinite { function, z } => {
                write!(f, "basis: function {function} is not finite at z = {z}")
            }
            Error::ColumnOutOfRange { index, m } => {
                write!(f, "function index {index} out of range (table has {m})")
            }
            Error::UnknownSolver(name) => write!(
                f,
                "unknown LP solver '{name}' (expected 'fast' or 'reference')"
            ),
            Error::MomentCount { expected, got } => {
                write!(f, "expected {expected} moments, got {got}")
            }
            Error::MomentNotFinite { index, value } => {
                write!(f, "moment {index} is not finite ({value})")
            }
            Error::ZfNaN => write!(f, "z_f is NaN"),
            Error::DistributionEntry {
                entry,
                index,
                n,
                weight,
            } => write!(
                f,
                "distribution entry {entry}: grid index {index} (of {n}) or weight {weight} \
                 invalid"
            ),
            Error::DistributionWeight => {
                write!(f, "distribution with zero (or infinite) total weight")
            }
            Error::WarmBasisSize { expected, got } => {
                write!(f, "basis: expected {expected} indices, got {got}")
            }
            Error::WarmBasisIndex { index } => {
                write!(f, "basis: index {index} out of range or repeated")
            }
            Error::Reference(why) => write!(f, "reference LP solver failed: {why}"),
        }
    }
}

impl std::error::Error for Error {}

/// The result of the LP's fallible calls.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// The two solvers of Algorithm 1 ([`super::make_solver`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum SolverKind {
    /// [`super::FastSolver`]: the certified revised simplex and its escalation chain.
    #[default]
    Fast,
    /// [`super::ReferenceSolver`]: good_lp + microlp on the LP as stated, uncertified.
    Reference,
}

impl SolverKind {
    /// Both solvers.
    pub const ALL: [SolverKind; 2] = [SolverKind::Fast, SolverKind::Reference];

    /// The name a batch file or `--solver` gives: "fast" or "reference".
    pub fn name(self) -> &'static str {
        match self {
            SolverKind::Fast => "fast",
            SolverKind::Reference => "reference",
        }
    }
}

impl std::str::FromStr for SolverKind {
    type Err = Error;

    /// "fast" or "reference"; "fast-strict", the fast solver's earlier name, is still read as
    /// "fast" (here only).
    fn from_str(s: &str) -> Result<SolverKind> {
        match s {
            "fast" | "fast-strict" => Ok(SolverKind::Fast),
            "reference" => Ok(SolverKind::Reference),
            other => Err(Error::UnknownSolver(other.to_string())),
        }
    }
}

impl fmt::Display for SolverKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}
