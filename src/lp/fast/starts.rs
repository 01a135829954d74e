//! Where a simplex run starts: the sequence of attempts (given distribution, a basis built
//! from the moments, warm basis, cold basis, Bland's rule), the crossover from a known
//! distribution to a basic feasible solution, and the warm-start memory of the last optimum.

use super::linalg::{complete_basis, dot, norm};
use super::{FastSolver, Outcome, Verdict, ART, REFACTOR_EVERY};

/// The basis a simplex attempt starts from.
#[derive(Clone, Copy)]
enum Start {
    /// The crossover from the given distribution.
    Hint,
    /// The last optimal basis.
    Warm,
    /// The basis built from the moments ([`super::recognise`]).
    Given,
    /// The band basis that did not certify on the whole grid (`bands.failed`, a steep
    /// table's band tried first): primal feasible up to the band's rounding.
    Band,
    /// The well-conditioned cold-start basis.
    Cold,
    /// The basis the previous attempt ended on.
    Current,
}

/// Smallest pivot element of a crossover step.
const PIV: f64 = 1e-8;

/// The warm start: the last optimal basis, if any, and the transformed moments it was optimal
/// for (another z_f for the same moments starts from it, primal feasible).
pub(super) struct WarmStart {
    pub(super) basis: Option<Vec<usize>>,
    pub(super) last_c: Vec<f64>,
    /// Warm start enabled ([`FastSolver::set_warm_start`]).
    pub(super) on: bool,
}

/// Crossover workspace: the start distribution, squared residual norms, a residual,
/// orthonormal directions and basis positions of its support points.
#[derive(Default)]
pub(super) struct Crossover {
    pub(super) dist: Vec<(usize, f64)>,
    pub(super) nrm: Vec<f64>,
    /// The support's columns coordinate-major (see [`FastSolver::load_hint`]) and their
    /// projections (see [`FastSolver::choose_support`]).
    pub(super) a: Vec<f64>,
    pub(super) stride: usize,
    pub(super) h: Vec<f64>,
    pub(super) v: Vec<f64>,
    pub(super) u: Vec<f64>,
    pub(super) pos: Vec<usize>,
}

impl FastSolver {
    /// Simplex runs from the hint, warm or cold bases, retrying after numerical trouble
    /// (two cold runs, the second with Bland's rule throughout).
    pub(super) fn attempts(
        &mut self,
        kf: usize,
        hint: Option<&[(u32, f64)]>,
        given: bool,
    ) -> Verdict {
        let (mut start, warm_or_cold) = self.first_start(hint.is_some());
        if given {
            start = Start::Given;
        } else if matches!(start, Start::Hint) && self.bands.failed.is_some() {
            // The band tried first (a steep table) found an optimum of the LP on the band
            // that the whole grid does not certify: a basis of the whole LP whose weights
            // solve it, which starts the run in place of the crossover (the hint's crossover
            // when it fails). Sweep fragments, m = 3, exp(±40z) tables: 2.3 → 1.2 crossover
            // pivots per LP, escalations 1.06 % → 0.86 % of LPs.
            start = Start::Band;
        }
        self.attempts_from(kf, hint, start, warm_or_cold)
    }

    /// [`Self::attempts`] again from the basis the last one ended on (with the full pricing
    /// pass unless `partial_optimum` is set).
    pub(super) fn resume(&mut self, kf: usize) -> Verdict {
        let (_, warm_or_cold) = self.first_start(false);
        self.attempts_from(kf, None, Start::Current, warm_or_cold)
    }

    /// The attempts of [`Self::attempts`] from `start`; `warm_or_cold` after a failed hint.
    fn attempts_from(
        &mut self,
        kf: usize,
        hint: Option<&[(u32, f64)]>,
        mut start: Start,
        warm_or_cold: Start,
    ) -> Verdict {
        let mut cold_runs = 0;
        let mut stash: Option<Vec<usize>> = None;
        for _attempt in 0..6 {
            self.crossed = false;
            if let Start::Hint = start {
                self.c.copy_from_slice(&self.c0);
                if !self.crossover(hint.unwrap_or(&[]), kf) {
                    // Unusable start (numerically dependent support): the usual way.
                    self.stats.hint_rejected += 1;
                    start = warm_or_cold;
                }
            }
            self.load_start(start, &mut cold_runs);
            // The second cold run uses Bland's rule throughout.
            self.c.copy_from_slice(&self.c0);
            match self.run(kf, cold_runs >= 2) {
                Outcome::RetryAccurate => {
                    self.stats.restarts += 1;
                    // The answer to certify if the accurate run fails.
                    stash = Some(self.basis.clone());
                    start = Start::Current;
                }
                Outcome::Optimal => return Verdict::Optimal,
                Outcome::Infeasible => return Verdict::Infeasible,
                Outcome::Retry => {
                    self.stats.restarts += 1;
                    start = Start::Current;
                }
                Outcome::Failed => {
                    self.stats.restarts += 1;
                    if cold_runs >= 2 || stash.is_some() {
                        break;
                    }
                    start = if matches!(start, Start::Band) && hint.is_some() {
                        Start::Hint
                    } else if matches!(start, Start::Hint | Start::Given | Start::Band) {
                        warm_or_cold
                    } else {
                        Start::Cold
                    };
                }
            }
        }
        self.stashed_verdict(stash)
    }

