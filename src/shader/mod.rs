//! Shader code from one representation: a straight-line f32 program ([`ir::Func`]) printed as
//! GLSL or HLSL ([`print`]) or WGSL ([`wgsl`]) and executed by an f32 interpreter ([`eval`]) that performs the same
//! operations in the same order, so tests measure what a shader computes.
//!
//! ```
//! use momentlab::shader::{Func, Module, Shape, glsl, hlsl};
//! let mut f = Func::new("square_plus_half");
//! let z = f.input_scalar("z");
//! let h = f.c(0.5);
//! let z2 = f.mul(z, z);
//! let y = f.add(z2, h);
//! f.ret(Shape::Scalar, &[y]);
//! assert_eq!(f.eval(&[3.0]).unwrap(), vec![9.5]);
//! let m = Module { header: vec!["example".into()], funcs: vec![f] };
//! assert!(glsl(&m).unwrap().contains("float square_plus_half(float z)"));
//! assert!(hlsl(&m).unwrap().contains("MOMENTLAB_PRECISE float t_2 = z * z;"));
//! ```

pub mod eval;
pub mod ir;
pub mod print;
pub mod wgsl;

pub use eval::Order;
pub use ir::{Cmp, Func, Module, Op, Param, Shape, V};
pub use print::{glsl, hlsl, literal, Lang};
pub use wgsl::wgsl;
