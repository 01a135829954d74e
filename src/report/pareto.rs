//! Speed against accuracy: the Pareto front of (error, cost) and the cheapest technique within a
//! tolerance of the best ("no more model than a scene needs").

use serde::{Deserialize, Serialize};

/// One technique configuration measured on a scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Entry {
    /// Technique name (e.g. "hamburger4", "lp:z,z^2,z^3,z^4").
    pub name: String,
    /// Storage precision label (e.g. "f32", "16-bit θ").
    pub precision: String,
    /// Mean |G − PCF| over all fragments.
    pub error: f64,
    /// Evaluation cost in nanoseconds per fragment (one core).
    pub ns_per_fragment: f64,
    /// Bits stored per shadow-map texel.
    pub bits_per_texel: u32,
}

/// Indices (ascending) of the entries on the Pareto front of (error, ns_per_fragment): no other
/// entry is at least as good in both and strictly better in one. Entries with a non-finite error
/// or cost are never on the front.
pub fn pareto_front(entries: &[Entry]) -> Vec<usize> {
    let ok = |e: &Entry| e.error.is_finite() && e.ns_per_fragment.is_finite();
    (0..entries.len())
        .filter(|&i| {
            let a = &entries[i];
            ok(a)
                && !entries.iter().any(|b| {
                    ok(b)
                        && b.error <= a.error
                        && b.ns_per_fragment <= a.ns_per_fragment
                        && (b.error < a.error || b.ns_per_fragment < a.ns_per_fragment)
                })
        })
        .collect()
}

/// The cheapest entry whose error is at most `best + tolerance` (absolute, in the units of the
/// error, e.g. 0.002 = 0.2 percentage points): fewest bits per texel first, then fewest
/// nanoseconds per fragment, then lowest error. `None` when no entry has a finite error.
pub fn recommend(entries: &[Entry], tolerance: f64) -> Option<usize> {
    let best = entries
        .iter()
        .map(|e| e.error)
        .filter(|e| e.is_finite())
        .fold(f64::INFINITY, f64::min);
    if !best.is_finite() {
        return None;
    }
    (0..entries.len())
        .filter(|&i| entries[i].error.is_finite() && entries[i].error <= best + tolerance)
        .min_by(|&i, &j| {
            let (a, b) = (&entries[i], &entries[j]);
            a.bits_per_texel
                .cmp(&b.bits_per_texel)
                .then(a.ns_per_fragment.total_cmp(&b.ns_per_fragment))
                .then(a.error.total_cmp(&b.error))
        })
}

/// The alternative to the recommended entry `chosen`: the lowest-error entry that is cheaper
/// (fewer ns per fragment; what a user gives up in error to go faster), or — when nothing is
/// cheaper — the next entry within `tolerance` of the best in [`recommend`]'s order.
pub fn runner_up(entries: &[Entry], chosen: usize, tolerance: f64) -> Option<usize> {
    let c = &entries[chosen];
    let finite = |i: &usize| *i != chosen && entries[*i].error.is_finite();
    let cheaper = (0..entries.len())
        .filter(finite)
        .filter(|&i| entries[i].ns_per_fragment < c.ns_per_fragment)
        .min_by(|&i, &j| {
            let (a, b) = (&entries[i], &entries[j]);
            a.error
                .total_cmp(&b.error)
                .then(a.ns_per_fragment.total_cmp(&b.ns_per_fragment))
        });
    if cheaper.is_some() {
        return cheaper;
    }
    let rest: Vec<usize> = (0..entries.len()).filter(finite).collect();
    let sub: Vec<Entry> = rest.iter().map(|&i| entries[i].clone()).collect();
    let best = entries
        .iter()
        .map(|e| e.error)
        .filter(|e| e.is_finite())
        .fold(f64::INFINITY, f64::min);
    // Keep the tolerance relative to the overall best, not the best of the rest.
    let within: Vec<usize> = (0..sub.len())
        .filter(|&k| sub[k].error <= best + tolerance)
        .collect();
    let pick = recommend(
        &within.iter().map(|&k| sub[k].clone()).collect::<Vec<_>>(),
        f64::INFINITY,
    )?;
    Some(rest[within[pick]])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn e(name: &str, error: f64, ns: f64, bits: u32) -> Entry {
        Entry {
            name: name.into(),
            precision: "f32".into(),
            error,
            ns_per_fragment: ns,
            bits_per_texel: bits,
        }
    }

    #[test]
    fn runner_up_is_the_most_accurate_cheaper_entry() {
        let v = vec![
            e("fast-bad", 0.05, 5.0, 32),
            e("slow-good", 0.01, 50.0, 128),
            e("middle", 0.02, 20.0, 64),
            e("middle-worse", 0.03, 10.0, 64),
            e("nan", f64::NAN, 1.0, 32),
        ];
        // slow-good recommended; cheaper ones: middle (0.02) is the most accurate.
        assert_eq!(runner_up(&v, 1, 0.001), Some(2));
        // Nothing cheaper than fast-bad: the next within tolerance of the best (only slow-good).
        assert_eq!(runner_up(&v, 0, 0.001), Some(1));
        // With a loose tolerance the next in recommend's order (fewest bits): middle-worse.
        assert_eq!(runner_up(&v, 0, 1.0), Some(3));
    }

    #[test]
    fn front_excludes_dominated_and_non_finite() {
        let v = vec![
            e("fast-bad", 0.05, 5.0, 32),
            e("slow-good", 0.01, 50.0, 128),
            e("dominated", 0.06, 60.0, 64),
            e("middle", 0.02, 20.0, 64),
            e("nan", f64::NAN, 1.0, 32),
            e("tie", 0.05, 5.0, 64),
        ];
        assert_eq!(pareto_front(&v), vec![0, 1, 3, 5]);
    }

    #[test]
    fn recommend_prefers_fewest_bits_within_tolerance() {
        let v = vec![
            e("best", 0.010, 50.0, 128),
            e("close-cheap", 0.011, 30.0, 64),
            e("close-cheaper-ns", 0.0115, 10.0, 64),
            e("far", 0.05, 1.0, 32),
        ];
        assert_eq!(recommend(&v, 0.002), Some(2));
        assert_eq!(recommend(&v, 0.0), Some(0));
        assert_eq!(recommend(&v, 1.0), Some(3));
        assert_eq!(recommend(&[e("x", f64::NAN, 1.0, 8)], 1.0), None);
    }
}
