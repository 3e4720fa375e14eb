//! The master facets near a point, nearest boxes first (docs/method.md §18.1): a uniform grid of
//! cells about the mean facet size over the facets' bounding boxes, searched ring by ring around
//! the point. After ring r every facet not yet seen lies at least r·h away, so a projection
//! closer than that is the nearest; a point that has none within [`RINGS`] rings (far from the
//! surface, or off its rim) takes every facet in order of box distance, as a plain scan would.
//! Written by hand: the crates with spatial indices (rstar, kiddo) answer nearest-point queries,
//! not "boxes in order of distance, stopped by the caller".

use std::collections::HashMap;

/// Rings of cells searched before the plain scan; with cells of the mean facet size a node whose
/// gap is up to about 8 facets finds its facet within them.
pub const RINGS: i64 = 8;

/// An axis-aligned box: (lower corner, upper corner).
pub type Aabb<const D: usize> = ([f64; D], [f64; D]);

/// The grid over the facets' boxes.
pub struct FacetGrid<const D: usize> {
    boxes: Vec<Aabb<D>>,
    origin: [f64; D],
    h: f64,
    cells: HashMap<[i64; D], Vec<usize>>,
}

impl<const D: usize> FacetGrid<D> {
    pub fn new(boxes: Vec<Aabb<D>>) -> Self {
        let mut origin = [f64::INFINITY; D];
        let mut size = 0.0;
        for (lo, hi) in &boxes {
            for k in 0..D {
                origin[k] = origin[k].min(lo[k]);
            }
            size += (0..D).map(|k| hi[k] - lo[k]).fold(0.0, f64::max);
        }
        let h = (size / boxes.len().max(1) as f64).max(f64::MIN_POSITIVE);
        let mut grid = FacetGrid {
            boxes,
            origin,
            h,
            cells: HashMap::new(),
        };
        for (i, (lo, hi)) in grid.boxes.iter().enumerate() {
            let (a, b) = (grid.cell(lo), grid.cell(hi));
            let mut c = a;
            loop {
                grid.cells.entry(c).or_default().push(i);
                // the next cell of the box, the first axis fastest
                let mut k = 0;
                while k < D {
                    if c[k] < b[k] {
                        c[k] += 1;
                        break;
                    }
                    c[k] = a[k];
                    k += 1;
                }
                if k == D {
                    break;
                }
            }
        }
        grid
    }

    fn cell(&self, x: &[f64; D]) -> [i64; D] {
        std::array::from_fn(|k| ((x[k] - self.origin[k]) / self.h).floor() as i64)
    }

    /// The squared distance from `x` to facet i's box.
    pub fn box_distance2(&self, i: usize, x: &[f64; D]) -> f64 {
        let (lo, hi) = &self.boxes[i];
        (0..D).map(|k| (lo[k] - x[k]).max(x[k] - hi[k]).max(0.0).powi(2)).sum()
    }

    /// Offers the facets to `visit` nearest boxes first, in batches: each batch sorted by (box
    /// distance², index) with the distance below which every later facet lies; `visit` returns
    /// whether to go on.
    pub fn visit(&self, x: &[f64; D], mut visit: impl FnMut(&[(f64, usize)], f64) -> bool) {
        let centre = self.cell(x);
        let mut seen = vec![false; self.boxes.len()];
        for r in 0..=RINGS {
            let mut batch = Vec::new();
            self.ring(centre, r, &mut |c| {
                if let Some(list) = self.cells.get(c) {
                    for &i in list {
                        if !std::mem::replace(&mut seen[i], true) {
                            batch.push((self.box_distance2(i, x), i));
                        }
                    }
                }
            });
            batch.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            if !visit(&batch, r as f64 * self.h) {
                return;
            }
        }
        // the rest, as a plain scan
        let mut rest: Vec<(f64, usize)> = (0..self.boxes.len())
            .filter(|&i| !seen[i])
            .map(|i| (self.box_distance2(i, x), i))
            .collect();
        rest.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        visit(&rest, f64::INFINITY);
    }

    /// Calls `f` on every cell at Chebyshev distance exactly r from `centre`.
    fn ring(&self, centre: [i64; D], r: i64, f: &mut impl FnMut(&[i64; D])) {
        let mut offset = [-r; D];
        loop {
            if offset.iter().any(|o| o.abs() == r) {
                let c: [i64; D] = std::array::from_fn(|k| centre[k] + offset[k]);
                f(&c);
            }
            let mut k = 0;
            while k < D {
                if offset[k] < r {
                    offset[k] += 1;
                    break;
                }
                offset[k] = -r;
                k += 1;
            }
            if k == D {
                break;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every facet is offered exactly once, and the batches' bounds hold: a facet offered after
    /// a batch with bound b lies at least b away.
    #[test]
    fn every_facet_once_and_the_bounds_hold() {
        let boxes: Vec<Aabb<2>> = (0..50)
            .map(|i| {
                let x = (i as f64 * 0.37).sin() * 3.0;
                let y = (i as f64 * 0.71).cos() * 2.0;
                ([x, y], [x + 0.1 + 0.01 * i as f64, y + 0.2])
            })
            .collect();
        let grid = FacetGrid::new(boxes.clone());
        for x in [[0.0, 0.0], [10.0, -4.0], [1.3, 0.2]] {
            let mut offered = Vec::new();
            let mut bound: f64 = 0.0;
            grid.visit(&x, |batch, b| {
                for &(d2, i) in batch {
                    assert!(
                        d2.sqrt() >= bound - 1e-12,
                        "facet {i} at {} before bound {bound}",
                        d2.sqrt()
                    );
                    offered.push(i);
                }
                bound = b;
                true
            });
            offered.sort_unstable();
            assert_eq!(offered, (0..50).collect::<Vec<_>>());
        }
    }
}
