//! Starts from the moments alone (`solve(b, z_f)`, no distribution given): moments of one grid
//! point, or of two under a power basis, lie on the boundary of the moment space and have
//! those points as their only representation; under the power basis z, …, z⁴ (4MSM) interior
//! moments start from the canonical representation through the first grid point at or above
//! z_f (Peters & Klein 2015, Section 4.2, Algorithm 3), which the optimum of the discretised
//! problem nearly holds. Each becomes a start basis for the simplex, whose answer is certified
//! as any other; a start that does not factorise falls back to the usual one.

use super::linalg::norm;
use super::FastSolver;
use crate::linalg::Lu;
use crate::lp::fast::pricing::ColumnTable;
use crate::lp::GridTable;

/// Relative distance ‖c − Σ w_k a_k‖/‖c‖ up to which transformed moments c are taken as those
/// of one or two grid points (rounding of c = √n R⁻ᵀ b̄ is far below; another atom of weight w
/// moves c by about w‖a_i − a_j‖).
const ATOM_TOL: f64 = 1e-10;

/// Rows of the transformed LP at most for the nearest-column scan (m ≤ 12 and the constant).
const MAX_ROWS: usize = 13;

/// What the starts from moments need of the table, prepared once per table.
pub(super) struct Recognise {
    /// A coordinate k ≥ 1 of the transformed columns strictly monotone over the grid, with its
    /// direction (+1 increasing): a single atom is found by a binary search on it.
    pub(super) axis: Option<(usize, f64)>,
    /// Without such a coordinate: the columns with their squared norms as a last row,
    /// (a_i, ‖a_i‖²), whose scan with y = (2c, −1) and no step finds the column nearest c
    /// (the least ‖a_i‖² − 2 c·a_i).
    pub(super) table: ColumnTable,
    /// The table is the power basis z, …, z^m with m ≥ 4.
    pub(super) power: bool,
    /// The start basis of the current problem ([`FastSolver::moments_start`]).
    pub(super) basis: Vec<usize>,
    /// Factorisation workspace of the Hankel matrix.
    lu: Lu,
}

impl Recognise {
    /// For `table` and its transformed columns `cols` (column-major, cols[k·n + i] = a_i[k])
    /// of r rows.
    pub(super) fn new(table: &GridTable, cols: &[f64], r: usize) -> Recognise {
        let n = table.n();
        let coordinate = |k: usize| &cols[k * n..(k + 1) * n];
        let monotone =
            |k: usize, sign: f64| coordinate(k).windows(2).all(|w| sign * w[0] < sign * w[1]);
        let axis = (1..r)
            .flat_map(|k| [(k, 1.0), (k, -1.0)])
            .find(|&(k, sign)| monotone(k, sign));
        let scan_table = if axis.is_some() || r > MAX_ROWS {
            ColumnTable::default()
        } else {
            ColumnTable::new(r + 1, n, |k, i| {
                if k < r {
                    cols[k * n + i]
                } else {
                    (0..r).map(|t| cols[t * n + i] * cols[t * n + i]).sum()
                }
            })
        };
        let power = table.m() >= 4
            && (0..n).all(|i| {
                let z = table.grid().points()[i];
                let mut p = 1.0;
                table.row(i).iter().all(|&v| {
                    p *= z;
                    (v - p).abs() <= 1e-14 * p.abs()
                })
            });
        Recognise {
            axis,
            table: scan_table,
            power,
            basis: Vec::with_capacity(r),
            lu: Lu::default(),
        }
    }
}

impl FastSolver {
    /// The one or two grid points whose moments are `b` (transformed: c), if they are such
    /// moments ([`Self::single_atom`] given the `nearest` column, [`Self::two_atoms`]), as
    /// (atoms, count).
    pub(super) fn boundary_atoms(
        &mut self,
        b: &[f64],
        nearest: Option<(usize, f64)>,
    ) -> Option<([(u32, f64); 2], usize)> {
        if let Some(a) = self.single_atom(nearest) {
            return Some(([a, a], 1));
        }
        self.two_atoms(b).map(|p| (p, 2))
    }

