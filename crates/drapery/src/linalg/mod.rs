//! Linear algebra for the implicit step: the 3×3-block sparse matrix ([`BlockMatrix`]),
//! deterministic vector kernels ([`vector`]), the Baraff–Witkin filtered PCG ([`pcg`]) and a
//! sparse direct solve through faer ([`direct`]) and a smoothed-aggregation multigrid
//! preconditioner ([`amg`]); a system with couplings outside the preconditioner's pattern
//! is kept as two parts ([`split`]).

pub mod amg;
pub(crate) mod block;
pub mod bsr;
pub mod direct;
pub mod eigen;
pub mod pcg;
pub mod simd;
pub mod split;
pub mod sym;
pub mod vector;

pub use bsr::BlockMatrix;
