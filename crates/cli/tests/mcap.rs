//! `--mcap` on `detect`, `map` and `run`: the file Foxglove opens, read back
//! with the `mcap` crate; an unwritable path; a log of over a million scans
//! streamed in constant memory.

mod common;

use common::{data, pcaline, s, small_maze, tmp};
use std::collections::BTreeMap;
use std::io::Write;
use std::path::Path;
use std::process::{Command, Stdio};

/// Messages per topic, from the file's summary, and one decoded message of
/// each topic.
fn read_back(path: &Path) -> (BTreeMap<String, u64>, BTreeMap<String, serde_json::Value>) {
    let bytes = std::fs::read(path).unwrap();
    let summary = mcap::Summary::read(&bytes).unwrap().expect("a summary section");
    let stats = summary.stats.expect("statistics");
    let counts = summary
        .channels
        .values()
        .map(|c| (c.topic.clone(), stats.channel_message_counts[&c.id]))
        .collect();
    let mut first = BTreeMap::new();
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        assert_eq!(m.channel.message_encoding, "json");
        let v: serde_json::Value = serde_json::from_slice(&m.data).unwrap();
        first.entry(m.channel.topic.clone()).or_insert(v);
    }
    (counts, first)
}

#[test]
fn run_writes_every_topic_with_the_simulation_clock() {
    let scene = small_maze("mcap-maze.toml", 5);
    let (out, file) = (tmp("mcap-run"), tmp("run.mcap"));
    let o = pcaline(&["--quiet", "run", s(&scene), "--out", s(&out), "--json", "--mcap", s(&file)]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let summary: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let scans = summary["scans"].as_u64().unwrap();
    assert!(summary["outputs"].as_array().unwrap().iter().any(|p| p == s(&file)));
    let (counts, first) = read_back(&file);
    for topic in ["/scan", "/lines", "/pose/source", "/pose/corrected", "/truth/pose"] {
        assert_eq!(counts[topic], scans, "{topic}");
    }
    assert_eq!(counts["/tf"], 3 * scans, "source, corrected and true frames");
    assert_eq!(counts["/truth/walls"], 1);
    let duration_s = summary["duration_s"].as_f64().unwrap();
    // At most one map a second of simulated time, and the final one.
    assert!(counts["/map"] >= 2 && counts["/map"] as f64 <= duration_s + 2.0, "{counts:?}");
    assert_eq!(first["/scan"]["frame_id"], "sensor");
    assert_eq!(first["/scan"]["timestamp"]["sec"], 0, "the simulation's clock starts at 0");
    assert_eq!(first["/truth/walls"]["entities"][0]["frame_id"], "world");
}

#[test]
fn detect_and_map_write_the_logs_own_timestamps() {
    let Some(log) = data("intel/intel.gfs.log") else { return };
    let file = tmp("intel-detect.mcap");
    let o =
        pcaline(&["--quiet", "detect", s(&log), "-o", s(&tmp("intel.json")), "--mcap", s(&file)]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (counts, first) = read_back(&file);
    let expected: BTreeMap<String, u64> =
        [("/scan", 910), ("/lines", 910), ("/tf", 910), ("/pose/source", 910)]
            .map(|(t, n)| (t.to_string(), n))
            .into();
    assert_eq!(counts, expected, "the 910 FLASER scans, each with the log's pose");
    assert_eq!(first["/tf"]["child_frame_id"], "sensor", "scans follow the log's pose");
    let lines = first["/lines"]["entities"].as_array().unwrap();
    assert!(!lines.is_empty());
    let keys: Vec<&str> = lines[0]["metadata"]
        .as_array()
        .unwrap()
        .iter()
        .map(|kv| kv["key"].as_str().unwrap())
        .collect();
    assert!(keys.contains(&"id") && keys.contains(&"n_points"), "{keys:?}");

    let (out, file) = (tmp("intel-map"), tmp("intel-map.mcap"));
    let o = pcaline(&["--quiet", "map", s(&log), "--out", s(&out), "--mcap", s(&file)]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stdout).lines().any(|l| l == s(&file)));
    let (counts, first) = read_back(&file);
    assert_eq!(counts["/scan"], 910);
    assert_eq!(counts["/pose/corrected"], 910);
    assert_eq!(counts["/tf"], 2 * 910, "source and corrected frames");
    assert!(counts["/map"] > 100, "the map as it grows: {counts:?}");
    let map = &first["/map"]["entities"];
    let statuses: Vec<&str> =
        map.as_array().unwrap().iter().map(|e| e["id"].as_str().unwrap()).collect();
    assert_eq!(statuses, ["map-confirmed", "map-tentative", "map-not-straight"]);
    // The log's own clock (seconds after its start), not a made-up one.
    let t = &first["/scan"]["timestamp"];
    let t0_s = t["sec"].as_f64().unwrap() + 1e-9 * t["nsec"].as_f64().unwrap();
    assert!(t0_s > 0.0, "{t}");
}

#[test]
fn an_unwritable_mcap_path_is_an_error_naming_it_with_nothing_left_behind() {
    let scene = small_maze("mcap-bad-maze.toml", 6);
    let dir = tmp("mcap-unwritable");
    std::fs::create_dir_all(&dir).unwrap();
    let target = dir.join("no-such-folder").join("x.mcap");
    let json = dir.join("lines.json");
    let o = pcaline(&["run", s(&scene), "--out", s(&dir.join("out")), "--mcap", s(&target)]);
    assert_eq!(o.status.code(), Some(2), "a missing folder is bad input");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains(s(&target)), "{err}");
    let scan = tmp("mcap-bad.json");
    std::fs::write(
        &scan,
        r#"{"angle_min": -0.5, "angle_increment": 0.01, "range_min": 0.1, "range_max": 30.0, "ranges": [2.0, 2.0, 2.0]}"#,
    )
    .unwrap();
    let o = pcaline(&["detect", s(&scan), "-o", s(&json), "--mcap", s(&target)]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains(s(&target)));
    assert!(!json.exists(), "no lines file either");
    let left: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert!(left.iter().all(|n| n == "out"), "nothing left behind: {left:?}");
}

