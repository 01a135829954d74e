//! The shadow-map pipeline of every technique × storage on the GPU equals its CPU model
//! (`quantize::pipeline`) on the embedded scenes' fragments.

use crate::common::gpu::gpu_or_skip;
use momentlab::gpu::study;

#[test]
fn every_technique_and_storage_matches_the_model() {
    let Some(gpu) = gpu_or_skip("every_technique_and_storage_matches_the_model") else {
        return;
    };
    let stacks = momentlab::render::default_dataset(64).unwrap();
    let mut failures = Vec::new();
    // every setting on one view, the views taken in turn
    for (i, s) in study::settings().iter().enumerate() {
        {
            let stack = &stacks[(3 * i) % stacks.len()];
            let v = study::check_setting(gpu, s, None, stack, 10_000).unwrap();
            eprintln!(
                "{}: map {:.2} steps ({:.3} % inexact), G max {:.2e} excess {:.2e} outliers {:.4} %, whole max {:.2e} mean {:.2e} >1/255 {:.3} %",
                v.label, v.map_steps, 100.0 * v.map_inexact, v.g_max, v.g_excess, 100.0 * v.g_outliers, v.pipeline_max, v.pipeline_mean, 100.0 * v.pipeline_above_8bit
            );
            if let Some(f) = v.failure() {
                failures.push(f);
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
