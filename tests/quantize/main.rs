//! Quantization: the θ search and its published and recorded optima, `momentlab theta` and the
//! quantization study.

#[path = "../common/mod.rs"]
mod common;

mod cli;
mod optimum;
mod published;
mod quantize_study;
mod search;
