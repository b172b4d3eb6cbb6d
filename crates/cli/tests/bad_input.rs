//! Bad input the command once accepted, hung on or panicked on: each is now
//! a one-line error naming the file, line or option, with exit code 2.

mod common;

use common::{data, pcaline, s, tmp};

/// Runs `args`, expects exit code 2 and a message containing every
/// `wanted` (on stderr, or on stdout for `scene check`'s report per file).
fn refused(args: &[&str], wanted: &[&str]) {
    let out = pcaline(args);
    let err =
        String::from_utf8_lossy(&out.stderr).into_owned() + &String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
    for w in wanted {
        assert!(err.contains(w), "{args:?}: {err:?} lacks {w:?}");
    }
    assert!(!err.contains("panicked"), "{err}");
}

fn json_scan(name: &str, header: &str) -> std::path::PathBuf {
    let path = tmp(name);
    std::fs::write(&path, format!("{{{header}, \"ranges\": [2.0, 2.0, 2.0, 2.0]}}\n")).unwrap();
    path
}

#[test]
fn zero_counts_are_refused() {
    refused(&["eval", "--seeds", "0"], &["--seeds"]);
    refused(&["eval", "--scans", "0"], &["--scans", "at least 1"]);
    refused(&["reproduce", "table2", "--runs", "0"], &["--runs", "at least 1"]);
    refused(&["reproduce", "eth", "--eth-runs", "0"], &["--eth-runs"]);
}

