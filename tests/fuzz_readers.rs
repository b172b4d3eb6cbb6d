//! Every reader fed random bytes and truncated real files: an error or a
//! result, never a panic, and the same records and error read whole
//! (`read_log`) or in chunks parsed apart (`read_log_chunks`); the ROS
//! odometry and frames reader too (`read_ros_motion`). Seeded.

#![allow(clippy::print_stderr)] // the loud report of a missing dataset

use pcaline_io::{LogFormat, LogOptions, read_log, read_log_chunks, read_relations, read_scene};
use rand::{RngExt, SeedableRng, rngs::StdRng};
use std::ops::ControlFlow;
use std::path::{Path, PathBuf};

fn tmp_dir() -> PathBuf {
    let dir = std::env::temp_dir().join(format!("pcaline-fuzz-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn read_all(path: &Path, format: Option<LogFormat>) {
    let mut options = LogOptions::default();
    options.format = format;
    let mut whole = Vec::new();
    let read = read_log(path, &options, |r| {
        whole.push(format!("{r:?}"));
        ControlFlow::Continue(())
    });
    let whole_error = read.err().map(|e| e.to_string());
    let mut chunks = Vec::new();
    let read = read_log_chunks(path, &options, 3, |c| {
        chunks.push(c);
        ControlFlow::Continue(())
    });
    let mut in_chunks = Vec::new();
    let mut chunks_error = None;
    for chunk in chunks {
        let parsed = chunk.parse(|r| {
            in_chunks.push(format!("{r:?}"));
            ControlFlow::Continue(())
        });
        if let Err(e) = parsed {
            chunks_error = Some(e.to_string());
            break;
        }
    }
    if chunks_error.is_none() {
        chunks_error = read.err().map(|e| e.to_string());
    }
    assert_eq!((in_chunks, chunks_error), (whole, whole_error), "{}", path.display());
    // The odometry pass of `pcaline map` over the same file: a result or an
    // error, never a panic.
    if let Some(f) = format.or_else(|| LogFormat::detect(path).ok()) {
        let _ = pcaline_io::read_ros_motion(path, f, None);
    }
}

const FORMATS: [(&str, LogFormat); 6] = [
    ("clf", LogFormat::Carmen),
    ("bag", LogFormat::Ros1Bag),
    ("db3", LogFormat::Ros2Bag),
    ("mcap", LogFormat::Mcap),
    ("json", LogFormat::Json),
    ("csv", LogFormat::Csv),
];

#[test]
fn random_bytes_never_panic() {
    let dir = tmp_dir();
    let mut rng = StdRng::seed_from_u64(11);
    for round in 0..20 {
        let len = rng.random_range(0..4096);
        let mut bytes: Vec<u8> = (0..len).map(|_| rng.random()).collect();
        for (ext, format) in FORMATS {
            // Half the rounds start with the format's magic, to get past it.
            if round % 2 == 1 {
                let magic: &[u8] = match format {
                    LogFormat::Ros1Bag => b"#ROSBAG V2.0\n",
                    LogFormat::Mcap => b"\x89MCAP0\r\n",
                    LogFormat::Ros2Bag => b"SQLite format 3\0",
                    LogFormat::Json => b"[{\"ranges\": [1, 2",
                    LogFormat::Csv => b"stamp_s,angle_min\n1,2,3",
                    LogFormat::Carmen => b"FLASER 180 1 2 3",
                    // A format added later starts with nothing special.
                    _ => b"",
                };
                bytes.splice(0..0, magic.iter().copied());
            }
            let path = dir.join(format!("random-{round}.{ext}"));
            std::fs::write(&path, &bytes).unwrap();
            read_all(&path, Some(format));
            read_all(&path, None);
        }
        let path = dir.join(format!("random-{round}.toml"));
        std::fs::write(&path, &bytes).unwrap();
        let _ = read_scene(&path);
        let _ = read_relations(&path);
    }
}

#[test]
fn truncated_real_files_never_panic() {
    let root = std::env::var_os("PCALINE_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/data"));
    let files = [
        "intel/intel.gfs.log",
        "mit-csail/mit-csail.clf",
        "utm30lx-ros2/rosbag2_2024_02_21-16_20_44_0.db3",
        "ros1/laser_scan_matcher_demo.bag",
        "single-scans/laser_scan_1.json",
    ];
    let dir = tmp_dir();
    let ci = std::env::var("CI").is_ok_and(|v| v == "true");
    let (mut checked, mut skipped) = (0, 0);
    for rel in files {
        let Ok(bytes) = std::fs::read(root.join(rel)) else {
            // Missing data is a failure under CI, and a loud skip elsewhere.
            assert!(!ci, "missing dataset {} (CI=true)", root.join(rel).display());
            eprintln!("SKIPPED: {} not found (set PCALINE_DATA)", root.join(rel).display());
            skipped += 1;
            continue;
        };
        let ext = Path::new(rel).extension().unwrap().to_string_lossy().into_owned();
        for fraction in [0.0, 0.001, 0.1, 0.5, 0.9, 0.999] {
            let cut = (bytes.len() as f64 * fraction) as usize;
            let path = dir.join(format!("cut-{checked}.{ext}"));
            std::fs::write(&path, &bytes[..cut]).unwrap();
            read_all(&path, None);
            checked += 1;
        }
    }
    // Corrupted (not truncated) middles too.
    let mut rng = StdRng::seed_from_u64(5);
    for rel in files {
        let Ok(mut bytes) = std::fs::read(root.join(rel)) else { continue };
        let ext = Path::new(rel).extension().unwrap().to_string_lossy().into_owned();
        for _ in 0..50 {
            let k = rng.random_range(0..bytes.len());
            bytes[k] = rng.random();
        }
        let path = dir.join(format!("corrupt.{ext}"));
        std::fs::write(&path, &bytes).unwrap();
        read_all(&path, None);
    }
    // Six truncations of every file found, and only the missing skipped.
    assert_eq!(checked, 6 * (files.len() - skipped));
    eprintln!("{checked} truncated files read, {skipped} datasets skipped");
}
