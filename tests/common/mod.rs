//! Helpers shared by the test binaries; each `tests/<group>/main.rs` declares this module
//! with `#[path = "../common/mod.rs"]`.
#![allow(dead_code)]

pub mod kernel;
pub mod shader;
