//! Every core, the same answer: `detect`, `eval` and `eval --real` write the
//! same bytes, and report the same errors, whatever `--threads` says.

mod common;

use common::{data, pcaline, s, small_maze, tmp};

/// `pcaline --threads N ARGS...`, asserted to succeed; its stdout.
fn with_threads(n: usize, args: &[&str]) -> Vec<u8> {
    let threads = n.to_string();
    let all: Vec<&str> =
        ["--quiet", "--threads", &threads].into_iter().chain(args.iter().copied()).collect();
    let out = pcaline(&all);
    assert!(out.status.success(), "{all:?}: {}", String::from_utf8_lossy(&out.stderr));
    out.stdout
}

/// A CARMEN log of the MIT CSAIL scans repeated until it spans several of
/// the pipeline's batches (256 scans), with `tail` appended.
fn long_log(name: &str, tail: &str) -> Option<std::path::PathBuf> {
    let csail = data("mit-csail/mit-csail.clf")?;
    let text = std::fs::read_to_string(csail).unwrap();
    let path = tmp(name);
    std::fs::write(&path, format!("{text}{tail}")).unwrap();
    Some(path)
}

#[test]
fn detect_writes_the_same_bytes_on_one_thread_and_on_several() {
    let Some(log) = long_log("threads.clf", "") else { return };
    for format in [&[][..], &["--csv"][..]] {
        let one = with_threads(1, &[&["detect", s(&log)][..], format].concat());
        let three = with_threads(3, &[&["detect", s(&log)][..], format].concat());
        assert!(one.len() > 100_000, "{} bytes", one.len());
        assert!(one == three, "detect {format:?}: the outputs differ");
    }
    // The JSON array into a file, and the MCAP file beside it.
    let mut files = Vec::new();
    for n in [1, 2] {
        let (json, mcap) = (tmp(&format!("threads-{n}.json")), tmp(&format!("threads-{n}.mcap")));
        with_threads(n, &["detect", s(&log), "-o", s(&json), "--mcap", s(&mcap)]);
        files.push((std::fs::read(json).unwrap(), std::fs::read(mcap).unwrap()));
    }
    assert!(files[0].0 == files[1].0, "the JSON files differ");
    assert!(files[0].1 == files[1].1, "the MCAP files differ");
}

/// A format parsed on the reader thread (JSON Lines) goes through the same
/// chunks: the same bytes on any number of threads, every scan numbered in
/// order across the batches, and a bad scan after them the same error.
#[test]
fn a_json_log_gives_the_same_bytes_and_error_on_any_number_of_threads() {
    let scan = |k: usize| {
        let ranges: Vec<String> =
            (0..180).map(|i| format!("{}", 2.0 + 0.01 * ((i + k) % 9) as f64)).collect();
        format!(
            "{{\"angle_min\": -1.57, \"angle_increment\": 0.0175, \"range_min\": 0.1, \"range_max\": 30.0, \"ranges\": [{}], \"stamp_s\": {k}}}\n",
            ranges.join(", ")
        )
    };
    let text: String = (0..600).map(scan).collect();
    let log = tmp("threads.jsonl");
    std::fs::write(&log, &text).unwrap();
    let one = with_threads(1, &["detect", s(&log)]);
    let two = with_threads(2, &["detect", s(&log)]);
    assert!(one == two, "the outputs differ");
    let scans = common::json_lines(&one);
    assert_eq!(scans.len(), 600);
    assert!(scans.iter().enumerate().all(|(k, v)| v["scan"] == k), "scan numbers out of order");
    let bad = tmp("threads-bad.jsonl");
    std::fs::write(&bad, format!("{text}{{\"ranges\": 5}}\n")).unwrap();
    let runs: Vec<_> = ["1", "2"]
        .into_iter()
        .map(|n| {
            let out = pcaline(&["--threads", n, "detect", s(&bad)]);
            assert_eq!(out.status.code(), Some(2), "--threads {n}");
            (out.stdout, String::from_utf8_lossy(&out.stderr).to_string())
        })
        .collect();
    assert!(runs[0].1.contains("threads-bad.jsonl"), "{}", runs[0].1);
    assert_eq!(common::json_lines(&runs[0].0).len(), 600);
    assert!(runs[0] == runs[1], "the runs differ");
}

#[test]
fn a_bad_line_is_the_same_error_on_any_number_of_threads() {
    // The 1988 scans of the log, then a FLASER line whose range is not a number.
    let bad = format!("FLASER 180{} 0 0 0 0 0 0 1 host 1\n", " 1.5".repeat(179) + " x");
    let Some(log) = long_log("threads-bad.clf", &bad) else { return };
    let lines = std::fs::read_to_string(&log).unwrap().lines().count();
    let mut results = Vec::new();
    for n in ["1", "2", "4"] {
        let out = pcaline(&["--threads", n, "detect", s(&log)]);
        assert_eq!(out.status.code(), Some(2), "--threads {n}");
        let err = String::from_utf8_lossy(&out.stderr).to_string();
        assert!(err.contains(&format!(":{lines}:")) && err.contains("range 180"), "{err}");
        results.push((out.stdout, err));
    }
    // The scans before the bad line are on stdout, as a sequential run
    // writes them, then the same message.
    assert_eq!(common::json_lines(&results[0].0).len(), 1988);
    assert!(results.iter().all(|r| *r == results[0]), "the runs differ");
}

#[test]
fn eval_tables_do_not_depend_on_the_threads() {
    let maze = small_maze("threads-maze.toml", 5);
    let args = ["eval", "--scene", s(&maze), "--seeds", "2", "--scans", "3", "--json"];
    let mut one: serde_json::Value = serde_json::from_slice(&with_threads(1, &args)).unwrap();
    let mut two: serde_json::Value = serde_json::from_slice(&with_threads(2, &args)).unwrap();
    // The detection time per scan is a measurement, not a result.
    for v in [&mut one, &mut two] {
        for row in v["detection"].as_array_mut().unwrap() {
            row.as_object_mut().unwrap().remove("time_per_scan_us");
        }
    }
    assert!(!one["localization"].as_array().unwrap().is_empty());
    assert_eq!(one, two);
}

#[test]
fn threads_must_be_at_least_one() {
    let out = pcaline(&["--threads", "0", "run"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--threads"));
}

#[test]
fn real_data_eval_does_not_depend_on_the_threads() {
    let Some(data) = data("mit-csail").map(|p| p.parent().unwrap().to_path_buf()) else { return };
    let args = ["eval", "--real", "--json", "--data", s(&data)];
    assert!(with_threads(1, &args) == with_threads(2, &args), "eval --real differs");
}

#[test]
fn detect_counts_every_line_in_its_summary() {
    // The count on stderr is the sum of the lines written, with and without
    // --mcap (the lines themselves are kept only for the MCAP file).
    let Some(log) = data("intel/intel.gfs.log") else { return };
    let out = pcaline(&["detect", s(&log)]);
    assert!(out.status.success());
    let written: usize = common::json_lines(&out.stdout)
        .iter()
        .map(|scan| scan["lines"].as_array().unwrap().len())
        .sum();
    assert!(written > 1000, "{written} lines");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains(&format!("910 scans, {written} lines")), "{err}");
}
