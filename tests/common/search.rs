//! Function tables of closed-form functions for the sweep tests.

use momentlab::search::FunctionTable;
use momentlab::Grid;
use std::f64::consts::PI;

/// A named function of depth.
pub type Named = (&'static str, fn(f64) -> f64);

/// 0 z, 1 z², 2 z³, 3 sin 2πz, 4 cos 2πz, 5 e^{2z}, 6 1 − z (degenerate with z),
/// 7 2z² + 1 (same span as z²).
pub const WITH_DEGENERATE: [Named; 8] = [
    ("z", |z| z),
    ("z^2", |z| z * z),
    ("z^3", |z| z * z * z),
    ("sin(2pi z)", |z| (2.0 * PI * z).sin()),
    ("cos(2pi z)", |z| (2.0 * PI * z).cos()),
    ("exp(2z)", |z| (2.0 * z).exp()),
    ("1-z", |z| 1.0 - z),
    ("2z^2+1", |z| 2.0 * z * z + 1.0),
];

/// 0 z, 1 z², 2 z³, 3 z⁴, 4 sin 2πz, 5 cos 2πz, 6 exp(2z), 7 exp(−10(z−½)²).
pub const SMOOTH: [Named; 8] = [
    ("z", |z| z.powi(1)),
    ("z^2", |z| z.powi(2)),
    ("z^3", |z| z.powi(3)),
    ("z^4", |z| z.powi(4)),
    ("sin(2pi z)", |z| (2.0 * PI * z).sin()),
    ("cos(2pi z)", |z| (2.0 * PI * z).cos()),
    ("exp(2z)", |z| (2.0 * z).exp()),
    ("bump", |z| (-10.0 * (z - 0.5) * (z - 0.5)).exp()),
];

/// The table of `functions` on `grid`.
pub fn table(grid: &Grid, functions: &[Named]) -> FunctionTable {
    FunctionTable::new(
        grid,
        functions.iter().map(|f| f.0.to_string()).collect(),
        |j, z| (functions[j].1)(z),
    )
    .unwrap()
}