#[test]
fn impossible_scan_headers_name_the_file_and_the_field() {
    let good =
        "\"angle_min\": -0.5, \"angle_increment\": 0.01, \"range_min\": 0.1, \"range_max\": 30.0";
    let out = pcaline(&["--quiet", "detect", s(&json_scan("good.json", good))]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    for (name, header, what) in [
        (
            "inc0.json",
            "\"angle_min\": -0.5, \"angle_increment\": 0.0, \"range_min\": 0.1, \"range_max\": 30.0",
            "angle_increment",
        ),
        (
            "inc-huge.json",
            "\"angle_min\": -0.5, \"angle_increment\": 1e30, \"range_min\": 0.1, \"range_max\": 30.0",
            "more than a turn",
        ),
        (
            "min-max.json",
            "\"angle_min\": -0.5, \"angle_increment\": 0.01, \"range_min\": 5.0, \"range_max\": 1.0",
            "range_max",
        ),
        (
            "neg-max.json",
            "\"angle_min\": -0.5, \"angle_increment\": 0.01, \"range_min\": 0.0, \"range_max\": -1.0",
            "range_max",
        ),
        (
            "amin.json",
            "\"angle_min\": 1e38, \"angle_increment\": 0.01, \"range_min\": 0.1, \"range_max\": 30.0",
            "angle_min",
        ),
    ] {
        let path = json_scan(name, header);
        refused(&["detect", s(&path)], &[name, "scan 1", what]);
    }
}

#[test]
fn carmen_lines_that_do_not_add_up_or_hold_nan_are_refused() {
    let line = |extra: &str, pose: &str| {
        format!("FLASER 3 2.0 2.0 2.0 {pose} 0 0 0 1.0 host 1.0{extra}\n")
    };
    let ok = tmp("ok.clf");
    std::fs::write(&ok, line("", "0 0 0")).unwrap();
    let out = pcaline(&["--quiet", "detect", s(&ok), "--fov", "2"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let extra = tmp("extra.clf");
    std::fs::write(&extra, format!("{}{}", line("", "0 0 0"), line(" 9", "0 0 0"))).unwrap();
    refused(&["detect", s(&extra), "--fov", "2"], &["extra.clf:2", "expected 13"]);
    let nan = tmp("nan.clf");
    std::fs::write(&nan, line("", "nan 0 0")).unwrap();
    refused(&["detect", s(&nan), "--fov", "2"], &["nan.clf:1", "not finite"]);
    let far = tmp("far.clf");
    std::fs::write(&far, line("", "1e16 0 0")).unwrap();
    refused(&["map", s(&far), "--fov", "2", "--out", s(&tmp("far-map"))], &["far.clf:1", "beyond"]);
    for fov in ["nan", "0", "1e9", "-180"] {
        refused(&["detect", s(&ok), &format!("--fov={fov}")], &["--fov"]);
    }
    refused(&["detect", s(&ok), "--fov", "2", "--max-range", "nan"], &["--max-range"]);
}

#[test]
fn a_topic_without_laserscans_lists_the_topics_that_have_them() {
    let Some(bag) = data("ros1/laser_scan_matcher_demo.bag") else { return };
    refused(&["detect", s(&bag), "--topic", "/nope"], &["\"/nope\"", "scan topics: /scan"]);
}

#[test]
fn draw_scan_reads_the_whole_file_and_bounds_its_size() {
    let good = "{\"angle_min\": -0.5, \"angle_increment\": 0.01, \"range_min\": 0.1, \"range_max\": 30.0, \"ranges\": [2.0, 2.0, 2.0]}";
    let broken = tmp("broken.jsonl");
    std::fs::write(&broken, format!("{good}\n{{\"angle_min\": oops}}\n")).unwrap();
    refused(&["draw", "scan", s(&broken), "-o", s(&tmp("broken.svg"))], &["broken.jsonl"]);
    assert!(!tmp("broken.svg").exists());
    let n = 100_001;
    let wide = tmp("wide.json");
    std::fs::write(
        &wide,
        format!(
            "{{\"angle_min\": -3.0, \"angle_increment\": 0.00006, \"range_min\": 0.1, \"range_max\": 30.0, \"ranges\": [{}]}}",
            vec!["2.0"; n].join(",")
        ),
    )
    .unwrap();
    refused(
        &["draw", "scan", s(&wide), "-o", s(&tmp("wide.svg"))],
        &["100001 beams", "at most 100000"],
    );
}

#[test]
fn scenes_a_run_cannot_handle_fail_the_check() {
    let scene = |name: &str, walls: &str, trajectory: &str| {
        let path = tmp(name);
        std::fs::write(
            &path,
            format!(
                "name = \"t\"\n[[walls]]\nname = \"room\"\nclosed = true\npoints = {walls}\n[trajectory]\n{trajectory}\n"
            ),
        )
        .unwrap();
        path
    };
    let square = "[[0, 0], [10, 0], [10, 10], [0, 10]]";
    let ok =
        scene("ok.toml", square, "start = { x = 1, y = 1, heading_deg = 0 }\nwaypoints = [[9, 1]]");
    let out = pcaline(&["scene", "check", s(&ok)]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let cases = [
        (
            "huge.toml",
            "[[0, 0], [1e20, 0], [1e20, 1e20], [0, 1e20]]",
            "start = { x = 1, y = 1, heading_deg = 0 }\nwaypoints = [[9, 1]]",
            "beyond",
        ),
        (
            "laps.toml",
            square,
            "start = { x = 1, y = 1, heading_deg = 0 }\nwaypoints = [[9, 1]]\nlaps = 100000000",
            "scans",
        ),
        (
            "slow.toml",
            square,
            "start = { x = 1, y = 1, heading_deg = 0 }\nwaypoints = [[9, 1]]\nspeed_m_s = 1e-6",
            "scans",
        ),
        (
            "fast.toml",
            square,
            "start = { x = 1, y = 1, heading_deg = 0 }\nwaypoints = [[9, 1]]\nscan_rate_hz = 1e9",
            "scans",
        ),
        (
            "l-room.toml",
            "[[0, 0], [10, 0], [10, 5], [5, 5], [5, 10], [0, 10]]",
            "start = { x = 8, y = 8, heading_deg = 0 }\nwaypoints = [[4, 1]]",
            "outside the walls",
        ),
    ];
    for (name, walls, trajectory, what) in cases {
        let path = scene(name, walls, trajectory);
        refused(&["scene", "check", s(&path)], &[name, what]);
        refused(&["run", s(&path), "--out", s(&tmp("never"))], &[name, what]);
    }
}

#[test]
fn files_without_scans_are_errors_not_empty_results() {
    let text: String = (0..20_000).map(|k| format!("line {k} of plain text\n")).collect();
    let cases: [(&str, &str); 7] = [
        ("empty.clf", ""),
        ("comments.clf", "# only\n# comments\n"),
        ("odom-only.clf", "ODOM 0 0 0 0 0 0 1.0 gen 1.0\n"),
        ("plain.txt", &text),
        ("empty.csv", ""),
        ("header-only.csv", "stamp_s,angle_min,angle_increment,range_min,range_max,r0\n"),
        ("empty-array.json", "[]"),
    ];
    for (name, content) in cases {
        let path = tmp(name);
        std::fs::write(&path, content).unwrap();
        let out = pcaline(&["detect", s(&path)]);
        assert_eq!(out.status.code(), Some(2), "{name}: {}", String::from_utf8_lossy(&out.stderr));
        assert!(out.stdout.is_empty(), "{name}: nothing on stdout");
        assert!(String::from_utf8_lossy(&out.stderr).contains(name), "{name}");
    }
}

#[test]
fn a_grid_cell_too_small_to_index_is_refused() {
    let config = tmp("tiny-cell.toml");
    std::fs::write(&config, "preset = \"default\"\n[map]\ngrid_cell_m = 1e-9\n").unwrap();
    let log = tmp("tiny-cell.clf");
    std::fs::write(&log, "FLASER 3 2.0 2.0 2.0 0 0 0 0 0 0 1.0 host 1.0\n").unwrap();
    refused(
        &["map", s(&log), "--fov", "2", "--config", s(&config), "--out", s(&tmp("tiny-cell-out"))],
        &["tiny-cell.toml", "map.grid_cell_m"],
    );
}
