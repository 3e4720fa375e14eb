//! Point location and interpolation of nodal P1/Q1 fields between meshes (docs/method.md §6: a
//! coarse solution is compared with the reference by carrying it onto the reference mesh).
//!
//! [`Locator`] puts the cells of a mesh into a uniform bucket grid over their bounding boxes,
//! once; [`Locator::locate`] then finds the cell holding a point and its reference
//! coordinates (barycentric for P1, Newton on the bi- or trilinear map for Q1), in 2D and 3D. [`Transfer`] keeps
//! the located weights for a fixed set of target points, so that many fields (one per output
//! time) are carried at the cost of a sparse product each.
//!
//! Carrying is nodal interpolation: exact for nested meshes (a coarse Q1/P1 field is itself
//! in the fine space) and for linear fields on any meshes.

use crate::mesh::element::{invert, map_at, reference, reference_centroid, shape_at, MAX_NODES};
use crate::mesh::vector::distance;
use crate::mesh::{Cell, CellKind, Mesh};

/// Relative tolerance (of the mesh diameter) for points on or just outside the boundary.
pub const OUTSIDE_TOLERANCE: f64 = 1e-10;

/// A bucket grid over the cells of one mesh (2D or 3D), for point location.
pub struct Locator<'m, const D: usize> {
    cells: &'m [Cell],
    points: &'m [[f64; D]],
    origin: [f64; D],
    bucket: [f64; D],
    dims: [usize; D],
    /// CSR: cells of bucket b are `items[start[b]..start[b + 1]]`.
    start: Vec<usize>,
    items: Vec<u32>,
    /// Physical tolerance for points outside every cell.
    tolerance: f64,
}

impl<'m, const D: usize> Locator<'m, D> {
    /// Builds the bucket grid of `mesh` (about one cell per bucket).
    pub fn new(mesh: &'m Mesh<D>) -> Self {
        Self::from_parts(&mesh.cells, &mesh.points)
    }

    /// Builds the bucket grid of the given cells and points.
    pub fn from_parts(cells: &'m [Cell], points: &'m [[f64; D]]) -> Self {
        let (mut lo, mut hi) = ([f64::INFINITY; D], [f64::NEG_INFINITY; D]);
        for c in cells {
            for &p in c.nodes() {
                for d in 0..D {
                    lo[d] = lo[d].min(points[p][d]);
                    hi[d] = hi[d].max(points[p][d]);
                }
            }
        }
        if cells.is_empty() {
            (lo, hi) = ([0.0; D], [0.0; D]);
        }
        let diam = (0..D).map(|d| (hi[d] - lo[d]).powi(2)).sum::<f64>().sqrt();
        let tolerance = OUTSIDE_TOLERANCE * diam;
        let pad = 2.0 * tolerance + f64::MIN_POSITIVE;
        let ext: [f64; D] = std::array::from_fn(|d| (hi[d] - lo[d]).max(diam * 1e-6) + 2.0 * pad);
        let origin: [f64; D] = std::array::from_fn(|d| lo[d] - pad);
        // about one cell per bucket, buckets as square as the box allows; at most about 4·10⁶
        // buckets (2048 per side in 2D, 160 in 3D)
        let n = cells.len().max(1) as f64;
        let per_cell = ext.iter().product::<f64>() / n;
        let side = if D == 2 { per_cell.sqrt() } else { per_cell.cbrt() }.max(f64::MIN_POSITIVE);
        let limit = if D == 2 { 2048 } else { 160 };
        let dims: [usize; D] = std::array::from_fn(|d| ((ext[d] / side).ceil() as usize).clamp(1, limit));
        let bucket: [f64; D] = std::array::from_fn(|d| ext[d] / dims[d] as f64);
        let range = |c: &Cell| {
            let (mut a, mut b) = ([f64::INFINITY; D], [f64::NEG_INFINITY; D]);
            for &p in c.nodes() {
                for d in 0..D {
                    a[d] = a[d].min(points[p][d] - pad);
                    b[d] = b[d].max(points[p][d] + pad);
                }
            }
            let i = |v: f64, d: usize| (((v - origin[d]) / bucket[d]).floor().max(0.0) as usize).min(dims[d] - 1);
            (
                std::array::from_fn::<usize, D, _>(|d| i(a[d], d)),
                std::array::from_fn::<usize, D, _>(|d| i(b[d], d)),
            )
        };
        // the buckets of the index box [a, b] (first axis fastest)
        let buckets = |a: [usize; D], b: [usize; D]| {
            let mut out = Vec::new();
            let mut idx = a;
            loop {
                out.push(flat(&dims, &idx));
                let mut d = 0;
                loop {
                    if d == D {
                        return out;
                    }
                    if idx[d] < b[d] {
                        idx[d] += 1;
                        break;
                    }
                    idx[d] = a[d];
                    d += 1;
                }
            }
        };
        let mut count = vec![0usize; dims.iter().product::<usize>() + 1];
        for c in cells {
            let (a, b) = range(c);
            for k in buckets(a, b) {
                count[k + 1] += 1;
            }
        }
        for b in 1..count.len() {
            count[b] += count[b - 1];
        }
        let start = count.clone();
        let mut items = vec![0u32; *count.last().unwrap_or(&0)];
        for (k, c) in cells.iter().enumerate() {
            let (a, b) = range(c);
            for j in buckets(a, b) {
                let slot = &mut count[j];
                items[*slot] = k as u32;
                *slot += 1;
            }
        }
        Locator {
            cells,
            points,
            origin,
            bucket,
            dims,
            start,
            items,
            tolerance,
        }
    }

