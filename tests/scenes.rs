//! The shipped scene files load and validate, and malformed scenes are clear
//! errors that name the file and the item.

use pcaline_io::{IoError, read_scene};
use std::path::{Path, PathBuf};

fn scene_files() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("sim-scenes");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml" || e == "json"))
        .collect();
    files.sort();
    files
}

#[test]
fn every_shipped_scene_is_valid() {
    let files = scene_files();
    let names: Vec<_> =
        files.iter().map(|p| p.file_stem().unwrap().to_string_lossy().into_owned()).collect();
    for expected in
        ["corridor-doors", "office-clutter", "hall-pillars", "paper-maze", "large-building"]
    {
        assert!(names.iter().any(|n| n == expected), "sim-scenes/ lacks {expected}: {names:?}");
    }
    for file in files {
        let scene = read_scene(&file).unwrap_or_else(|e| panic!("{e}"));
        assert!(!scene.walls.is_empty(), "{}", file.display());
    }
    let large =
        read_scene(&Path::new(env!("CARGO_MANIFEST_DIR")).join("sim-scenes/large-building.json"))
            .unwrap();
    assert!(large.world_walls().len() >= 2000, "{} walls", large.world_walls().len());
}

fn write_tmp(name: &str, text: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("pcaline-scenes-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

const BASE: &str = r#"name = "t"
[[walls]]
name = "outer"
points = [[0.0, 0.0], [8.0, 0.0], [8.0, 6.0], [0.0, 6.0]]
closed = true
[trajectory]
start = { x = 1.0, y = 1.0 }
waypoints = [[7.0, 1.0], [7.0, 5.0]]
"#;

#[test]
fn malformed_scenes_name_file_and_item() {
    let cases = [
        (BASE.replace("closed = true", "closed = true\nheight = 2"), "bad1.toml:6:", "height"),
        (
            BASE.replace("[[0.0, 0.0], [8.0, 0.0], [8.0, 6.0], [0.0, 6.0]]", "[[0.0, 0.0]]"),
            "bad2.toml",
            "walls[0] \"outer\": needs at least 3 vertices",
        ),
        (
            BASE.replace("[8.0, 0.0], [8.0, 6.0]", "[8.0, 0.0], [8.0, 0.0]"),
            "bad3.toml",
            "zero length",
        ),
        (
            BASE.replace("[[7.0, 1.0], [7.0, 5.0]]", "[[7.0, 1.0], [17.0, 5.0]]"),
            "bad4.toml",
            "trajectory.waypoints[1]",
        ),
        (
            BASE.replace("waypoints", "speed_m_s = -1.0\nwaypoints"),
            "bad5.toml",
            "trajectory.speed_m_s",
        ),
        (
            BASE.replace("[trajectory]", "[sensor]\nrange_sigma_m = nan\n[trajectory]"),
            "bad6.toml",
            "sensor",
        ),
        ("{\"name\": \"t\", \"walls\": [".to_string(), "bad7.json:1:", "EOF"),
    ];
    for (i, (text, where_, what)) in cases.iter().enumerate() {
        let ext = if where_.contains(".json") { "json" } else { "toml" };
        let path = write_tmp(&format!("bad{}.{ext}", i + 1), text);
        let err = read_scene(&path).unwrap_err();
        let msg = err.to_string();
        assert!(msg.contains(where_) && msg.contains(what), "case {}: {msg}", i + 1);
        assert!(!matches!(err, IoError::Io { .. }));
    }
    let missing = read_scene(Path::new("no/such/scene.toml")).unwrap_err().to_string();
    assert!(missing.starts_with("no/such/scene.toml:"), "{missing}");
}

#[test]
fn schema_example_in_the_scene_readme_is_valid() {
    let readme =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("sim-scenes/README.md"))
            .unwrap();
    let example = readme.split("```toml\n").nth(1).and_then(|s| s.split("```").next()).unwrap();
    let path = write_tmp("readme-example.toml", example);
    let scene = read_scene(&path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(scene.name, "example");
}
