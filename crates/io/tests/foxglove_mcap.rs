//! The Foxglove MCAP writer, read back with the `mcap` crate: schemas,
//! channels, message counts, one decoded message of each channel, and every
//! message validated against the Foxglove JSON Schema its channel names.

use pcaline_fitting::{Moments, fit_pca};
use pcaline_geometry::{LineSegment, Point2, Pose2, Scan};
use pcaline_io::{FoxgloveMcapWriter, PoseKind, Stamp, Topic, foxglove_schema};
use pcaline_mapping::{LineMap, MapConfig};
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::PathBuf;

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("pcaline-mcap-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn wall(a: [f64; 2], b: [f64; 2], n: usize) -> (LineSegment, Moments) {
    let pts: Vec<Point2<f64>> = (0..n)
        .map(|k| {
            let t = k as f64 / (n - 1) as f64;
            Point2::new(a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]))
        })
        .collect();
    (fit_pca(&pts).unwrap(), Moments::from_points(&pts))
}

/// Three scans with every topic, as `pcaline run` writes them.
fn write_sample(path: &std::path::Path) -> BTreeMap<&'static str, u64> {
    let mut map = LineMap::new(MapConfig::default()).unwrap();
    let (l0, m0) = wall([1.0, -1.0], [1.0, 1.0], 20);
    let (l1, _) = wall([0.0, 2.0], [2.0, 2.0], 15);
    map.insert(&l0, &m0);
    let mut w = FoxgloveMcapWriter::create(path).unwrap();
    w.write_walls(Stamp(0), &[[[0.0, 0.0], [3.0, 0.0]], [[3.0, 0.0], [3.0, 3.0]]]).unwrap();
    for k in 0..3u64 {
        let stamp = Stamp(1_000_000_000 + k * 25_000_000);
        let mut ranges = vec![2.0f32; 9];
        ranges[3] = f32::NAN;
        ranges[4] = f32::INFINITY;
        ranges[5] = 100.0; // beyond range_max
        let scan = Scan::new(-1.0, 0.25, 0.1, 30.0, ranges);
        w.write_scan(stamp, &scan).unwrap();
        w.write_lines(stamp, [&l0, &l1]).unwrap();
        let pose = Pose2::new(0.1 * k as f64, 0.0, 0.05 * k as f64);
        w.write_pose(stamp, PoseKind::Source, &pose).unwrap();
        w.write_pose(stamp, PoseKind::Corrected, &pose).unwrap();
        w.write_pose(stamp, PoseKind::Truth, &pose).unwrap();
        w.write_pose(stamp, PoseKind::Truth, &Pose2::new(f64::NAN, 0.0, 0.0)).unwrap();
        w.write_map(stamp, &map).unwrap();
    }
    w.finish().unwrap()
}