    /// The physical distance tolerated outside the mesh (1e-10 × its diameter).
    pub fn tolerance(&self) -> f64 {
        self.tolerance
    }

    /// The cell holding `x` and the reference coordinates of `x` in it (P1: barycentrics
    /// (1 − Σξ, ξ₁, …); Q1: ξ ∈ [−1, 1]^D; 3 components, the unused ones 0), or None if `x` is
    /// outside the mesh by more than [`Locator::tolerance`].
    pub fn locate(&self, x: [f64; D]) -> Option<(usize, [f64; 3])> {
        self.locate_with_distance(x)
            .filter(|&(_, _, d)| d <= self.tolerance)
            .map(|(c, xi, _)| (c, xi))
    }

    /// Like [`Locator::locate`], but returns the best candidate whatever its distance,
    /// with that distance (None only if no cell's bucket covers `x`).
    pub fn locate_with_distance(&self, x: [f64; D]) -> Option<(usize, [f64; 3], f64)> {
        let mut idx = [0usize; D];
        for d in 0..D {
            let f = (x[d] - self.origin[d]) / self.bucket[d];
            if !(f >= 0.0 && f < self.dims[d] as f64) {
                return None;
            }
            idx[d] = f as usize;
        }
        let b = flat(&self.dims, &idx);
        let mut best: Option<(usize, [f64; 3], f64)> = None;
        for &k in &self.items[self.start[b]..self.start[b + 1]] {
            let k = k as usize;
            let (xi, dist) = reference_coordinates(&self.cells[k], self.points, x);
            if best.is_none_or(|(_, _, d)| dist < d) {
                best = Some((k, xi, dist));
                if dist == 0.0 {
                    break;
                }
            }
        }
        best
    }

    /// Locates every point once, for carrying many fields to the same points.
    pub fn transfer(&self, to_points: &[[f64; D]]) -> Result<Transfer, String> {
        self.locate_all(to_points, self.tolerance, |x| self.outside_message(x))
            .map(|(transfer, _)| transfer)
    }

    /// [`Locator::transfer`] for meshes of a curved domain that are not nested: a target point
    /// outside the mesh by at most `allowed` (the O(h²) gap between two polygonal approximations
    /// of one curved boundary, [`boundary_sagitta`]) is evaluated by extending its nearest cell's
    /// map there; farther is an error. Reports how many points were extended and the farthest.
    pub fn transfer_extending(&self, to_points: &[[f64; D]], allowed: f64) -> Result<(Transfer, Extension), String> {
        let allowed = allowed.max(self.tolerance);
        self.locate_all(to_points, allowed, |x| {
            format!(
                "{}; a curved boundary meshed twice differs by O(h²), bounded here by {allowed:.3e} (the coarse \
                 boundary's chords' sagitta, twice over): farther means the meshes are not of the same geometry (or \
                 not in the same units)",
                self.outside_message(x)
            )
        })
    }

