//! Band solves: the fast simplex on a window of the grid, for answers the whole-grid run could
//! not certify (steep functions such as exp(±40z)).
//!
//! On the whole grid exp(40z) spans 10^17, and √n·Q resolves it relative to its largest values
//! only: for a distribution at z ≤ 0.45 the moment b_j ≈ 10⁻¹⁰ max|f_j| is seen to ~10⁻⁶ of
//! itself, so a weight of −10⁻¹⁵ at z = 1 (inside the absolute tolerance TOL_P) absorbs the
//! whole row and the "optimal" basis misses the moment by 10⁻³…10⁻¹. Restricted to an interval
//! [z_s, z_t] of the grid that holds the window's atoms and z_f, the same function spans
//! e^{40(z_t−z_s)}, the orthonormalised coordinates of that sub-table resolve the row, and the
//! fast simplex finds the optimum of the LP on the band. That basis is a basis of the whole LP
//! (same rows, a subset of its columns); the certificate on the WHOLE grid decides whether it
//! is optimal there (the band optimum is the grid optimum iff no column outside the band has a
//! negative reduced cost), with accurate pivots from it when it is not.
//!
//! On a steep table ([`is_steep`]) a distribution start goes to its band first (measured on
//! the stacks corpus with z, z², exp(±40z): 45 → 21 µs mean against trying the whole grid
//! first); elsewhere the band is tried only after the whole-grid optimum failed to certify,
//! before the accurate pivots and the escalation.

use super::{FastSolver, Verdict, IMPROVE_STEPS};
use crate::lp::certify::Certified;
use crate::lp::GridTable;
use crate::Grid;

/// Band lengths tried, as fractions 1/BAND_DIVS[k] of the grid (longest last).
const BAND_DIVS: [usize; 3] = [8, 4, 2];
/// Smallest grid on which bands are used.
const MIN_GRID: usize = 64;
/// Grid points of margin around the window's atoms and z_f inside a band.
const PAD: usize = 2;

/// The band sub-solvers of a table, built on first use: (first grid index, length, solver).
#[derive(Default)]
pub(super) struct Bands {
    pub(super) solvers: Vec<(usize, usize, Box<FastSolver>)>,
    /// Bands are used (off in the band solvers themselves).
    pub(super) on: bool,
    /// The table has a steep function ([`is_steep`]): distribution starts go to the band
    /// first.
    pub(super) first: bool,
    /// The band of the current problem was tried already.
    pub(super) tried: bool,
}

/// Ratio max over the grid / max over a half of it above which a function counts as steep.
const STEEP: f64 = 1e6;

/// Whether some function of `table` is steep: its largest magnitude on one half of the grid is
/// below 1/[`STEEP`] of its largest on the whole grid (exp(40z): e^−20; z^12: 2^−12 is not).
pub(super) fn is_steep(table: &GridTable) -> bool {
    let n = table.n();
    (0..table.m()).any(|j| {
        let half =
            |lo: usize, hi: usize| (lo..hi).fold(0.0f64, |a, i| a.max(table.row(i)[j].abs()));
        let (a, b) = (half(0, n / 2), half(n / 2, n));
        a.max(b) > STEEP * a.min(b)
    })
}

impl Bands {
    /// Forget every band solver's warm start (see [`FastSolver::reset`]).
    pub(super) fn reset(&mut self) {
        for (_, _, s) in &mut self.solvers {
            s.reset();
        }
    }
}

/// The shortest band [s, s + len) with len = n/8, n/4 or n/2 and s a multiple of len/2 (or
/// n − len) that holds [lo, hi]; None when only the whole grid does.
fn pick_band(n: usize, lo: usize, hi: usize) -> Option<(usize, usize)> {
    if n < MIN_GRID {
        return None;
    }
    for div in BAND_DIVS {
        let len = n / div;
        let step = len / 2;
        let s = ((lo / step) * step).min(n - len);
        if s <= lo && hi < s + len {
            return Some((s, len));
        }
    }
    None
}

