//! File formats for pcaline: scene files (TOML/JSON); logs of scans (CARMEN,
//! ROS 1 bags, ROS 2 sqlite3 bags, MCAP, JSON, CSV) read by [`read_log`],
//! streaming, or by [`read_log_chunks`] to parse on other threads; relation files; Foxglove MCAP output ([`FoxgloveMcapWriter`]). Only this crate knows file formats. Every error
//! names the file and, where it can, the line, message or item; every output
//! is written atomically.
//!
//! ```no_run
//! use pcaline_io::read_scene;
//! let scene = read_scene(std::path::Path::new("sim-scenes/paper-maze.toml"))?;
//! println!("{} walls", scene.walls.len());
//! # Ok::<(), pcaline_io::IoError>(())
//! ```

mod atomic;
mod carmen;
mod error;
mod foxglove_mcap;
mod laserscan_codec;
mod lines_file;
mod log;
mod log_chunks;
mod mount;
mod odometry_codec;
mod record;
mod relations;
mod ros;
mod ros_cursor;
mod scan_text;
mod scene_file;
mod tf_codec;
mod tf_odometry;

pub use atomic::{AtomicFile, OutputSet, remove_temporary_files, write_atomic, write_atomic_with};
pub use carmen::{CarmenOptions, CarmenReader, RawLaserScans, front_laser_params, has_posed_scans};
pub use error::IoError;
pub use foxglove_mcap::{
    FRAME_SENSOR, FRAME_WORLD, FoxgloveMcapWriter, PoseKind, Stamp, Topic, TopicCounts,
    foxglove_schema,
};
pub use laserscan_codec::{
    Echo, decode_laserscan_cdr, decode_laserscan_ros1, decode_multiecho_cdr, decode_multiecho_ros1,
    encode_laserscan_cdr, encode_multiecho_cdr,
};
pub use lines_file::{
    LineRecord, LinesFormat, LinesWriter, NoiseRecord, PoseSeries, ScanLines, json_bytes,
    lines_to_csv, lines_to_json, map_csv_text, map_json_bytes, read_map, read_pose_series,
    write_json, write_map_csv, write_map_json,
};
pub use log::{LogFormat, LogOptions, MAX_COORDINATE_M, check_record, check_scan_header, read_log};
pub use log_chunks::{LogChunk, read_log_chunks};
pub use mount::{
    MOUNT_AGREEMENT_M, MOUNT_AGREEMENT_RAD, MOUNT_MAX_M, MOUNT_MIN_PAIRS, MOUNT_TRIVIAL_M,
    MOUNT_TRIVIAL_RAD, PlanarMount, mount_from_pose_pairs, mount_from_transforms,
};
pub use odometry_codec::{
    OdometryMessage, decode_odometry_cdr, decode_odometry_ros1, encode_odometry_cdr,
};
pub use pcaline_geometry::Relation;
pub use record::{LogRecord, OdometryRecord, ScanRecord};
pub use relations::{ScanPair, read_relations, read_scan_pairs};
pub use ros::{
    DecompressedBag, OdometryTrack, RosMotion, keep_decompressed, read_mcap, read_ros_motion,
    read_ros1_bag, read_ros2_bag,
};
pub use scan_text::{ScanJson, read_scan_csv, read_scan_json, scans_to_csv};
pub use scene_file::{parse_scene, read_scene, write_scene};
pub use tf_codec::{FrameTransform, decode_tf_cdr, decode_tf_ros1, encode_tf_cdr};
pub use tf_odometry::{TfOdometry, odometry_from_transforms};
