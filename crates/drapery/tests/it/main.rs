//! Integration tests of the drapery library, gathered in one binary (one link step).
// (as in the library: NaN-refusing comparisons, loops indexed as the formulas are)
#![allow(clippy::neg_cmp_op_on_partial_ord, clippy::needless_range_loop)]

mod balloon;
mod cloth_friction;
mod collisions;
mod common;
mod determinism;
mod drape;
mod equilibrium;
mod implicit_step;
mod pcg_breakdowns;
mod sequences;
mod solvers;
mod step_failures;
mod textile;
mod three_particles;
