//! [`generate_maze`]: seeded random mazes on a grid, with rooms, doorways,
//! clutter and a trajectory that visits every cell, as a [`Scene`].

use crate::rng::{Stream, stream_rng};
use crate::{OdometrySpec, Scene, SensorSpec, Shape, StartPose, TrajectorySpec};
use pcaline_geometry::ConfigError;
use rand::RngExt;

/// How walls are drawn.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum WallStyle {
    /// Each wall is one segment (a thin panel seen from both sides).
    Single,
    /// Each wall is a closed rectangle of this thickness, metres.
    Double {
        /// Wall thickness, metres.
        thickness_m: f64,
    },
}

/// Parameters of a generated maze.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct MazeConfig {
    /// Scene name.
    pub name: String,
    /// Cells along x.
    pub cols: usize,
    /// Cells along y.
    pub rows: usize,
    /// Cell size, metres.
    pub cell_m: f64,
    /// Wall drawing.
    pub walls: WallStyle,
    /// Probability that a wall left by the spanning tree is opened anyway
    /// (makes loops).
    pub loop_probability: f64,
    /// Probability that a cell is joined with its right and upper neighbours
    /// (makes rooms).
    pub room_probability: f64,
    /// Width of the doorway in an opened wall; `None` opens the whole wall.
    pub doorway_m: Option<f64>,
    /// Number of clutter boxes placed off the path.
    pub clutter: usize,
    /// Driving speed, m/s.
    pub speed_m_s: f64,
    /// Stop the tour after this many waypoints (`None`: visit every cell).
    pub max_waypoints: Option<usize>,
}

impl MazeConfig {
    /// A small maze: 5 x 4 cells of 2.5 m, double walls 10 cm thick, 1 m doors.
    pub fn small(name: &str) -> Self {
        MazeConfig {
            name: name.into(),
            cols: 5,
            rows: 4,
            cell_m: 2.5,
            walls: WallStyle::Double { thickness_m: 0.1 },
            loop_probability: 0.1,
            room_probability: 0.1,
            doorway_m: Some(1.0),
            clutter: 6,
            speed_m_s: 1.0,
            max_waypoints: None,
        }
    }

    /// The same maze with `cols` x `rows` cells.
    pub fn with_grid(self, cols: usize, rows: usize) -> Self {
        MazeConfig { cols, rows, ..self }
    }

    /// The same maze with the tour stopped after `waypoints` waypoints.
    pub fn with_max_waypoints(self, waypoints: usize) -> Self {
        MazeConfig { max_waypoints: Some(waypoints), ..self }
    }

    fn validate(&self) -> Result<(), ConfigError> {
        ConfigError::check(self.cols >= 1, "maze.cols", self.cols as f64, "must be >= 1")?;
        ConfigError::check(self.rows >= 1, "maze.rows", self.rows as f64, "must be >= 1")?;
        ConfigError::check(
            self.cols * self.rows <= 1_000_000,
            "maze.cells",
            (self.cols * self.rows) as f64,
            "must be <= 1e6",
        )?;
        ConfigError::check(
            self.cell_m > 0.5 && self.cell_m.is_finite(),
            "maze.cell_m",
            self.cell_m,
            "must be finite and > 0.5",
        )?;
        if let WallStyle::Double { thickness_m } = self.walls {
            ConfigError::check(
                thickness_m > 0.0 && thickness_m < 0.25 * self.cell_m,
                "maze.thickness_m",
                thickness_m,
                "must be > 0 and below a quarter of the cell",
            )?;
        }
        if let Some(w) = self.doorway_m {
            ConfigError::check(
                w > 0.3 && w < self.cell_m - 0.2,
                "maze.doorway_m",
                w,
                "must be > 0.3 and at least 0.2 below the cell size",
            )?;
        }
        for (field, p) in [
            ("maze.loop_probability", self.loop_probability),
            ("maze.room_probability", self.room_probability),
        ] {
            ConfigError::unit_interval(field, p)?;
        }
        ConfigError::positive("maze.speed_m_s", self.speed_m_s)
    }
}

