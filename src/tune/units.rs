//! Units of a tuning kept across runs (a checkpoint), so that `tune` after a kill continues
//! where the killed run stopped and ends with the tuning of an uninterrupted run.
//!
//! A unit is one result of one phase, keyed `<phase>.<index>`:
//!
//! * `floor.<target>.<family>`: the smallest feasible α of a family on a target (a scene, or
//!   all scenes);
//! * `screen.<setting>`: the per-scene accumulators of one setting of the grid on the screening
//!   subsample;
//! * `confirm.<setting>`: the same on the whole sample, with every fragment's noise.
//!
//! Every unit is a deterministic function of the options and the stacks (which the store's
//! owner checks before it offers any unit), and the indices are those of the deterministic
//! grid and target order, so a unit read back equals the one an uninterrupted run computes.
//! Floats are kept as their bits (`f64::to_bits`, `f32::to_bits`): exact, and JSON has no NaN.

use super::score::Acc;
use anyhow::{Context, Result};
use serde::{Deserialize, Serialize};

/// Where completed units of a tuning are kept (see the module docs).
pub trait UnitStore: Sync {
    /// The value of unit `key` if an earlier run completed it.
    fn get(&self, key: &str) -> Result<Option<serde_json::Value>>;
    /// Unit `key` is complete with `value`.
    fn put(&self, key: &str, value: &serde_json::Value) -> Result<()>;
}

impl UnitStore for crate::artefact::Checkpoint {
    fn get(&self, key: &str) -> Result<Option<serde_json::Value>> {
        crate::artefact::Checkpoint::get(self, key)
    }
    fn put(&self, key: &str, value: &serde_json::Value) -> Result<()> {
        crate::artefact::Checkpoint::put(self, key, value)
    }
}

/// The checkpoint's name in an output folder.
pub const CHECKPOINT: &str = "tune";

/// What a tuning's units depend on: the options (but the cost model, a pure function) and the
/// stacks by content. A checkpoint of other parameters is not resumed.
pub fn params(opts: &super::Options, stacks: &[crate::stack::DepthStack]) -> serde_json::Value {
    let stack_ids: Vec<String> = stacks
        .iter()
        .map(|s| format!("{}/{} {}", s.meta.scene, s.meta.view, s.digest()))
        .collect();
    serde_json::json!({
        "technique": opts.techniques.iter().map(|t| t.name()).collect::<Vec<_>>(),
        "storages": opts.storages.iter().map(|s| s.name()).collect::<Vec<_>>(),
        "tolerance": opts.tolerance.to_bits(), "max_noise": opts.max_noise.to_bits(),
        "fragments": opts.fragments_per_scene, "screen": opts.screen_per_scene,
        "keep": opts.keep, "seed": opts.seed, "speed_inputs": opts.speed_inputs,
        "stacks": stack_ids,
    })
}

/// An [`Acc`] with its floats as bits.
#[derive(Serialize, Deserialize)]
struct AccBits {
    n: usize,
    leak: u64,
    dark: u64,
    noise: u64,
    noisy: usize,
    non_finite: usize,
    noise_values: Option<Vec<u32>>,
}

impl From<&Acc> for AccBits {
    fn from(a: &Acc) -> AccBits {
        AccBits {
            n: a.n,
            leak: a.leak.to_bits(),
            dark: a.dark.to_bits(),
            noise: a.noise.to_bits(),
            noisy: a.noisy,
            non_finite: a.non_finite,
            noise_values: a
                .noise_values
                .as_ref()
                .map(|v| v.iter().map(|x| x.to_bits()).collect()),
        }
    }
}

impl From<AccBits> for Acc {
    fn from(b: AccBits) -> Acc {
        Acc {
            n: b.n,
            leak: f64::from_bits(b.leak),
            dark: f64::from_bits(b.dark),
            noise: f64::from_bits(b.noise),
            noisy: b.noisy,
            non_finite: b.non_finite,
            noise_values: b
                .noise_values
                .map(|v| v.into_iter().map(f32::from_bits).collect()),
        }
    }
}

