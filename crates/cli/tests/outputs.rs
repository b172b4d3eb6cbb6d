//! What the command writes and where: stdout that fails or closes early, a
//! log without scans, picture formats, and pictures that read at a glance.

mod common;

use common::{pcaline, s, small_maze, tmp};
use std::io::{Read, Write};
use std::process::{Command, Stdio};

/// A generated CARMEN log of `scans` three-beam scans.
fn carmen_log(name: &str, scans: usize) -> std::path::PathBuf {
    let log = tmp(name);
    let mut w = std::io::BufWriter::new(std::fs::File::create(&log).unwrap());
    for k in 0..scans {
        let t = k as f64 * 0.025;
        writeln!(w, "FLASER 3 2.0 2.1 2.2 0 0 0 0 0 0 {t:.3} gen {t:.3}").unwrap();
    }
    log
}

#[test]
fn a_full_stdout_is_an_error_naming_stdout() {
    let log = carmen_log("full.clf", 10);
    let full = std::fs::OpenOptions::new().write(true).open("/dev/full").unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_pcaline"))
        .args(["detect", s(&log), "--fov", "2"])
        .stdout(full)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("stdout") && !err.contains("panicked"), "{err}");
}

#[test]
fn a_reader_that_stops_early_ends_detect_quietly() {
    let log = carmen_log("pipe.clf", 50_000);
    let mut child = Command::new(env!("CARGO_BIN_EXE_pcaline"))
        .args(["--quiet", "detect", s(&log), "--fov", "2"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut head = [0u8; 100];
    child.stdout.as_mut().unwrap().read_exact(&mut head).unwrap();
    drop(child.stdout.take()); // `| head -c 100`
    let out = child.wait_with_output().unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(out.stderr.is_empty(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(head.starts_with(b"{\"scan\":0"), "JSON Lines on stdout");
}

#[test]
fn detect_on_a_log_without_scans_fails_and_writes_nothing() {
    let log = tmp("odom-only.clf");
    std::fs::write(&log, "# a comment\nODOM 0 0 0 0 0 0 1.0 gen 1.0\n").unwrap();
    let (json, mcap) = (tmp("no-scans.json"), tmp("no-scans.mcap"));
    let out = pcaline(&["detect", s(&log), "-o", s(&json), "--mcap", s(&mcap)]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no scans"));
    assert!(!json.exists() && !mcap.exists());
    let out = pcaline(&["detect", s(&log)]);
    assert_eq!(out.status.code(), Some(2));
    assert!(out.stdout.is_empty(), "nothing on stdout either");
}

#[test]
fn pictures_other_than_svg_or_png_are_refused_before_any_work() {
    let scene = small_maze("pdf-maze.toml", 4);
    for args in [
        vec!["scene", "draw", s(&scene), "-o"],
        vec!["draw", "scan", "/no/such/scan.json", "-o"],
        vec!["draw", "map", "/no/such/map.json", "-o"],
    ] {
        let pdf = tmp("picture.pdf");
        let mut all = args.clone();
        all.push(s(&pdf));
        let out = pcaline(&all);
        assert_eq!(out.status.code(), Some(2), "{all:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("picture.pdf") && err.contains(".svg, .png"), "{err}");
        assert!(!pdf.exists());
    }
}

#[test]
fn run_draws_the_truth_under_the_estimate_and_dashes_odometry_in_the_legend() {
    let scene = small_maze("legend-maze.toml", 8);
    let out_dir = tmp("legend-run");
    let out = pcaline(&["--quiet", "run", s(&scene), "--out", s(&out_dir)]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let svg = std::fs::read_to_string(out_dir.join("map.svg")).unwrap();
    let polylines: Vec<&str> = svg.lines().filter(|l| l.starts_with("<polyline")).collect();
    let truth = polylines.iter().position(|l| l.contains("#a6dba0")).expect("the true trajectory");
    let estimate = polylines.iter().position(|l| l.contains("#9467bd")).expect("the estimator");
    assert!(truth < estimate, "the truth is drawn first, under the estimate");
    let width = |l: &str| -> f64 {
        let at = l.find("stroke-width=\"").unwrap() + 14;
        l[at..].split('"').next().unwrap().parse().unwrap()
    };
    assert!(width(polylines[truth]) >= 3.0 * width(polylines[estimate]));
    // Legend swatches are `<line>`s after the plot: the odometry's is dashed.
    let odometry_swatch = svg
        .lines()
        .rfind(|l| l.starts_with("<line") && l.contains("#1f77b4"))
        .expect("an odometry swatch");
    assert!(odometry_swatch.contains("stroke-dasharray"), "{odometry_swatch}");
}

#[test]
fn detect_writes_json_lines_to_stdout_or_dash_and_an_array_to_a_json_file() {
    let log = carmen_log("formats.clf", 3);
    for args in [vec![], vec!["-o", "-"]] {
        let mut all = vec!["--quiet", "detect", s(&log), "--fov", "2"];
        all.extend(args);
        let out = pcaline(&all);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let objects = common::json_lines(&out.stdout);
        assert_eq!(objects.len(), 3);
        assert_eq!(objects[2]["scan"], 2);
    }
    let (json, jsonl) = (tmp("formats.json"), tmp("formats.jsonl"));
    for path in [&json, &jsonl] {
        let out = pcaline(&["--quiet", "detect", s(&log), "--fov", "2", "-o", s(path)]);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    }
    let array: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    assert_eq!(array.as_array().unwrap().len(), 3);
    assert_eq!(common::json_lines(&std::fs::read(&jsonl).unwrap()).len(), 3);
}

#[test]
fn output_onto_a_device_writes_through_it_and_never_replaces_it() {
    let log = carmen_log("device.clf", 3);
    let out = pcaline(&["--quiet", "detect", s(&log), "--fov", "2", "-o", "/dev/null"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(!std::fs::metadata("/dev/null").unwrap().is_file(), "/dev/null is still a device");
    let dir = tmp("a-folder");
    std::fs::create_dir_all(&dir).unwrap();
    let out = pcaline(&["detect", s(&log), "--fov", "2", "-o", s(&dir)]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("is a directory"));
}

#[test]
fn an_interrupted_write_leaves_no_temporary_file() {
    let log = carmen_log("interrupted.clf", 400_000);
    let dir = tmp("interrupted");
    std::fs::create_dir_all(&dir).unwrap();
    for signal in ["-INT", "-TERM"] {
        let target = dir.join("lines.json");
        let mut child = Command::new(env!("CARGO_BIN_EXE_pcaline"))
            .args(["--quiet", "detect", s(&log), "--fov", "2", "-o", s(&target)])
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        // Wait for the temporary file, then interrupt the write.
        let started = std::time::Instant::now();
        while std::fs::read_dir(&dir).unwrap().count() == 0 {
            assert!(child.try_wait().unwrap().is_none(), "detect ended before it was interrupted");
            assert!(started.elapsed().as_secs() < 60, "no temporary file appeared");
            std::thread::sleep(std::time::Duration::from_millis(5));
        }
        let kill = Command::new("kill").args([signal, &child.id().to_string()]).status().unwrap();
        assert!(kill.success());
        let status = child.wait().unwrap();
        assert_eq!(status.code(), Some(130), "{signal}");
        let left: Vec<_> =
            std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert!(left.is_empty(), "{signal} left {left:?}");
    }
}

#[test]
fn every_command_fails_cleanly_on_a_full_stdout() {
    let scene = small_maze("full-maze.toml", 9);
    let out_dir = tmp("full-run");
    for args in [
        vec!["eval", "--show-config", "default"],
        vec!["--quiet", "run", s(&scene), "--out", s(&out_dir)],
        vec!["scene", "check", s(&scene)],
        vec!["reproduce", "table2", "--runs", "10"],
    ] {
        let full = std::fs::OpenOptions::new().write(true).open("/dev/full").unwrap();
        let out =
            Command::new(env!("CARGO_BIN_EXE_pcaline")).args(&args).stdout(full).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
        assert!(err.contains("stdout") && !err.contains("panicked"), "{args:?}: {err}");
    }
}

#[test]
fn every_subcommand_help_has_an_example() {
    for args in [
        vec!["run"],
        vec!["detect"],
        vec!["map"],
        vec!["draw", "scan"],
        vec!["draw", "map"],
        vec!["draw", "heading"],
        vec!["scene", "generate"],
        vec!["scene", "check"],
        vec!["scene", "draw"],
        vec!["eval"],
        vec!["reproduce"],
    ] {
        let mut all = args.clone();
        all.push("--help");
        let out = pcaline(&all);
        assert!(out.status.success(), "{args:?}");
        let help = String::from_utf8_lossy(&out.stdout);
        let example = help.split_once("Example").map(|(_, e)| e).unwrap_or_default();
        assert!(example.contains(&format!("pcaline {}", args.join(" "))), "{args:?}: {help}");
    }
}
