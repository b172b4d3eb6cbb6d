//! `pcaline map LOG`: the line map and the aided trajectory of a log, with
//! the log's own odometry as the localization source.

use crate::exit::BadInput;
use crate::log_args::LogArgs;
use crate::mcap_out::McapOut;
use crate::out::outln;
use crate::picture::add_svg_and_png;
use crate::pipeline::for_each_scan;
use crate::progress;
use crate::svg::{Mark, Plot};
use anyhow::{Context, Result};
use clap::ValueEnum;
use pcaline::aiding::{AidingMode, EdgeKind, LoopOutcome, LoopSearch};
use pcaline::{Mapper, MapperConfig, Pose2};
use pcaline_io::{OutputSet, PoseKind, ScanRecord, json_bytes, map_csv_text, map_json_bytes};
use serde::Serialize;
use std::ops::ControlFlow;
use std::path::PathBuf;

/// Which aiding corrects the log's odometry.
#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum AidingArg {
    /// None: the map is built with the odometry as it is.
    None,
    /// Heading (the paper's eq. 11-14).
    Heading,
    /// Heading and translation, each scan's correction in full.
    Full,
    /// The estimator: odometry and line matches fused by their uncertainty.
    Estimator,
}

/// Arguments of `pcaline map`.
#[derive(Debug, clap::Args)]
#[command(after_help = "Examples:
  pcaline map intel.gfs.log --out out/intel --png       map, trajectory, graph, pictures
  pcaline map raw.clf --translation-noise-per-m 0.1     a noisier odometry
  pcaline map bag_dir --mcap out/run.mcap                also every scan for Foxglove
  pcaline map log.clf --aiding heading --no-loop-closure   the paper's aiding alone
  pcaline map robot.bag --mount 0.25,0,180              a LIDAR 25 cm ahead, mounted backwards")]
pub struct MapArgs {
    /// Log with scans (CARMEN, ROS 1 bag, ROS 2 bag or folder, MCAP, JSON, CSV).
    log: PathBuf,
    #[command(flatten)]
    input: LogArgs,
    /// Detector and map: a preset or a configuration file (as `pcaline detect`).
    #[arg(long, default_value = "default")]
    config: String,
    /// Aiding.
    #[arg(long, value_enum, default_value_t = AidingArg::Estimator)]
    aiding: AidingArg,
    /// The odometry's translation error per metre travelled (0.05 = 5%), for
    /// the estimator; overrides the configuration's
    /// `aiding.estimator.motion.translation_per_m`.
    #[arg(long, allow_negative_numbers = true)]
    translation_noise_per_m: Option<f64>,
    /// The odometry's heading error per metre travelled, degrees (the
    /// configuration's `aiding.estimator.motion.rotation_per_m`, in radians).
    #[arg(long, allow_negative_numbers = true)]
    rotation_noise_deg_per_m: Option<f64>,
    /// Do not close loops: keep the estimator's trajectory and map as they
    /// come (by default, keyframes, loop closure from lines and a pose graph
    /// undo the drift when the log returns to a mapped place).
    #[arg(long)]
    no_loop_closure: bool,
    /// Where the LIDAR sits on the vehicle whose poses the log gives:
    /// `X_M,Y_M,YAW_DEG` (forward, left, counter-clockwise). The trajectory
    /// is written for the vehicle; the map, the scans and Foxglove's poses
    /// are placed with the sensor's. Default: the configuration's
    /// `[vehicle_from_sensor]` when it is not the identity; else, for a log
    /// that stores both the laser's pose and the odometry pose with each
    /// scan (CARMEN), the offset between them when it is the same on the
    /// first 200 scans; for a ROS log with odometry, its `/tf_static` chain
    /// from the odometry's frame to the scans' (said on stderr); else the
    /// identity (the log's poses are the sensor's).
    #[arg(long, value_name = "X_M,Y_M,YAW_DEG", value_parser = parse_mount, allow_hyphen_values = true)]
    mount: Option<Pose2>,
    /// The `nav_msgs/Odometry` topic to use as the source (ROS 1, ROS 2 and
    /// MCAP logs). Default: the log's only Odometry topic; with several,
    /// none is guessed (LIDAR-only mode, and stderr lists them); with none,
    /// the first moving transform of `/tf` above the scans' frame (`odom ->
    /// base_link`). Each scan takes the pose interpolated at its stamp from
    /// the messages either side, within 1 s. The LIDAR's mount comes from
    /// the transform tree (the chain from the odometry's child frame to the
    /// scans' frame; an upside-down LIDAR's scans are mirrored) unless
    /// `--mount` or the configuration gives it.
    #[arg(long, value_name = "TOPIC")]
    odom_topic: Option<String>,
    /// Output folder.
    #[arg(long, default_value = "out/map")]
    out: PathBuf,
    /// Also write the picture as PNG.
    #[arg(long)]
    png: bool,
    /// Also write the log scan by scan to this MCAP file, for Foxglove:
    /// scans, lines, the map as it grows, the source and corrected poses
    /// (topics in the README).
    #[arg(long, value_name = "OUT.mcap")]
    mcap: Option<PathBuf>,
}