/// Peak resident memory (VmHWM) of a running child, polled until it exits.
fn run_measuring_peak_kb(mut cmd: Command) -> (std::process::ExitStatus, u64, String) {
    let mut child = cmd.stdout(Stdio::null()).stderr(Stdio::piped()).spawn().unwrap();
    let status_path = format!("/proc/{}/status", child.id());
    let mut peak_kb = 0;
    let status = loop {
        if let Ok(text) = std::fs::read_to_string(&status_path)
            && let Some(kb) = text
                .lines()
                .find_map(|l| l.strip_prefix("VmHWM:"))
                .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
        {
            peak_kb = peak_kb.max(kb);
        }
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    };
    let mut stderr = String::new();
    std::io::Read::read_to_string(&mut child.stderr.take().unwrap(), &mut stderr).unwrap();
    (status, peak_kb, stderr)
}

#[test]
fn a_log_of_over_a_million_scans_streams_in_constant_memory() {
    const SCANS: usize = 1_000_001;
    // A generated CARMEN log: three beams on a wall 2 m ahead, the pose
    // moving along x.
    let log = tmp("million.clf");
    {
        let mut w = std::io::BufWriter::new(std::fs::File::create(&log).unwrap());
        for k in 0..SCANS {
            let (t, x) = (k as f64 * 0.025, k as f64 * 1e-3);
            writeln!(w, "FLASER 3 2.0 2.0 2.0 {x:.3} 0 0 {x:.3} 0 0 {t:.3} gen {t:.3}").unwrap();
        }
    }
    let file = tmp("million.mcap");
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_pcaline"));
    cmd.args(["detect", s(&log), "--fov", "2", "--mcap", s(&file)]);
    let (status, peak_kb, stderr) = run_measuring_peak_kb(cmd);
    assert!(status.success(), "{stderr}");
    assert!(stderr.contains(&format!("{SCANS} scans")), "{stderr}");
    // Holding a million scans, or their lines, would take hundreds of MB;
    // streamed, the process stays near its size for one scan.
    assert!(peak_kb > 0 && peak_kb < 64 * 1024, "peak {peak_kb} kB");
    let bytes = std::fs::read(&file).unwrap();
    let stats = mcap::Summary::read(&bytes).unwrap().unwrap().stats.unwrap();
    assert_eq!(stats.message_count, 4 * SCANS as u64, "scan, lines, /tf, pose per scan");
    std::fs::remove_file(&log).unwrap();
    std::fs::remove_file(&file).unwrap();
}