    /// The first start of [`Self::attempts`] and the usual one (warm when there is a warm
    /// basis, else cold).
    fn first_start(&mut self, hint: bool) -> (Start, Start) {
        let warm_or_cold = if self.warm.on && self.warm.basis.is_some() {
            Start::Warm
        } else {
            Start::Cold
        };
        // The same moments as the last solved problem (another fragment depth for the same
        // texel): its optimal basis is primal feasible here, a better start than the crossover.
        let same_moments = matches!(warm_or_cold, Start::Warm) && self.warm.last_c == self.c0;
        if hint && same_moments {
            self.stats.same_moments += 1;
        }
        let start = if hint && !same_moments {
            Start::Hint
        } else {
            warm_or_cold
        };
        (start, warm_or_cold)
    }

    /// Put the basis of `start` in place (the crossover has already placed the hint's);
    /// counts cold runs.
    fn load_start(&mut self, start: Start, cold_runs: &mut usize) {
        match start {
            Start::Hint | Start::Current => {}
            Start::Given => {
                self.mark_basic(false);
                self.basis.copy_from_slice(&self.recognise.basis);
                self.mark_basic(true);
            }
            Start::Band => {
                self.mark_basic(false);
                let band = self.bands.failed.as_ref().expect("band basis");
                self.basis.copy_from_slice(band);
                self.mark_basic(true);
            }
            Start::Warm => {
                self.mark_basic(false);
                let wb = self.warm.basis.as_ref().expect("warm basis");
                self.basis.copy_from_slice(wb);
                self.mark_basic(true);
            }
            Start::Cold => {
                self.mark_basic(false);
                self.basis.copy_from_slice(&self.b0);
                self.mark_basic(true);
                *cold_runs += 1;
            }
        }
    }

    /// When the attempts ran out: the optimum stashed before an accurate rerun, if any.
    fn stashed_verdict(&mut self, stash: Option<Vec<usize>>) -> Verdict {
        match stash {
            Some(basis) => {
                self.stats.loose += 1;
                self.full_pass_skipped = false;
                self.mark_basic(false);
                self.basis.copy_from_slice(&basis);
                self.mark_basic(true);
                Verdict::Optimal
            }
            None => Verdict::Failed,
        }
    }

    /// After a certified fast optimum: its basis is the next warm start.
    pub(super) fn remember_optimal(&mut self) {
        self.last_bound =
            f64::EPSILON * self.ortho.condition * norm(&self.binv.inv) * (1.0 + norm(&self.c));
        if self.warm.on {
            match &mut self.warm.basis {
                Some(wb) => wb.copy_from_slice(&self.basis),
                None => self.warm.basis = Some(self.basis.clone()),
            }
            self.warm.last_c.copy_from_slice(&self.c0);
        }
    }

    /// The rounding bound of [`Self::remember_optimal`] for `basis`, certified without this
    /// solver's simplex (a band in local coordinates), from its factorisation in these
    /// coordinates (∞ where it is singular there).
    pub(super) fn set_bound_of(&mut self, basis: &[usize]) {
        let (r, rows) = (self.r, &self.ortho.rows);
        let column = |i: usize| &rows[i * r..(i + 1) * r];
        self.last_bound = if self.binv.factor(basis, column, ART, f64::INFINITY) {
            f64::EPSILON * self.ortho.condition * norm(&self.binv.inv) * (1.0 + norm(&self.c))
        } else {
            f64::INFINITY
        };
    }

