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

/// Simplex iterations (Bland's rule) minimising cost over columns < `allowed`.
fn run(
    t: &mut [Vec<f64>],
    basis: &mut [usize],
    cost: &[f64],
    allowed: usize,
    tol: f64,
) -> Option<()> {
    let rhs = t[0].len() - 1;
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
        let mut best: Option<(f64, usize, usize)> = None;
        for (i, row) in t.iter().enumerate() {
            if row[j] > tol {
                let ratio = row[rhs] / row[j];
                let better = match best {
                    None => true,
                    Some((br, _, bb)) => {
                        ratio < br - 1e-15 || (ratio <= br + 1e-15 && basis[i] < bb)
                    }
                };
                if better {
                    best = Some((ratio, i, basis[i]));
                }
            }
        }
        let (_, r, _) = best?; // unbounded direction in the dual: primal infeasible
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
