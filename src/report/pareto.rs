//! Speed against accuracy: the Pareto front of (error, cost) of the measured techniques (the
//! recommendation itself is `tune`'s, [`super::recommend::recommendations`]).

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
}