    /// After accurate pivots certified `basis` (not the basis the simplex ended on): it is
    /// the next warm start instead, so that the warm basis is always a certified optimum.
    pub(super) fn remember_certified(&mut self, basis: &[usize]) {
        if self.warm.on && basis.len() == self.r && basis.iter().all(|&i| i < self.n) {
            self.warm.basis = Some(basis.to_vec());
            self.warm.last_c.copy_from_slice(&self.c0);
        }
    }

    /// The support of a distribution with at most r atoms, completed to r columns from the
    /// cold-start basis (None for larger supports).
    pub(super) fn support_basis(&self, dist: &[(u32, f64)]) -> Option<Vec<usize>> {
        let mut basis: Vec<usize> = Vec::with_capacity(self.r);
        for &(i, w) in dist {
            let i = i as usize;
            if w > 0.0 && !basis.contains(&i) {
                if basis.len() == self.r {
                    return None;
                }
                basis.push(i);
            }
        }
        let rows = &self.ortho.rows;
        complete_basis(rows, self.n, self.r, &basis, &self.b0)
    }

    /// Crossover from a known distribution `start` = [(grid index, weight)] with these moments
    /// (e.g. the filtered depth distribution of a kernel) to a basis whose basic solution is
    /// feasible and costs no more. The basis is the support columns of greatest volume (greedy
    /// Gram–Schmidt), completed from the cold-start basis; every other support point is then
    /// pushed out, to weight 0 or into the basis, in the direction that does not increase
    /// Σ_{z_i<z_f} w_i (one ratio test and exchange each). This replaces phase 1. False when
    /// the start is unusable (then the caller starts as usual). The run goes on from the
    /// inverse and weights the pushes leave; the certificate recomputes the weights of the
    /// final basis from the true moments, so a drifted start cannot change the answer.
    fn crossover(&mut self, start: &[(u32, f64)], kf: usize) -> bool {
        self.stats.hinted += 1;
        if !self.load_hint(start) {
            return false;
        }
        self.mark_basic(false);
        // The optimum nearly always holds the first grid point at or above z_f, and often the
        // last grid point: reserved (weight 0) ahead of the support's columns, they save pivots
        // (stacks corpus: 12 → 10 per problem).
        let (r, n) = (self.r, self.n);
        let mut first = [usize::MAX; 2];
        let mut reserved = 0;
        for i in [kf, n - 1] {
            if i < n && reserved + 1 < r && !first[..reserved].contains(&i) {
                first[reserved] = i;
                reserved += 1;
            }
        }
        let chosen = self.choose_support(r - reserved);
        let chosen = self.complete_from_cold(chosen, &first[..reserved]);
        if chosen < self.r {
            return false;
        }
        self.mark_basic(true);
        if !self.factor() {
            return false;
        }
        // The basis inverse and weights the pushes leave are the run's start as they stand
        // (at most REFACTOR_EVERY updates since a factorisation, like any simplex iterate).
        self.crossed = self.push_out_superbasic(kf);
        self.crossed
    }

    /// The start's positive atoms into `hint`, their squared column norms into `hint_nrm`,
    /// their columns coordinate-major into `hint_a` (`hint_a[c·stride + k] = a_{i_k}[c]`,
    /// stride = the start's length, so one pass fills it), and every atom superbasic in
    /// `hint_pos`; false for an invalid or empty start.
    fn load_hint(&mut self, start: &[(u32, f64)]) -> bool {
        let (n, r) = (self.n, self.r);
        let stride = start.len();
        self.cross.dist.clear();
        self.cross.nrm.clear();
        // Entries past each coordinate's s atoms are never read: no need to clear them.
        if self.cross.a.len() < r * stride {
            self.cross.a.resize(r * stride, 0.0);
        }
        for &(i, w) in start {
            let i = i as usize;
            if i >= n || !w.is_finite() || w < 0.0 {
                return false;
            }
            if w > 0.0 {
                let k = self.cross.dist.len();
                let a = &self.ortho.rows[i * r..(i + 1) * r];
                let mut nrm = 0.0;
                for (c, &ac) in a.iter().enumerate() {
                    self.cross.a[c * stride + k] = ac;
                    nrm += ac * ac;
                }
                self.cross.dist.push((i, w));
                self.cross.nrm.push(nrm);
            }
        }
        self.cross.stride = stride;
        let s = self.cross.dist.len();
        if s == 0 {
            return false;
        }
        self.cross.u.clear();
        // hint_pos[k]: basis position of support point k, or usize::MAX (superbasic).
        self.cross.pos.clear();
        self.cross.pos.resize(s, usize::MAX);
        true
    }

