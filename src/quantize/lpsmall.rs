//! A small dense LP solver for the row subproblem of the θ search: max c·x s.t. G x ≤ h with
//! x ∈ R^n free and few variables (n ≤ ~13). Solved through its dual min h·y s.t. Gᵀy = c,
//! y ≥ 0 by a two-phase tableau simplex with Bland's rule (terminates on degenerate
//! problems); the primal x solves the n basic (tight) rows G_B x = h_B. Checked against the
//! good_lp/microlp reference in the tests.

use super::linalg::Lu;

/// Maximiser of c·x subject to G x ≤ h (rows of `g`), or None if unbounded, infeasible or
/// degenerate beyond what this solver handles (callers then fall back to good_lp).
pub fn max_free(c: &[f64], g: &[Vec<f64>], h: &[f64]) -> Option<Vec<f64>> {
    let n = c.len();
    let nn = g.len();
    let cols = nn + n + 1; // y, artificials, rhs
    let rhs = nn + n;
    let tol = 1e-11;
    // rows: Gᵀ y = c, sign-normalised so that rhs ≥ 0
    let mut t = vec![vec![0.0; cols]; n];
    for i in 0..n {
        let s = if c[i] < 0.0 { -1.0 } else { 1.0 };
        for (k, row) in g.iter().enumerate() {
            t[i][k] = s * row[i];
        }
        t[i][nn + i] = 1.0;
        t[i][rhs] = s * c[i];
    }
    let mut basis: Vec<usize> = (nn..nn + n).collect();
    // phase 1: minimise the sum of artificials
    let mut cost1 = vec![0.0; nn + n];
    cost1[nn..].iter_mut().for_each(|v| *v = 1.0);
    run(&mut t, &mut basis, &cost1, nn + n, tol)?;
    let infeas: f64 = basis
        .iter()
        .zip(&t)
        .filter(|(&b, _)| b >= nn)
        .map(|(_, r)| r[rhs])
        .sum();
    if infeas > 1e-9 {
        return None; // dual infeasible: primal unbounded
    }
    // drive basic artificials (at level 0) out of the basis
    for i in 0..n {
        if basis[i] >= nn {
            let j = (0..nn).find(|&j| t[i][j].abs() > 1e-9)?;
            pivot(&mut t, &mut basis, i, j);
        }
    }
    let mut cost2 = h.to_vec();
    cost2.extend(std::iter::repeat_n(0.0, n));
    run(&mut t, &mut basis, &cost2, nn, tol)?;
    let gb: Vec<Vec<f64>> = basis.iter().map(|&k| g[k].clone()).collect();
    let hb: Vec<f64> = basis.iter().map(|&k| h[k]).collect();
    let x = Lu::new(&gb)?.solve(&hb);
    x.iter().all(|v| v.is_finite()).then_some(x)
}

fn pivot(t: &mut [Vec<f64>], basis: &mut [usize], r: usize, j: usize) {
    let p = t[r][j];
    t[r].iter_mut().for_each(|v| *v /= p);
    let prow = t[r].clone();
    for (i, row) in t.iter_mut().enumerate() {
        if i != r {
            let f = row[j];
            if f != 0.0 {
                for (v, pv) in row.iter_mut().zip(&prow) {
                    *v -= f * pv;
                }
            }
        }
    }
    basis[r] = j;
}

/// The leaving row for entering column `j`: the least ratio x_i/α_i over the rows with
/// α_i = t[i][j] > `piv`, x_i = t[i][last] as it stands (a slightly negative x_i gives a
/// negative ratio), rows scanned in order and a ratio within 10⁻¹⁵ (absolute) of the best so
/// far counting as a tie, resolved to the smallest basic index. None when no α_i exceeds `piv`.
///
/// This is not the crate's ratio test (`lp::ratio::harris`, whose tol = 0 case with keys is
/// Bland's): that one reads x_i < 0 as 0 and has no absolute window, so on degenerate θ row
/// LPs it picks other rows, and the seeded θ₄ search (`momentlab theta --m 4 --restarts 4
/// --hops 10 --hop-sigma 0.3`) then ends at another θ₄ (entries differ by up to 2·10⁻³).
fn leaving_row(t: &[Vec<f64>], basis: &[usize], j: usize, piv: f64) -> Option<usize> {
    let rhs = t[0].len() - 1;
    let mut best: Option<(f64, usize, usize)> = None;
    for (i, row) in t.iter().enumerate() {
        if row[j] > piv {
            let ratio = row[rhs] / row[j];
            let better = match best {
                None => true,
                Some((br, _, bb)) => ratio < br - 1e-15 || (ratio <= br + 1e-15 && basis[i] < bb),
            };
            if better {
                best = Some((ratio, i, basis[i]));
            }
        }
    }
    best.map(|(_, i, _)| i)
}

