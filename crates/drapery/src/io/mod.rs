//! File formats, one file per format (PLY, glTF, USD and PC2 behind the `formats` feature). Every writer goes through [`write_atomic`]: a file is
//! written whole (temporary file in the same folder, then rename) or not at all.

pub mod frames;
#[cfg(feature = "formats")]
pub mod gltf;
pub mod obj;
#[cfg(feature = "formats")]
pub mod pc2;
#[cfg(feature = "formats")]
pub mod ply;
#[cfg(feature = "formats")]
pub mod usd;

use crate::error::{Error, Result};
use std::io::Write;
use std::path::Path;

/// Writes `bytes` to `path` atomically: a temporary sibling file, flushed and synced, then renamed.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = dir.join(format!(".{name}.tmp{}", std::process::id()));
    let res = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if let Err(e) = res {
        let _ = std::fs::remove_file(&tmp);
        return Err(Error::io(path.display(), e));
    }
    Ok(())
}