impl FastSolver {
    /// The optimal basis of the LP restricted to the band that holds `dist`'s atoms and the
    /// first grid point at or above z_f (grid indices of the whole table), from the band's own
    /// fast simplex (crossover from `dist`); None when no band applies or the band run does
    /// not end optimal. Not certified: the caller certifies it on the whole grid.
    pub(super) fn band_basis(
        &mut self,
        moments: &[f64],
        kf: usize,
        zf: f64,
        dist: &[(u32, f64)],
    ) -> Option<Vec<usize>> {
        if !self.bands.on || self.bands.tried {
            return None;
        }
        self.bands.tried = true;
        let n = self.n;
        let atoms = dist.iter().filter(|e| e.1 > 0.0).map(|e| e.0 as usize);
        let lo = atoms.clone().min()?.saturating_sub(PAD);
        let hi = (atoms.max()?.max(kf) + PAD).min(n - 1);
        let (s, len) = pick_band(n, lo, hi)?;
        let k = match self
            .bands
            .solvers
            .iter()
            .position(|b| b.0 == s && b.1 == len)
        {
            Some(k) => k,
            None => {
                let sub = self.band_solver(s, len)?;
                self.bands.solvers.push((s, len, Box::new(sub)));
                self.bands.solvers.len() - 1
            }
        };
        self.stats.band_solves += 1;
        let shifted: Vec<(u32, f64)> = dist
            .iter()
            .filter(|e| e.1 > 0.0)
            .map(|&(i, w)| (i - s as u32, w))
            .collect();
        let sub = &mut self.bands.solvers[k].2;
        if sub.r != self.r {
            return None;
        }
        let basis = sub.band_optimum(moments, zf, &shifted)?;
        Some(basis.iter().map(|&i| i + s).collect())
    }

    /// The band's optimal basis ([`Self::band_basis`]) certified on the whole grid, as it
    /// stands or after accurate pivots (columns outside the band entering); it becomes the
    /// warm start. None when no band applies, it was tried for this problem already, or
    /// nothing certifies.
    pub(super) fn band_certified(
        &mut self,
        moments: &[f64],
        kf: usize,
        zf: f64,
        dist: &[(u32, f64)],
    ) -> Option<Certified> {
        let mut basis = self.band_basis(moments, kf, zf, dist)?;
        let found = match self.cert.optimal(moments, kf, &basis) {
            Err(why) => self
                .cert
                .improve_checked(moments, kf, &mut basis, IMPROVE_STEPS, why),
            ok => ok,
        };
        let c = found.ok()?;
        self.stats.band_certified += 1;
        self.remember_certified(&basis);
        Some(c)
    }

    /// The fast solver on grid points s..s + len of this table (no bands of its own).
    fn band_solver(&self, s: usize, len: usize) -> Option<FastSolver> {
        let grid = Grid::from_values(self.table.grid().points()[s..s + len].to_vec()).ok()?;
        let mut i = s;
        let table = GridTable::from_fn(&grid, self.m, |_, out| {
            out.copy_from_slice(self.table.row(i));
            i += 1;
        })
        .ok()?;
        let mut sub = FastSolver::new(table);
        sub.bands.on = false;
        Some(sub)
    }

    /// The fast simplex from distribution `dist` (indices of this table) to its verdict,
    /// without certificate or escalation: the optimal basis, or None.
    fn band_optimum(
        &mut self,
        moments: &[f64],
        zf: f64,
        dist: &[(u32, f64)],
    ) -> Option<Vec<usize>> {
        self.stats.solves += 1;
        self.last_exact = None;
        self.accurate = false;
        self.b_orig.copy_from_slice(moments);
        let kf = self.table.grid().points().partition_point(|&z| z < zf);
        self.distribution_coordinates(dist);
        self.c0.copy_from_slice(&self.c);
        // No certificate pass stands in for the full pricing pass here.
        self.partial_optimum = false;
        self.full_pass_skipped = false;
        match self.attempts(kf, Some(dist)) {
            Verdict::Optimal if self.basis.iter().all(|&i| i < self.n) => {
                self.remember_optimal();
                Some(self.basis.clone())
            }
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::pick_band;

    #[test]
    fn bands_hold_the_window() {
        assert_eq!(pick_band(32, 0, 3), None);
        assert_eq!(pick_band(1024, 140, 180), Some((128, 128)));
        assert_eq!(pick_band(1024, 140, 260), Some((128, 256)));
        assert_eq!(pick_band(1024, 100, 200), Some((0, 256)));
        assert_eq!(pick_band(1024, 1000, 1023), Some((896, 128)));
        assert_eq!(pick_band(1024, 200, 700), None);
        for (lo, hi) in [(0, 0), (5, 500), (511, 513), (900, 1023)] {
            if let Some((s, len)) = pick_band(1024, lo, hi) {
                assert!(s <= lo && hi < s + len && s + len <= 1024);
            }
        }
    }
}
