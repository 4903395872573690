//! What every loader checks of its input file before it builds triangles: the file read
//! as a regular file of bounded size whose first bytes name its format, and the triangle
//! count against [`MAX_TRIANGLES`] and the memory limit.

use crate::error::{Error, Result};
use crate::files;
use crate::limits;
use std::path::Path;

/// The most triangles a scene may hold; larger scenes are refused before allocation.
pub const MAX_TRIANGLES: usize = 50_000_000;

/// Triangles [`Scene::place_camera`](crate::scene::Scene::place_camera) adds as the ground plane under a bare mesh; loaders
/// count them in before they compare a file's triangles with [`MAX_TRIANGLES`].
pub const GROUND_TRIANGLES: usize = 2;

/// Bytes a run holds per scene triangle, for the estimate checked before a file's
/// triangles are built. Measured: `compare` on 4,000,000 random triangles (scene, the ray
/// tracer's BVH and its build scratch, the technique's light-space set-up) peaks at
/// 1.26 GB, about 300 bytes a triangle; `render`, without the BVH, at about 80. The
/// estimate is the larger, with the loader's decoded copy on top.
pub const BYTES_PER_TRIANGLE: u64 = 320;

/// Refuses a file that would bring `triangles` triangles (with the ground plane a bare
/// mesh gets), naming the file, the count and the limit, before they are built: above
/// [`MAX_TRIANGLES`], or an estimate above [`limits::memory_limit`].
pub fn check_triangle_count(path: &Path, triangles: u64) -> Result<()> {
    let total = triangles.saturating_add(GROUND_TRIANGLES as u64);
    if total > MAX_TRIANGLES as u64 {
        return Err(Error::Limit(format!(
            "{} holds {triangles} triangles, more than the limit of {} (the scene's limit of {MAX_TRIANGLES} less the {GROUND_TRIANGLES} of the ground plane)",
            path.display(),
            MAX_TRIANGLES - GROUND_TRIANGLES
        )));
    }
    limits::check_bytes(
        || format!("{}: its {triangles} triangles", path.display()),
        total.saturating_mul(BYTES_PER_TRIANGLE),
    )
}

/// The bytes of the scene or mesh file `path`, which must be a regular file of at most
/// `limit` bytes whose first bytes `sniff` accepts as its format
/// ([`files::read_sniffed`]).
pub(crate) fn read_input(
    path: &Path,
    limit: u64,
    sniff: impl FnOnce(&[u8]) -> std::result::Result<(), String>,
) -> Result<Vec<u8>> {
    files::read_sniffed(path, limit, sniff).map_err(|e| match e {
        files::Unread::File(why) => Error::io(path, why),
        files::Unread::Format(what) => Error::format(path, what),
    })
}

/// The last component of `path` as text (lossily, for a name that is not UTF-8), empty
/// when there is none: the name a loaded scene gets and its messages use.
pub(crate) fn file_name(path: &Path) -> String {
    path.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}