/// `pcaline map LOG --out OUT`, which must succeed; its stderr.
fn map_log(log: &Path, out: &Path) -> String {
    let o = pcaline(&["map", s(log), "--out", s(out)]);
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "{err}");
    err
}

/// A ROS log with `nav_msgs/Odometry` beside its scans: `map` takes the
/// odometry, interpolated at each scan's stamp, as the source (it ran
/// LIDAR-only before, whatever the log held), picks no topic when there are
/// several, and places the LIDAR on the vehicle by `/tf_static`.
#[test]
fn map_takes_a_ros_logs_odometry_as_the_source() {
    let scene_path = small_maze("odom-maze.toml", 7);
    let scene = pcaline_io::read_scene(&scene_path).unwrap();
    let sim = pcaline_sim::Simulator::new(&scene, 3).unwrap();
    let frames: Vec<_> = sim.frames().collect();
    let odometry = sim.odometry_poses();
    // Odometry halfway between scans (and at the first and last), so that
    // every scan's pose is interpolated.
    let mut odom: Vec<(f64, pcaline::Pose2)> = vec![(frames[0].time_s, odometry[0])];
    for k in 1..frames.len() {
        let t = 0.5 * (frames[k - 1].time_s + frames[k].time_s);
        odom.push((t, odometry[k - 1].lerp(&odometry[k], 0.5)));
    }
    let last = frames.len() - 1;
    odom.push((frames[last].time_s + 1e-3, odometry[last]));
    // With a mount, the odometry is the vehicle's (`base`), the LIDAR
    // (`laser`) sits at the mount, and `/tf_static` says so.
    // `odom_topics` "/tf": the odometry as `odom -> base` transforms.
    // `laser`: how the LIDAR sits on its mount: level, rolled by 180°
    // (its scans mirrored, and /tf_static saying so), or pitched.
    let write = |path: &Path, odom_topics: &[&str], mount: Option<pcaline::Pose2>, laser| {
        let file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
        let mut w = mcap::Writer::new(file).unwrap();
        let scan_schema = w.add_schema("sensor_msgs/msg/LaserScan", "ros2msg", b"").unwrap();
        let odom_schema = w.add_schema("nav_msgs/msg/Odometry", "ros2msg", b"").unwrap();
        let tf_schema = w.add_schema("tf2_msgs/msg/TFMessage", "ros2msg", b"").unwrap();
        let scans = w.add_channel(scan_schema, "/scan", "cdr", &BTreeMap::new()).unwrap();
        let odoms: Vec<(u16, bool)> = odom_topics
            .iter()
            .map(|t| {
                let schema = if *t == "/tf" { tf_schema } else { odom_schema };
                (w.add_channel(schema, t, "cdr", &BTreeMap::new()).unwrap(), *t == "/tf")
            })
            .collect();
        let mut messages: Vec<(f64, u16, Vec<u8>)> = Vec::new();
        let sensor_from_vehicle = mount.unwrap_or_default().inverse();
        if let Some(m) = mount {
            let tf = w.add_channel(tf_schema, "/tf_static", "cdr", &BTreeMap::new()).unwrap();
            let t = match laser {
                Laser::Level => pcaline_io::FrameTransform::planar("base", "laser", m, 0.0),
                Laser::UpsideDown => {
                    pcaline_io::FrameTransform::rolled_over("base", "laser", m, 0.0)
                }
                Laser::PitchedDeg(pitch) => {
                    // Rz(yaw) Ry(pitch) as a quaternion (x, y, z, w).
                    let ((sy, cy), (sp, cp)) =
                        ((0.5 * m.heading()).sin_cos(), (0.5 * pitch.to_radians()).sin_cos());
                    let q = [-sy * sp, cy * sp, sy * cp, cy * cp];
                    pcaline_io::FrameTransform::from_3d(
                        "base",
                        "laser",
                        [m.x(), m.y(), 0.2],
                        q,
                        0.0,
                    )
                    .unwrap()
                }
            };
            messages.push((0.0, tf, pcaline_io::encode_tf_cdr(&[t])));
        }
        for f in &frames {
            let mut scan = f.scan.clone();
            if laser == Laser::UpsideDown {
                scan.mirror();
            }
            messages.push((f.time_s, scans, pcaline_io::encode_laserscan_cdr(&scan, "laser")));
        }
        for (t, p) in &odom {
            let vehicle = p.compose(&sensor_from_vehicle);
            for (ch, tf) in &odoms {
                let data = if *tf {
                    pcaline_io::encode_tf_cdr(&[pcaline_io::FrameTransform::planar(
                        "odom", "base", vehicle, *t,
                    )])
                } else {
                    pcaline_io::encode_odometry_cdr(*t, &vehicle, "odom", "base")
                };
                messages.push((*t, *ch, data));
            }
        }
        messages.sort_by(|a, b| a.0.total_cmp(&b.0));
        for (k, (t, ch, data)) in messages.iter().enumerate() {
            let ns = (t * 1e9) as u64;
            let header = mcap::records::MessageHeader {
                channel_id: *ch,
                sequence: k as u32,
                log_time: ns,
                publish_time: ns,
            };
            w.write_to_known_channel(&header, data).unwrap();
        }
        w.finish().unwrap();
    };
    let log = tmp("odom.mcap");
    write(&log, &["/odom"], None, Laser::Level);
    let out = tmp("odom-map");
    let o = pcaline(&["map", s(&log), "--out", s(&out)]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("odometry from /odom"), "{err}");
    assert!(!err.contains("LIDAR-only"), "{err}");
    let v: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("trajectory.json")).unwrap()).unwrap();
    let pose = |p: &serde_json::Value| {
        pcaline::Pose2::new(p[0].as_f64().unwrap(), p[1].as_f64().unwrap(), p[2].as_f64().unwrap())
    };
    let records = v.as_array().unwrap();
    assert_eq!(records.len(), frames.len());
    // The source each scan got is its odometry pose (to the interpolation's
    // second order), and the aided trajectory follows the truth.
    let mut worst_source = 0.0f64;
    let aided: Vec<pcaline::Pose2> = records.iter().map(|r| pose(&r["aided"])).collect();
    for (r, o) in records.iter().zip(odometry) {
        let d = pose(&r["source"]).between(o);
        worst_source = worst_source.max(d.x().hypot(d.y()));
    }
    assert!(worst_source < 0.01, "source off the odometry by {worst_source} m");
    let e = pcaline_eval::trajectory_errors(&aided, sim.true_poses()).unwrap();
    // Measured: 0.10° / 4.3 mm (the generated maze's odometry is exact);
    // the same log run LIDAR-only (the two-topic run below): 5.8° / 1.84 m.
    assert!(
        e.heading_rms_rad.to_degrees() < 0.5 && e.position_rms_m < 0.05,
        "{:.3}° / {:.3} m",
        e.heading_rms_rad.to_degrees(),
        e.position_rms_m
    );
    // Two Odometry topics and none chosen: none used, and said; chosen: used.
    let two = tmp("odom2.mcap");
    write(&two, &["/odom", "/wheel_odom"], None, Laser::Level);
    let o = pcaline(&["map", s(&two), "--out", s(&tmp("odom2-map"))]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("several nav_msgs/Odometry topics (/odom, /wheel_odom)"), "{err}");
    assert!(err.contains("LIDAR-only"), "{err}");
    let o = pcaline(&["map", s(&two), "--odom-topic", "/wheel_odom", "--out", s(&tmp("odom3"))]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success() && err.contains("odometry from /wheel_odom"), "{err}");
    let o = pcaline(&["map", s(&two), "--odom-topic", "/nope", "--out", s(&tmp("odom4"))]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("--odom-topic /nope") && err.contains("/odom, /wheel_odom"), "{err}");
    // The vehicle's odometry, the LIDAR 30 cm ahead and turned 10°: the
    // mount from /tf_static, and the scans placed as before.
    let mount = pcaline::Pose2::new(0.3, -0.05, 10f64.to_radians());
    let offset = tmp("odom-offset.mcap");
    write(&offset, &["/odom"], Some(mount), Laser::Level);
    let out_offset = tmp("odom-offset-map");
    let err = map_log(&offset, &out_offset);
    assert!(err.contains("0.300 m forward, -0.050 m left and 10.00° turned"), "{err}");
    assert!(!err.contains("tilts"), "{err}");
    let v: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out_offset.join("trajectory.json")).unwrap())
            .unwrap();
    let mut worst = 0.0f64;
    for (r, a) in v.as_array().unwrap().iter().zip(&aided) {
        let d = a.between(&pose(&r["aided"]).compose(&mount));
        worst = worst.max(d.x().hypot(d.y()));
    }
    // Measured: within 0.08 mm of the run without the offset (the odometry
    // composed with the mount and back, rounded, moves the estimator's
    // inputs by a few ulps).
    assert!(worst < 1e-3, "the mounted run's LIDAR off the plain run's by {worst} m");
    // The same odometry kept in the transform tree instead (`/tf`, odom ->
    // base; no nav_msgs/Odometry, as many ROS bags have it): the same map.
    let in_tree = tmp("odom-tf.mcap");
    write(&in_tree, &["/tf"], Some(mount), Laser::Level);
    let out_tree = tmp("odom-tf-map");
    let err = map_log(&in_tree, &out_tree);
    assert!(err.contains("odometry from /tf (odom -> base)"), "{err}");
    assert!(err.contains("0.300 m forward, -0.050 m left and 10.00° turned"), "{err}");
    assert!(!err.contains("LIDAR-only"), "{err}");
    let trajectory = |dir: &Path| std::fs::read(dir.join("trajectory.json")).unwrap();
    assert!(trajectory(&out_tree) == trajectory(&out_offset), "/tf and Odometry differ");
    // The LIDAR mounted upside down, which mirrors its scans, and the
    // transform tree saying so: the scans are mirrored back, the same map.
    let flipped = tmp("odom-upside-down.mcap");
    write(&flipped, &["/odom"], Some(mount), Laser::UpsideDown);
    let out_flipped = tmp("odom-upside-down-map");
    let err = map_log(&flipped, &out_flipped);
    assert!(err.contains("upside down (its scans mirrored)"), "{err}");
    assert!(
        trajectory(&out_flipped) == trajectory(&out_offset),
        "the upside-down LIDAR's map differs"
    );
    assert!(!err.contains("tilts"), "{err}");
    // A LIDAR pitched 5° on its mount: its scans are taken as level, and
    // stderr says so.
    let pitched = tmp("odom-pitched.mcap");
    write(&pitched, &["/odom"], Some(mount), Laser::PitchedDeg(5.0));
    let err = map_log(&pitched, &tmp("odom-pitched-map"));
    assert!(err.contains("0.300 m forward, -0.050 m left and 10.00° turned"), "{err}");
    assert!(err.contains("tilts the scans' frame laser 5.0° out of the plane of base"), "{err}");
}

