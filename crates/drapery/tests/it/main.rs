//! Integration tests of the drapery library, gathered in one binary (one link step).

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
