//! Files the unit tests make: hostile inputs built from real ones.

use std::path::Path;

use crate::frame_files::FrameFiles;

/// Writes a real 2 × 2 EXR at `path` whose header then declares `side` × `side` pixels (its
/// data and display windows patched): a file of a few hundred bytes that claims a huge image.
pub(crate) fn write_exr_declaring(path: &Path, side: i32) {
    refract_scene::Frame::new(2, 2)
        .write_exr(path)
        .expect("write");
    let mut bytes = std::fs::read(path).expect("read");
    // A box2i attribute: its name, its type, a 4-byte size, then xMin, yMin, xMax, yMax.
    for name in [&b"dataWindow\0box2i\0"[..], &b"displayWindow\0box2i\0"[..]] {
        let at = bytes
            .windows(name.len())
            .position(|w| w == name)
            .expect("the attribute")
            + name.len()
            + 4;
        for (k, v) in [0, 0, side - 1, side - 1].into_iter().enumerate() {
            bytes[at + 4 * k..at + 4 * k + 4].copy_from_slice(&v.to_le_bytes());
        }
    }
    std::fs::write(path, &bytes).expect("patch");
}
