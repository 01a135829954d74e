//! Depth stacks: the ray caster and scenes, mesh formats, rectified bounds, stack files and
//! deep OpenEXR import.

#[path = "../common/mod.rs"]
mod common;

mod deep_import;
mod mesh_formats;
mod rectified_bounds;
mod render_analytic;
mod render_scene;
mod stack_io;