/// `X_M,Y_M,YAW_DEG` as `vehicle_from_sensor`.
fn parse_mount(text: &str) -> Result<Pose2, String> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    let values = parts.iter().map(|p| p.parse::<f64>()).collect::<Result<Vec<_>, _>>();
    match values.as_deref() {
        Ok([x, y, yaw_deg]) if [x, y, yaw_deg].iter().all(|v| v.is_finite()) => {
            Ok(Pose2::new(*x, *y, yaw_deg.to_radians()))
        }
        _ => Err(format!("{text:?}: expected three finite numbers X_M,Y_M,YAW_DEG")),
    }
}

#[derive(Debug, Serialize)]
struct PoseOut {
    scan: usize,
    stamp_s: Option<f64>,
    /// The source pose (odometry), x, y, heading; absent when the log has none.
    source: Option<[f64; 3]>,
    /// The corrected pose (of the vehicle, with `--mount`).
    aided: [f64; 3],
    matches: usize,
}

/// A LIDAR tilted by more than this out of the vehicle's plane is warned
/// of, radians (1°: ranges 0.015% long, 1.7 cm of height at 1 m).
const TILT_WARNING_RAD: f64 = 0.017_453;

/// Scans read to find a log's mount.
const MOUNT_SCANS: usize = 200;

/// The LIDAR's mount that the first [`MOUNT_SCANS`] scans of a log imply
/// when each stores both the laser's pose and the vehicle's odometry pose
/// (CARMEN), by [`pcaline_io::mount_from_pose_pairs`]; `None` for a log
/// without both poses, whose two poses are one or drift apart, or that
/// cannot be read (the mapping pass then reports the error).
fn mount_of_log(log: &std::path::Path, options: &pcaline_io::LogOptions) -> Option<Pose2> {
    // Only CARMEN records carry both poses: other logs are not read twice.
    let format = options.format.map_or_else(|| pcaline_io::LogFormat::detect(log), Ok).ok()?;
    if format != pcaline_io::LogFormat::Carmen {
        return None;
    }
    let mut pairs = Vec::new();
    let read = pcaline_io::read_log(log, options, |record| {
        if let pcaline_io::LogRecord::Scan(s) = record {
            let (Some(vehicle), Some(sensor)) = (s.odometry, s.pose) else {
                return ControlFlow::Break(());
            };
            pairs.push((vehicle, sensor));
        }
        if pairs.len() >= MOUNT_SCANS { ControlFlow::Break(()) } else { ControlFlow::Continue(()) }
    });
    read.ok().and_then(|_| pcaline_io::mount_from_pose_pairs(&pairs))
}

/// The odometry of a log that comes apart from its scans, as `map` takes
/// it: a ROS log's `nav_msgs/Odometry`, or the `ODOM` lines of a CARMEN log
/// whose scans carry no pose (`RAWLASER1`).
enum LogOdometry {
    /// None apart from the scans (a CARMEN log's posed scans, JSON, CSV, a
    /// ROS log without `nav_msgs/Odometry`).
    None,
    /// The topic used, its poses sorted by stamp, its vehicle frame, the
    /// scans' frame, and the LIDAR's mount the static transforms give.
    Track {
        topic: String,
        poses: Vec<pcaline_io::OdometryRecord>,
        vehicle: String,
        sensor: String,
        mount: Option<pcaline_io::PlanarMount>,
    },
    /// A CARMEN log's `ODOM` poses, sorted by stamp.
    CarmenOdom(Vec<pcaline_io::OdometryRecord>),
    /// Several topics and none chosen.
    Several(Vec<String>),
}

impl LogOdometry {
    /// The poses that the scans' stamps are interpolated in.
    fn poses(&self) -> Option<&[pcaline_io::OdometryRecord]> {
        match self {
            LogOdometry::Track { poses, .. } | LogOdometry::CarmenOdom(poses) => Some(poses),
            LogOdometry::None | LogOdometry::Several(_) => None,
        }
    }
}

