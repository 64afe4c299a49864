//! Sewing patterns in the GarmentCode format, triangulated into panel meshes with stitches.
//!
//! [`Pattern::load`] reads a pattern specification as `pygarment` writes it
//! (`*_specification.json`: panels with 2-D outlines of straight, Bézier and arc edges, their
//! 3-D placement, and the stitches between edges); [`Pattern::triangulate`] turns it into a
//! [`Garment`]: one triangle mesh per panel, placed in 3-D, with each outline edge's vertices
//! listed in order, and each stitch as vertex pairs matched by arc length.
//!
//! ```no_run
//! use drapery::garment::Pattern;
//! let pattern = Pattern::load("examples/garments/skirt_specification.json")?;
//! let garment = pattern.triangulate(0.02)?; // about 2 cm triangle edges
//! for panel in &garment.panels {
//!     println!("{}: {} vertices", panel.name, panel.mesh.vertex_count());
//! }
//! # Ok::<(), drapery::Error>(())
//! ```

pub mod pattern;
pub mod triangulate;

pub use pattern::{Curve, Edge, EdgeRef, Panel, Pattern, StitchSpec};
pub use triangulate::{Garment, PanelMesh, Stitch};