    /// The start basis from the moments alone into `recognise.basis`; false when there is
    /// none. With `atoms` (boundary moments) and r = 5 rows: each atom and its grid neighbour
    /// towards z_f, where the optimal dual polynomial touches the step from below, then the
    /// first grid point at or above z_f and the ends of the grid. Otherwise, under the power
    /// basis with m = 4: the canonical representation through z_kf
    /// ([`Self::canonical_atoms`]), each of its two other atoms bracketed by its grid
    /// neighbours, and z_kf.
    pub(super) fn moments_start(
        &mut self,
        b: &[f64],
        kf: usize,
        atoms: Option<&[(u32, f64)]>,
    ) -> bool {
        let n = self.n;
        let mut basis = std::mem::take(&mut self.recognise.basis);
        basis.clear();
        match atoms {
            // More rows than z, …, z⁴ would fill the basis with neighbouring grid points (cond
            // beyond 1e12 under a power basis): the crossover from the atoms instead.
            Some(_) if self.r != 5 => return false,
            Some(atoms) => {
                for &(i, _) in atoms {
                    let i = i as usize;
                    let toward = if i < kf { i + 1 } else { i.wrapping_sub(1) };
                    push_distinct(&mut basis, self.r, &[i, toward], n);
                }
            }
            None => {
                if let Some((z2, z3)) = self.canonical_atoms(b, kf) {
                    let z = self.table.grid().points();
                    push_distinct(&mut basis, self.r, &[kf], n);
                    for root in [z2, z3] {
                        let p = z.partition_point(|&x| x < root);
                        push_distinct(&mut basis, self.r, &[p.wrapping_sub(1), p], n);
                    }
                }
            }
        }
        let found = !basis.is_empty();
        let fill = [kf, 0, n - 1, kf + 1, kf.wrapping_sub(1), n / 2];
        push_distinct(&mut basis, self.r, &fill, n);
        self.recognise.basis = basis;
        found && self.recognise.basis.len() == self.r
    }

    /// Under the power basis z, …, z⁴: the atoms z₂ ≤ z₃ of the canonical representation of
    /// the moments b through ζ = z_kf, the roots of c₁ + c₂z + c₃z² for H c = (1, ζ, ζ²), H the
    /// Hankel matrix of (1, b₁, …, b₄) (Algorithm 3, steps 2–3). None for boundary moments
    /// (H not positive definite), complex roots or kf at an end of the grid.
    fn canonical_atoms(&mut self, b: &[f64], kf: usize) -> Option<(f64, f64)> {
        if !self.recognise.power || self.r != 5 || kf == 0 || kf >= self.n {
            return None;
        }
        let zeta = self.table.grid().points()[kf];
        let h = [
            1.0, b[0], b[1], //
            b[0], b[1], b[2], //
            b[1], b[2], b[3],
        ];
        if b[1] - b[0] * b[0] <= 0.0 || b[1].is_nan() {
            return None;
        }
        let lu = &mut self.recognise.lu;
        if !lu.factor(&h, 3) || lu.log2_abs_det().1 <= 0.0 {
            return None;
        }
        let mut c = [1.0, zeta, zeta * zeta];
        lu.solve(&mut c);
        quadratic_roots(c[1] / c[2], c[0] / c[2])
    }

    /// The grid point whose column equals the transformed moments c to rounding,
    /// ‖c − a_j‖ ≤ [`ATOM_TOL`] ‖c‖, as a one-atom distribution, given the `nearest` column
    /// ([`Self::nearest_column`]).
    pub(super) fn single_atom(&mut self, nearest: Option<(usize, f64)>) -> Option<(u32, f64)> {
        let (j, gap) = nearest?;
        (gap <= ATOM_TOL).then(|| {
            self.stats.single_atom += 1;
            (j as u32, 1.0)
        })
    }

