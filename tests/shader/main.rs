//! Shader code: the straight-line IR and its f32 interpreter (both operation orders), the
//! emitted θ encoders and decoders, and the committed shader files compiled by real compilers.

#[path = "../common/mod.rs"]
mod common;

mod committed_shaders;
mod shader;
mod shader_ir;
