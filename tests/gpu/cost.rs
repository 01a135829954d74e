//! `gpu::cost::measured_costs` on a real driver: the lookup pass timed by `gpu bench`.

use crate::common::gpu::gpu_or_skip;
use momentlab::gpu::cost::{gpu_cost, measured_costs, CostSource};
use momentlab::tune::space::{StorageKind, TechniqueKind};

#[test]
fn measured_costs_name_the_adapter_and_rank_tmsm_far_above_hamburger4() {
    let Some(gpu) =
        gpu_or_skip("measured_costs_name_the_adapter_and_rank_tmsm_far_above_hamburger4")
    else {
        return;
    };
    let stacks = momentlab::render::default_dataset(64).unwrap();
    let pairs = [
        (TechniqueKind::Vsm, StorageKind::F32),
        (TechniqueKind::Hamburger4, StorageKind::Unorm16Theta),
        (TechniqueKind::Tmsm, StorageKind::F32),
    ];
    let costs = measured_costs(gpu, &pairs, &stacks[0]).unwrap();
    assert_eq!(costs.len(), pairs.len());
    for (c, &(t, s)) in costs.iter().zip(&pairs) {
        eprintln!(
            "{} {} on {}: {:.1} ns per lookup (model {:.1})",
            t.name(),
            s.name(),
            gpu.adapter.name,
            c.ns_per_lookup,
            gpu_cost(t, s).unwrap().ns_per_lookup
        );
        assert!(
            c.ns_per_lookup.is_finite() && c.ns_per_lookup > 0.0,
            "{c:?}"
        );
        assert_eq!(
            c.source,
            CostSource::Measured {
                adapter: gpu.adapter.name.clone()
            }
        );
        // op counts and export size are the program's, as the model has them
        let m = gpu_cost(t, s).unwrap();
        assert_eq!((c.ops, c.export_lines), (m.ops, m.export_lines));
    }
    assert!(
        costs[2].ns_per_lookup > 10.0 * costs[1].ns_per_lookup,
        "TMSM {} ns, Hamburger 4MSM {} ns",
        costs[2].ns_per_lookup,
        costs[1].ns_per_lookup
    );
    // a pair outside tune's space is an error before any GPU work
    let e = measured_costs(
        gpu,
        &[(TechniqueKind::Esm, StorageKind::Unorm16)],
        &stacks[0],
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("esm") && e.contains("unorm16"), "{e}");
}