    /// The grid point j whose column is nearest the transformed moments c, with the relative
    /// distance ‖c − a_j‖/‖c‖: by a binary search on the monotone coordinate (the nearer of
    /// the two grid points around c), else by the scan of `recognise.table`. None with more
    /// rows than the scan holds.
    pub(super) fn nearest_column(&self) -> Option<(usize, f64)> {
        let r = self.r;
        let gap = |j: usize| {
            let aj = &self.ortho.rows[j * r..(j + 1) * r];
            aj.iter()
                .zip(&self.c)
                .map(|(a, c)| (a - c) * (a - c))
                .sum::<f64>()
        };
        let j = match self.recognise.axis {
            Some((k, sign)) => {
                // a_i[k] is strictly monotone in i: the two grid points around c[k].
                let key = |i: usize| sign * self.ortho.rows[i * r + k];
                let p = partition_point(self.n, |i| key(i) < sign * self.c[k]);
                let (lo, hi) = (p.saturating_sub(1), p.min(self.n - 1));
                if gap(lo) <= gap(hi) {
                    lo
                } else {
                    hi
                }
            }
            None if r > MAX_ROWS => return None,
            None => {
                let near = &self.recognise.table;
                let mut y = [0.0; MAX_ROWS + 1];
                for (yk, ck) in y.iter_mut().zip(&self.c) {
                    *yk = 2.0 * ck;
                }
                y[r] = -1.0;
                let none = (usize::MAX, f64::INFINITY);
                near.scan(&y[..r + 1], 0, 0, near.blocks(), none).0
            }
        };
        (j < self.n).then(|| (j, gap(j).sqrt() / norm(&self.c)))
    }

    /// Under a power basis z, …, z^m (m ≥ 4): the two grid points whose mixture has the
    /// moments `b`. A two-point measure w δ(z₁) + (1 − w) δ(z₂) has m_{s+2} + p₁ m_{s+1} +
    /// p₀ m_s = 0 (s = 0, 1) for (z − z₁)(z − z₂) = z² + p₁z + p₀ (Prony's method), so
    /// p₁ = (m₁m₂ − m₃)/(m₂ − m₁²), p₀ = −m₂ − p₁m₁. Its roots are snapped to the grid, w is
    /// the least-squares weight of the pair in the transformed coordinates, and the mixture
    /// must equal c to ‖c − w a_i − (1 − w) a_j‖ ≤ [`ATOM_TOL`] ‖c‖. Such moments lie on the
    /// boundary of the moment space (2 < (m + 1)/2 points).
    pub(super) fn two_atoms(&mut self, b: &[f64]) -> Option<[(u32, f64); 2]> {
        if !self.recognise.power {
            return None;
        }
        let (m1, m2, m3) = (b[0], b[1], b[2]);
        let var = m2 - m1 * m1;
        if var.is_nan() || var <= 0.0 {
            return None;
        }
        let p1 = (m1 * m2 - m3) / var;
        let (z1, z2) = quadratic_roots(p1, -m2 - p1 * m1)?;
        let grid = self.table.grid();
        let (i, j) = (grid.nearest(z1), grid.nearest(z2));
        if i == j {
            return None;
        }
        let r = self.r;
        let (ai, aj) = (
            &self.ortho.rows[i * r..(i + 1) * r],
            &self.ortho.rows[j * r..(j + 1) * r],
        );
        // w = (c − a_j)·(a_i − a_j) / ‖a_i − a_j‖².
        let (mut num, mut den) = (0.0, 0.0);
        for k in 0..r {
            let d = ai[k] - aj[k];
            num += (self.c[k] - aj[k]) * d;
            den += d * d;
        }
        let w = num / den;
        if !(w > 0.0 && w < 1.0) {
            return None;
        }
        let gap: f64 = (0..r)
            .map(|k| (self.c[k] - w * ai[k] - (1.0 - w) * aj[k]).powi(2))
            .sum();
        (gap.sqrt() <= ATOM_TOL * norm(&self.c)).then(|| {
            self.stats.two_atoms += 1;
            [(i as u32, w), (j as u32, 1.0 - w)]
        })
    }
}