    /// The interpolation weights of every point in the cell nearest to it, when that is at most
    /// `allowed` away (else the error `refuse` words), and the points beyond round-off.
    fn locate_all(
        &self,
        to_points: &[[f64; D]],
        allowed: f64,
        refuse: impl Fn([f64; D]) -> String,
    ) -> Result<(Transfer, Extension), String> {
        let mut extension = Extension {
            points: 0,
            farthest: 0.0,
            allowed,
        };
        let mut weights = Vec::with_capacity(to_points.len());
        for &x in to_points {
            let (c, xi, d) = match self.locate_with_distance(x) {
                Some(found) if found.2 <= allowed => found,
                _ => return Err(refuse(x)),
            };
            if d > self.tolerance {
                extension.points += 1;
                extension.farthest = extension.farthest.max(d);
            }
            let cell = &self.cells[c];
            let s = shape_at(cell, self.points, xi);
            let mut nodes = [0usize; MAX_NODES];
            let mut w = [0.0; MAX_NODES];
            nodes[..s.n].copy_from_slice(&cell.nodes()[..s.n]);
            w[..s.n].copy_from_slice(&s.value[..s.n]);
            weights.push((s.n as u8, nodes, w));
        }
        let transfer = Transfer {
            n_from: self.points.len(),
            weights,
        };
        Ok((transfer, extension))
    }

    fn outside_message(&self, x: [f64; D]) -> String {
        let at = x.iter().map(|v| format!("{v:.17e}")).collect::<Vec<_>>().join(", ");
        match self.locate_with_distance(x) {
            Some((_, _, d)) => format!(
                "point ({at}) lies outside the mesh: {d:.3e} from the nearest cell (tolerance {:.3e})",
                self.tolerance
            ),
            None => format!("point ({at}) lies outside the bounding box of the mesh"),
        }
    }
}

/// Target points evaluated outside the source mesh by [`Locator::transfer_extending`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Extension {
    /// How many lay outside (beyond round-off).
    pub points: usize,
    /// The largest distance of one from the mesh.
    pub farthest: f64,
    /// The distance that was allowed.
    pub allowed: f64,
}

/// A bound on how far a polygonal (faceted) boundary can lie inside the curved boundary it
/// approximates, from the mesh alone: at each boundary node (2D) or edge (3D) where two boundary
/// facets meet at an angle θ below 30° (a curve, not a corner of the geometry), a chord of length
/// h on a circle turning by θ per chord has sagitta h θ / 8; twice that, over the boundary. Zero
/// on a polygonal domain (θ = 0 or a corner everywhere).
pub fn boundary_sagitta<const D: usize>(mesh: &Mesh<D>) -> f64 {
    let facets = mesh.boundary_facets();
    let x = |p: usize| mesh.points[p];
    let sub = |a: [f64; D], b: [f64; D]| -> [f64; 3] { std::array::from_fn(|k| if k < D { a[k] - b[k] } else { 0.0 }) };
    let norm = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    // each facet's outward normal (unnormalised) and its longest edge
    let shape: Vec<([f64; 3], f64)> = facets
        .iter()
        .map(|f| {
            let n = f.nodes();
            let longest = (0..n.len())
                .map(|i| norm(sub(x(n[(i + 1) % n.len()]), x(n[i]))))
                .fold(0.0, f64::max);
            let normal = match n.len() {
                2 => {
                    let d = sub(x(n[1]), x(n[0]));
                    [d[1], -d[0], 0.0]
                }
                3 => cross(sub(x(n[1]), x(n[0])), sub(x(n[2]), x(n[0]))),
                _ => cross(sub(x(n[2]), x(n[0])), sub(x(n[3]), x(n[1]))),
            };
            (normal, longest)
        })
        .collect();
    // facets meeting at a node (2D) or an edge (3D)
    let mut by_key: std::collections::HashMap<(usize, usize), Vec<usize>> = std::collections::HashMap::new();
    for (i, f) in facets.iter().enumerate() {
        let n = f.nodes();
        if D == 2 {
            for &p in n {
                by_key.entry((p, p)).or_default().push(i);
            }
        } else {
            for k in 0..n.len() {
                let (a, b) = (n[k], n[(k + 1) % n.len()]);
                by_key.entry((a.min(b), a.max(b))).or_default().push(i);
            }
        }
    }
    let limit = 30f64.to_radians();
    let mut bound = 0.0f64;
    for list in by_key.values() {
        for (a, &i) in list.iter().enumerate() {
            for &j in &list[a + 1..] {
                let (ni, nj) = (shape[i].0, shape[j].0);
                let cos = (ni[0] * nj[0] + ni[1] * nj[1] + ni[2] * nj[2]) / (norm(ni) * norm(nj));
                let theta = cos.clamp(-1.0, 1.0).acos();
                if theta < limit {
                    bound = bound.max(shape[i].1.max(shape[j].1) * theta / 4.0);
                }
            }
        }
    }
    bound
}