#[test]
fn file_reads_back_with_schemas_channels_and_counts() {
    let dir = temp_dir("readback");
    let path = dir.join("run.mcap");
    let counts = write_sample(&path);
    let expected: BTreeMap<&str, u64> = [
        ("/scan", 3),
        ("/lines", 3),
        ("/map", 3),
        ("/tf", 9),
        ("/pose/source", 3),
        ("/pose/corrected", 3),
        ("/truth/pose", 3),
        ("/truth/walls", 1),
    ]
    .into();
    assert_eq!(counts, expected, "the non-finite pose is not written");
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1, "no temporary file left");

    let bytes = std::fs::read(&path).unwrap();
    let summary = mcap::Summary::read(&bytes).unwrap().expect("a summary section");
    let stats = summary.stats.as_ref().unwrap();
    assert_eq!(stats.message_count, expected.values().sum::<u64>());
    assert_eq!(stats.channel_count as usize, expected.len());
    assert_eq!(stats.schema_count, 4, "one schema per Foxglove type");
    for channel in summary.channels.values() {
        let schema = channel.schema.as_ref().unwrap();
        assert_eq!(channel.message_encoding, "json");
        assert_eq!(schema.encoding, "jsonschema");
        let topic = Topic::ALL.iter().find(|t| t.name() == channel.topic).unwrap();
        assert_eq!(schema.name, topic.schema());
        assert_eq!(&*schema.data, foxglove_schema(&schema.name).unwrap().as_bytes());
        assert_eq!(stats.channel_message_counts[&channel.id], expected[channel.topic.as_str()]);
    }

    // One message of each channel, decoded.
    let mut first: BTreeMap<String, Value> = BTreeMap::new();
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        let v: Value = serde_json::from_slice(&m.data).unwrap();
        first.entry(m.channel.topic.clone()).or_insert(v);
    }
    let scan = &first["/scan"];
    assert_eq!(scan["frame_id"], "sensor");
    assert_eq!(scan["ranges"].as_array().unwrap().len(), 9);
    assert_eq!(scan["ranges"][0], 2.0);
    assert_eq!(scan["ranges"][3], 0.0, "NaN written as 0");
    assert_eq!(scan["ranges"][5], 0.0, "beyond range_max written as 0");
    assert!((scan["end_angle"].as_f64().unwrap() - 1.0).abs() < 1e-6);
    let lines = &first["/lines"];
    assert_eq!(lines["deletions"][0]["type"], 1, "the last scan's lines are deleted");
    let entities = lines["entities"].as_array().unwrap();
    assert_eq!(entities.len(), 2);
    let meta: BTreeMap<&str, &str> = entities[0]["metadata"]
        .as_array()
        .unwrap()
        .iter()
        .map(|kv| (kv["key"].as_str().unwrap(), kv["value"].as_str().unwrap()))
        .collect();
    assert_eq!(meta["id"], "0");
    assert_eq!(meta["n_points"], "20");
    let ends = &entities[0]["lines"][0]["points"];
    assert!((ends[0]["x"].as_f64().unwrap() - 1.0).abs() < 1e-9);
    let map = &first["/map"];
    assert_eq!(map["entities"][0]["frame_id"], "world");
    let tf = &first["/tf"];
    assert_eq!(tf["parent_frame_id"], "world");
    assert_eq!(tf["child_frame_id"], "source");
    assert_eq!(first["/pose/corrected"]["frame_id"], "world");
    assert_eq!(
        first["/truth/walls"]["entities"][0]["lines"][0]["points"].as_array().unwrap().len(),
        4
    );
    assert_eq!(first["/pose/source"]["timestamp"]["sec"], 1);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn every_message_is_valid_against_its_foxglove_schema() {
    let dir = temp_dir("schema");
    let path = dir.join("run.mcap");
    write_sample(&path);
    let bytes = std::fs::read(&path).unwrap();
    let mut checked = BTreeMap::new();
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        let schema_name = &m.channel.schema.as_ref().unwrap().name;
        let schema: Value = serde_json::from_str(foxglove_schema(schema_name).unwrap()).unwrap();
        let message: Value = serde_json::from_slice(&m.data).unwrap();
        if let Err(e) = validate(&schema, &message, "$") {
            panic!("{} ({schema_name}): {e}", m.channel.topic);
        }
        *checked.entry(schema_name.clone()).or_insert(0) += 1;
    }
    assert_eq!(checked.len(), 4, "{checked:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn the_validator_refuses_what_the_schemas_forbid() {
    let schema: Value =
        serde_json::from_str(foxglove_schema("foxglove.PoseInFrame").unwrap()).unwrap();
    let good: Value = serde_json::json!({
        "timestamp": {"sec": 1, "nsec": 2}, "frame_id": "world",
        "pose": {"position": {"x": 0, "y": 0, "z": 0}, "orientation": {"x": 0, "y": 0, "z": 0, "w": 1}}
    });
    validate(&schema, &good, "$").unwrap();
    let mut missing = good.clone();
    missing["pose"]["orientation"].as_object_mut().unwrap().remove("w");
    assert!(validate(&schema, &missing, "$").unwrap_err().contains("$.pose.orientation"));
    let mut negative = good.clone();
    negative["timestamp"]["sec"] = (-1).into();
    assert!(validate(&schema, &negative, "$").is_err());
    let mut too_many_nsec = good.clone();
    too_many_nsec["timestamp"]["nsec"] = 1_000_000_000.into();
    assert!(validate(&schema, &too_many_nsec, "$").is_err());
    let mut wrong_type = good;
    wrong_type["frame_id"] = 3.into();
    assert!(validate(&schema, &wrong_type, "$").is_err());
    let scene: Value =
        serde_json::from_str(foxglove_schema("foxglove.SceneUpdate").unwrap()).unwrap();
    let bad_deletion = serde_json::json!({"deletions": [{"timestamp": {"sec": 0, "nsec": 0}, "type": 7, "id": ""}], "entities": []});
    assert!(validate(&scene, &bad_deletion, "$").unwrap_err().contains("oneOf"));
}

/// The JSON Schema subset the Foxglove schemas use: `type`, `properties`,
/// `required`, `items`, `minimum`, `maximum`, `oneOf` of `const`s. Stricter
/// than JSON Schema, a field the schema does not name is an error, so a
/// misspelt field cannot pass.
fn validate(schema: &Value, v: &Value, at: &str) -> Result<(), String> {
    if let Some(t) = schema.get("type").and_then(Value::as_str) {
        let ok = match t {
            "object" => v.is_object(),
            "array" => v.is_array(),
            "string" => v.is_string(),
            "boolean" => v.is_boolean(),
            "number" => v.is_number(),
            "integer" => v.is_i64() || v.is_u64(),
            other => return Err(format!("{at}: schema type {other} not handled")),
        };
        if !ok {
            return Err(format!("{at}: expected {t}, found {v}"));
        }
    }
    if let Some(min) = schema.get("minimum").and_then(Value::as_f64)
        && v.as_f64().is_some_and(|x| x < min)
    {
        return Err(format!("{at}: {v} below the minimum {min}"));
    }
    if let Some(max) = schema.get("maximum").and_then(Value::as_f64)
        && v.as_f64().is_some_and(|x| x > max)
    {
        return Err(format!("{at}: {v} above the maximum {max}"));
    }
    if let Some(options) = schema.get("oneOf").and_then(Value::as_array)
        && !options.iter().any(|o| o.get("const") == Some(v))
    {
        return Err(format!("{at}: {v} is none of the oneOf constants"));
    }
    if let Some(required) = schema.get("required").and_then(Value::as_array) {
        for key in required.iter().filter_map(Value::as_str) {
            if v.get(key).is_none() {
                return Err(format!("{at}: missing required field {key}"));
            }
        }
    }
    if let (Some(props), Some(obj)) =
        (schema.get("properties").and_then(Value::as_object), v.as_object())
    {
        for (key, value) in obj {
            let sub = props.get(key).ok_or_else(|| format!("{at}: unknown field {key}"))?;
            validate(sub, value, &format!("{at}.{key}"))?;
        }
    }
    if let (Some(items), Some(arr)) = (schema.get("items"), v.as_array()) {
        for (k, item) in arr.iter().enumerate() {
            validate(items, item, &format!("{at}[{k}]"))?;
        }
    }
    Ok(())
}
