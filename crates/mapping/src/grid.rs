//! A uniform grid over segment extents: the spatial index that keeps matching
//! cost independent of the size of the map. Each segment remembers the cells
//! it is registered in, so it can be removed or renumbered exactly.

use crate::fast_hash::FastMap;
use pcaline_geometry::Point2;

type Key = (i32, i32);

/// Cells of `cell_m` metres, each listing the segments that pass through it.
#[derive(Debug, Clone, Default)]
pub(crate) struct Grid {
    cell_m: f64,
    cells: FastMap<Key, Vec<u32>>,
    /// `cells_of[id]`: the cells segment `id` is registered in.
    cells_of: Vec<Vec<Key>>,
}

impl Grid {
    pub(crate) fn new(cell_m: f64) -> Self {
        Grid { cell_m, cells: FastMap::default(), cells_of: Vec::new() }
    }

    fn key(&self, x: f64, y: f64) -> Key {
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
        if self.cells_of.len() <= id as usize {
            self.cells_of.resize_with(id as usize + 1, Vec::new);
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
                self.cells_of[id as usize].push(key);
            }
        }
    }

    /// Removes segment `id` from every cell it is registered in.
    pub(crate) fn remove(&mut self, id: u32) {
        let Some(keys) = self.cells_of.get_mut(id as usize).map(std::mem::take) else { return };
        for key in keys {
            if let Some(ids) = self.cells.get_mut(&key) {
                ids.retain(|&i| i != id);
                if ids.is_empty() {
                    self.cells.remove(&key);
                }
            }
        }
    }

    /// Renumbers segment `from` as `to` (which must not be registered).
    pub(crate) fn rename(&mut self, from: u32, to: u32) {
        let Some(keys) = self.cells_of.get_mut(from as usize).map(std::mem::take) else { return };
        for key in &keys {
            if let Some(ids) = self.cells.get_mut(key) {
                ids.iter_mut().filter(|i| **i == from).for_each(|i| *i = to);
            }
        }
        if self.cells_of.len() <= to as usize {
            self.cells_of.resize_with(to as usize + 1, Vec::new);
        }
        self.cells_of[to as usize] = keys;
    }

    /// Calls `f` for each segment registered in a cell within `radius_m` of
    /// `p` (a segment may be reported more than once). Nothing for a
    /// non-finite point; a radius wider than the occupied cells costs no more
    /// than visiting all of them.
    pub(crate) fn for_each_near(&self, p: &Point2<f64>, radius_m: f64, mut f: impl FnMut(u32)) {
        if !(p.x.is_finite() && p.y.is_finite()) {
            return;
        }
        let (lo, hi) =
            (self.key(p.x - radius_m, p.y - radius_m), self.key(p.x + radius_m, p.y + radius_m));
        // A radius spanning more cells than are occupied: visit the occupied
        // ones instead of walking a huge empty window.
        let window =
            (i64::from(hi.0) - i64::from(lo.0) + 1) * (i64::from(hi.1) - i64::from(lo.1) + 1);
        if window > self.cells.len() as i64 {
            let inside = |k: &Key| (lo.0..=hi.0).contains(&k.0) && (lo.1..=hi.1).contains(&k.1);
            self.cells.iter().filter(|(k, _)| inside(k)).for_each(|(_, ids)| {
                ids.iter().for_each(|&id| f(id));
            });
            return;
        }
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

    fn near(g: &Grid, x: f64, y: f64) -> Vec<u32> {
        let mut found = vec![];
        g.for_each_near(&Point2::new(x, y), 1.0, |id| found.push(id));
        found
    }

    #[test]
    fn finds_segments_passing_nearby() {
        let mut g = Grid::new(1.0);
        g.insert(7, &Point2::new(0.0, 0.0), &Point2::new(10.0, 0.0));
        assert!(near(&g, 9.5, 0.8).contains(&7));
        assert!(near(&g, 5.0, 5.0).is_empty());
        assert!(near(&g, f64::NAN, 0.0).is_empty());
    }

    #[test]
    fn a_huge_radius_visits_the_occupied_cells_once() {
        let mut g = Grid::new(1.0);
        g.insert(3, &Point2::new(0.0, 0.0), &Point2::new(2.5, 0.0));
        g.insert(4, &Point2::new(100.0, 50.0), &Point2::new(100.5, 50.0));
        let mut wide = vec![];
        g.for_each_near(&Point2::new(0.0, 0.0), 1e12, |id| wide.push(id));
        wide.sort_unstable();
        assert_eq!(wide, vec![3, 3, 3, 4]);
        let mut narrow = vec![];
        g.for_each_near(&Point2::new(0.0, 0.0), 10.0, |id| narrow.push(id));
        assert_eq!(narrow, vec![3, 3, 3]);
    }

    #[test]
    fn removal_and_renaming_are_exact() {
        let mut g = Grid::new(1.0);
        g.insert(0, &Point2::new(0.0, 0.0), &Point2::new(3.0, 0.0));
        g.insert(1, &Point2::new(0.0, 5.0), &Point2::new(3.0, 5.0));
        // Re-registering a grown extent adds cells, never duplicates.
        g.insert(1, &Point2::new(0.0, 5.0), &Point2::new(6.0, 5.0));
        g.remove(0);
        assert!(near(&g, 1.0, 0.0).is_empty());
        g.rename(1, 0);
        assert!(near(&g, 5.5, 5.0).contains(&0));
        assert!(!near(&g, 5.5, 5.0).contains(&1));
        g.remove(0);
        assert!(g.cells.is_empty(), "{:?}", g.cells);
    }
}
