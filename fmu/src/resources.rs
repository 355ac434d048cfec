//! What an FMU finds in its `resources/` folder, for both APIs' instantiation: a forging
//! scene (`scene.toml`) or, FMI 2.0 only, a press plant (`press.toml`); the folder from FMI
//! 2.0's `file:` URI; the check of the host's GUID or instantiation token against it.

use crate::instance::Instance;
use crate::press;
use crate::slave::Slave;
use std::path::{Path, PathBuf};

/// The forging instance of the scene in `folder` (`scene.toml`).
pub fn scene_instance(folder: &Path) -> Result<Instance, String> {
    let path = folder.join("scene.toml");
    let scene = std::fs::read_to_string(&path)
        .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    Instance::new(&scene, &path.display().to_string()).map_err(|e| e.to_string())
}

/// The slave `folder` describes: a press plant (`press.toml`: `press = "crank"`, and
/// `model_copies = 4` when its forging FMU models a quarter of the workpiece) or a forging
/// scene (`scene.toml`).
pub fn slave(folder: &Path) -> Result<Box<dyn Slave>, String> {
    let press = folder.join("press.toml");
    if press.is_file() {
        let text = std::fs::read_to_string(&press)
            .map_err(|e| format!("cannot read {}: {e}", press.display()))?;
        let name = text
            .lines()
            .find_map(|l| l.trim().strip_prefix("press = "))
            .map(|v| v.trim().trim_matches('"'))
            .unwrap_or_default();
        let kind = press::parse(name).ok_or_else(|| {
            format!(
                "{}: `press = \"{name}\"` is no press of rkforge",
                press.display()
            )
        })?;
        let copies = match text
            .lines()
            .find_map(|l| l.trim().strip_prefix("model_copies = "))
        {
            None => 1.0,
            Some(v) => v
                .trim()
                .parse::<f64>()
                .ok()
                .filter(|x| *x >= 1.0 && x.is_finite())
                .ok_or_else(|| {
                    format!(
                        "{}: `model_copies = {v}` is not a number of at least 1",
                        press.display()
                    )
                })?,
        };
        return Ok(Box::new(press::Press::new(kind, copies)));
    }
    Ok(Box::new(scene_instance(folder)?))
}

/// The host's `given` GUID or token (`what`, if it gave one) is the `own` one of the
/// `model` in `resources/`.
pub fn check_token(
    given: Option<String>,
    what: &str,
    own: &str,
    model: &str,
) -> Result<(), String> {
    match given {
        Some(g) if g != own => Err(format!(
            "{what} {g} does not match the {model} in resources/ ({own})"
        )),
        _ => Ok(()),
    }
}

/// The folder of a `file:` URI (`file:///a/b%20c`, `file:/a/b`).
pub fn uri_to_path(uri: &str) -> Option<PathBuf> {
    let rest = uri
        .strip_prefix("file://")
        .map(|r| r.strip_prefix("localhost").unwrap_or(r))
        .or_else(|| uri.strip_prefix("file:"))?;
    let mut out = Vec::new();
    let b = rest.as_bytes();
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' && i + 2 < b.len() {
            let hex = std::str::from_utf8(&b[i + 1..i + 3]).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    Some(PathBuf::from(String::from_utf8(out).ok()?))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn file_uris_become_paths() {
        assert_eq!(
            uri_to_path("file:///tmp/a%20b/resources").unwrap(),
            PathBuf::from("/tmp/a b/resources")
        );
        assert_eq!(uri_to_path("file:/tmp/x").unwrap(), PathBuf::from("/tmp/x"));
        assert_eq!(
            uri_to_path("file://localhost/tmp/x").unwrap(),
            PathBuf::from("/tmp/x")
        );
        assert!(uri_to_path("http://example.org/x").is_none());
    }
}