/// The flat index of a bucket (first axis fastest).
fn flat<const D: usize>(dims: &[usize; D], idx: &[usize; D]) -> usize {
    (0..D).rev().fold(0, |acc, d| acc * dims[d] + idx[d])
}

/// Interpolation weights from the nodes of one mesh to a fixed list of points.
pub struct Transfer {
    n_from: usize,
    weights: Vec<(u8, [usize; MAX_NODES], [f64; MAX_NODES])>,
}

impl Transfer {
    /// Number of target points.
    pub fn len(&self) -> usize {
        self.weights.len()
    }

    /// True if there are no target points.
    pub fn is_empty(&self) -> bool {
        self.weights.is_empty()
    }

    /// Evaluates the nodal field `u` (on the source mesh) at the target points.
    pub fn apply<const D: usize>(&self, u: &[[f64; D]]) -> Vec<[f64; D]> {
        assert_eq!(
            u.len(),
            self.n_from,
            "field has {} nodes, the source mesh {}",
            u.len(),
            self.n_from
        );
        self.weights
            .iter()
            .map(|(n, nodes, w)| {
                let mut v = [0.0; D];
                for a in 0..*n as usize {
                    for (d, vd) in v.iter_mut().enumerate() {
                        *vd += w[a] * u[nodes[a]][d];
                    }
                }
                v
            })
            .collect()
    }
}

/// Evaluates the FE field `u` (nodal values on `from`) at each of `to_points`. A point outside
/// `from` by more than 1e-10 × its diameter is an error naming the point.
pub fn interpolate_nodal<const D: usize>(
    from: &Mesh<D>,
    u: &[[f64; D]],
    to_points: &[[f64; D]],
) -> Result<Vec<[f64; D]>, String> {
    if u.len() != from.points.len() {
        return Err(format!(
            "field has {} nodal values, the mesh {} nodes",
            u.len(),
            from.points.len()
        ));
    }
    Ok(Locator::new(from).transfer(to_points)?.apply(u))
}