/// The odometry of `log` that comes apart from its scans: see
/// [`LogOdometry`]. For a ROS log, [`ros_odometry`]; for a CARMEN log whose
/// scans are its `RAWLASER1` lines (`options` decided so), its `ODOM` lines.
fn log_odometry(
    log: &std::path::Path,
    options: &pcaline_io::LogOptions,
    chosen: Option<&str>,
) -> Result<LogOdometry> {
    let format = match options.format {
        Some(f) => f,
        None => pcaline_io::LogFormat::detect(log)?,
    };
    match format {
        pcaline_io::LogFormat::Carmen
            if options.carmen.raw_laser == pcaline_io::RawLaserScans::Always =>
        {
            let mut poses = Vec::new();
            pcaline_io::read_log(log, options, |record| {
                if let pcaline_io::LogRecord::Odometry(o) = record {
                    poses.push(o);
                }
                ControlFlow::Continue(())
            })?;
            if poses.is_empty() {
                return Ok(LogOdometry::None);
            }
            // Stable: messages of one stamp keep the log's order.
            poses.sort_by(|a, b| a.stamp_s.total_cmp(&b.stamp_s));
            Ok(LogOdometry::CarmenOdom(poses))
        }
        pcaline_io::LogFormat::Ros1Bag
        | pcaline_io::LogFormat::Ros2Bag
        | pcaline_io::LogFormat::Mcap => ros_odometry(log, format, options, chosen),
        _ => Ok(LogOdometry::None),
    }
}

/// The odometry of a ROS 1, ROS 2 or MCAP log: the `nav_msgs/Odometry`
/// topic `chosen`, else the only one, with the mount from its child frame
/// to the scans' frame through `/tf_static` (the identity when they are one
/// frame); without any, the odometry the transform tree holds (`/tf`,
/// [`pcaline_io::odometry_from_transforms`]). A chosen topic the log does
/// not have, or LaserScans on several topics when no `--topic` chose one,
/// is an error listing those it has.
fn ros_odometry(
    log: &std::path::Path,
    format: pcaline_io::LogFormat,
    options: &pcaline_io::LogOptions,
    chosen: Option<&str>,
) -> Result<LogOdometry> {
    let mut motion = pcaline_io::read_ros_motion(log, format, options.topic.as_deref())?;
    // Scans of several LIDARs, each on its own mount, are not one LIDAR's
    // motion: one is chosen, or none is guessed.
    if options.topic.is_none() && motion.scan_topics.len() > 1 {
        let topics: Vec<&str> = motion.scan_topics.iter().map(String::as_str).collect();
        return Err(BadInput(format!(
            "{}: LaserScans on several topics ({}): map takes one LIDAR's scans, give its \
             topic with --topic",
            log.display(),
            topics.join(", ")
        ))
        .into());
    }
    let tracks = &mut motion.odometry;
    let topic = match chosen {
        Some(t) if tracks.contains_key(t) => t.to_string(),
        Some(t) => {
            let have: Vec<&str> = tracks.keys().map(String::as_str).collect();
            return Err(BadInput(format!(
                "--odom-topic {t}: {} has no nav_msgs/Odometry on it (Odometry topics: {})",
                log.display(),
                if have.is_empty() { "none".to_string() } else { have.join(", ") }
            ))
            .into());
        }
        None if tracks.len() == 1 => tracks.keys().next().cloned().unwrap_or_default(),
        None if tracks.is_empty() => {
            // No Odometry topic: the transform tree may hold it (`/tf`).
            let sensor = motion.scan_frame.unwrap_or_default();
            let found = pcaline_io::odometry_from_transforms(
                &motion.static_transforms,
                &motion.transforms,
                &sensor,
            );
            return Ok(found.map_or(LogOdometry::None, |o| {
                let mut poses = o.records;
                poses.sort_by(|a, b| a.stamp_s.total_cmp(&b.stamp_s));
                LogOdometry::Track {
                    topic: format!("/tf ({} -> {})", o.parent, o.child),
                    poses,
                    vehicle: o.child,
                    sensor,
                    mount: Some(o.mount),
                }
            }));
        }
        None => return Ok(LogOdometry::Several(tracks.keys().cloned().collect())),
    };
    let track = tracks.remove(&topic).unwrap_or_default();
    let mut poses = track.records;
    poses.sort_by(|a, b| a.stamp_s.total_cmp(&b.stamp_s));
    let vehicle = track.child_frame_id;
    let sensor = motion.scan_frame.unwrap_or_default();
    let mount = pcaline_io::mount_from_transforms(&motion.static_transforms, &vehicle, &sensor);
    Ok(LogOdometry::Track { topic, poses, vehicle, sensor, mount })
}

/// Odometry messages farther apart than this do not bracket a scan, seconds.
const MAX_ODOMETRY_GAP_S: f64 = 1.0;