    /// Greedy maximal volume (QR with column pivoting on the support columns), for up to
    /// `limit` basis positions: the support
    /// column with the largest residual after projecting out the chosen ones enters the basis
    /// with its weight, while that residual is ≥ 1e-5 (columns have RMS 1 over the grid and
    /// first coordinate 1); returns the number of basis positions filled. The residual norms
    /// are downdated (‖r‖² −= (a·u)² per chosen direction u); only the chosen column's
    /// residual is formed, by modified Gram–Schmidt twice.
    fn choose_support(&mut self, limit: usize) -> usize {
        let (r, s) = (self.r, self.cross.dist.len());
        let mut chosen = 0usize;
        while chosen < limit.min(r) {
            // The last of the largest norms ≥ 1e-10 (chosen points have norm −∞ and keep it
            // through the downdates).
            let (top, best) = last_max(&self.cross.nrm);
            if top < 1e-10 {
                break;
            }
            let i = self.cross.dist[best].0;
            let v = &mut self.cross.v;
            v.copy_from_slice(&self.ortho.rows[i * r..(i + 1) * r]);
            for _pass in 0..2 {
                for u in self.cross.u.chunks(r) {
                    let h = dot(v, u);
                    v.iter_mut().zip(u).for_each(|(a, b)| *a -= h * b);
                }
            }
            let nv = norm(v);
            if nv.is_nan() || nv < 1e-5 {
                // The downdated norm drifted: this column is dependent on the chosen ones.
                self.cross.nrm[best] = 0.0;
                continue;
            }
            v.iter_mut().for_each(|a| *a /= nv);
            // ‖r_k‖² −= (a_k·v)² for every support point (the chosen ones' values are unused).
            let h = &mut self.cross.h;
            h.clear();
            h.resize(s, 0.0);
            let st = self.cross.stride;
            for (c, &vc) in v.iter().enumerate() {
                let a = &self.cross.a[c * st..c * st + s];
                h.iter_mut().zip(a).for_each(|(h, a)| *h += a * vc);
            }
            self.cross
                .nrm
                .iter_mut()
                .zip(h.iter())
                .for_each(|(n, h)| *n -= h * h);
            self.cross.u.extend_from_slice(v);
            self.cross.nrm[best] = f64::NEG_INFINITY;
            self.cross.pos[best] = chosen;
            self.basis[chosen] = i;
            self.x[chosen] = self.cross.dist[best].1;
            chosen += 1;
        }
        chosen
    }

    /// Complete the first `chosen` basis positions from `first`, then the cold-start basis
    /// (which spans R^r), with zero weights: columns independent of the span so far (relative residual > 1e-5);
    /// returns the number of positions filled.
    fn complete_from_cold(&mut self, mut chosen: usize, first: &[usize]) -> usize {
        let r = self.r;
        let mut t0 = 0;
        while chosen < r && t0 < first.len() + r {
            let i = if t0 < first.len() {
                first[t0]
            } else {
                self.b0[t0 - first.len()]
            };
            t0 += 1;
            if self.basis[..chosen].contains(&i) {
                continue;
            }
            let v = &mut self.cross.v;
            v.copy_from_slice(&self.ortho.rows[i * r..(i + 1) * r]);
            let n0 = norm(v);
            for _pass in 0..2 {
                for u in self.cross.u.chunks(r) {
                    let h = dot(v, u);
                    for (a, b) in v.iter_mut().zip(u) {
                        *a -= h * b;
                    }
                }
            }
            let nv = norm(v);
            if nv <= 1e-5 * n0 {
                continue;
            }
            v.iter_mut().for_each(|a| *a /= nv);
            self.cross.u.extend_from_slice(v);
            self.basis[chosen] = i;
            self.x[chosen] = 0.0;
            chosen += 1;
        }
        chosen
    }

    /// Push every superbasic support point out of the interior (refactorising every
    /// `REFACTOR_EVERY` exchanges); false on a singular basis.
    fn push_out_superbasic(&mut self, kf: usize) -> bool {
        let mut since = 0usize;
        for k in 0..self.cross.dist.len() {
            if self.cross.pos[k] != usize::MAX {
                continue;
            }
            let (j, w) = self.cross.dist[k];
            if self.pricing.is_basic[j] {
                // A completion column of the cold basis is also in the support: give it the
                // weight (same column, same point of the feasible set).
                let Some(t) = self.basis.iter().position(|&b| b == j) else {
                    return false;
                };
                self.x[t] += w;
                continue;
            }
            if self.push_out(j, w, kf) {
                self.stats.crossover_pivots += 1;
                since += 1;
                if since >= REFACTOR_EVERY {
                    if !self.factor() {
                        return false;
                    }
                    since = 0;
                }
            }
        }
        true
    }

