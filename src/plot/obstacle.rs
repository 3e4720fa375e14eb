//! The rigid obstacles in a picture (docs/method.md §12.4): the zero level set of φ(x − a(t)) by
//! marching squares, chained into curves, moved away from Γ₃ like the displacement.

use super::error::PlotError;
use crate::mesh::Mesh;
use crate::plot::kit::bounding_box;
use crate::plot::Gamma3;
use crate::scene::Scene;
use std::collections::HashMap;

/// The outlines of the scene's rigid obstacles at time `time` (moved by their motion a(t)) for
/// the deformed picture: the zero level set of φ(x − a(t)) over the body's box with a margin
/// of 15 % of its diagonal ([`level_set_segments`], 400 cells along the longer side), moved by
/// [`magnify_from`] like the displacement, and kept where it falls within 8 % of the picture's
/// diagonal around the body (docs/method.md §12.4).
#[allow(clippy::too_many_arguments)]
pub(super) fn obstacle_edges(
    scene: &Scene,
    mesh: &Mesh<2>,
    u: &[[f64; 2]],
    moved: &[[f64; 2]],
    foundation: Option<&[[f64; 2]]>,
    gamma3: Option<&Gamma3>,
    time: f64,
    scale: f64,
) -> Result<Vec<ObstacleEdge>, PlotError> {
    if scene.contact.iter().all(|c| c.obstacle.is_none()) {
        return Ok(vec![]);
    }
    let deformed: Vec<[f64; 2]> = mesh
        .points
        .iter()
        .zip(u)
        .map(|(p, d)| [p[0] + d[0], p[1] + d[1]])
        .collect();
    let grow = |(lo, hi): ([f64; 2], [f64; 2]), by: f64| {
        let m = by * ((hi[0] - lo[0]).powi(2) + (hi[1] - lo[1]).powi(2)).sqrt();
        ([lo[0] - m, lo[1] - m], [hi[0] + m, hi[1] + m])
    };
    let all: Vec<[f64; 2]> = mesh.points.iter().chain(&deformed).copied().collect();
    let (lo, hi) = grow(bounding_box(&all), 0.15);
    let mut shown: Vec<[f64; 2]> = mesh.points.iter().chain(moved).copied().collect();
    shown.extend(foundation.into_iter().flatten());
    let (plo, phi_) = grow(bounding_box(&shown), 0.08);
    let within = |p: [f64; 2]| p[0] >= plo[0] && p[0] <= phi_[0] && p[1] >= plo[1] && p[1] <= phi_[1];
    // Γ₃'s segments: consecutive nodes along it that are joined by a boundary edge
    let segments: Vec<[[f64; 2]; 2]> = gamma3.map_or_else(Vec::new, |g3| {
        g3.order
            .windows(2)
            .filter_map(|w| {
                let (p, q) = (mesh.points[g3.nodes[w[0]]], mesh.points[g3.nodes[w[1]]]);
                let d = ((q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2)).sqrt();
                ((g3.arc[w[1]] - g3.arc[w[0]] - d).abs() <= 1e-9 * d.max(1e-300) && d > 0.0).then_some([p, q])
            })
            .collect()
    });
    let diagonal = ((hi[0] - lo[0]).powi(2) + (hi[1] - lo[1]).powi(2)).sqrt();
    let longer = (hi[0] - lo[0]).max(hi[1] - lo[1]);
    let cells = |extent: f64| ((400.0 * extent / longer).ceil() as usize).max(1);
    let mut edges = Vec::new();
    for (i, c) in scene.contact.iter().enumerate() {
        let Some(spec) = &c.obstacle else { continue };
        let key = format!("{}.obstacle", scene.contact_key(i));
        let obstacle = crate::solver::contact::obstacle_of::<2>(spec, &key, "scene.toml", diagonal)
            .map_err(|e| PlotError::Scene(e.to_string()))?;
        let mut a = [0.0; 2];
        for (k, e) in spec.motion().unwrap_or(&[]).iter().enumerate().take(2) {
            let expr = crate::scene::Expr::parse(e, &["t"])
                .map_err(|err| PlotError::Scene(format!("scene.toml: {key}.motion[{k}] = \"{e}\": {err}")))?;
            a[k] = expr.eval(&[time]);
        }
        let phi = |x: [f64; 2]| obstacle.phi(&[x[0] - a[0], x[1] - a[1]]);
        let mut found = level_set_segments(&phi, lo, hi, cells(hi[0] - lo[0]), cells(hi[1] - lo[1]));
        magnify_from(&mut found, &segments, scale);
        edges.extend(found.into_iter().filter(|e| within(e.a) && within(e.b)));
    }
    Ok(edges)
}

