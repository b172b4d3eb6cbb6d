//! Scene files (TOML or JSON, chosen by extension): read, validated, written.

use crate::{IoError, write_atomic};
use pcaline_sim::Scene;
use std::path::Path;

/// Reads and validates a scene file (`.toml` or `.json`). Errors name the file
/// and the line (syntax, unknown key, wrong type) or the item (invalid value).
pub fn read_scene(path: &Path) -> Result<Scene, IoError> {
    let text = std::fs::read_to_string(path).map_err(|e| IoError::io(path, e))?;
    let scene = parse_scene(path, &text)?;
    scene.validate().map_err(|e| IoError::Invalid {
        path: path.to_path_buf(),
        item: e.item,
        message: e.message,
    })?;
    Ok(scene)
}

/// Parses scene text in the format named by `path`'s extension, without validating it.
pub fn parse_scene(path: &Path, text: &str) -> Result<Scene, IoError> {
    match extension(path).as_str() {
        "toml" => toml::from_str(text).map_err(|e| {
            let line = e.span().map(|s| text[..s.start.min(text.len())].matches('\n').count() + 1);
            IoError::parse(path, line, e.message().trim().to_string())
        }),
        "json" => serde_json::from_str(text)
            .map_err(|e| IoError::parse(path, Some(e.line()), e.to_string())),
        _ => Err(IoError::UnknownFormat { path: path.to_path_buf(), expected: ".toml, .json" }),
    }
}

/// Writes a scene (`.toml` or `.json` by extension), atomically.
pub fn write_scene(path: &Path, scene: &Scene) -> Result<(), IoError> {
    let text = match extension(path).as_str() {
        "toml" => toml::to_string_pretty(scene)
            .map_err(|e| IoError::parse(path, None, format!("cannot encode scene: {e}")))?,
        "json" => serde_json::to_string_pretty(scene)
            .map_err(|e| IoError::parse(path, None, format!("cannot encode scene: {e}")))?,
        _ => {
            return Err(IoError::UnknownFormat {
                path: path.to_path_buf(),
                expected: ".toml, .json",
            });
        }
    };
    write_atomic(path, text.as_bytes())
}

fn extension(path: &Path) -> String {
    path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase()).unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = r#"
name = "box"
[[walls]]
name = "outer"
points = [[0, 0], [6, 0], [6, 4], [0, 4]]
closed = true
[trajectory]
start = { x = 1, y = 1 }
waypoints = [[5, 1], [5, 3]]
"#;

    #[test]
    fn parses_toml_with_integer_coordinates() {
        let s = parse_scene(Path::new("a.toml"), GOOD).unwrap();
        assert_eq!(s.walls[0].points[2], [6.0, 4.0]);
        assert_eq!(s.trajectory.speed_m_s, 1.0);
        assert!(s.validate().is_ok());
    }

    #[test]
    fn unknown_key_names_file_and_line() {
        let bad = GOOD.replace("closed = true", "closed = true\ncolour = \"red\"");
        let e = parse_scene(Path::new("scenes/a.toml"), &bad).unwrap_err().to_string();
        assert!(e.starts_with("scenes/a.toml:7:"), "{e}");
        assert!(e.contains("colour"), "{e}");
    }

    #[test]
    fn json_errors_carry_lines() {
        let e = parse_scene(Path::new("a.json"), "{\n\"name\": 3\n}").unwrap_err().to_string();
        assert!(e.starts_with("a.json:2:"), "{e}");
        let e = parse_scene(Path::new("a.yaml"), "").unwrap_err().to_string();
        assert!(e.contains("unknown format"), "{e}");
    }
}