/// The odometry pose at `stamp_s`, interpolated between the messages either
/// side (`poses` sorted by stamp); `None` before the first, after the last,
/// or in a gap over [`MAX_ODOMETRY_GAP_S`]. A message at the stamp itself
/// is taken as it is.
fn odometry_at(poses: &[pcaline_io::OdometryRecord], stamp_s: f64) -> Option<Pose2> {
    let after = poses.partition_point(|o| o.stamp_s < stamp_s);
    let next = poses.get(after)?;
    if next.stamp_s == stamp_s {
        return Some(next.pose);
    }
    let before = poses.get(after.checked_sub(1)?)?;
    let gap = next.stamp_s - before.stamp_s;
    if !(gap > 0.0 && gap <= MAX_ODOMETRY_GAP_S) {
        return None;
    }
    Some(before.pose.lerp(&next.pose, (stamp_s - before.stamp_s) / gap))
}

/// Runs `pcaline map`.
pub fn run(args: &MapArgs, quiet: bool) -> Result<()> {
    if !args.log.exists() {
        return Err(BadInput(format!("{}: no such file or folder", args.log.display())).into());
    }
    let config = crate::config_file::resolve(&args.config, 0.01)?;
    let aiding_config = match args.aiding {
        AidingArg::None => config.aiding_in(AidingMode::None),
        AidingArg::Heading => config.aiding_in(AidingMode::Heading),
        AidingArg::Full => config.aiding_in(AidingMode::FullPose),
        AidingArg::Estimator => config.aiding_in(AidingMode::Estimator),
    };
    let mut aiding_config = aiding_config;
    if let Some(v) = args.translation_noise_per_m {
        aiding_config.estimator.motion.translation_per_m = v;
    }
    if let Some(v) = args.rotation_noise_deg_per_m {
        aiding_config.estimator.motion.rotation_per_m = v.to_radians();
    }
    aiding_config.validate().map_err(|e| {
        BadInput(format!("--translation-noise-per-m / --rotation-noise-deg-per-m: {e}"))
    })?;
    let _copies = args.input.keep_decompressed(&args.log);
    let sensor = args.input.sensor(&args.log, config.sensor)?;
    let mut options = args.input.options()?;
    // Whether a CARMEN log's scans are its RAWLASER1 lines, decided once for
    // every read below.
    if options.format.map_or_else(|| pcaline_io::LogFormat::detect(&args.log), Ok)?
        == pcaline_io::LogFormat::Carmen
    {
        options.carmen = options.carmen.decided_for(&args.log)?;
    }
    let odometry = log_odometry(&args.log, &options, args.odom_topic.as_deref())?;
    let log = args.log.display();
    // Where the LIDAR sits: as told, else as the log says (a CARMEN log's
    // two poses, a ROS log's static transforms), else at the vehicle's origin.
    let told = args.mount.or(Some(config.vehicle_from_sensor).filter(|m| *m != Pose2::identity()));
    // A LIDAR the transform tree tilts out of the vehicle's plane (other
    // than upside down) still has its scans projected as level: said.
    if let LogOdometry::Track { mount: Some(m), vehicle, sensor, .. } = &odometry
        && m.tilt_rad() > TILT_WARNING_RAD
        && !quiet
    {
        eprintln!(
            "{log}: warning: the transform tree tilts the scans' frame {sensor} {:.1}° out of \
             the plane of {vehicle}: its scans are taken as level, so the returns of beams \
             along the tilt land up to {:.1}% too far",
            m.tilt_rad().to_degrees(),
            100.0 * (1.0 / m.tilt_rad().cos() - 1.0)
        );
    }
    // An upside-down LIDAR (the transform tree says so) sees the plane
    // mirrored: its scans are mirrored before they are used.
    let mut mirrored = false;
    let mount = match (told, &odometry) {
        (Some(m), _) => m,
        (None, LogOdometry::Track { mount: Some(m), vehicle, sensor, .. }) => {
            let p = m.vehicle_from_sensor;
            if !quiet && (p != Pose2::identity() || m.mirrored) {
                eprintln!(
                    "{log}: the scans' frame {sensor} lies {:.3} m forward, {:.3} m left and \
                     {:.2}° turned from the odometry's {vehicle}{} (the transform tree): taken as \
                     the LIDAR's mount (--mount overrides)",
                    p.x(),
                    p.y(),
                    p.heading().to_degrees(),
                    if m.mirrored { ", upside down (its scans mirrored)" } else { "" }
                );
            }
            mirrored = m.mirrored;
            p
        }
        (None, LogOdometry::Track { mount: None, vehicle, sensor, .. }) => {
            if !quiet {
                eprintln!(
                    "{log}: no /tf_static chain from the odometry's {vehicle} to the scans' \
                     frame {sensor}: the LIDAR taken at {vehicle} unless --mount says where"
                );
            }
            Pose2::identity()
        }
        (None, _) => match mount_of_log(&args.log, &options) {
            Some(m) => {
                if !quiet {
                    eprintln!(
                        "{log}: each scan's laser pose lies {:.3} m forward, {:.3} m left and \
                         {:.2}° turned from its odometry pose: taken as the LIDAR's mount \
                         (--mount overrides)",
                        m.x(),
                        m.y(),
                        m.heading().to_degrees()
                    );
                }
                m
            }
            // Scans without a pose (RAWLASER1, the motion in ODOM lines):
            // the log's PARAM lines.
            None if matches!(odometry, LogOdometry::CarmenOdom(_)) => {
                match pcaline_io::front_laser_params(&args.log)? {
                    Some(m) => {
                        if !quiet {
                            eprintln!(
                                "{log}: its PARAM lines put the front laser {:.3} m forward, \
                                 {:.3} m left and {:.2}° turned on the robot: taken as the \
                                 LIDAR's mount (--mount overrides)",
                                m.x(),
                                m.y(),
                                m.heading().to_degrees()
                            );
                        }
                        m
                    }
                    None => Pose2::identity(),
                }
            }
            None => Pose2::identity(),
        },
    };
    let mut mapper = Mapper::new(
        MapperConfig::new(config.detector_for(sensor), config.map, aiding_config)
            .with_loop_closure((!args.no_loop_closure).then_some(config.loop_closure))
            .with_mount(mount),
    )?;
    if !quiet {
        match &odometry {
            LogOdometry::Track { topic, poses, .. } => {
                eprintln!("{log}: odometry from {topic} ({} messages) as the source", poses.len())
            }
            LogOdometry::CarmenOdom(poses) => eprintln!(
                "{log}: its scans carry no pose: the odometry of its {} ODOM lines, \
                 interpolated at each scan's stamp, is the source",
                poses.len()
            ),
            LogOdometry::Several(topics) => eprintln!(
                "{log}: several nav_msgs/Odometry topics ({}): give one with --odom-topic; none \
                 is used",
                topics.join(", ")
            ),
            LogOdometry::None => {}
        }
    }
    let bar = progress::spinner("scans", quiet);
    let mut poses: Vec<PoseOut> = Vec::new();
    let mut without_odometry = 0;
    let mut sharpness = pcaline_eval::OccupiedCells::new(0.05);
    let mut mcap = McapOut::create(args.mcap.as_deref())?;
    let mut failed: Option<anyhow::Error> = None;
    // The log is parsed on its own thread, ahead of the mapping. Detection
    // stays here: its deskew uses the velocity of the step before, which
    // the estimator gives in LIDAR-only mode.
    let no_work = |_: usize, batch: &[ScanRecord]| vec![(); batch.len()];
    for_each_scan(&args.log, &options, no_work, |mut s, ()| {
        if mirrored {
            s.scan.mirror();
        }
        // Deskewed with the velocity of the last step (the source's, or the
        // estimator's without one), when the scan has its beam timing (ROS
        // time_increment).
        let source =
            s.odometry.or(s.pose).or_else(|| odometry_at(odometry.poses()?, s.scan.stamp_s?));
        let step = match source {
            Some(p) => mapper.process(&s.scan, &p),
            None => {
                // No motion source: LIDAR-only mode, the last estimated
                // motion repeated as the prediction, the lines estimating it.
                without_odometry += 1;
                mapper.process_without_source(&s.scan)
            }
        };
        sharpness.add(&s.scan, &step.world_from_sensor);
        if let Some(m) = mcap.as_mut() {
            let stamp = m.stamp(s.scan.stamp_s);
            let source_sensor = source.map(|p| p.compose(&mount));
            let poses = [
                (PoseKind::Source, source_sensor),
                (PoseKind::Corrected, Some(step.world_from_sensor)),
            ];
            let lines = mapper.lines().iter().map(|l| &l.line);
            let written = m
                .scan(stamp, &s.scan, lines, &poses)
                .and_then(|()| m.map_if_due(stamp, mapper.map()));
            if let Err(e) = written {
                failed = Some(e);
                return ControlFlow::Break(());
            }
        }
        let pose = step.pose;
        poses.push(PoseOut {
            scan: poses.len(),
            stamp_s: s.scan.stamp_s,
            source: source.map(|p| [p.x(), p.y(), p.heading()]),
            aided: [pose.x(), pose.y(), pose.heading()],
            matches: step.report.matches,
        });
        bar.inc(1);
        ControlFlow::Continue(())
    })?;
    bar.finish_and_clear();
    if let Some(e) = failed {
        return Err(e);
    }
    if poses.is_empty() {
        return Err(BadInput(format!("{}: no scans", args.log.display())).into());
    }
    let graph = finish(&mut mapper, &mut poses);
    if let Some(m) = mcap.as_mut() {
        m.final_map(mapper.map())?;
    }
    // An output folder that cannot be made (a file in its path, no
    // permission) is the user's argument: exit 2, naming the folder.
    std::fs::create_dir_all(&args.out)
        .map_err(|e| pcaline_io::IoError::io(&args.out, e))
        .context("creating the output folder")?;
    // Written as a set: a failure part-way (a full disk) leaves none of them.
    let mut outputs = OutputSet::new();
    let path = args.out.join("map.json");
    outputs.add(&path, &map_json_bytes(&path, mapper.map())?)?;
    outputs.add(&args.out.join("map.csv"), map_csv_text(mapper.map()).as_bytes())?;
    let path = args.out.join("trajectory.json");
    outputs.add(&path, &json_bytes(&path, &poses)?)?;
    if let Some(g) = &graph {
        let path = args.out.join("graph.json");
        outputs.add(&path, &json_bytes(&path, g)?)?;
    }
    let svg = draw(mapper.map(), &poses, graph.as_ref(), &args.log.display().to_string());
    add_svg_and_png(&mut outputs, &args.out, "map", &svg, args.png)?;
    let written = outputs.commit()?;
    let mcap_path = mcap.map(|m| m.finish(quiet)).transpose()?;
    if !quiet {
        eprintln!(
            "{}: {} scans, {} map lines, {} occupied 5 cm cells (every return placed with the \
             online trajectory; fewer is sharper){}{}",
            args.log.display(),
            poses.len(),
            mapper.map().len(),
            sharpness.count(),
            graph.as_ref().map_or(String::new(), |g| format!(
                ", {} keyframes, {} loops accepted ({} found by place recognition; {} switched \
                 off by the optimizer, {} candidates refused by the consistency test)",
                g.nodes.len(),
                g.loops.iter().filter(|l| l.outcome == "accepted").count(),
                g.loops
                    .iter()
                    .filter(|l| l.outcome == "accepted" && l.search == "place_recognition")
                    .count(),
                g.loops.iter().filter(|l| l.outcome == "switched_off").count(),
                g.loops
                    .iter()
                    .filter(|l| l.outcome != "accepted" && l.outcome != "switched_off")
                    .count(),
            )),
            if without_odometry > 0 {
                format!(
                    ", {without_odometry} scans without odometry (LIDAR-only mode: \
                     constant-velocity prediction, motion from each scan's registration to the previous one \
                     and the line matches)"
                )
            } else {
                String::new()
            },
        );
        if let Some(c) = calibration_summary(mapper.localizer().aiding())
            .filter(|_| without_odometry < poses.len())
        {
            eprintln!("{}: {c}", args.log.display());
        }
    }
    for p in written.iter().chain(&mcap_path) {
        outln!("{}", p.display())?;
    }
    Ok(())
}