/// A piece of an obstacle's outline in the deformed picture (docs/method.md §12.4): a segment
/// and the unit direction from it into the obstacle (where φ < 0).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ObstacleEdge {
    pub a: [f64; 2],
    pub b: [f64; 2],
    pub inward: [f64; 2],
}

/// The zero level set of φ over the box `lo`–`hi` by marching squares on an `nx` × `ny` grid
/// (the crossing on each grid edge by linear interpolation, a saddle resolved by the value at
/// the cell's centre), each segment with the direction −∇φ/|∇φ| at its midpoint (central
/// differences of a tenth of a grid cell). Exact for a plane; for a circle of radius R the
/// vertices lie within about h²/(8R) of it, h the grid spacing.
pub fn level_set_segments(
    phi: &dyn Fn([f64; 2]) -> f64,
    lo: [f64; 2],
    hi: [f64; 2],
    nx: usize,
    ny: usize,
) -> Vec<ObstacleEdge> {
    let (nx, ny) = (nx.max(1), ny.max(1));
    let d = [(hi[0] - lo[0]) / nx as f64, (hi[1] - lo[1]) / ny as f64];
    let at = |i: usize, j: usize| [lo[0] + i as f64 * d[0], lo[1] + j as f64 * d[1]];
    let values: Vec<f64> = (0..=ny)
        .flat_map(|j| (0..=nx).map(move |i| (i, j)))
        .map(|(i, j)| phi(at(i, j)))
        .collect();
    let v = |i: usize, j: usize| values[j * (nx + 1) + i];
    let cross = |p: [f64; 2], q: [f64; 2], a: f64, b: f64| {
        let t = if a == b { 0.5 } else { a / (a - b) };
        [p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])]
    };
    let step = 0.1 * d[0].abs().min(d[1].abs());
    let inward = |m: [f64; 2]| {
        let g = [
            phi([m[0] + step, m[1]]) - phi([m[0] - step, m[1]]),
            phi([m[0], m[1] + step]) - phi([m[0], m[1] - step]),
        ];
        let n = (g[0] * g[0] + g[1] * g[1]).sqrt();
        if n > 0.0 && n.is_finite() {
            [-g[0] / n, -g[1] / n]
        } else {
            [0.0, 0.0]
        }
    };
    let mut edges = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            let corner = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)];
            let val = corner.map(|(a, b)| v(a, b));
            if val.iter().any(|x| !x.is_finite()) {
                continue;
            }
            let inside = val.map(|x| x < 0.0);
            // the crossings on the edges bottom, right, top, left (corner k to k + 1)
            let crossings: Vec<(usize, [f64; 2])> = (0..4)
                .filter(|&k| inside[k] != inside[(k + 1) % 4])
                .map(|k| {
                    // from the corner of lower (j, i) to the other, as the neighbouring cell
                    // does too: both compute the same point, bit for bit
                    let (mut p, mut q, mut vp, mut vq) = (corner[k], corner[(k + 1) % 4], val[k], val[(k + 1) % 4]);
                    if (q.1, q.0) < (p.1, p.0) {
                        std::mem::swap(&mut p, &mut q);
                        std::mem::swap(&mut vp, &mut vq);
                    }
                    (k, cross(at(p.0, p.1), at(q.0, q.1), vp, vq))
                })
                .collect();
            let pairs: Vec<([f64; 2], [f64; 2])> = match crossings.len() {
                2 => vec![(crossings[0].1, crossings[1].1)],
                4 => {
                    let centre = phi([at(i, j)[0] + 0.5 * d[0], at(i, j)[1] + 0.5 * d[1]]);
                    let c = |k: usize| crossings[k].1;
                    if (centre < 0.0) == inside[0] {
                        // corners 0 and 2 joined through the centre: cut off corners 1 and 3
                        vec![(c(0), c(1)), (c(2), c(3))]
                    } else {
                        vec![(c(3), c(0)), (c(1), c(2))]
                    }
                }
                _ => vec![],
            };
            for (a, b) in pairs {
                let m = [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0];
                edges.push(ObstacleEdge {
                    a,
                    b,
                    inward: inward(m),
                });
            }
        }
    }
    // a grid vertex exactly on the curve (φ = 0) makes a segment of no length in a cell
    // touching it: dropped, the curve runs through the vertex in the neighbouring cells
    let tol = 1e-9 * d[0].abs().max(d[1].abs());
    edges.retain(|e| (e.a[0] - e.b[0]).abs().max((e.a[1] - e.b[1]).abs()) > tol);
    chain(edges, tol)
}