/// A random maze scene: a spanning tree of the grid (depth-first), extra
/// loops and rooms, walls merged into maximal straight runs, clutter boxes
/// away from the path, and a trajectory touring the tree through cell centres
/// and doorways. The same config and seed give the same scene.
pub fn generate_maze(config: &MazeConfig, seed: u64) -> Result<Scene, ConfigError> {
    config.validate()?;
    let mut rng = stream_rng(seed, Stream::Maze, 0);
    // The random draws happen in this order: the tree, the loops and rooms,
    // the clutter (the same seed keeps giving the same maze).
    let mut grid = Openings::spanning_tree(config.cols, config.rows, &mut rng);
    grid.open_loops_and_rooms(config, &mut rng);
    let walls = grid.wall_shapes(config);
    let obstacles = clutter(config, &mut rng);
    let waypoints = grid.tour(config);
    let (cols, rows, cell) = (config.cols, config.rows, config.cell_m);
    let start = grid.centre(0, cell);
    Ok(Scene {
        name: config.name.clone(),
        description: format!(
            "Generated maze: {cols} x {rows} cells of {cell} m, seed {seed}, {} walls, {} boxes",
            walls.len(),
            obstacles.len()
        ),
        sensor: SensorSpec::default(),
        walls,
        obstacles,
        trajectory: TrajectorySpec {
            start: StartPose { x: start[0], y: start[1], heading_deg: 0.0 },
            waypoints,
            speed_m_s: config.speed_m_s,
            yaw_rate_deg_s: 90.0,
            laps: 1,
            scan_rate_hz: None,
        },
        odometry: OdometrySpec::default(),
    })
}

/// Which walls of the cell grid are open, and the spanning tree's edges.
struct Openings {
    cols: usize,
    rows: usize,
    /// `open_right[i]`: the wall between cell `i` and its +x neighbour is open.
    open_right: Vec<bool>,
    /// `open_up[i]`: the wall between cell `i` and its +y neighbour is open.
    open_up: Vec<bool>,
    /// Each cell's neighbours in the spanning tree.
    tree: Vec<Vec<usize>>,
}

impl Openings {
    fn idx(&self, c: usize, r: usize) -> usize {
        r * self.cols + c
    }

    /// A depth-first spanning tree of the grid, its edges opened.
    fn spanning_tree(cols: usize, rows: usize, rng: &mut impl RngExt) -> Self {
        let mut g = Openings {
            cols,
            rows,
            open_right: vec![false; cols * rows],
            open_up: vec![false; cols * rows],
            tree: vec![Vec::new(); cols * rows],
        };
        let mut visited = vec![false; cols * rows];
        let mut stack = vec![0usize];
        visited[0] = true;
        while let Some(&cur) = stack.last() {
            let (c, r) = (cur % cols, cur / cols);
            let mut next = Vec::with_capacity(4);
            if c + 1 < cols && !visited[g.idx(c + 1, r)] {
                next.push(g.idx(c + 1, r));
            }
            if c > 0 && !visited[g.idx(c - 1, r)] {
                next.push(g.idx(c - 1, r));
            }
            if r + 1 < rows && !visited[g.idx(c, r + 1)] {
                next.push(g.idx(c, r + 1));
            }
            if r > 0 && !visited[g.idx(c, r - 1)] {
                next.push(g.idx(c, r - 1));
            }
            if next.is_empty() {
                stack.pop();
                continue;
            }
            let n = next[rng.random_range(0..next.len())];
            open_between(cur, n, cols, &mut g.open_right, &mut g.open_up);
            g.tree[cur].push(n);
            g.tree[n].push(cur);
            visited[n] = true;
            stack.push(n);
        }
        g
    }

    /// Opens extra walls: whole rooms, and loops.
    fn open_loops_and_rooms(&mut self, config: &MazeConfig, rng: &mut impl RngExt) {
        for r in 0..self.rows {
            for c in 0..self.cols {
                let i = self.idx(c, r);
                let room = rng.random_bool(config.room_probability);
                if c + 1 < self.cols && (room || rng.random_bool(config.loop_probability)) {
                    self.open_right[i] = true;
                }
                if r + 1 < self.rows && (room || rng.random_bool(config.loop_probability)) {
                    self.open_up[i] = true;
                }
            }
        }
    }