/// What the estimator learnt of the source's heading-rate bias, speed scale
/// error and latency, each with its standard deviation; `None` when it
/// estimated none (another aiding mode, or no calibration configured). The
/// bias and the latency need stamped scans, the scale travel past walls
/// across it: without them they stay at their priors, and the line says
/// so.
fn calibration_summary(aiding: &pcaline::aiding::Aiding) -> Option<String> {
    let config = aiding.config();
    let c = config.estimator.calibration.filter(|_| config.mode == AidingMode::Estimator)?;
    let cal = aiding.calibration();
    let mut parts = Vec::new();
    let learnt = |var: f64, prior: f64| var < 0.99 * prior * prior;
    if let Some(prior) = c.heading_rate_bias_std_rad_s {
        let tail = if learnt(cal.heading_rate_bias_var, prior) { "" } else { " (not learnt)" };
        parts.push(format!(
            "heading-rate bias {:.3} ± {:.3} °/s{tail}",
            rounded(cal.heading_rate_bias_rad_s.to_degrees(), 3),
            cal.heading_rate_bias_var.sqrt().to_degrees()
        ));
    }
    if let Some(prior) = c.speed_scale_std {
        let tail = if learnt(cal.speed_scale_var, prior) { "" } else { " (not learnt)" };
        parts.push(format!(
            "speed scale error {:.2} ± {:.2} %{tail}",
            rounded(100.0 * cal.speed_scale_error, 2),
            100.0 * cal.speed_scale_var.sqrt()
        ));
    }
    if let Some(prior) = c.latency_std_s {
        let tail = if learnt(cal.latency_var, prior) { "" } else { " (not learnt)" };
        parts.push(format!(
            "latency {:.0} ± {:.0} ms{tail}",
            rounded(1e3 * cal.latency_s, 0),
            1e3 * cal.latency_var.sqrt()
        ));
    }
    (!parts.is_empty()).then(|| format!("the source's calibration: {}", parts.join(", ")))
}