/// The edges reordered (and turned) so that each next one starts where the previous one ended,
/// curve by curve (open curves from an end): the hatching then runs at an even pitch along each
/// curve. Ends closer than `tol` are one point (a grid edge's crossing is computed in both cells
/// that share it).
pub(super) fn chain(edges: Vec<ObstacleEdge>, tol: f64) -> Vec<ObstacleEdge> {
    let key = |p: [f64; 2]| ((p[0] / tol).round() as i64, (p[1] / tol).round() as i64);
    let mut at: HashMap<(i64, i64), Vec<usize>> = HashMap::new();
    for (i, e) in edges.iter().enumerate() {
        at.entry(key(e.a)).or_default().push(i);
        at.entry(key(e.b)).or_default().push(i);
    }
    let degree = |p: [f64; 2]| at.get(&key(p)).map_or(0, Vec::len);
    let n = edges.len();
    let starts: Vec<usize> = (0..n)
        .filter(|&i| degree(edges[i].a) == 1 || degree(edges[i].b) == 1)
        .chain(0..n)
        .collect();
    let mut used = vec![false; n];
    let mut out = Vec::with_capacity(n);
    for start in starts {
        if used[start] {
            continue;
        }
        used[start] = true;
        let mut e = edges[start];
        if degree(e.b) == 1 && degree(e.a) != 1 {
            std::mem::swap(&mut e.a, &mut e.b);
        }
        loop {
            out.push(e);
            let end = e.b;
            let Some(j) = at.get(&key(end)).and_then(|v| v.iter().copied().find(|&j| !used[j])) else {
                break;
            };
            used[j] = true;
            e = edges[j];
            if key(e.a) != key(end) {
                std::mem::swap(&mut e.a, &mut e.b);
            }
        }
    }
    out
}

/// The outline moved into a picture whose displacements are magnified by `scale`: each point y
/// goes to f + scale·(y − f), f the closest point of the undeformed Γ₃ (`gamma3`, its segments),
/// so that distances from Γ₃ are magnified like the displacement and a node resting on the
/// obstacle is drawn on it (docs/method.md §12.4). Unchanged at scale 1 or without Γ₃.
pub fn magnify_from(edges: &mut [ObstacleEdge], gamma3: &[[[f64; 2]; 2]], scale: f64) {
    if scale == 1.0 || gamma3.is_empty() {
        return;
    }
    let closest = |y: [f64; 2]| {
        gamma3
            .iter()
            .map(|[p, q]| {
                let e = [q[0] - p[0], q[1] - p[1]];
                let ee = e[0] * e[0] + e[1] * e[1];
                let t = if ee > 0.0 {
                    (((y[0] - p[0]) * e[0] + (y[1] - p[1]) * e[1]) / ee).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                let f = [p[0] + t * e[0], p[1] + t * e[1]];
                ((y[0] - f[0]).powi(2) + (y[1] - f[1]).powi(2), f)
            })
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .map(|(_, f)| f)
            .expect("Γ₃ has a segment")
    };
    let map = |y: [f64; 2]| {
        let f = closest(y);
        [f[0] + scale * (y[0] - f[0]), f[1] + scale * (y[1] - f[1])]
    };
    for e in edges.iter_mut() {
        e.a = map(e.a);
        e.b = map(e.b);
    }
}
