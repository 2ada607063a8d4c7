//! The scene files of `scenes/` that read meshes from the shared data (`../shared/data`),
//! embedded so that `refract bench` and `refract claims` can load them with any `--data`.

use std::path::Path;

use crate::progress::{Note, Progress};

use refract_eval::load_scene_str;
use refract_scene::Scene;

/// The scene files' path to the shared data, replaced by `--data`.
const SCENE_DATA_PREFIX: &str = "../../shared/data";

/// Name and text of every embedded scene file.
pub const DATA_SCENES: [(&str, &str); 6] = [
    (
        "igea-bunny",
        include_str!("../../../scenes/igea-bunny.toml"),
    ),
    (
        "horse-bunny",
        include_str!("../../../scenes/horse-bunny.toml"),
    ),
    (
        "sphere-igea",
        include_str!("../../../scenes/sphere-igea.toml"),
    ),
    (
        "igea-planes",
        include_str!("../../../scenes/igea-planes.toml"),
    ),
    (
        "horse-igea",
        include_str!("../../../scenes/horse-igea.toml"),
    ),
    (
        "teapot-box",
        include_str!("../../../scenes/teapot-box.toml"),
    ),
];

/// The embedded scene `name` with its meshes read from `data`, or `None` (after a note to
/// `progress`) when `data/meshes` does not exist.
pub fn load(name: &str, data: &Path, progress: &dyn Progress) -> crate::Result<Option<Scene>> {
    let Some(&(_, text)) = DATA_SCENES.iter().find(|s| s.0 == name) else {
        crate::bail!("no embedded scene `{name}`");
    };
    load_text(name, text, data, progress)
}

/// A scene from TOML text whose mesh paths start with `../../shared/data`, read from `data`.
pub fn load_text(
    name: &str,
    text: &str,
    data: &Path,
    progress: &dyn Progress,
) -> crate::Result<Option<Scene>> {
    if text.contains(SCENE_DATA_PREFIX) && !data.join("meshes").is_dir() {
        progress.note(Note::Skipped(format!(
            "{}/meshes not found; skipping {name}",
            data.display()
        )));
        return Ok(None);
    }
    let text = text.replace(SCENE_DATA_PREFIX, &data.display().to_string());
    Ok(Some(
        load_scene_str(name, &text, Path::new("."), &format!("scenes/{name}.toml"))?.scene,
    ))
}