/// `x` rounded to `decimals`, with no negative zero.
fn rounded(x: f64, decimals: i32) -> f64 {
    let k = 10f64.powi(decimals);
    (x * k).round() / k + 0.0
}

/// With loop closure: a last optimization, the trajectory replaced by the
/// optimized one, and the graph to write.
fn finish(mapper: &mut Mapper, poses: &mut [PoseOut]) -> Option<GraphOut> {
    mapper.optimize()?;
    let trajectory = mapper.trajectory()?;
    let l = mapper.loop_closing()?;
    for (out, p) in poses.iter_mut().zip(trajectory) {
        if let Some(p) = p {
            out.aided = [p.x(), p.y(), p.heading()];
        }
    }
    let g = l.graph();
    Some(GraphOut {
        nodes: g
            .nodes
            .iter()
            .zip(l.keyframes())
            .map(|(n, k)| NodeOut {
                scan: k.scan,
                stamp_s: k.stamp_s,
                pose: [n.x(), n.y(), n.heading()],
            })
            .collect(),
        edges: g
            .edges
            .iter()
            .map(|e| EdgeOut {
                from: e.from,
                to: e.to,
                kind: match e.kind {
                    EdgeKind::Loop => "loop",
                    _ => "sequential",
                },
                active: e.active,
                from_from_to: [e.from_from_to.x(), e.from_from_to.y(), e.from_from_to.heading()],
                covariance: std::array::from_fn(|r| std::array::from_fn(|c| e.covariance[(r, c)])),
            })
            .collect(),
        loops: l
            .loops()
            .iter()
            .map(|r| LoopOut {
                keyframe: r.keyframe,
                candidate: r.candidate,
                edge: r.edge,
                outcome: match r.outcome {
                    LoopOutcome::Accepted => "accepted",
                    LoopOutcome::SwitchedOff => "switched_off",
                    LoopOutcome::TooLittleMatched => "too_little_matched",
                    LoopOutcome::Unconstrained => "unconstrained",
                    LoopOutcome::LargeResidual => "large_residual",
                    LoopOutcome::SeesThroughWalls => "sees_through_walls",
                    LoopOutcome::Ambiguous => "ambiguous",
                    LoopOutcome::LookAlikePlace => "look_alike_place",
                    LoopOutcome::Unconfirmed => "unconfirmed",
                    _ => "other",
                },
                candidate_from_current: [
                    r.candidate_from_current.x(),
                    r.candidate_from_current.y(),
                    r.candidate_from_current.heading(),
                ],
                matched_length_m: r.matched_length_m,
                weakest_direction_m: r.weakest_direction_m,
                runner_up_length_m: r.runner_up_length_m,
                rms_m: r.rms_m,
                see_through: r.see_through,
                other_place_length_m: r.other_place_length_m,
                search: match r.search {
                    LoopSearch::Local => "local",
                    LoopSearch::PlaceRecognition => "place_recognition",
                    _ => "other",
                },
                weak_prior: r.weak_prior,
                confirmed_with: r.confirmed_with,
            })
            .collect(),
        optimizations: l.optimizations(),
        last_optimization_kept: l
            .last_optimization()
            .and_then(|r| r.kept)
            .map(|k| format!("{k:?}")),
    })
}