    /// Move the superbasic point j (weight w) to weight 0, or into the basis when a basic
    /// weight reaches 0 first, in the direction whose reduced cost d_j does not increase the
    /// cost; true when the basis changed.
    fn push_out(&mut self, j: usize, w: f64, kf: usize) -> bool {
        let r = self.r;
        self.load_alpha(j);
        let mut dj = (j < kf) as u8 as f64;
        for t in 0..r {
            if self.basis[t] < kf {
                dj -= self.alpha[t];
            }
        }
        // Decreasing w_j moves the basic weights by +t·α; increasing by −t·α.
        let mut decrease = dj >= 0.0;
        if !decrease && !self.alpha[..r].iter().any(|&a| a > PIV) {
            decrease = true;
        }
        let (step, l) = self.push_ratio(decrease, w);
        let sign = if decrease { 1.0 } else { -1.0 };
        for t in 0..r {
            self.x[t] += sign * step * self.alpha[t];
        }
        if l == usize::MAX {
            return false;
        }
        let wl = if decrease { w - step } else { w + step };
        self.exchange(l, j);
        self.x[l] = wl;
        true
    }

    /// Ratio test of [`Self::push_out`]: the step (at most w when decreasing) and the basis
    /// position whose weight reaches 0 first (usize::MAX if none).
    fn push_ratio(&self, decrease: bool, w: f64) -> (f64, usize) {
        // The least ratio x_t / a_t as a fraction num / den (one division at the end):
        // x_t / a < num / den ⟺ x_t · den < num · a for a, den > 0.
        let (mut num, mut den) = (if decrease { w } else { f64::INFINITY }, 1.0);
        let mut l = usize::MAX;
        for t in 0..self.r {
            let a = self.alpha[t];
            let a = if decrease { -a } else { a };
            let xt = self.x[t].max(0.0);
            if a > PIV && xt * den < num * a {
                (num, den) = (xt, a);
                l = t;
            }
        }
        if l == usize::MAX {
            (num, l)
        } else {
            (num / den, l)
        }
    }
}

/// The largest value of `v` (NaN never counts) and the last index holding it; (−∞, 0) when
/// there is none. Eight independent lanes, so the comparisons vectorise.
fn last_max(v: &[f64]) -> (f64, usize) {
    const L: usize = 8;
    let mut bv = [f64::NEG_INFINITY; L];
    let mut bi = [0usize; L];
    let chunks = v.len() / L;
    for c in 0..chunks {
        let ch = &v[c * L..c * L + L];
        for l in 0..L {
            // `>=`: a later index wins among equals.
            if ch[l] >= bv[l] {
                bv[l] = ch[l];
                bi[l] = c * L + l;
            }
        }
    }
    for (i, &x) in v.iter().enumerate().skip(chunks * L) {
        let l = i % L;
        if x >= bv[l] {
            bv[l] = x;
            bi[l] = i;
        }
    }
    let mut best = (f64::NEG_INFINITY, 0usize);
    for l in 0..L {
        if bv[l] > best.0 || (bv[l] == best.0 && bi[l] > best.1) {
            best = (bv[l], bi[l]);
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::last_max;
    use rand::{Rng, SeedableRng};

    /// Against the definition (fold then rposition) on random vectors with ties, −∞ and NaN.
    #[test]
    fn last_max_is_the_last_of_the_largest() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        for _ in 0..3000 {
            let len = rng.gen_range(0..40);
            let v: Vec<f64> = (0..len)
                .map(|_| match rng.gen_range(0..10) {
                    0 => f64::NEG_INFINITY,
                    1 => f64::NAN,
                    2..=4 => rng.gen_range(0..3) as f64,
                    _ => rng.gen_range(-1.0..1.0),
                })
                .collect();
            let top = v
                .iter()
                .filter(|x| !x.is_nan())
                .fold(f64::NEG_INFINITY, |a, &x| a.max(x));
            let (got, at) = last_max(&v);
            assert_eq!(got, top, "{v:?}");
            if top > f64::NEG_INFINITY {
                assert_eq!(Some(at), v.iter().rposition(|&x| x == top), "{v:?}");
            }
        }
    }
}
