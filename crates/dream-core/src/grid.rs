//! Uniform grid over the plane: the spatial index behind every "who is near whom" query.
//!
//! Cells are squares of side `cell`; a query within distance `cell` of a point only has to
//! look at the 3x3 block of cells around it, so a whole-swarm query costs O(N * k), not O(N^2).

use std::collections::HashMap;

/// Points bucketed by cell, stored as CSR (`starts`, `members`) so a cell's points are contiguous.
#[derive(Debug, Clone)]
pub struct Grid {
    cell: f64,
    index: HashMap<(i64, i64), usize>,
    starts: Vec<usize>,
    members: Vec<usize>,
}

impl Grid {
    /// Buckets the points `(xs[i], ys[i])` into cells of side `cell` (> 0, finite: checked by the caller).
    pub fn new(xs: &[f64], ys: &[f64], cell: f64) -> Self {
        let keys: Vec<(i64, i64)> = xs
            .iter()
            .zip(ys)
            .map(|(&x, &y)| cell_of(x, y, cell))
            .collect();
        let mut index: HashMap<(i64, i64), usize> = HashMap::with_capacity(keys.len());
        let mut counts: Vec<usize> = Vec::new();
        let slots: Vec<usize> = keys
            .iter()
            .map(|key| {
                let next = counts.len();
                let slot = *index.entry(*key).or_insert(next);
                if slot == next {
                    counts.push(0);
                }
                counts[slot] += 1;
                slot
            })
            .collect();
        let mut starts = Vec::with_capacity(counts.len() + 1);
        starts.push(0);
        for count in &counts {
            starts.push(starts.last().copied().unwrap_or(0) + count);
        }
        let mut fill = starts.clone();
        let mut members = vec![0; keys.len()];
        for (point, &slot) in slots.iter().enumerate() {
            members[fill[slot]] = point;
            fill[slot] += 1;
        }
        Self {
            cell,
            index,
            starts,
            members,
        }
    }

    /// Calls `visit(j)` for every point in the 3x3 block of cells around `(x, y)`
    /// (a superset of the points within `cell` of it), in increasing cell order.
    pub fn for_each_near(&self, x: f64, y: f64, mut visit: impl FnMut(usize)) {
        let (cx, cy) = cell_of(x, y, self.cell);
        for dx in -1..=1_i64 {
            for dy in -1..=1_i64 {
                let key = (cx.saturating_add(dx), cy.saturating_add(dy));
                if let Some(&slot) = self.index.get(&key) {
                    for &j in &self.members[self.starts[slot]..self.starts[slot + 1]] {
                        visit(j);
                    }
                }
            }
        }
    }
}

fn cell_of(x: f64, y: f64, cell: f64) -> (i64, i64) {
    // `as` saturates for huge coordinates, which only merges far-away cells: still correct.
    ((x / cell).floor() as i64, (y / cell).floor() as i64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn near_points_are_visited_once() {
        let xs = [0.0, 0.05, 0.3, -0.09, 5.0];
        let ys = [0.0, 0.02, 0.0, 0.0, 5.0];
        let grid = Grid::new(&xs, &ys, 0.1);
        let mut seen = Vec::new();
        grid.for_each_near(0.0, 0.0, |j| seen.push(j));
        seen.sort();
        assert_eq!(seen, vec![0, 1, 3]);
    }

    #[test]
    fn empty_grid_visits_nothing() {
        let grid = Grid::new(&[], &[], 1.0);
        let mut count = 0;
        grid.for_each_near(0.0, 0.0, |_| count += 1);
        assert_eq!(count, 0);
    }
}