/// The real roots z₁ ≤ z₂ of z² + p₁z + p₀ (the larger in magnitude without cancellation, the
/// other from z₁z₂ = p₀); None when they are complex, coincide or are not finite.
fn quadratic_roots(p1: f64, p0: f64) -> Option<(f64, f64)> {
    let disc = p1 * p1 - 4.0 * p0;
    if disc.is_nan() || disc <= 0.0 {
        return None;
    }
    let q = -0.5 * (p1 + disc.sqrt().copysign(p1));
    let (a, b) = (q, p0 / q);
    (a.is_finite() && b.is_finite()).then_some((a.min(b), a.max(b)))
}

/// Appends the grid indices of `cols` below `n` not yet in `basis`, up to `r` entries
/// (indices may wrap below 0 to usize::MAX, which is skipped).
fn push_distinct(basis: &mut Vec<usize>, r: usize, cols: &[usize], n: usize) {
    for &c in cols {
        if basis.len() < r && c < n && !basis.contains(&c) {
            basis.push(c);
        }
    }
}

/// The first i in 0..n with `!below(i)` (n if none), for `below` true on a prefix.
fn partition_point(n: usize, below: impl Fn(usize) -> bool) -> usize {
    let (mut lo, mut hi) = (0, n);
    while lo < hi {
        let mid = (lo + hi) / 2;
        if below(mid) {
            lo = mid + 1;
        } else {
            hi = mid;
        }
    }
    lo
}

#[cfg(test)]
mod tests {
    use super::{partition_point, quadratic_roots};
    use crate::lp::corpus::{moments_groups, problem, Kind};
    use crate::lp::{distribution_moments, FastSolver, GridTable, MomentSolver, Status};
    use crate::Grid;
    use rand::{Rng, SeedableRng};

    fn power(z: f64, o: &mut [f64]) {
        let mut p = 1.0;
        for v in o.iter_mut() {
            p *= z;
            *v = p;
        }
    }

    fn trig(z: f64, o: &mut [f64]) {
        let t = std::f64::consts::TAU * z;
        o.copy_from_slice(&[t.sin(), t.cos(), (2.0 * t).sin(), (2.0 * t).cos()]);
    }

    fn solver(n: usize, m: usize, f: fn(f64, &mut [f64])) -> FastSolver {
        FastSolver::new(GridTable::from_fn(&Grid::uniform(n).unwrap(), m, f).unwrap())
    }

    /// Moments of one grid point z_j have that atom as their only representation: G is
    /// [z_j < z_f] with support δ(z_j) (to rounding), found by the binary search on a monotone
    /// coordinate (power basis) and by the nearest-column scan (trigonometric basis, no
    /// monotone coordinate).
    #[test]
    fn single_atom_moments_start_from_that_atom() {
        for (f, monotone) in [(power as fn(f64, &mut [f64]), true), (trig, false)] {
            let mut s = solver(301, 4, f);
            assert_eq!(s.recognise.axis.is_some(), monotone);
            let z = s.table().grid().points().to_vec();
            let mut b = [0.0; 4];
            // (The trigonometric columns of z = 0 and z = 1 coincide: the ends are left out.)
            for j in (1..300).step_by(7) {
                f(z[j], &mut b);
                for zf in [z[j] - 1e-3, z[j] + 1e-3] {
                    let before = s.stats().single_atom;
                    let sol = s.solve(&b, zf).unwrap();
                    assert_eq!(s.stats().single_atom, before + 1, "z = {}", z[j]);
                    assert_eq!(sol.status, Status::Optimal);
                    let want = if z[j] < zf { 1.0 } else { 0.0 };
                    assert!((sol.g - want).abs() <= 1e-12, "{} {want}", sol.g);
                    for &(zi, w) in &sol.support {
                        let at = if zi == z[j] { 1.0 } else { 0.0 };
                        assert!((w - at).abs() <= 1e-12, "{:?}", sol.support);
                    }
                }
            }
        }
    }