    /// The closed walls as maximal runs along each grid line, with doorway
    /// gaps, drawn in the configured style.
    fn wall_shapes(&self, config: &MazeConfig) -> Vec<Shape> {
        let (cols, rows, cell) = (self.cols, self.rows, config.cell_m);
        let mut runs: Vec<([f64; 2], [f64; 2])> = Vec::new();
        let door = config.doorway_m;
        // Vertical grid lines x = k * cell.
        for k in 0..=cols {
            let solid = |r: usize| k == 0 || k == cols || !self.open_right[self.idx(k - 1, r)];
            line_runs(rows, cell, door, solid, |a, b| {
                runs.push(([k as f64 * cell, a], [k as f64 * cell, b]))
            });
        }
        for k in 0..=rows {
            let solid = |c: usize| k == 0 || k == rows || !self.open_up[self.idx(c, k - 1)];
            line_runs(cols, cell, door, solid, |a, b| {
                runs.push(([a, k as f64 * cell], [b, k as f64 * cell]))
            });
        }
        runs.iter()
            .enumerate()
            .map(|(i, (a, b))| {
                let name = format!("wall-{i}");
                match config.walls {
                    WallStyle::Single => Shape { name, points: vec![*a, *b], closed: false },
                    WallStyle::Double { thickness_m } => {
                        let h = thickness_m / 2.0;
                        let (x0, x1) = (a[0].min(b[0]) - h, a[0].max(b[0]) + h);
                        let (y0, y1) = (a[1].min(b[1]) - h, a[1].max(b[1]) + h);
                        Shape {
                            name,
                            points: vec![[x0, y0], [x1, y0], [x1, y1], [x0, y1]],
                            closed: true,
                        }
                    }
                }
            })
            .collect()
    }

    /// The centre of cell `i`.
    fn centre(&self, i: usize, cell: f64) -> [f64; 2] {
        [((i % self.cols) as f64 + 0.5) * cell, ((i / self.cols) as f64 + 0.5) * cell]
    }

    /// Waypoints of an Euler tour of the spanning tree through cell
    /// centres, the middle of three collinear ones dropped, truncated to
    /// the configured count.
    fn tour(&self, config: &MazeConfig) -> Vec<[f64; 2]> {
        let mut tour = vec![0usize];
        let mut seen = vec![false; self.cols * self.rows];
        seen[0] = true;
        let mut path_stack: Vec<(usize, usize)> = vec![(0, 0)];
        while let Some((cur, child)) = path_stack.pop() {
            if child < self.tree[cur].len() {
                path_stack.push((cur, child + 1));
                let n = self.tree[cur][child];
                if !seen[n] {
                    seen[n] = true;
                    tour.push(n);
                    path_stack.push((n, 0));
                }
            } else if let Some(&(parent, _)) = path_stack.last() {
                tour.push(parent);
            }
        }
        let mut waypoints: Vec<[f64; 2]> = Vec::new();
        for &i in tour.iter().skip(1) {
            let p = self.centre(i, config.cell_m);
            if waypoints.len() >= 2 {
                let (a, b) = (waypoints[waypoints.len() - 2], waypoints[waypoints.len() - 1]);
                let cross = (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]);
                let forward = (b[0] - a[0]) * (p[0] - b[0]) + (b[1] - a[1]) * (p[1] - b[1]);
                if cross.abs() < 1e-9 && forward > 0.0 {
                    waypoints.pop();
                }
            }
            waypoints.push(p);
        }
        if let Some(max) = config.max_waypoints {
            waypoints.truncate(max);
        }
        waypoints
    }
}

