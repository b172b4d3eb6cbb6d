//! [`WallGrid`]: a uniform grid over the walls of a world, each cell listing
//! the walls that cross it, and the cell walk of a ray through it
//! (Amanatides & Woo, "A fast voxel traversal algorithm for ray tracing",
//! 1987). [`crate::World`] casts its rays with it.
//!
//! parry2d's bounding boxes and its box/segment clipping decide which cells a
//! wall crosses; the walk and the exact hit are `f64` code of our own. A ray
//! visits the cells it crosses in order and stops at the first cell whose far
//! side lies beyond the nearest hit found so far, so it tests only the walls
//! near its own path: one step and one or two wall tests per cell, with no
//! tree to descend (parry2d's BVH traversal measured 20-42 nodes a ray).

use parry2d::bounding_volume::Aabb;
use parry2d::math::Vector as GlamVec;
use pcaline_geometry::{Point2, Vector2};

/// Cells per wall the grid aims at: `cell_m = sqrt(area / (CELLS_PER_WALL *
/// walls))`. Measured on generated mazes of 50 to 10,000 walls
/// (`benches/raycast.rs`, 2026-12-02): 1, 2, 4 and 8 cells per wall cost
/// within the bench's noise of each other (64-109 µs a scan); 2 is the middle.
const CELLS_PER_WALL: f64 = 2.0;

/// A uniform grid of square cells over the bounding box of the walls, in the
/// world frame, with the walls crossing each cell in compressed rows.
///
/// Edge cases: no walls (or only walls with non-finite points) gives an empty
/// grid that no ray enters; walls along one line (a bounding box of zero
/// area) give a single row of cells; a wall lying on a cell boundary is listed
/// in the cells on both sides (the cells are padded when the walls are
/// assigned, so rounding cannot lose a wall).
#[derive(Debug, Clone)]
pub(crate) struct WallGrid {
    /// World-frame corner of cell (0, 0), metres.
    min_m: [f64; 2],
    /// Side of a cell, metres (> 0 when the grid has cells).
    cell_m: f64,
    cols: usize,
    rows: usize,
    /// Cell `c = row * cols + col` lists `walls[starts[c]..starts[c + 1]]`.
    starts: Vec<u32>,
    walls: Vec<u32>,
}

impl WallGrid {
    /// The grid over the segments `ends` (world frame, metres), indexed as
    /// given.
    pub(crate) fn new(ends: &[(Point2<f64>, Point2<f64>)]) -> Self {
        let finite = |(a, b): &&(Point2<f64>, Point2<f64>)| {
            a.x.is_finite() && a.y.is_finite() && b.x.is_finite() && b.y.is_finite()
        };
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        let mut count = 0usize;
        for (a, b) in ends.iter().filter(finite) {
            for p in [a, b] {
                lo = [lo[0].min(p.x), lo[1].min(p.y)];
                hi = [hi[0].max(p.x), hi[1].max(p.y)];
            }
            count += 1;
        }
        if count == 0 {
            return WallGrid {
                min_m: [0.0; 2],
                cell_m: 1.0,
                cols: 0,
                rows: 0,
                starts: vec![0],
                walls: Vec::new(),
            };
        }
        let (width, height) = (hi[0] - lo[0], hi[1] - lo[1]);
        let longest = width.max(height);
        // sqrt(area / cells) for the cell count aimed at; never so small that
        // one side gets more than `CELLS_PER_WALL * walls` cells (a thin
        // world), never zero (a single point).
        let cell_m = (width * height / (CELLS_PER_WALL * count as f64))
            .sqrt()
            .max(longest / (CELLS_PER_WALL * count as f64))
            .max(1e-6);
        // One spare cell on each side keeps every wall strictly inside.
        let min_m = [lo[0] - cell_m, lo[1] - cell_m];
        let cols = (width / cell_m) as usize + 3;
        let rows = (height / cell_m) as usize + 3;
        let mut grid =
            WallGrid { min_m, cell_m, cols, rows, starts: Vec::new(), walls: Vec::new() };

        // (cell, wall) pairs, sorted by cell into compressed rows.
        let pad = (1e-3 * cell_m) as f32 + 1e-4;
        let mut pairs: Vec<(u32, u32)> = Vec::new();
        for (i, (a, b)) in ends.iter().enumerate() {
            if !finite(&&(*a, *b)) {
                continue;
            }
            let (c0, r0) = grid.cell_of(a.x.min(b.x), a.y.min(b.y));
            let (c1, r1) = grid.cell_of(a.x.max(b.x), a.y.max(b.y));
            let (pa, pb) =
                (GlamVec::new(a.x as f32, a.y as f32), GlamVec::new(b.x as f32, b.y as f32));
            for r in r0.saturating_sub(1)..=(r1 + 1).min(rows - 1) {
                for c in c0.saturating_sub(1)..=(c1 + 1).min(cols - 1) {
                    let cell_lo = GlamVec::new(
                        (min_m[0] + c as f64 * cell_m) as f32 - pad,
                        (min_m[1] + r as f64 * cell_m) as f32 - pad,
                    );
                    let side = cell_m as f32 + 2.0 * pad;
                    let cell = Aabb::new(cell_lo, cell_lo + GlamVec::new(side, side));
                    if cell.clip_segment(pa, pb).is_some() {
                        pairs.push(((r * cols + c) as u32, i as u32));
                    }
                }
            }
        }
        pairs.sort_unstable();
        grid.starts = vec![0; cols * rows + 1];
        for &(cell, _) in &pairs {
            grid.starts[cell as usize + 1] += 1;
        }
        for c in 0..cols * rows {
            grid.starts[c + 1] += grid.starts[c];
        }
        grid.walls = pairs.into_iter().map(|(_, w)| w).collect();
        grid
    }