/// Simplex iterations (Bland's rule) minimising cost over columns < `allowed`.
fn run(
    t: &mut [Vec<f64>],
    basis: &mut [usize],
    cost: &[f64],
    allowed: usize,
    tol: f64,
) -> Option<()> {
    for _ in 0..100_000 {
        // reduced costs r_j = cost_j − Σ_i cost_{B_i} t[i][j]
        let entering = (0..allowed).find(|&j| {
            if basis.contains(&j) {
                return false;
            }
            let r = cost[j]
                - basis
                    .iter()
                    .zip(t.iter())
                    .map(|(&b, row)| cost[b] * row[j])
                    .sum::<f64>();
            r < -tol
        });
        let Some(j) = entering else {
            return Some(());
        };
        // unbounded direction in the dual: primal infeasible
        let r = leaving_row(t, basis, j, tol)?;
        pivot(t, basis, r, j);
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use good_lp::{microlp, variable, variables, Expression, Solution, SolverModel, Variable};
    use rand::{Rng, SeedableRng};

    fn reference(c: &[f64], g: &[Vec<f64>], h: &[f64]) -> Option<f64> {
        let mut vars = variables!();
        let x: Vec<Variable> = c
            .iter()
            .map(|_| vars.add(variable().min(-1e6).max(1e6)))
            .collect();
        let obj: Expression = x.iter().zip(c).map(|(v, &ci)| ci * *v).sum();
        let mut model = vars.maximise(obj).using(microlp);
        for (row, &hk) in g.iter().zip(h) {
            let e: Expression = x.iter().zip(row).map(|(v, &gi)| gi * *v).sum();
            model = model.with(e.leq(hk));
        }
        let s = model.solve().ok()?;
        Some(x.iter().zip(c).map(|(v, &ci)| ci * s.value(*v)).sum())
    }

    #[test]
    fn leaving_row_takes_the_least_raw_ratio_with_an_absolute_tie_window() {
        // Tableau rows [α_i, x_i], entering column 0.
        let rows = |v: &[[f64; 2]]| v.iter().map(|r| r.to_vec()).collect::<Vec<_>>();
        // Ratios 1e-16 and 0 tie (within 1e-15): the smaller basic index leaves.
        let t = rows(&[[1.0, 1e-16], [1.0, 0.0]]);
        assert_eq!(leaving_row(&t, &[3, 7], 0, 1e-11), Some(0));
        assert_eq!(leaving_row(&t, &[7, 3], 0, 1e-11), Some(1));
        // A negative x_i counts as it is: ratio −1.6e-15 is below 1e-16 − 1e-15.
        let t = rows(&[[1.0, 1e-16], [0.125, -2e-16]]);
        assert_eq!(leaving_row(&t, &[3, 7], 0, 1e-11), Some(1));
        // Ties are against the best so far: 0 (key 3), 0.8e-15 (key 2), 1.6e-15 (key 1).
        let t = rows(&[[1.0, 0.0], [1.0, 0.8e-15], [1.0, 1.6e-15]]);
        assert_eq!(leaving_row(&t, &[3, 2, 1], 0, 1e-11), Some(2));
        // Entries at or below the pivot tolerance never leave.
        let t = rows(&[[1e-12, 0.0], [-1.0, 0.0], [2.0, 1.0]]);
        assert_eq!(leaving_row(&t, &[0, 1, 2], 0, 1e-11), Some(2));
        assert_eq!(leaving_row(&t[..2], &[0, 1], 0, 1e-11), None);
    }

    #[test]
    fn agrees_with_microlp_on_random_band_lps() {
        // the θ row LP: 0 ≤ q_k·a + t ≤ 1, random points q_k, random objective
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
        for trial in 0..1500 {
            let m = rng.gen_range(1..7);
            let k = rng.gen_range(m + 2..6 * m + 6);
            let mut g = Vec::new();
            let mut h = Vec::new();
            for _ in 0..k {
                let q: Vec<f64> = (0..m).map(|_| rng.gen_range(-2.0..2.0)).collect();
                let mut up = q.clone();
                up.push(1.0);
                g.push(up.clone());
                h.push(1.0);
                g.push(up.iter().map(|v| -v).collect());
                h.push(0.0);
                // adversarial: duplicate constraints (degeneracy)
                if trial % 5 == 0 {
                    g.push(up);
                    h.push(1.0);
                }
            }
            let mut c: Vec<f64> = (0..m).map(|_| rng.gen_range(-1.0..1.0)).collect();
            c.push(0.0);
            let want = reference(&c, &g, &h).unwrap();
            let x = max_free(&c, &g, &h).unwrap();
            let got: f64 = x.iter().zip(&c).map(|(p, q)| p * q).sum();
            assert!(
                (got - want).abs() < 1e-7 * (1.0 + want.abs()),
                "{got} vs {want}"
            );
            for (row, &hk) in g.iter().zip(&h) {
                let s: f64 = row.iter().zip(&x).map(|(p, q)| p * q).sum();
                assert!(s <= hk + 1e-8);
            }
        }
    }
}
