//! # momentlab
//!
//! A research pipeline for moment-based shadow mapping (Peters & Klein, "Moment Shadow
//! Mapping", I3D 2015). Data flows
//!
//! ```text
//! render / stack  →  kernel (depth distributions, filtered moments)  →  lp | technique
//!                 →  metrics (error against PCF)  →  search / quantize  →  report
//! ```
//!
//! * [`grid`]: the discrete depth set I of Algorithm 1.
//! * [`basis`]: the catalog of candidate functions b_j(z), formulas, m-subsets (candidates).
//! * [`linalg`]: the shared dense linear algebra (small LUs, 3-vectors, slices' dot products).
//! * [`lp`]: Algorithm 1 (the discretized general moment problem): reference and fast solver.
//! * [`bench`]: problem corpora and timing loops of `momentlab bench` (LP, shadow lookups).
//! * [`technique`]: the [`technique::Technique`] trait shared by LP candidates and closed-form
//!   solvers (Hamburger/Hausdorff MSM, TMSM, VSM, ESM, EVSM, CSM).
//! * [`render`], [`stack`]: the reference ray caster and depth-stack files (OpenEXR + JSON).
//! * [`kernel`]: the 9×9 Gaussian PCF reference and filtered moment maps.
//! * [`metrics`]: error of a technique against PCF over all fragments of all layers.
//! * [`quantize`]: optimal affine quantization transforms θ.
//! * [`search`]: the candidate sweep (racing, shards, resumable).
//! * [`tune`]: technique × storage × biases per scene on the pipeline model, with noise as
//!   error, and the shader export of the chosen setting.
//! * [`gpu`]: the shadow-map pipeline and the emitted shader code run by a GPU driver (wgpu).
//! * [`shader`]: straight-line f32 shader functions printed as GLSL/HLSL and interpreted in f32.
//! * [`stability`]: the stress harness — every technique on random and adversarial inputs,
//!   exact and quantized, against the sharp bound of Algorithm 1.
//! * [`report`]: plots and HTML/Markdown reports, the stability study's files.
//! * [`pipeline`]: the whole study (typed configuration, resumable steps) behind
//!   `momentlab reproduce`.
//! * [`artefact`]: JSON files written atomically, JSON lines appended (one helper for all).
//! * [`progress`]: progress bars on a terminal, periodic lines in batch logs.
//! * [`batch`]: the JSON batches of `momentlab lp` and `momentlab shadow`.
//!
//! The command line (src/cli, one file per subcommand) belongs to the binary, not the library.

#![warn(missing_docs)]

pub mod artefact;
pub mod basis;
pub mod batch;
pub mod bench;
pub mod gpu;
pub mod grid;
pub mod kernel;
pub mod linalg;
pub mod lp;
pub mod metrics;
pub mod pipeline;
pub mod progress;
pub mod quantize;
pub mod render;
pub mod report;
pub mod search;
pub mod shader;
pub mod stability;
pub mod stack;
pub mod technique;
pub mod tune;

pub use grid::Grid;