/// How the simulated LIDAR sits on its mount in the odometry test above.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Laser {
    Level,
    UpsideDown,
    PitchedDeg(f64),
}

/// Scans on two topics (two LIDARs, each on its own mount) are not one
/// LIDAR's motion: `map` asks which, naming them, and maps the one given.
#[test]
fn map_takes_one_lidars_scans() {
    let log = tmp("two-lidars.mcap");
    {
        let file = std::io::BufWriter::new(std::fs::File::create(&log).unwrap());
        let mut w = mcap::Writer::new(file).unwrap();
        let schema = w.add_schema("sensor_msgs/msg/LaserScan", "ros2msg", b"").unwrap();
        let front = w.add_channel(schema, "/front/scan", "cdr", &BTreeMap::new()).unwrap();
        let rear = w.add_channel(schema, "/rear/scan", "cdr", &BTreeMap::new()).unwrap();
        for k in 0..20u32 {
            let scan = pcaline::Scan::new(-1.5, 0.01, 0.1, 30.0, vec![2.0; 300])
                .with_stamp(f64::from(k) * 0.1);
            for (ch, frame) in [(front, "front_laser"), (rear, "rear_laser")] {
                let t = u64::from(k) * 100_000_000;
                let header = mcap::records::MessageHeader {
                    channel_id: ch,
                    sequence: k,
                    log_time: t,
                    publish_time: t,
                };
                let data = pcaline_io::encode_laserscan_cdr(&scan, frame);
                w.write_to_known_channel(&header, &data).unwrap();
            }
        }
        w.finish().unwrap();
    }
    let o = pcaline(&["map", s(&log), "--out", s(&tmp("two-lidars-map"))]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("several topics (/front/scan, /rear/scan)") && err.contains("--topic"),
        "{err}"
    );
    let out = tmp("front-map");
    let o = pcaline(&["map", s(&log), "--topic", "/front/scan", "--out", s(&out)]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("trajectory.json")).unwrap()).unwrap();
    assert_eq!(v.as_array().unwrap().len(), 20);
}