/// Unit `key` from `store`, else `compute` it and record it there; `T` travels as `R`.
fn cached<T, R>(
    store: Option<&dyn UnitStore>,
    key: &str,
    compute: impl FnOnce() -> Result<T>,
    to: impl FnOnce(&T) -> R,
    from: impl FnOnce(R) -> T,
) -> Result<T>
where
    R: Serialize + for<'de> Deserialize<'de>,
{
    let Some(store) = store else {
        return compute();
    };
    if let Some(v) = store.get(key)? {
        let r = R::deserialize(v)
            .with_context(|| format!("tune checkpoint: unit '{key}' is unreadable"))?;
        return Ok(from(r));
    }
    let t = compute()?;
    store.put(key, &serde_json::to_value(to(&t))?)?;
    Ok(t)
}

/// The per-scene accumulators of unit `key` (`screen.<g>` or `confirm.<g>`).
pub(super) fn accs(
    store: Option<&dyn UnitStore>,
    key: &str,
    compute: impl FnOnce() -> Result<Vec<Acc>>,
) -> Result<Vec<Acc>> {
    cached(
        store,
        key,
        compute,
        |v: &Vec<Acc>| v.iter().map(AccBits::from).collect::<Vec<_>>(),
        |r: Vec<AccBits>| r.into_iter().map(Acc::from).collect(),
    )
}

/// The α floor of unit `key` (`floor.<target>.<family>`).
pub(super) fn floor(
    store: Option<&dyn UnitStore>,
    key: &str,
    compute: impl FnOnce() -> Result<Option<f64>>,
) -> Result<Option<f64>> {
    cached(
        store,
        key,
        compute,
        |a: &Option<f64>| a.map(f64::to_bits),
        |r: Option<u64>| r.map(f64::from_bits),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;
    use std::sync::Mutex;

    #[derive(Default)]
    struct Map(Mutex<BTreeMap<String, serde_json::Value>>);

    impl UnitStore for Map {
        fn get(&self, key: &str) -> Result<Option<serde_json::Value>> {
            Ok(self.0.lock().unwrap().get(key).cloned())
        }
        fn put(&self, key: &str, value: &serde_json::Value) -> Result<()> {
            self.0.lock().unwrap().insert(key.into(), value.clone());
            Ok(())
        }
    }

    #[test]
    fn units_read_back_bit_for_bit_and_are_not_recomputed() {
        let store = Map::default();
        let acc = Acc {
            n: 3,
            leak: 0.1 + 0.2,
            dark: 1e-300,
            noise: std::f64::consts::PI,
            noisy: 1,
            non_finite: 1,
            noise_values: Some(vec![0.1, f32::MIN_POSITIVE, 3.0]),
        };
        let first = accs(Some(&store), "confirm.0", || Ok(vec![acc.clone()])).unwrap();
        let again = accs(Some(&store), "confirm.0", || panic!("recomputed")).unwrap();
        for a in [&first[0], &again[0]] {
            assert_eq!(a.leak.to_bits(), acc.leak.to_bits());
            assert_eq!(a.dark.to_bits(), acc.dark.to_bits());
            assert_eq!(a.noise.to_bits(), acc.noise.to_bits());
            assert_eq!((a.n, a.noisy, a.non_finite), (3, 1, 1));
            assert_eq!(a.noise_values, acc.noise_values);
        }
        let f = floor(Some(&store), "floor.0.0", || Ok(Some(3e-5 + 1e-20))).unwrap();
        assert_eq!(
            floor(Some(&store), "floor.0.0", || panic!("recomputed")).unwrap(),
            f
        );
        assert_eq!(floor(Some(&store), "floor.0.1", || Ok(None)).unwrap(), None);
        assert_eq!(
            floor(Some(&store), "floor.0.1", || panic!("recomputed")).unwrap(),
            None
        );
        // Without a store, every unit is computed.
        assert_eq!(
            floor(None, "floor.0.1", || Ok(Some(1.0))).unwrap(),
            Some(1.0)
        );
    }
}
