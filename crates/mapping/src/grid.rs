//! A uniform grid over segment extents: the spatial index that keeps matching
//! cost independent of the size of the map.

use pcaline_geometry::Point2;
use std::collections::HashMap;

/// Cells of `cell_m` metres, each listing the segments that pass through it.
#[derive(Debug, Clone, Default)]
pub(crate) struct Grid {
    cell_m: f64,
    cells: HashMap<(i32, i32), Vec<u32>>,
}

impl Grid {
    pub(crate) fn new(cell_m: f64) -> Self {
        Grid { cell_m, cells: HashMap::new() }
    }

    fn key(&self, x: f64, y: f64) -> (i32, i32) {
        let clamp = |v: f64| (v / self.cell_m).floor().clamp(-1e9, 1e9) as i32;
        (clamp(x), clamp(y))
    }

    /// Registers segment `id` in every cell it passes through (sampled at a
    /// third of a cell, so no cell is skipped). Already registered cells are
    /// not duplicated.
    pub(crate) fn insert(&mut self, id: u32, a: &Point2<f64>, b: &Point2<f64>) {
        let len = (b - a).norm();
        if !len.is_finite() {
            return;
        }
        let steps = ((len / (self.cell_m / 3.0)).ceil() as usize).clamp(1, 1 << 20);
        let mut last = None;
        for k in 0..=steps {
            let p = a + (b - a) * (k as f64 / steps as f64);
            let key = self.key(p.x, p.y);
            if last == Some(key) {
                continue;
            }
            last = Some(key);
            let ids = self.cells.entry(key).or_default();
            if !ids.contains(&id) {
                ids.push(id);
            }
        }
    }

    /// Calls `f` for each segment registered in a cell within `radius_m` of
    /// `p` (a segment may be reported more than once).
    pub(crate) fn for_each_near(&self, p: &Point2<f64>, radius_m: f64, mut f: impl FnMut(u32)) {
        if !(p.x.is_finite() && p.y.is_finite()) {
            return;
        }
        let (lo, hi) =
            (self.key(p.x - radius_m, p.y - radius_m), self.key(p.x + radius_m, p.y + radius_m));
        for i in lo.0..=hi.0 {
            for j in lo.1..=hi.1 {
                if let Some(ids) = self.cells.get(&(i, j)) {
                    ids.iter().for_each(|&id| f(id));
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_segments_passing_nearby() {
        let mut g = Grid::new(1.0);
        g.insert(7, &Point2::new(0.0, 0.0), &Point2::new(10.0, 0.0));
        let mut found = vec![];
        g.for_each_near(&Point2::new(9.5, 0.8), 1.0, |id| found.push(id));
        assert!(found.contains(&7));
        found.clear();
        g.for_each_near(&Point2::new(5.0, 5.0), 1.0, |id| found.push(id));
        assert!(found.is_empty());
        g.for_each_near(&Point2::new(f64::NAN, 0.0), 1.0, |id| found.push(id));
        assert!(found.is_empty());
    }
}
