//! Collision geometry: closest points, penalty repulsion, continuous collision detection,
//! broad phase, obstacle shapes and an intersection checker.
//!
//! Everything here is pure geometry on `f64` positions: no state, no printing, no panics on
//! degenerate input (zero-length edges and zero-area triangles are handled explicitly and never
//! produce NaN from finite input). The implicit step wires these pieces together:
//!
//! * [`broad_phase`] finds vertex–triangle and edge–edge candidates from swept boxes
//!   (`bvh`'s trees; `pair_sort` puts their pairs in order);
//! * [`distance`] gives closest points and the barycentric weights of a contact;
//! * [`proximity`] turns candidates into contact stencils (particle indices and weights);
//! * [`repulsion`] turns a close pair into forces and a 12×12 Jacobian (docs/MATH.md §4);
//! * [`obstacle_proximity`] finds cloth edges and triangles close to mesh colliders' sharp
//!   edges and vertices (docs/MATH.md §24);
//! * [`friction`] applies Coulomb friction to cloth–cloth contacts after the solve;
//! * [`seams`] exempts the contact pairs around stitched vertices, so a seam can close;
//! * [`ccd`] finds the earliest time of impact over a step, so nothing passes through;
//! * [`failsafe`] makes each step free of crossings with it, first by translating impact zones
//!   (`zones`), then by pulling vertices back along their paths;
//! * [`colliders`] describes analytic and mesh obstacles with rigid motion;
//! * [`check`] counts intersecting triangle pairs and penetrating vertices (a test oracle),
//!   with the exact orientation tests of [`predicates`].

pub mod broad_phase;
pub mod bvh;
pub mod ccd;
pub mod check;
pub mod colliders;
pub mod distance;
pub mod failsafe;
pub mod frame_check;
pub mod friction;
pub mod obstacle_proximity;
mod pair_sort;
pub mod predicates;
pub mod proximity;
pub mod repulsion;
pub mod seam_crossings;
pub mod seams;
pub mod settings;
mod sweep;
pub mod tessellate;
mod union_find;
mod zones;