/// `graph.json`: the pose graph after the last optimization.
#[derive(Debug, Serialize)]
struct GraphOut {
    /// One per keyframe: its scan, stamp and optimized pose (x, y, heading).
    nodes: Vec<NodeOut>,
    edges: Vec<EdgeOut>,
    /// Every aligned loop candidate, accepted or not, and why.
    loops: Vec<LoopOut>,
    optimizations: usize,
    /// Why the last optimization kept the poses, if it did.
    last_optimization_kept: Option<String>,
}

#[derive(Debug, Serialize)]
struct NodeOut {
    scan: usize,
    stamp_s: Option<f64>,
    pose: [f64; 3],
}

#[derive(Debug, Serialize)]
struct EdgeOut {
    from: usize,
    to: usize,
    kind: &'static str,
    active: bool,
    from_from_to: [f64; 3],
    covariance: [[f64; 3]; 3],
}

#[derive(Debug, Serialize)]
struct LoopOut {
    keyframe: usize,
    candidate: usize,
    edge: Option<usize>,
    outcome: &'static str,
    candidate_from_current: [f64; 3],
    matched_length_m: f64,
    weakest_direction_m: f64,
    /// Wall matched by the best alignment at least 0.5 m or 5° away from
    /// this one (repeated structure scores close to `matched_length_m`).
    runner_up_length_m: f64,
    rms_m: f64,
    see_through: f64,
    /// Wall matched by the best alignment with another place nearby
    /// (`loop_closure.place_search_scale`), or by another verified
    /// candidate (`loop_closure.place_recognition`): a look-alike place.
    other_place_length_m: f64,
    /// How the candidate was found: `local` (within the search radius) or
    /// `place_recognition` (beyond it, by the likeness of the line sets).
    search: &'static str,
    /// The prior did not vouch for the place (place recognition, or an
    /// uncertainty beyond the search radius): confirmed only with a loop
    /// from independent lines (`loop_closure.independent_confirm_keyframes`).
    weak_prior: bool,
    /// The other loop of the confirming pair (an index into `loops`).
    confirmed_with: Option<usize>,
}

