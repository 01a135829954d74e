//! Quantization: the θ search and its published and recorded optima, `momentlab theta`, the
//! shader representation and emitted shaders, the quantization study, `tune` and its export.

#[path = "../common/mod.rs"]
mod common;

mod cli;
mod committed_shaders;
mod optimum;
mod published;
mod quantize_study;
mod search;
mod shader;
mod shader_ir;
mod tune;
mod tune_export;
