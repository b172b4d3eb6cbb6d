//! `pcaline scene generate|check|draw`.

use crate::exit::BadInput;
use crate::out::outln;
use crate::svg::{Mark, Plot};
use anyhow::{Context, Result};
use clap::{Subcommand, ValueEnum};
use pcaline_io::{read_scene, write_scene};
use pcaline_sim::{MazeConfig, Scene, WallStyle, generate_maze};
use std::path::PathBuf;

/// Scene subcommands.
#[derive(Debug, Subcommand)]
pub enum SceneCommand {
    /// Write a random maze scene (TOML or JSON by extension).
    #[command(after_help = "Example:
  pcaline scene generate --seed 7 --cols 6 --rows 4 -o my-maze.toml")]
    Generate(GenerateArgs),
    /// Validate scene files; prints one line per file.
    #[command(after_help = "Example:
  pcaline scene check sim-scenes/*.toml")]
    Check {
        /// Scene files.
        #[arg(required = true)]
        files: Vec<PathBuf>,
    },
    /// Draw a scene and its trajectory as SVG.
    #[command(after_help = "Example:
  pcaline scene draw my-maze.toml -o my-maze.svg")]
    Draw {
        /// Scene file.
        file: PathBuf,
        /// Output picture: SVG, or PNG when the name ends in `.png`.
        #[arg(short, long)]
        output: PathBuf,
    },
}

/// Wall drawing of a generated maze.
#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum Walls {
    /// Thin panels, one segment each.
    Single,
    /// Walls with a thickness, drawn as rectangles.
    Double,
}

/// Arguments of `scene generate`.
#[derive(Debug, clap::Args)]
pub struct GenerateArgs {
    /// Random seed.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Scene name.
    #[arg(long, default_value = "maze")]
    name: String,
    /// Cells along x.
    #[arg(long, default_value_t = 5)]
    cols: usize,
    /// Cells along y.
    #[arg(long, default_value_t = 4)]
    rows: usize,
    /// Cell size in metres.
    #[arg(long, default_value_t = 2.5)]
    cell_m: f64,
    /// Wall style.
    #[arg(long, value_enum, default_value_t = Walls::Double)]
    walls: Walls,
    /// Wall thickness in metres (double walls).
    #[arg(long, default_value_t = 0.1)]
    thickness_m: f64,
    /// Doorway width in metres; 0 opens whole walls.
    #[arg(long, default_value_t = 1.0)]
    doorway_m: f64,
    /// Probability of extra openings (loops).
    #[arg(long, default_value_t = 0.1)]
    loops: f64,
    /// Probability that a cell joins its neighbours into a room.
    #[arg(long, default_value_t = 0.1)]
    rooms: f64,
    /// Number of clutter boxes.
    #[arg(long, default_value_t = 6)]
    clutter: usize,
    /// Driving speed, m/s.
    #[arg(long, default_value_t = 1.0)]
    speed: f64,
    /// Keep only the first N waypoints of the tour.
    #[arg(long)]
    max_waypoints: Option<usize>,
    /// Output file (.toml or .json).
    #[arg(short, long)]
    output: PathBuf,
}

/// Runs a scene subcommand.
pub fn run(cmd: &SceneCommand, quiet: bool) -> Result<()> {
    match cmd {
        SceneCommand::Generate(a) => {
            let mut config = MazeConfig::small(&a.name).with_grid(a.cols, a.rows);
            config.cell_m = a.cell_m;
            config.walls = match a.walls {
                Walls::Single => WallStyle::Single,
                Walls::Double => WallStyle::Double { thickness_m: a.thickness_m },
            };
            config.loop_probability = a.loops;
            config.room_probability = a.rooms;
            config.doorway_m = (a.doorway_m > 0.0).then_some(a.doorway_m);
            config.clutter = a.clutter;
            config.speed_m_s = a.speed;
            config.max_waypoints = a.max_waypoints;
            let scene = generate_maze(&config, a.seed).map_err(|e| BadInput(e.to_string()))?;
            write_scene(&a.output, &scene)?;
            if !quiet {
                eprintln!(
                    "wrote {} ({} wall segments, {} waypoints)",
                    a.output.display(),
                    scene.world_walls().len(),
                    scene.trajectory.waypoints.len()
                );
            }
            Ok(())
        }
        SceneCommand::Check { files } => {
            let mut failed = 0;
            for f in files {
                match read_scene(f) {
                    Ok(s) => outln!(
                        "ok    {}: \"{}\", {} wall segments, {} waypoints",
                        f.display(),
                        s.name,
                        s.world_walls().len(),
                        s.trajectory.waypoints.len()
                    )?,
                    Err(e) => {
                        outln!("error {e}")?;
                        failed += 1;
                    }
                }
            }
            if failed > 0 {
                return Err(BadInput(format!(
                    "{failed} of {} scene files are invalid",
                    files.len()
                ))
                .into());
            }
            Ok(())
        }
        SceneCommand::Draw { file, output } => {
            crate::picture::PictureFormat::of(output)?;
            let scene = read_scene(file)?;
            let svg = draw_scene(&scene, None).finish(&format!("Scene \"{}\"", scene.name));
            crate::picture::write_picture(output, &svg)
                .with_context(|| format!("writing {}", output.display()))?;
            Ok(())
        }
    }
}

/// A plot of a scene's walls, obstacles and trajectory, ready for more layers.
pub fn draw_scene(scene: &Scene, extra_bounds: Option<([f64; 2], [f64; 2])>) -> Plot {
    let (lo, hi) = scene.bounds();
    let (mut lo, mut hi) = ([lo.x, lo.y], [hi.x, hi.y]);
    if let Some((a, b)) = extra_bounds {
        lo = [lo[0].min(a[0]), lo[1].min(a[1])];
        hi = [hi[0].max(b[0]), hi[1].max(b[1])];
    }
    let mut plot = Plot::new(lo, hi, 1000.0);
    for w in scene.world_walls() {
        plot.line([w.a.x, w.a.y], [w.b.x, w.b.y], "#222", 2.0);
    }
    let t = &scene.trajectory;
    let mut path = vec![[t.start.x, t.start.y]];
    path.extend(t.waypoints.iter().copied());
    plot.polyline(&path, "#1f77b4", 1.5, true);
    plot.label([t.start.x, t.start.y], "start", "#1f77b4");
    plot.legend("walls and obstacles", "#222", Mark::Line(2.0));
    plot.legend("planned path", "#1f77b4", Mark::Dashed(1.5));
    plot
}