fn draw(
    map: &pcaline::mapping::LineMap,
    poses: &[PoseOut],
    graph: Option<&GraphOut>,
    name: &str,
) -> String {
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    let mut grow = |p: [f64; 2]| {
        if p[0].is_finite() && p[1].is_finite() {
            lo = [lo[0].min(p[0]), lo[1].min(p[1])];
            hi = [hi[0].max(p[0]), hi[1].max(p[1])];
        }
    };
    for m in map.lines() {
        grow([m.line.start().x, m.line.start().y]);
        grow([m.line.end().x, m.line.end().y]);
    }
    for p in poses {
        grow([p.aided[0], p.aided[1]]);
        if let Some(s) = p.source {
            grow([s[0], s[1]]);
        }
    }
    let mut plot = Plot::new(lo, hi, 1000.0);
    for m in map.lines() {
        let l = &m.line;
        plot.line([l.start().x, l.start().y], [l.end().x, l.end().y], "#d62728", 1.5);
    }
    let source: Vec<[f64; 2]> =
        poses.iter().filter_map(|p| p.source.map(|s| [s[0], s[1]])).collect();
    let aided: Vec<[f64; 2]> = poses.iter().map(|p| [p.aided[0], p.aided[1]]).collect();
    plot.polyline(&source, "#1f77b4", 1.0, true);
    plot.polyline(&aided, "#9467bd", 1.5, false);
    plot.legend("line map", "#d62728", Mark::Line(1.5));
    plot.legend("log odometry", "#1f77b4", Mark::Dashed(1.0));
    plot.legend("aided trajectory", "#9467bd", Mark::Line(1.5));
    if let Some(g) = graph {
        for e in g.edges.iter().filter(|e| e.kind == "loop") {
            let (a, b) = (g.nodes[e.from].pose, g.nodes[e.to].pose);
            let colour = if e.active { "#2ca02c" } else { "#7f7f7f" };
            plot.line([a[0], a[1]], [b[0], b[1]], colour, 2.0);
        }
        plot.legend("loop closure (grey: switched off)", "#2ca02c", Mark::Line(2.0));
    }
    plot.finish(&format!("{name}: line map and trajectory"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use pcaline_io::OdometryRecord;

    #[test]
    fn odometry_is_interpolated_between_the_messages_either_side() {
        let at = |t: f64, x: f64, h: f64| OdometryRecord {
            pose: Pose2::new(x, 0.0, h),
            stamp_s: t,
            position: 0,
        };
        let poses = [at(1.0, 0.0, 3.0), at(1.5, 1.0, -3.0), at(3.0, 2.0, 0.0)];
        let p = odometry_at(&poses, 1.25).unwrap();
        assert!((p.x() - 0.5).abs() < 1e-12);
        // 3 rad to -3 rad the short way: through pi.
        assert!((p.heading().abs() - std::f64::consts::PI).abs() < 1e-9, "{p:?}");
        assert_eq!(odometry_at(&poses, 1.5).unwrap(), poses[1].pose);
        assert_eq!(odometry_at(&poses, 1.0).unwrap(), poses[0].pose);
        // Before the first, after the last, across a 1.5 s gap: none.
        assert!(odometry_at(&poses, 0.9).is_none());
        assert!(odometry_at(&poses, 3.1).is_none());
        assert!(odometry_at(&poses, 2.0).is_none());
        assert!(odometry_at(&[], 1.0).is_none());
        assert!(odometry_at(&poses, f64::NAN).is_none());
    }
}