    /// The cell holding the world point `(x, y)`, clamped to the grid.
    fn cell_of(&self, x: f64, y: f64) -> (usize, usize) {
        let clamp = |v: f64, n: usize| (v.max(0.0) as usize).min(n - 1);
        (
            clamp((x - self.min_m[0]) / self.cell_m, self.cols),
            clamp((y - self.min_m[1]) / self.cell_m, self.rows),
        )
    }

    /// Walks the cells the ray `origin + t dir` crosses for `t` in
    /// `[0, max_t]`, in order, handing each cell's walls to `test`, which
    /// returns the distance of the nearest hit found so far (or `max_t`).
    /// Stops at the first cell whose far side lies at or beyond that
    /// distance: no wall in a later cell can be nearer.
    ///
    /// Edge cases: a ray starting outside the grid enters it where it
    /// crosses the grid's box (or never); a ray along a cell boundary walks
    /// the cells on one side, which list the boundary's walls as well; a zero
    /// direction component never steps along that axis; a non-finite origin or
    /// direction visits nothing.
    pub(crate) fn walk(
        &self,
        origin: &Point2<f64>,
        dir: &Vector2<f64>,
        max_t: f64,
        mut test: impl FnMut(&[u32]) -> f64,
    ) {
        if self.cols == 0 {
            return;
        }
        // Entry into the grid's box (slab test).
        let span = [self.cols as f64 * self.cell_m, self.rows as f64 * self.cell_m];
        let (mut enter, mut exit) = (0.0f64, max_t);
        for axis in 0..2 {
            let (o, d) = (origin[axis] - self.min_m[axis], dir[axis]);
            if d == 0.0 {
                if !(0.0..=span[axis]).contains(&o) {
                    return;
                }
            } else {
                let (t0, t1) = (-o / d, (span[axis] - o) / d);
                enter = enter.max(t0.min(t1));
                exit = exit.min(t0.max(t1));
            }
        }
        if enter.is_nan() || exit.is_nan() || enter > exit {
            return; // misses the grid, or a non-finite ray
        }
        let start = origin + dir * enter;
        let (mut col, mut row) = self.cell_of(start.x, start.y);
        // Per axis: the step, the t of the next boundary, the t between
        // boundaries.
        let setup = |axis: usize, cell: usize| -> (isize, f64, f64) {
            let d = dir[axis];
            if d > 0.0 {
                let edge = self.min_m[axis] + (cell + 1) as f64 * self.cell_m;
                (1, (edge - origin[axis]) / d, self.cell_m / d)
            } else if d < 0.0 {
                let edge = self.min_m[axis] + cell as f64 * self.cell_m;
                (-1, (edge - origin[axis]) / d, -self.cell_m / d)
            } else {
                (0, f64::INFINITY, f64::INFINITY)
            }
        };
        let (step_c, mut next_c, delta_c) = setup(0, col);
        let (step_r, mut next_r, delta_r) = setup(1, row);
        let mut best = max_t;
        loop {
            let cell = row * self.cols + col;
            let walls = &self.walls[self.starts[cell] as usize..self.starts[cell + 1] as usize];
            if !walls.is_empty() {
                best = test(walls);
            }
            let cell_exit = next_c.min(next_r);
            if best <= cell_exit || cell_exit > exit {
                return;
            }
            if next_c < next_r {
                match col.checked_add_signed(step_c) {
                    Some(c) if c < self.cols => col = c,
                    _ => return,
                }
                next_c += delta_c;
            } else {
                match row.checked_add_signed(step_r) {
                    Some(r) if r < self.rows => row = r,
                    _ => return,
                }
                next_r += delta_r;
            }
        }
    }
}
