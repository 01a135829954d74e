//! The GPU path on a real driver (lavapipe in CI): the shadow-map pipeline against its CPU
//! model, the emitted programs run under wgpu, `momentlab gpu`.

#[path = "../common/mod.rs"]
mod common;

mod cli;
mod cost;
mod exports;
mod pipeline;
mod programs;
