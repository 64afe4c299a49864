//! drapery from Python: the `drapery` module (pyo3 + rust-numpy, built by maturin).
//!
//! The bindings ([`py`], feature `python`) call the library's public API only: a scene is
//! loaded ([`drapery::scene::Scene`]), built into a [`drapery::Simulation`] and stepped with
//! [`drapery::scene::Scene::step_size`], exactly as `drapery run` does, so the bits are the
//! same from either front end. [`frames`] is the frame loop of `drapery.run`, pure Rust.
#![warn(missing_docs)]
#![deny(unsafe_code)]

pub mod frames;
pub mod messages;
#[cfg(feature = "python")]
mod py;