/// Reference coordinates of `x` in `cell` (3 components, the unused ones 0) and the physical
/// distance from `x` to the cell (0 inside), in any dimension: Newton on the cell's (affine,
/// bilinear, trilinear or, for a pyramid, rational) map from the cell's centre. The distance: for P1 the largest signed
/// distance to a facet (−λ_i / |∇λ_i|); for a Q1 quadrilateral, whose edges are straight, the
/// distance to the polygon; for a Q1 hexahedron 0 when ξ ∈ [−1, 1]³, else |x − x(clamp ξ)| (an
/// upper bound, exact in the direction of one face), and likewise for prisms and pyramids
/// (clamped into their reference cells). Far from the cell (farther than half its
/// size from its bounding box) the distance to that box, without coordinates. Outside the cell
/// the coordinates extrapolate the map (exactly for P1; for Q1 Newton's last iterate,
/// meaningful only close to the cell).
pub fn reference_coordinates<const D: usize>(cell: &Cell, points: &[[f64; D]], x: [f64; D]) -> ([f64; 3], f64) {
    let nodes = cell.nodes();
    let (mut lo, mut hi) = ([f64::INFINITY; D], [f64::NEG_INFINITY; D]);
    for &p in nodes {
        for d in 0..D {
            lo[d] = lo[d].min(points[p][d]);
            hi[d] = hi[d].max(points[p][d]);
        }
    }
    let size = (0..D).map(|d| hi[d] - lo[d]).fold(0.0, f64::max);
    let outside_box = (0..D)
        .map(|d| (lo[d] - x[d]).max(x[d] - hi[d]).max(0.0).powi(2))
        .sum::<f64>()
        .sqrt();
    if outside_box > 0.5 * size {
        return ([f64::NAN; 3], outside_box);
    }
    let map = |xi: [f64; 3]| {
        let (n, v, g) = reference(cell, xi);
        map_at(cell, points, n, &v, &g)
    };
    let linear_simplex = matches!(cell, Cell::Tri3(_) | Cell::Tet4(_));
    let start = reference_centroid(cell);
    let Some(xi) = newton(map, x, start, size) else {
        return ([0.0; 3], f64::INFINITY);
    };
    let (y, _) = map(xi);
    let residual = distance(&x, &y);
    if residual > 1e-10 * size {
        // Newton failed (a degenerate cell): unusable
        return (xi, f64::INFINITY);
    }
    let dist = if linear_simplex {
        let s = shape_at(cell, points, xi);
        (0..nodes.len())
            .map(|a| {
                let g = s.grad[a].iter().map(|v| v * v).sum::<f64>().sqrt();
                -s.value[a] / g
            })
            .fold(0.0, f64::max)
    } else if cell.kind().is_simplex() {
        // a second-order (curved) simplex: inside when every barycentric coordinate is ≥ 0; else
        // the distance to the map of the reference point clamped into the simplex (an upper
        // bound, exact across one face)
        let dim = cell.dim();
        let sum: f64 = xi[..dim].iter().sum();
        if xi[..dim].iter().all(|&v| v >= 0.0) && sum <= 1.0 {
            0.0
        } else {
            let mut c = xi.map(|v| v.max(0.0));
            c[dim..].iter_mut().for_each(|v| *v = 0.0);
            let s: f64 = c.iter().sum();
            if s > 1.0 {
                c.iter_mut().for_each(|v| *v /= s);
            }
            let (y, _) = map(c);
            distance(&x, &y)
        }
    } else if let Cell::Quad4(_) = cell {
        // the edges of a Q1 quadrilateral are straight: the distance to the polygon
        let corner: Vec<[f64; 2]> = nodes.iter().map(|&p| [points[p][0], points[p][1]]).collect();
        let at = [x[0], x[1]];
        if polygon_contains(&corner, at) {
            0.0
        } else {
            polygon_distance(&corner, at)
        }
    } else if cell.kind().linear() == CellKind::Prism6 {
        // triangle × segment: inside when ξ, η ≥ 0, ξ + η ≤ 1, |ζ| ≤ 1; else the distance to the
        // map of the nearest such point (clamped: an upper bound, exact across one face)
        let inside = xi[0] >= 0.0 && xi[1] >= 0.0 && xi[0] + xi[1] <= 1.0 && xi[2].abs() <= 1.0;
        if inside {
            0.0
        } else {
            let (mut a, mut b) = (xi[0].max(0.0), xi[1].max(0.0));
            if a + b > 1.0 {
                let excess = 0.5 * (a + b - 1.0);
                (a, b) = ((a - excess).max(0.0), (b - excess).max(0.0));
                let s = a + b;
                if s > 1.0 {
                    (a, b) = (a / s, b / s);
                }
            }
            let (y, _) = map([a, b, xi[2].clamp(-1.0, 1.0)]);
            distance(&x, &y)
        }
    } else if let Cell::Pyr5(_) = cell {
        // inside when 0 ≤ ζ ≤ 1 and |ξ|, |η| ≤ 1 − ζ; else the distance to the map of the point
        // clamped into the pyramid (an upper bound, exact across one face)
        let side = 1.0 - xi[2];
        if (0.0..=1.0).contains(&xi[2]) && xi[0].abs() <= side && xi[1].abs() <= side {
            0.0
        } else {
            let z = xi[2].clamp(0.0, 1.0);
            let (y, _) = map([xi[0].clamp(z - 1.0, 1.0 - z), xi[1].clamp(z - 1.0, 1.0 - z), z]);
            distance(&x, &y)
        }
    } else if xi.iter().all(|v| v.abs() <= 1.0) {
        0.0
    } else {
        let (y, _) = map(xi.map(|v| v.clamp(-1.0, 1.0)));
        distance(&x, &y)
    };
    (xi, dist)
}

/// Newton on a cell's map x(ξ) (value and Jacobian) from `start` towards `x`: at most 50 steps,
/// far-away iterates kept bounded; None when a step is not finite.
fn newton<const D: usize>(
    map: impl Fn([f64; 3]) -> ([f64; D], [[f64; D]; D]),
    x: [f64; D],
    start: [f64; 3],
    size: f64,
) -> Option<[f64; 3]> {
    let mut xi = start;
    for _ in 0..50 {
        let (y, j) = map(xi);
        let r: [f64; D] = std::array::from_fn(|k| x[k] - y[k]);
        if r.iter().map(|v| v.abs()).sum::<f64>() <= 1e-15 * size {
            break;
        }
        let (inv, det) = invert(&j);
        if det.abs() <= f64::MIN_POSITIVE {
            break;
        }
        let d: [f64; D] = std::array::from_fn(|k| (0..D).map(|c| inv[k][c] * r[c]).sum());
        if d.iter().any(|v| !v.is_finite()) {
            return None;
        }
        let mut step = 0.0;
        for k in 0..D {
            // keep far-away iterates bounded (the point is outside then anyway)
            xi[k] = (xi[k] + d[k]).clamp(-1e3, 1e3);
            step += d[k].abs();
        }
        if step <= 1e-15 {
            break;
        }
    }
    Some(xi)
}

