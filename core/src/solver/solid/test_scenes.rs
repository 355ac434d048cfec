//! Scene text read for the 3D solver's unit tests (`tests.rs`, `ridge_tests.rs`).

use crate::scene::solid::SolidScene;
use crate::scene::SceneFile;

/// The scene text `text` read as a 3D scene from the file `file` (its STL files relative to
/// it); a panic when it does not parse or reads as 2D.
pub(super) fn solid_scene(text: &str, file: &str) -> SolidScene {
    match SceneFile::from_str_named(text, file).unwrap() {
        SceneFile::Solid(s) => *s,
        SceneFile::Plane(_) => panic!("not 3D"),
    }
}
