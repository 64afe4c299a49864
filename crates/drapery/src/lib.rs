//! # drapery
//!
//! A mass-spring cloth simulator advanced by linearized implicit Euler (Baraff & Witkin,
//! "Large Steps in Cloth Simulation", 1998): stretch, shear and bend springs with damping,
//! gravity and air drag; a 3×3-block sparse system solved by filtered PCG or sparse Cholesky;
//! pins as velocity filters.
//!
//! Data flows one way: scene → [`model::Model`] → [`step::Simulation::step`] → frames out.
//! The library never prints and never exits: every failure is an [`Error`] value.
//! `docs/ARCHITECTURE.md` says what each module owns; `docs/MATH.md` gives the equations.
//!
//! Cargo features (both on by default): `render` (the `render` module: pictures of frames,
//! PNG and GIF) and `formats` (PLY, glTF and USD in `io`). An application that only embeds the
//! solver can turn them off (`default-features = false`) and compiles no image encoder.
//!
//! SIMD is chosen at run time: the block kernels use AVX when the CPU running the program has
//! it, whatever CPU the build targeted, with the same bits either way (`linalg::simd`).
#![warn(missing_docs)]
// Comparisons written `!(x > 0.0)` are true for NaN on purpose (a NaN is refused, not let
// through), and the numeric kernels index their loops as the formulas subscript them.
#![allow(clippy::neg_cmp_op_on_partial_ord, clippy::needless_range_loop)]
// `unsafe` only in the AVX block kernels (`linalg::block::avx`, `linalg::sym::avx`), which allow it
#![deny(unsafe_code)]

pub mod animation;
pub mod collision;
pub mod constraints;
pub mod error;
pub mod fingerprint;
pub mod forces;
pub mod garment;
pub mod io;
pub mod linalg;
pub mod math;
pub mod mesh;
pub mod model;
pub mod presets;
#[cfg(feature = "render")]
pub mod render;
pub mod scene;
pub mod snapshot;
pub mod stats;
pub mod step;
pub mod textile;
pub mod validate;

pub use error::{Error, Result};
pub use math::{Mat3, Vec3};
pub use mesh::{Face, Mesh};
pub use model::{ClothDesc, MassSpec, Material, Model};
pub use step::{
    LinearSolver, Simulation, SolverSettings, StageTimes, StartCheck, StepReport, Tangled,
};