/// True if `x` lies in the closed polygon `p` (crossing number; points on an edge count in).
fn polygon_contains(p: &[[f64; 2]], x: [f64; 2]) -> bool {
    if polygon_distance(p, x) == 0.0 {
        return true;
    }
    let mut inside = false;
    for i in 0..p.len() {
        let (a, b) = (p[i], p[(i + 1) % p.len()]);
        if (a[1] > x[1]) != (b[1] > x[1]) {
            let cross = a[0] + (x[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
            if x[0] < cross {
                inside = !inside;
            }
        }
    }
    inside
}

/// Euclidean distance from `x` to the boundary of the polygon `p`.
fn polygon_distance(p: &[[f64; 2]], x: [f64; 2]) -> f64 {
    (0..p.len())
        .map(|i| {
            let (a, b) = (p[i], p[(i + 1) % p.len()]);
            let (e, r) = ([b[0] - a[0], b[1] - a[1]], [x[0] - a[0], x[1] - a[1]]);
            let ee = e[0] * e[0] + e[1] * e[1];
            let s = if ee > 0.0 {
                ((r[0] * e[0] + r[1] * e[1]) / ee).clamp(0.0, 1.0)
            } else {
                0.0
            };
            ((r[0] - s * e[0]).powi(2) + (r[1] - s * e[1]).powi(2)).sqrt()
        })
        .fold(f64::INFINITY, f64::min)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Point location in a pyramid (docs/method.md §8.1): Newton on its rational map recovers
    /// the reference coordinates of points all over a pyramid with a warped base and a tilted
    /// apex (to 1e-10: Newton's stopping test is 1e-15 of the cell size on the residual, and
    /// det J is of order 1 there), with distance 0; a point at δ below the base or beyond a
    /// triangle of the right pyramid is at a distance between δ and √2 δ (the clamped point on
    /// the face, not the nearest: an upper bound, exact across the base).
    #[test]
    fn points_are_located_in_pyramids() {
        let warped = [
            [0.0, 0.0, 0.05],
            [1.2, 0.1, 0.0],
            [1.0, 0.9, -0.1],
            [-0.1, 1.1, 0.02],
            [0.7, 0.3, 0.8],
        ];
        let cell = Cell::Pyr5([0, 1, 2, 3, 4]);
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed % 1_000_001) as f64 / 1_000_000.0
        };
        for _ in 0..200 {
            let z = 0.99 * next();
            let xi = [(2.0 * next() - 1.0) * (1.0 - z), (2.0 * next() - 1.0) * (1.0 - z), z];
            let x = shape_at(&cell, &warped, xi).x;
            let (found, dist) = reference_coordinates(&cell, &warped, x);
            assert_eq!(dist, 0.0, "{xi:?} → {found:?}");
            for k in 0..3 {
                assert!((found[k] - xi[k]).abs() < 1e-10, "{xi:?} → {found:?}");
            }
        }
        let right = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.5, 0.5, 0.5],
        ];
        let delta = 0.01;
        let (_, below) = reference_coordinates(&cell, &right, [0.3, 0.6, -delta]);
        assert!((below - delta).abs() < 1e-12, "below the base: {below}");
        // beyond the triangle y = z (outward normal (0, −1, 1)/√2) from its point (0.5, 0.2, 0.2)
        let s = delta / 2f64.sqrt();
        let (_, beyond) = reference_coordinates(&cell, &right, [0.5, 0.2 - s, 0.2 + s]);
        assert!(
            beyond >= delta * (1.0 - 1e-9) && beyond <= 2f64.sqrt() * delta * (1.0 + 1e-9),
            "beyond a triangle: {beyond}"
        );
        // inside, near the apex
        let (found, dist) = reference_coordinates(&cell, &right, [0.5, 0.5, 0.49]);
        assert_eq!(dist, 0.0);
        assert!((found[2] - 0.98).abs() < 1e-12 && found[0].abs() < 1e-12, "{found:?}");
    }
}
