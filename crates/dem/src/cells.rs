//! Linked-cell neighbour search: O(N), rayon-parallel, deterministic (the pair list depends
//! only on the positions, never on the thread count).

use super::grains::Grains;
use rayon::prelude::*;

/// Grains binned into square cells at least as wide as the largest contact distance.
#[derive(Debug, Clone, Default)]
pub struct CellList {
    nx: usize,
    ny: usize,
    /// Grains of cell c are `order[start[c]..start[c + 1]]`, in increasing index.
    start: Vec<u32>,
    order: Vec<u32>,
}

impl CellList {
    /// Bin `g` into cells of width ≥ `min_size` (m), normally twice the largest radius.
    /// The grid covers the grains' bounding box; it is coarsened when that box is sparse, so
    /// memory stays O(N).
    pub fn build(g: &Grains, min_size: f64) -> Self {
        let n = g.len();
        if n == 0 {
            return Self::default();
        }
        let fold = |v: &[f64]| {
            v.iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                    (a.min(x), b.max(x))
                })
        };
        let ((x0, x1), (y0, y1)) = (fold(&g.x), fold(&g.y));
        // Grains flung to infinity (a run going unstable) share one cell rather than
        // overflow the grid; the run's energy check then stops it.
        let (x1, y1) = (
            if (x1 - x0).is_finite() { x1 } else { x0 },
            if (y1 - y0).is_finite() { y1 } else { y0 },
        );
        let mut size = min_size;
        let cells = |s: f64| {
            let along = |span: f64| ((span / s) as usize).saturating_add(1);
            along(x1 - x0).saturating_mul(along(y1 - y0))
        };
        while cells(size) > 4 * n + 64 {
            size *= 2.0;
        }
        let nx = ((x1 - x0) / size) as usize + 1;
        let ny = ((y1 - y0) / size) as usize + 1;
        // NaN and infinite positions fall in cell 0 or the last column/row (`as usize`
        // saturates), never outside the grid.
        let cell_of = |i: usize| {
            let cx = (((g.x[i] - x0) / size) as usize).min(nx - 1);
            let cy = (((g.y[i] - y0) / size) as usize).min(ny - 1);
            cy * nx + cx
        };
        // Counting sort: stable, so each cell lists its grains in increasing index.
        let mut start = vec![0u32; nx * ny + 1];
        let which: Vec<usize> = (0..n).map(cell_of).collect();
        for &c in &which {
            start[c + 1] += 1;
        }
        for c in 0..nx * ny {
            start[c + 1] += start[c];
        }
        let mut fill = start.clone();
        let mut order = vec![0u32; n];
        for (i, &c) in which.iter().enumerate() {
            order[fill[c] as usize] = i as u32;
            fill[c] += 1;
        }
        Self {
            nx,
            ny,
            start,
            order,
        }
    }

    fn cell(&self, c: usize) -> &[u32] {
        &self.order[self.start[c] as usize..self.start[c + 1] as usize]
    }

    /// The grains below `owned` in cell order (row-major cells, increasing index within a
    /// cell): a permutation that puts grains near each other close in memory.
    pub fn owned_order(&self, owned: usize) -> Vec<u32> {
        self.order
            .iter()
            .copied()
            .filter(|&i| (i as usize) < owned)
            .collect()
    }

    /// Follow a reordering of the grains: new grain k is old grain `order[k]` for
    /// k < `order.len()`; later grains keep their index.
    pub fn renumber(&mut self, order: &[u32]) {
        let mut new_of = vec![0u32; order.len()];
        for (k, &o) in order.iter().enumerate() {
            new_of[o as usize] = k as u32;
        }
        for i in &mut self.order {
            if (*i as usize) < order.len() {
                *i = new_of[*i as usize];
            }
        }
    }

    /// Every touching pair (i < j, overlap > 0), in cell order.
    pub fn touching_pairs(&self, g: &Grains) -> Vec<(u32, u32)> {
        self.pairs_within(g, 0.0)
    }

    /// Every pair (i < j) closer than r_i + r_j + `skin`, in cell order: each cell with
    /// itself, then with its E, NE, N and NW neighbours (each pair of cells visited once).
    /// Precondition: the cells were built at least 2 r_max + `skin` wide.
    pub fn pairs_within(&self, g: &Grains, skin: f64) -> Vec<(u32, u32)> {
        if self.order.is_empty() {
            return Vec::new();
        }
        let (nx, ny) = (self.nx as isize, self.ny as isize);
        // One task per row of cells (one allocation per row, not per cell).
        (0..self.ny)
            .into_par_iter()
            .flat_map_iter(|row| {
                let mut out = Vec::new();
                let mut test = |i: u32, j: u32| {
                    let (a, b) = (i as usize, j as usize);
                    let dx = g.x[b] - g.x[a];
                    let dy = g.y[b] - g.y[a];
                    let reach = g.r[a] + g.r[b] + skin;
                    if dx * dx + dy * dy < reach * reach {
                        out.push((i.min(j), i.max(j)));
                    }
                };
                for c in row * self.nx..(row + 1) * self.nx {
                    let (cx, cy) = ((c % self.nx) as isize, (c / self.nx) as isize);
                    let mine = self.cell(c);
                    for (k, &i) in mine.iter().enumerate() {
                        for &j in &mine[k + 1..] {
                            test(i, j);
                        }
                    }
                    for (dx, dy) in [(1, 0), (1, 1), (0, 1), (-1, 1)] {
                        let (ox, oy) = (cx + dx, cy + dy);
                        if ox < 0 || ox >= nx || oy >= ny {
                            continue;
                        }
                        let other = self.cell((oy * nx + ox) as usize);
                        for &i in mine {
                            for &j in other {
                                test(i, j);
                            }
                        }
                    }
                }
                out.into_iter()
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The cell list finds exactly the pairs a brute-force O(N²) search finds.
    #[test]
    fn matches_brute_force() {
        let mut g = Grains::default();
        let mut rng = crate::sample::Rng::new(12345);
        let mut rnd = || rng.uniform();
        for _ in 0..600 {
            let (x, y, r) = (rnd(), rnd() * 0.5, 0.005 + 0.01 * rnd());
            g.push([x, y], r, 2500.0, false);
        }
        let rmax = g.r.iter().cloned().fold(0.0, f64::max);
        let mut fast = CellList::build(&g, 2.0 * rmax).touching_pairs(&g);
        let mut slow = Vec::new();
        for i in 0..g.len() {
            for j in i + 1..g.len() {
                let (dx, dy) = (g.x[j] - g.x[i], g.y[j] - g.y[i]);
                if dx * dx + dy * dy < (g.r[i] + g.r[j]).powi(2) {
                    slow.push((i as u32, j as u32));
                }
            }
        }
        fast.sort();
        assert!(!slow.is_empty());
        assert_eq!(fast, slow);
    }
}