    /// Moments of two grid points under a power basis (m = 4 and 6) are recognised by Prony's
    /// method: G = w[z_i < z_f] + (1 − w)[z_j < z_f] with the mass on the pair, for pairs far
    /// apart, neighbours and the ends of the grid; under the trigonometric basis they are not
    /// recognised, and G is the same.
    #[test]
    fn two_atom_moments_start_from_that_pair() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        for (f, m, power_basis) in [
            (power as fn(f64, &mut [f64]), 4, true),
            (power, 6, true),
            (trig, 4, false),
        ] {
            let mut s = solver(301, m, f);
            let z = s.table().grid().points().to_vec();
            for t in 0..300 {
                let i = match t % 3 {
                    0 => 1 + rng.gen_range(0..298),
                    1 => rng.gen_range(1..299),
                    _ => [1, 298][t % 2],
                };
                let j = if t % 3 == 1 {
                    i + 1
                } else {
                    rng.gen_range(1..300)
                };
                if i == j {
                    continue;
                }
                let w = rng.gen_range(0.05..0.95);
                let b = distribution_moments(s.table(), &[(i as u32, w), (j as u32, 1.0 - w)]);
                let b = b.unwrap();
                let zf = rng.gen_range(0.0..1.0);
                let before = s.stats().two_atoms;
                let sol = s.solve(&b, zf).unwrap();
                assert_eq!(s.stats().two_atoms - before, power_basis as u64, "{i} {j}");
                assert_eq!(sol.status, Status::Optimal);
                let want = w * (z[i] < zf) as u8 as f64 + (1.0 - w) * (z[j] < zf) as u8 as f64;
                assert!(
                    (sol.g - want).abs() <= 1e-9,
                    "{i} {j} {zf}: {} {want}",
                    sol.g
                );
                // The pair carries the mass (other basic points within the certificate's
                // tolerance).
                let on_pair: f64 = sol
                    .support
                    .iter()
                    .filter(|p| p.0 == z[i] || p.0 == z[j])
                    .map(|p| p.1)
                    .sum();
                assert!(on_pair >= 1.0 - 1e-6, "{i} {j}: {:?}", sol.support);
            }
        }
    }

    /// The canonical representation through ζ: the measure on (ζ, z₂, z₃) whose weights solve
    /// its Vandermonde system for (1, b₁, b₂) reproduces b₃ and b₄ too, with positive
    /// weights, for 2 000 random interior moment vectors (3–6 atoms anywhere in [0, 1], some in
    /// tight clusters) and ζ on the grid; for three atoms of which one is ζ, z₂ and z₃ are the
    /// other two.
    #[test]
    fn canonical_atoms_reproduce_the_moments() {
        let mut s = solver(1024, 4, power);
        let z = s.table().grid().points().to_vec();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
        let mut checked = 0;
        for t in 0..2000 {
            let k = rng.gen_range(3..=6);
            let centre: f64 = rng.gen_range(0.0..1.0);
            let spread = if t % 4 == 0 { 1e-3 } else { 1.0 };
            let mut atoms: Vec<(f64, f64)> = (0..k)
                .map(|_| {
                    let x = (centre + spread * rng.gen_range(-1.0..1.0)).clamp(0.0, 1.0);
                    (x, rng.gen_range(0.05..1.0))
                })
                .collect();
            let kf = rng.gen_range(1..1023);
            if t % 5 == 0 {
                // Three atoms apart, one of them at ζ.
                atoms = vec![
                    (rng.gen_range(0.0..1.0), 0.4),
                    (rng.gen_range(0.0..1.0), 0.3),
                ];
                atoms.push((z[kf], 0.3));
                let x: Vec<f64> = atoms.iter().map(|a| a.0).collect();
                if (x[0] - x[1])
                    .abs()
                    .min((x[0] - x[2]).abs())
                    .min((x[1] - x[2]).abs())
                    < 1e-2
                {
                    continue;
                }
            }
            let total: f64 = atoms.iter().map(|a| a.1).sum();
            let moment = |p: i32| atoms.iter().map(|a| a.1 * a.0.powi(p)).sum::<f64>() / total;
            let b = [moment(1), moment(2), moment(3), moment(4)];
            let Some((z2, z3)) = s.canonical_atoms(&b, kf) else {
                continue;
            };
            // Weights of (ζ, z₂, z₃) from the first three moments (Lagrange form).
            let x = [z[kf], z2, z3];
            let mut w = [0.0; 3];
            for a in 0..3 {
                let (p, q) = (x[(a + 1) % 3], x[(a + 2) % 3]);
                w[a] = (b[1] - (p + q) * b[0] + p * q) / ((x[a] - p) * (x[a] - q));
            }
            let scale = 1.0 + b.iter().fold(0.0f64, |acc, v| acc.max(v.abs()));
            let spread_ok = (x[0] - x[1])
                .abs()
                .min((x[0] - x[2]).abs())
                .min(x[2] - x[1]);
            if spread_ok < 1e-2 {
                continue; // clustered nodes: the weights from three moments are ill-conditioned
            }
            for p in 3..=4 {
                let got: f64 = (0..3).map(|a| w[a] * x[a].powi(p)).sum();
                assert!(
                    (got - b[p as usize - 1]).abs() <= 1e-9 * scale,
                    "{t}: {got} {b:?}"
                );
            }
            assert!(w.iter().all(|&v| v > -1e-12), "{t}: {w:?}");
            if t % 5 == 0 {
                let mut want = [atoms[0].0, atoms[1].0];
                want.sort_by(f64::total_cmp);
                assert!(
                    (z2 - want[0]).abs() < 1e-6 && (z3 - want[1]).abs() < 1e-6,
                    "{t}: {atoms:?} {z2} {z3}"
                );
            }
            checked += 1;
        }
        assert!(checked > 1000, "{checked}");
    }

    /// From the moments alone the fast solver answers as from the distribution: 2 500
    /// problems at n = 1024 (the Dirac row of `bench lp --corpus moments`: 1–4 Diracs on grid
    /// points, z_f uniform; and boundary moments, mixtures, clusters, adjacent points; power
    /// basis m = 4) certified both ways with G within 2e-9, most of them started from a basis
    /// built from the moments, none failed.
    #[test]
    fn moments_starts_answer_as_the_distribution_start() {
        let mut from_moments = solver(1024, 4, power);
        let mut from_dist = solver(1024, 4, power);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let diracs = moments_groups(from_moments.table(), "z..z^4", 2000, 11).swap_remove(0);
        let kinds = [Kind::Boundary, Kind::Mixture, Kind::Cluster, Kind::Adjacent];
        let others = (0..500).map(|t| {
            let dist = problem(&mut rng, 1024, 4, kinds[t % 4]).dist;
            (dist, rng.gen_range(0.0..1.0))
        });
        let problems: Vec<(Vec<(u32, f64)>, f64)> = diracs
            .problems
            .into_iter()
            .map(|p| (p.dist, p.zf[0]))
            .chain(others.collect::<Vec<_>>())
            .collect();
        for (t, (dist, zf)) in problems.iter().enumerate() {
            let b = distribution_moments(from_moments.table(), dist).unwrap();
            let got = from_moments.solve(&b, *zf).unwrap();
            let want = from_dist.solve_distribution(dist, *zf).unwrap();
            assert_eq!(got.status, Status::Optimal, "{t}: {dist:?} {zf}");
            assert_eq!(want.status, Status::Optimal, "{t}");
            assert!((got.g - want.g).abs() <= 2e-9, "{t}: {} {}", got.g, want.g);
        }
        let st = from_moments.stats();
        assert!(st.moments_starts > 1500, "{st:?}");
        assert_eq!(st.failed, 0, "{st:?}");
    }

    /// The quadratic's roots against the product form, and the first index where a prefix
    /// predicate turns false as the slice method finds it.
    #[test]
    fn quadratic_roots_and_partition_point() {
        assert_eq!(quadratic_roots(-3.0, 2.0), Some((1.0, 2.0)));
        assert_eq!(quadratic_roots(1e8, 1.0).map(|r| r.1), Some(-1e-8));
        assert_eq!(quadratic_roots(2.0, 1.0), None);
        assert_eq!(quadratic_roots(0.0, 1.0), None);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        for _ in 0..500 {
            let mut v: Vec<u32> = (0..rng.gen_range(0..30))
                .map(|_| rng.gen_range(0..20))
                .collect();
            v.sort();
            let t = rng.gen_range(0..21);
            let want = v.partition_point(|&x| x < t);
            assert_eq!(partition_point(v.len(), |i| v[i] < t), want);
        }
    }
}