/// Clutter: boxes in a quadrant of random cells, clear of walls and of the
/// centre lines the path uses.
fn clutter(config: &MazeConfig, rng: &mut impl RngExt) -> Vec<Shape> {
    let (cols, rows, cell) = (config.cols, config.rows, config.cell_m);
    let half_t = match config.walls {
        WallStyle::Double { thickness_m } => thickness_m / 2.0,
        _ => 0.0,
    };
    let mut obstacles = Vec::new();
    for n in 0..config.clutter {
        let size = rng.random_range(0.2..0.5);
        let lo = half_t + 0.15;
        let hi = cell / 2.0 - 0.3 - size;
        let c = rng.random_range(0..cols);
        let r = rng.random_range(0..rows);
        let (qx, qy) = (rng.random_bool(0.5), rng.random_bool(0.5));
        let (u, v) = (rng.random_range(0.0..1.0), rng.random_range(0.0..1.0));
        if hi <= lo {
            continue;
        }
        let ox = lo + u * (hi - lo);
        let oy = lo + v * (hi - lo);
        let x0 = c as f64 * cell + if qx { ox } else { cell - ox - size };
        let y0 = r as f64 * cell + if qy { oy } else { cell - oy - size };
        obstacles.push(Shape {
            name: format!("box-{n}"),
            points: vec![[x0, y0], [x0 + size, y0], [x0 + size, y0 + size], [x0, y0 + size]],
            closed: true,
        });
    }
    obstacles
}

fn open_between(a: usize, b: usize, cols: usize, right: &mut [bool], up: &mut [bool]) {
    let (lo, hi) = (a.min(b), a.max(b));
    if hi - lo == 1 && lo / cols == hi / cols {
        right[lo] = true;
    } else {
        up[lo] = true;
    }
}

/// Emits the solid runs along one grid line of `units` cells: consecutive
/// solid units join; an open unit with a doorway leaves wall on both sides of
/// a centred gap.
fn line_runs(
    units: usize,
    cell: f64,
    door: Option<f64>,
    solid: impl Fn(usize) -> bool,
    mut emit: impl FnMut(f64, f64),
) {
    let mut start: Option<f64> = None;
    for u in 0..units {
        let (a, b) = (u as f64 * cell, (u + 1) as f64 * cell);
        if solid(u) {
            start.get_or_insert(a);
            continue;
        }
        match door {
            Some(w) => {
                let gap_a = (a + b - w) / 2.0;
                emit(start.take().unwrap_or(a), gap_a);
                start = Some(gap_a + w);
            }
            None => {
                if let Some(s) = start.take() {
                    emit(s, a);
                }
            }
        }
    }
    if let Some(s) = start {
        emit(s, units as f64 * cell);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn generated_maze_is_valid_and_seeded() {
        for walls in [WallStyle::Single, WallStyle::Double { thickness_m: 0.1 }] {
            for door in [None, Some(1.0)] {
                let mut config = MazeConfig::small("t");
                config.walls = walls;
                config.doorway_m = door;
                let scene = generate_maze(&config, 42).unwrap();
                assert_eq!(scene.validate(), Ok(()), "{walls:?} {door:?}");
                assert_eq!(scene, generate_maze(&config, 42).unwrap());
                assert_ne!(scene, generate_maze(&config, 43).unwrap());
            }
        }
    }

    #[test]
    fn tour_visits_every_cell() {
        let config = MazeConfig { clutter: 0, ..MazeConfig::small("t") };
        let scene = generate_maze(&config, 7).unwrap();
        let cell = config.cell_m;
        let mut seen = vec![false; config.cols * config.rows];
        let mut prev = [scene.trajectory.start.x, scene.trajectory.start.y];
        for w in &scene.trajectory.waypoints {
            // Every cell centre on the straight leg from prev to w is visited.
            let steps = ((w[0] - prev[0]).abs() + (w[1] - prev[1]).abs()) / cell;
            for s in 0..=steps.round() as usize {
                let f = if steps > 0.0 { s as f64 / steps } else { 0.0 };
                let x = prev[0] + (w[0] - prev[0]) * f;
                let y = prev[1] + (w[1] - prev[1]) * f;
                seen[(y / cell) as usize * config.cols + (x / cell) as usize] = true;
            }
            prev = *w;
        }
        assert!(seen.iter().all(|s| *s));
    }

    #[test]
    fn bad_configs_are_errors() {
        let mut c = MazeConfig::small("t");
        c.cols = 0;
        assert!(generate_maze(&c, 1).is_err());
        let mut c = MazeConfig::small("t");
        c.doorway_m = Some(5.0);
        assert!(generate_maze(&c, 1).is_err());
    }
}
