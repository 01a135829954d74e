//! The GPU for tests that need one: lavapipe in CI. Without an adapter a test skips loudly,
//! unless MOMENTLAB_REQUIRE_GPU is set (then it fails).
#![allow(dead_code)]

use momentlab::gpu::Gpu;
use std::sync::OnceLock;

/// One device per test binary (creating one costs a few hundred ms on lavapipe).
pub fn gpu_or_skip(test: &str) -> Option<&'static Gpu> {
    static GPU: OnceLock<Result<Gpu, String>> = OnceLock::new();
    match GPU.get_or_init(|| Gpu::new().map_err(|e| e.to_string())) {
        Ok(g) => Some(g),
        Err(e) => {
            if std::env::var_os("MOMENTLAB_REQUIRE_GPU").is_some() {
                panic!("{test}: {e} (MOMENTLAB_REQUIRE_GPU is set)");
            }
            eprintln!("SKIPPED {test}: {e}; set MOMENTLAB_REQUIRE_GPU=1 to make this a failure");
            None
        }
    }
}
