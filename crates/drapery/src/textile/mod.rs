//! Textiles in physical units: fabric presets with their published sources ([`fabrics`]),
//! the heavy elastica of the cantilever stiffness test ([`elastica`]) and the Cusick drape
//! coefficient of a draped disc ([`drape`]). `docs/MATERIALS.md` gives the sources, the unit
//! conversions and the definitions.

pub mod drape;
pub mod elastica;
pub mod fabrics;

pub use drape::{disc, drape_coefficient};
pub use elastica::{Cantilever, cantilever};
pub use fabrics::{FABRICS, Fabric, fabric};
