//! File formats for pcaline: scene files (TOML/JSON) now; scans, logs, lines
//! and maps as they are added. Only this crate knows file formats. Every
//! error names the file and, where it can, the line or item; every output is
//! written atomically.
//!
//! ```no_run
//! use pcaline_io::read_scene;
//! let scene = read_scene(std::path::Path::new("sim-scenes/paper-maze.toml"))?;
//! println!("{} walls", scene.walls.len());
//! # Ok::<(), pcaline_io::IoError>(())
//! ```

mod atomic;
mod error;
mod scene_file;

pub use atomic::{write_atomic, write_atomic_with};
pub use error::IoError;
pub use scene_file::{parse_scene, read_scene, write_scene};
